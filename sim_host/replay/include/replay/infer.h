/* What dfp-sim replay takes from the capture when the command line does not say it
 * (docs/replay.md "What is inferred"): the card's address, the bus rate, how the times were
 * taken (a line, or a tty/PTY), whether the card was on the bus before the capture began, and
 * the inverter's service time — each with the reason, for the report. What the command line
 * gives always wins. */
#ifndef REPLAY_INFER_H
#define REPLAY_INFER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "replay/replay.h"

/* The command line; a field not given stays 0 / false. */
typedef struct replay_given {
    const char *file;      /* for messages */
    bool have_address;
    uint8_t address;
    uint32_t baud;         /* --baud; 0: not given */
    bool fixed_baud;       /* --fixed-baud */
    bool have_delay;       /* --inverter-delay */
    uint32_t delay_us;
    bool have_timing;      /* --timing line|relaxed */
    replay_timing_t timing;
} replay_given_t;

typedef struct replay_inferred {
    uint8_t address;
    bool address_inferred;
    char address_source[160];
    uint32_t baud;           /* for records without a rate (all records with baud_override) */
    bool baud_override;
    bool baud_inferred;      /* not given with --baud */
    char baud_source[640];
    replay_timing_t timing;
    bool timing_inferred;
    bool timing_given;       /* --timing */
    char timing_source[480];
    bool fixed_baud;         /* the card starts at the bus rate */
    bool fixed_inferred;
    char fixed_source[240];  /* "" when the card searches, as after power-up */
    uint32_t delay_us;       /* the emulated inverter's time per parameter service */
    bool delay_inferred;
    char delay_source[160];
} replay_inferred_t;

/* The rate a relaxed capture replays at: the recorded spacing then always fits. */
#define REPLAY_RELAXED_BAUD 12000000u

/* Decides from the first pass (scan; NULL when there was none: a pipe, everything the replay
 * needs given) and the command line. st is the first pass's file status (records, error) for
 * messages. Returns 0, or -1 with the message in err when the address cannot be had (no slave
 * answers, several do). */
int replay_infer(const replay_scan_t *scan, const replay_file_status_t *st,
                 const replay_given_t *g, replay_inferred_t *out, char *err, size_t errlen);

#endif
