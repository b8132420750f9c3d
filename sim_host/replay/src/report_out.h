/* Inside the replay reports: helpers the text report, the JSON and the JUnit writer share. */
#ifndef REPLAY_REPORT_OUT_H
#define REPLAY_REPORT_OUT_H

#include <stdio.h>

#include "replay/replay.h"

/* "1.5 Mbit/s", "500 kbit/s". */
const char *replay_baud_text(uint32_t baud, char *buf, size_t max);
/* "record 12 (byte 345)". */
void replay_where(const replay_report_info_t *info, uint64_t record, uint64_t position, char *out,
                  size_t max);
/* What differs in one mismatch, in words: "octets 16, 17 differ (data octets 9, 10)", "the card
 * did not answer", ... */
void replay_listed_what(const replay_listed_t *m, char *out, size_t max);
/* One kept mismatch as the text report lists it: where, what, the three telegrams in hex. */
void replay_print_listed(FILE *out, const replay_report_info_t *info, const replay_listed_t *m);
/* Below the table: the kept mismatches ("... and K more"), the masked octets. */
void replay_print_list(FILE *out, const replay_t *r, const replay_report_info_t *info);
/* How many mismatches of service s (all services: REPLAY_SVC_COUNT) are kept in the list. */
uint64_t replay_list_count(replay_list_t *l, replay_service_t s);

/* Text as a JSON string, quotes included (NULL: null). */
void replay_json_string(FILE *out, const char *s);
/* Octets as a JSON string "68 11 ..." (absent: null). */
void replay_json_hex(FILE *out, bool present, const uint8_t *p, size_t len);
/* Text for XML character data or an attribute value: & < > " ' escaped, control characters
 * XML 1.0 cannot carry replaced by '?'. */
void replay_xml_text(FILE *out, const char *s);

#endif
