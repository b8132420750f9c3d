/* dfp-sim monitor: a receive-only station on a tty/PTY (a USB adapter, a port of the virtual
 * line), an LCM segment, or a capture file, showing the live list the monitor library keeps
 * (sim_host/monitor/README.md): on the terminal, as event lines, through the control API, and
 * as a report at the end. The monitor never transmits. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "medium.h"
#include "mon_cmd.h"
#include "monitor/mon_live.h"
#include "monitor/monitor.h"

#define MONITOR_OPT(field) offsetof(mon_cmd_opts_t, field)

static const cli_choice_t view_words[] = {
    {"top", MON_VIEW_TOP, false},
    {"log", MON_VIEW_LOG, false},
    {"none", MON_VIEW_NONE, false},
    {NULL, 0, false},
};

static const cli_choice_t report_kinds[] = {
    {"json", MON_REPORT_JSON, false},
    {"junit", MON_REPORT_JUNIT, false},
    {NULL, 0, false},
};

static const cli_opt_t monitor_options[] = {
    {CLI_OPT("--baud", "RATE", CLI_BAUD, MONITOR_OPT(baud))},
    {CLI_OPT("--timing", NULL, CLI_FLAG, MONITOR_OPT(timing))},
    {CLI_OPT("--tsl", "BITS", CLI_U32, MONITOR_OPT(tsl_bits)), .min = 37, .max = 16383},
    {CLI_OPT("--ttr", "BITS", CLI_U32, MONITOR_OPT(ttr_bits)), .min = 256, .max = 16776960},
    {CLI_OPT("--seconds", "S", CLI_U32, MONITOR_OPT(seconds)), .min = 1, .max = 86400u * 365u},
    {CLI_OPT("--view", "top|log|none", CLI_CHOICE, MONITOR_OPT(view)), .choices = view_words,
     .bad = "monitor: --view '%s': use top, log or none",
     .seen = CLI_SEEN(mon_cmd_opts_t, view_given)},
    {CLI_OPT("--report", "json|junit FILE", CLI_KIND_FILE, MONITOR_OPT(reports)),
     .aux = MONITOR_OPT(n_reports), .max = MON_CMD_MAX_REPORTS, .choices = report_kinds},
    {CLI_OPT("--expect", "N|N-M,...", CLI_TEXT, MONITOR_OPT(expect_text))},
    {CLI_OPT("--max-repeats", "N", CLI_U32, MONITOR_OPT(max_repeats)), .min = 0,
     .max = UINT32_MAX},
    {CLI_OPT("--max-missing", "N", CLI_U32, MONITOR_OPT(max_missing)), .min = 0,
     .max = UINT32_MAX},
    {CLI_OPT("--pcapng", "FILE", CLI_TEXT, MONITOR_OPT(pcapng))},
    {CLI_OPT("--gsd", "FILE", CLI_LIST, MONITOR_OPT(gsd)), .aux = MONITOR_OPT(n_gsd),
     .max = MON_MAX_GSD},
};

static bool monitor_operand(void *opts, const char *word)
{
    mon_cmd_opts_t *o = opts;
    if (o->file != NULL) {
        cli_error("monitor: one capture FILE at a time ('%s' and '%s')", o->file, word);
        return false;
    }
    o->file = word;
    return true;
}

static const cli_group_t monitor_groups[] = {
    {medium_options, CLI_COUNT(medium_options), MONITOR_OPT(med)},
    {monitor_options, CLI_COUNT(monitor_options), 0},
    {instrument_options, CLI_COUNT(instrument_options), MONITOR_OPT(io)},
    {instrument_http_options, CLI_COUNT(instrument_http_options), MONITOR_OPT(io.web)},
};

const cli_command_t cli_monitor = {.name = "monitor", .groups = monitor_groups,
                                   .n_groups = CLI_COUNT(monitor_groups),
                                   .operands = CLI_OPERANDS, .operand = monitor_operand};

static bool monitor_check(mon_cmd_opts_t *o)
{
    if (!medium_check(&o->med, "monitor")) {
        return false;
    }
    int sources = (o->file != NULL) + (o->med.dev != NULL) + (o->med.bus != NULL);
    if (sources != 1) {
        cli_error("monitor: %s (--port DEV, --bus lcm:CHANNEL or a capture FILE)",
                  sources == 0 ? "where does it listen?" : "one source at a time");
        return false;
    }
    if (o->expect_text != NULL &&
        !cli_address_list("--expect", o->expect_text, o->expect, MON_STATIONS, &o->n_expect)) {
        return false;
    }
    if (o->file != NULL && (o->io.http != NULL || o->io.web.given)) {
        cli_error("monitor: --http is for a live source; a FILE gives its reports at the end");
        return false;
    }
    if (o->file != NULL && o->seconds != 0u) {
        cli_error("monitor: --seconds is for a live source; a FILE is read to its end");
        return false;
    }
    if (o->file != NULL && o->view == MON_VIEW_TOP && o->view_given) {
        cli_error("monitor: --view top is for a live source; a FILE gives its report at the end");
        return false;
    }
    cli_file_t files[MON_CMD_MAX_REPORTS + 2];
    size_t n = 0;
    if (o->file != NULL) {
        files[n++] = (cli_file_t){"FILE", o->file, true};
    }
    if (o->pcapng != NULL) {
        files[n++] = (cli_file_t){"--pcapng", o->pcapng, false};
    }
    for (size_t k = 0; k < o->n_reports; k++) {
        bool junit = o->reports[k].kind == MON_REPORT_JUNIT;
        files[n++] = (cli_file_t){junit ? "--report junit" : "--report json", o->reports[k].path,
                                  false};
    }
    return cli_files_distinct("monitor", files, n);
}

int cmd_monitor(int argc, char **argv)
{
    static mon_cmd_opts_t o;
    static mon_cmd_t run;
    memset(&o, 0, sizeof o);
    o.baud = 1500000u;
    instrument_defaults(&o.io, RIG_LOG_TIME_BUS);
    o.view = isatty(STDOUT_FILENO) ? MON_VIEW_TOP : MON_VIEW_LOG;
    o.max_repeats = UINT32_MAX;
    o.max_missing = UINT32_MAX;
    int rc = cli_parse(&cli_monitor, argc, argv, &o);
    if (rc != 0) {
        return rc;
    }
    if (!monitor_check(&o)) {
        return EXIT_USAGE;
    }
    if (o.file != NULL && !o.view_given) {
        o.view = MON_VIEW_NONE; /* a file: the report at the end is what is asked for */
    }
    return mon_cmd_run(&run, &o);
}
