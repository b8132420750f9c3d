/* dfp-sim monitor's run: its options (cmd_monitor.c reads them) and what it runs (mon_cmd.c):
 * the source, the views, the capture, the control API and the reports. */
#ifndef DFP_SIM_MON_CMD_H
#define DFP_SIM_MON_CMD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "medium.h"
#include "monitor/mon_live.h"
#include "monitor/mon_term.h"
#include "monitor/mon_view.h"
#include "monitor/monitor.h"
#include "capture/pcapng_writer.h"

#define MON_CMD_MAX_REPORTS 4u

typedef enum mon_view_kind {
    MON_VIEW_TOP = 0, /* the full-screen view (a terminal) */
    MON_VIEW_LOG,     /* one line per event */
    MON_VIEW_NONE,
} mon_view_kind_t;

typedef struct mon_cmd_report {
    const char *path;
    bool junit;
} mon_cmd_report_t;

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
    mon_cmd_report_t reports[MON_CMD_MAX_REPORTS];
    size_t n_reports;
    const char *expect_text;
    uint8_t expect[MON_STATIONS];
    size_t n_expect;
    uint32_t max_repeats;
    uint32_t max_missing;
    const char *pcapng;
} mon_cmd_opts_t;

typedef struct mon_cmd {
    const mon_cmd_opts_t *o;
    mon_t mon;
    mon_live_t live;
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

#endif
