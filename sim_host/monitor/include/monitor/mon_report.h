/* The monitor's reports: the JSON document (docs/monitor.md "Reports"; the HTTP API serves the
 * same document live), JUnit XML for a CI job ("every slave in data exchange, at most N
 * retries"), and the short summary a terminal shows at the end of a run. They read a mon_t
 * and write into a sink; nothing is kept between calls. */
#ifndef MONITOR_MON_REPORT_H
#define MONITOR_MON_REPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "monitor/mon_sink.h"
#include "monitor/monitor.h"

typedef struct mon_report_info {
    const char *source;     /* the line, port or file watched (NULL: "") */
    uint64_t t_start_ns;    /* when the monitor started, on the clock of its telegram times */
    uint64_t t_now_ns;      /* now, same clock: times are reported as seconds since the start */
    unsigned last_events;   /* how many of the newest events the report lists */
} mon_report_info_t;

/* What a CI run accepts. NULL: no repeat, no missing answer, nobody expected. */
typedef struct mon_report_opts {
    uint64_t max_repeats;   /* per slave: FCB repeats it may receive */
    uint64_t max_missing;   /* per slave: requests it may leave unanswered */
    const uint8_t *expect;  /* slaves that must be in data exchange, even if never heard */
    size_t n_expect;
} mon_report_opts_t;

/* The document of docs/monitor.md "Reports" (one JSON object and a newline). */
void mon_report_json(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out);
/* One testsuite "dfp-sim monitor": per DP slave (and per expected slave) "<a> data exchange",
 * "<a> retries", "<a> missing answers", "<a> station delay"; per master that passed the token
 * "<a> token rotation". A failure's message gives the figure. */
void mon_report_junit(const mon_t *m, const mon_report_info_t *info,
                      const mon_report_opts_t *opts, const mon_sink_t *out);
/* The end-of-run summary for a terminal: the live list as a table, the line's counts, the last
 * events. */
void mon_report_text(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out);
/* The JUnit report would have no failure (the command's exit status). */
bool mon_report_ok(const mon_t *m, const mon_report_opts_t *opts);

#endif
