/* What every running command shares: the log a person follows (--quiet, --log-level,
 * --timestamps) and the control API with the front panel (--http and its --http-* options),
 * both attached to the rig. */
#ifndef DFP_SIM_INSTRUMENT_H
#define DFP_SIM_INSTRUMENT_H

#include <stdbool.h>

#include "cli_table.h"
#include "http/http_server.h"
#include "monitor/mon_rig.h"
#include "rig/rig_ctl.h"
#include "rig/rig_log.h"

/* Who may use the control API (docs/api.md "Security"). */
typedef struct instrument_http_opts {
    const char *token_file;        /* --http-token-file, else $DFP_SIM_TOKEN, else made */
    const char *viewer_token_file; /* --http-viewer-token-file, else $DFP_SIM_VIEWER_TOKEN */
    bool no_auth;                  /* --http-no-auth (loopback only) */
    const char *allow_host[HTTP_MAX_ALLOWED];
    size_t n_allow_host;
    const char *allow_origin[HTTP_MAX_ALLOWED];
    size_t n_allow_origin;
    const char *cert; /* --http-cert and --http-key: HTTPS */
    const char *key;
    bool given; /* any of these was given */
} instrument_http_opts_t;

typedef struct instrument_opts {
    const char *http; /* [ADDR:]PORT, NULL: no server */
    instrument_http_opts_t web;
    rig_log_level_t level;
    rig_log_time_t time;
} instrument_opts_t;

/* Where an event of the API itself goes besides GET /api/v1/log and the event stream (the
 * LCM telemetry): its request threads publish it to the bridge, the loop passes it on. */
typedef void instrument_api_event_fn(void *ctx, const rig_ctl_event_t *e);
#define INSTRUMENT_EVENT_BATCH 16u
/* The API's events the loop passes on in one turn (every 20 ms in wall-clock modes). */
#define INSTRUMENT_API_EVENTS_PER_TURN 32u

typedef struct instrument {
    rig_log_t log;
    rig_ctl_t ctl;
    bool ctl_on;
    http_server_t *http;
    instrument_api_event_fn *api_event; /* NULL: only the terminal */
    void *api_event_ctx;
    uint64_t api_seen; /* the bridge's first event not looked at yet */
    /* With --http: the bus monitor of the rig's line (GET /api/v1/bus, the panel's bus page,
     * log kind "bus"). On the heap, and kept until the process ends: the rig's tap points
     * at it as long as the rig runs. NULL: none (out of memory, or no tap left). */
    mon_rig_t *mon;
    /* Set before instrument_start_http by a command that brings its own monitor (dfp-sim
     * monitor): no monitor is attached to the rig's telegrams. */
    bool no_bus_monitor;
    rig_ctl_event_t batch[INSTRUMENT_EVENT_BATCH];
} instrument_t;

void instrument_defaults(instrument_opts_t *o, rig_log_time_t time);
/* --http [ADDR:]PORT and the log options (--quiet, --log-level, --timestamps) into an
 * instrument_opts_t; the --http-* options into its web (or another instrument_http_opts_t, for
 * a command that reads --http itself). */
extern const cli_opt_t instrument_options[4];
extern const cli_opt_t instrument_http_options[7];
/* Attaches the log to the rig (before its cards and master, so it sees their first events). */
void instrument_attach_log(instrument_t *in, rig_t *r, const instrument_opts_t *o);
/* Starts the control API when asked (after rig_open) and prints on stderr the URL to open, with
 * its token. Returns 0, or EXIT_USAGE after reporting (a taken port, a bad token or TLS file,
 * --http-no-auth off loopback: usage errors). */
int instrument_start_http(instrument_t *in, rig_t *r, const instrument_opts_t *o,
                          const char *mode, bool read_only);
/* From the loop: carries out queued actions, publishes the state (and the bus monitor's
 * document every MON_RIG_PUBLISH_NS), and prints the API's own
 * events (source "http": the audit of each action, a connection closed by a limit) on the
 * terminal log and hands them to api_event. */
void instrument_service(instrument_t *in);
void instrument_stop(instrument_t *in);

#endif
