/* Octets of the card's answers that the replay check leaves out (dfp-sim replay --ignore,
 * docs/replay.md "Masks"): values that depend on the plant, not on the firmware — the process
 * input words of a running drive, a counter in a diagnosis.
 *
 * Two kinds, any number of each:
 *   PIn, PIn-m   process input words of Data_Exchange and Rd_Inp answers, counted from 1 after
 *                the 4-word parameter channel when the card's configuration has one (the
 *                configuration the card holds when the answer is judged: the capture's Chk_Cfg);
 *   SERVICE:n, SERVICE:n-m   octets of the data unit (after DA SA FC and the SAPs, counted from
 *                0) of the answers to that service; SERVICE is a short name (dx, diag, status,
 *                prm, cfg) or a service of the report's table (data_exchange, slave_diag,
 *                msac1_read ...; case, blanks and '_' alike).
 * A masked octet is not compared, and neither is the FCS of an answer with a masked octet (it
 * covers the masked octets). */
#ifndef REPLAY_MASK_H
#define REPLAY_MASK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "replay/decode.h"

/* The longest data unit of an FDL telegram: SD2 with LE = 249 leaves 246 octets after DA SA FC. */
#define REPLAY_MASK_OCTETS 246u
/* Process input words: at most 244 input octets. */
#define REPLAY_MASK_PI_WORDS 122u

typedef struct replay_mask {
    bool any;
    uint8_t pi[(REPLAY_MASK_PI_WORDS + 7u) / 8u];             /* bit k-1: PIk */
    uint8_t du[REPLAY_SVC_COUNT][(REPLAY_MASK_OCTETS + 7u) / 8u]; /* bit n: data octet n */
    char text[240]; /* the specs as given, comma-separated, for the report ("..." when cut) */
} replay_mask_t;

/* Adds one --ignore argument: items separated by commas. False, with the bad item and why in
 * err ("'dx:9-4': the range runs backwards"), when any item is wrong; m is then unchanged. */
bool replay_mask_add(replay_mask_t *m, const char *spec, char *err, size_t errlen);

/* The service a name stands for: a short name, a key (replay_service_key) or the report's
 * name, case, blanks, '-' and '_' alike. */
bool replay_service_parse(const char *name, replay_service_t *out);
/* A service's name for machines: the report's name in lower case, blanks as '_'
 * ("data_exchange", "msac1_read"). */
const char *replay_service_key(replay_service_t s, char *buf, size_t max);

/* The octets of one answer that m leaves out, as bits of its octet offsets (bit n: octet n of
 * the telegram); the FCS is included when any octet of the data unit is. service is the
 * request's; pi_offset is where PI1 begins in the data unit (8 with the parameter channel),
 * negative when the card's configuration is not known (PI words are then not masked). Returns
 * how many octets are masked. */
unsigned replay_mask_answer(const replay_mask_t *m, replay_service_t service, int pi_offset,
                            const uint8_t *answer, size_t len, uint8_t *bits, size_t bits_len);

static inline bool replay_bit(const uint8_t *bits, size_t n)
{
    return (bits[n / 8u] & (1u << (n % 8u))) != 0u;
}

#endif
