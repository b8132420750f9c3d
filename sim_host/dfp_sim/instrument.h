/* What every running command shares: the log a person follows (--quiet, --log-level,
 * --timestamps) and the control API with the front panel (--http), both attached to the rig. */
#ifndef DFP_SIM_INSTRUMENT_H
#define DFP_SIM_INSTRUMENT_H

#include <stdbool.h>

#include "http/http_server.h"
#include "rig/rig_ctl.h"
#include "rig/rig_log.h"

typedef struct instrument_opts {
    const char *http; /* [ADDR:]PORT, NULL: no server */
    rig_log_level_t level;
    rig_log_time_t time;
} instrument_opts_t;

typedef struct instrument {
    rig_log_t log;
    rig_ctl_t ctl;
    bool ctl_on;
    http_server_t *http;
} instrument_t;

void instrument_defaults(instrument_opts_t *o, rig_log_time_t time);
/* --http, --quiet, --log-level, --timestamps: 1 when argv[*i] was one (consumed), 0 when not,
 * -1 after reporting a bad value. */
int instrument_option(int argc, char **argv, int *i, instrument_opts_t *o);
/* Attaches the log to the rig (before its cards and master, so it sees their first events). */
void instrument_attach_log(instrument_t *in, rig_t *r, const instrument_opts_t *o);
/* Starts the control API when asked (after rig_open). Returns 0, or EXIT_USAGE after reporting
 * (a taken port is a usage error: the user picks another). */
int instrument_start_http(instrument_t *in, rig_t *r, const instrument_opts_t *o,
                          const char *mode, bool read_only);
/* From the loop: carries out queued actions and publishes the state. */
void instrument_service(instrument_t *in);
void instrument_stop(instrument_t *in);

#endif
