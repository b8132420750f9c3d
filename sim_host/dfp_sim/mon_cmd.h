/* dfp-sim monitor's run: its options (cmd_monitor.c reads them) and what it runs (mon_cmd.c):
 * the source, the views, the capture, the control API and the reports. */
#ifndef DFP_SIM_MON_CMD_H
#define DFP_SIM_MON_CMD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cli_table.h"
#include "instrument.h"
#include "medium.h"
#include "monitor/mon_live.h"
#include "monitor/mon_rig.h"
#include "monitor/mon_term.h"
#include "monitor/mon_view.h"
#include "monitor/monitor.h"
#include "capture/pcapng_writer.h"
#include "session.h"

#define MON_CMD_MAX_REPORTS 4u

typedef enum mon_view_kind {
    MON_VIEW_TOP = 0, /* the full-screen view (a terminal) */
    MON_VIEW_LOG,     /* one line per event */
    MON_VIEW_NONE,
} mon_view_kind_t;

/* --report KIND FILE: KIND as cli_kind_file_t.kind. */
enum { MON_REPORT_JSON, MON_REPORT_JUNIT };

typedef struct mon_cmd_opts {
    medium_opts_t med;
    const char *file;
    uint32_t baud;
    bool timing;
    uint32_t tsl_bits;
    uint32_t ttr_bits;
    uint32_t seconds;
    int view; /* mon_view_kind_t */
    bool view_given;
    cli_kind_file_t reports[MON_CMD_MAX_REPORTS];
    size_t n_reports;
    const char *expect_text;
    uint8_t expect[MON_STATIONS];
    size_t n_expect;
    uint32_t max_repeats;
    uint32_t max_missing;
    const char *pcapng;
    const char *gsd[MON_MAX_GSD];
    size_t n_gsd;
    instrument_opts_t io;
} mon_cmd_opts_t;

typedef struct mon_cmd {
    const mon_cmd_opts_t *o;
    mon_t own;        /* the monitor, unless the API's is used */
    mon_t *mon;       /* own, or api->mon */
    mon_rig_t *api;   /* --http: the monitor the API publishes (kept to the end: its log
                         events and document are read by the server's threads) */
    void (*api_event)(void *ctx, const mon_event_t *ev); /* the API's event hook, chained */
    void *api_ctx;
    mon_live_t live;
    session_t session; /* a live source: the medium, the log and the API */
    pcapng_writer_t pcapng;
    bool recording;
    mon_term_t term;
    mon_view_t view;
    bool top; /* the full-screen view is up */
    char source[600];
    uint64_t now_ns;
    uint64_t last_flush_ns;
} mon_cmd_t;

/* Runs the monitor as o says. The exit status: 0 when every check of the report passes, 1
 * when one fails or the source failed, 2 (EXIT_USAGE) for a file that cannot be written. */
int mon_cmd_run(mon_cmd_t *c, const mon_cmd_opts_t *o);

/* mon_cmd_live.c: a live source (--port, --bus) with its views and the API; 0, 1 when the
 * source failed, EXIT_USAGE when it could not be opened as asked. */
int mon_cmd_live(mon_cmd_t *c);
/* mon_cmd.c, for mon_cmd_live.c */
void mon_cmd_event(void *ctx, const mon_event_t *ev);
void mon_cmd_frame(void *ctx, const uint8_t *f, size_t len, uint64_t t_ns, bool garbled);
void mon_cmd_pcapng_tick(mon_cmd_t *c, uint64_t now_ns);

#endif
