/* What the monitor's three reports share: times relative to the start, hex, escaping, and the
 * verdicts the JUnit report and mon_report_ok give. */
#ifndef MONITOR_MON_REPORT_PRIV_H
#define MONITOR_MON_REPORT_PRIV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "monitor/mon_report.h"

#define MON_NO_HOLDER 255u
#define MON_HEX_MAX (2u * MON_IO_MAX + 1u)

/* Seconds from the monitor's start to t_ns (0 before it). */
double mon_rel_s(const mon_report_info_t *info, uint64_t t_ns);
/* "0205" for {0x02, 0x05}: out holds MON_HEX_MAX characters. */
void mon_hex(const uint8_t *p, size_t len, char *out);
/* s as a JSON string (quotes included) / as XML character data or attribute text. */
void mon_json_str(const mon_sink_t *out, const char *s);
void mon_xml_text(const mon_sink_t *out, const char *s);
/* The events that "last" lists: seqs [*first, total). */
uint64_t mon_first_listed(const mon_t *m, unsigned last_events);
/* "passive", "not ready", "ready", "in ring" for an FDL status octet. */
const char *mon_fdl_status_name(uint8_t fdl_status);

typedef enum mon_verdict {
    MON_PASS = 0,
    MON_FAIL,
    MON_SKIP,
} mon_verdict_t;

typedef struct mon_case {
    char name[40];
    mon_verdict_t verdict;
    char message[200];
} mon_case_t;

#define MON_CASES_PER_STATION 5u

/* The test cases of one address, in report order; returns how many (0: none). */
unsigned mon_station_cases(const mon_t *m, const mon_report_opts_t *opts, unsigned addr,
                           mon_case_t cases[MON_CASES_PER_STATION]);

#endif
