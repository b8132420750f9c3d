/* The command line of dfp-sim replay (docs/replay.md): what to replay, what the user gives
 * instead of letting the capture say it, and what the check reports where. */
#ifndef DFP_SIM_REPLAY_ARGS_H
#define DFP_SIM_REPLAY_ARGS_H

#include <stdbool.h>
#include <stdint.h>

#include "capture/capture.h"
#include "cli_table.h"
#include "instrument.h"
#include "replay/infer.h"
#include "replay/mask.h"
#include "replay/replay.h"

/* --report json|junit FILE, at most this many. */
#define REPLAY_MAX_REPORTS 4u

/* KIND of --report KIND FILE, as cli_kind_file_t.kind. */
enum { REPLAY_REPORT_JSON, REPLAY_REPORT_JUNIT };

typedef struct replay_args {
    const char *file;
    replay_given_t given; /* --address, --baud, --fixed-baud, --inverter-delay, --timing */
    bool check;
    bool check_options; /* --report, --ignore or --max-mismatches given: they need --check */
    bool verbose;
    cap_format_t format;
    const char *lcm_channel;
    card_inverter_t inverter;
    replay_speed_t speed;
    const char *lcm_url;
    const char *http;
    instrument_http_opts_t web; /* --http-token-file ... */
    uint64_t max_listed;  /* --max-mismatches (0 given: REPLAY_LIST_ALL) */
    replay_mask_t mask;   /* --ignore */
    size_t n_reports;
    cli_kind_file_t reports[REPLAY_MAX_REPORTS];
} replay_args_t;

/* Parses and checks argv[2..]: 0, or EXIT_USAGE after one line on stderr. */
int replay_parse_args(int argc, char **argv, replay_args_t *a);

#endif
