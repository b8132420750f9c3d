/* dfp-sim conformance: the conformance suite (sim_host/conformance/README.md) against a slave
 * on a tty/PTY, an LCM segment, or the card in process at one rate or every rate its GSD
 * claims. Terminal report always; JUnit and HTML reports on request. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "dfp_sim_version.h"
#include "conformance/cf.h"
#include "conformance/cf_report.h"
#include "conformance/cf_rig.h"
#include "medium.h"

#define CF_CMD_MAX_REPORTS 2u
#define CF_WALL_CLOCK_WATCHDOG_MS 1000u

/* --report KIND FILE: KIND as cli_kind_file_t.kind. */
enum { CF_REPORT_JUNIT, CF_REPORT_HTML };

typedef struct cf_cmd_opts {
    medium_opts_t med;
    bool card;
    uint32_t address;
    bool address_given;
    const char *gsd_path;
    const char *modules[CF_MAX_MODULES];
    size_t n_modules;
    uint32_t baud;
    bool all_rates;
    const char *only;
    uint32_t master;
    bool echo;
    bool list;
    cli_kind_file_t reports[CF_CMD_MAX_REPORTS];
    size_t n_reports;
    FILE *report_files[CF_CMD_MAX_REPORTS]; /* opened before the run: a bad path costs no run */
} cf_cmd_opts_t;

#define CF_OPT(field) offsetof(cf_cmd_opts_t, field)

static const cli_choice_t report_kinds[] = {
    {"junit", CF_REPORT_JUNIT, false},
    {"html", CF_REPORT_HTML, false},
    {NULL, 0, false},
};

/* --baud RATE|all. */
static bool set_baud(void *base, const cli_opt_t *opt, const char *value, cli_args_t *args)
{
    (void)args;
    cf_cmd_opts_t *o = base;
    if (strcmp(value, "all") == 0) {
        o->all_rates = true;
        return true;
    }
    o->all_rates = false;
    return cli_baud(opt->name, value, false, &o->baud);
}

static const cli_choice_t baud_words[] = {
    {"all", 0, false},
    {NULL, 0, false},
};

static const cli_opt_t conformance_options[] = {
    {CLI_OPT("--card", NULL, CLI_FLAG, CF_OPT(card))},
    {CLI_OPT("--address", "A", CLI_U32, CF_OPT(address)), .min = 0, .max = 125,
     .seen = CLI_SEEN(cf_cmd_opts_t, address_given)},
    {CLI_OPT("--gsd", "FILE", CLI_TEXT, CF_OPT(gsd_path))},
    {CLI_OPT("--module", "NAME", CLI_LIST, CF_OPT(modules)), .aux = CF_OPT(n_modules),
     .max = CF_MAX_MODULES},
    {CLI_OPT("--baud", "RATE|all", CLI_CALL, 0), .choices = baud_words, .set = set_baud},
    {CLI_OPT("--only", "PREFIX", CLI_TEXT, CF_OPT(only))},
    {CLI_OPT("--master-address", "N", CLI_U32, CF_OPT(master)), .min = 0, .max = 125},
    {CLI_OPT("--report", "junit|html FILE", CLI_KIND_FILE, CF_OPT(reports)),
     .aux = CF_OPT(n_reports), .max = CF_CMD_MAX_REPORTS, .choices = report_kinds},
    {CLI_OPT("--echo-suppress", NULL, CLI_FLAG, CF_OPT(echo))},
    {CLI_OPT("--list", NULL, CLI_FLAG, CF_OPT(list))},
};

static const cli_group_t conformance_groups[] = {
    {medium_options, CLI_COUNT(medium_options), CF_OPT(med)},
    {conformance_options, CLI_COUNT(conformance_options), 0},
};

const cli_command_t cli_conformance = {.name = "conformance", .groups = conformance_groups,
                                       .n_groups = CLI_COUNT(conformance_groups),
                                       .operands = CLI_NO_OPERANDS};

/* --only must name some case: a typo would otherwise be a green run of nothing. */
static bool only_matches(const char *only)
{
    static cf_case_t cases[CF_MAX_CASES];
    size_t n = cf_all_cases(cases, CF_MAX_CASES);
    for (size_t i = 0; i < n; i++) {
        if (strncmp(cases[i].id, only, strlen(only)) == 0) {
            return true;
        }
    }
    return false;
}

/* The class-2 master and the second class-1 master: the lowest addresses from 2 up that are
 * neither the tester's nor the slave's (the slave must never be asked by itself). */
static uint8_t free_address(uint8_t from, uint8_t a, uint8_t b, uint8_t c)
{
    uint8_t x = from;
    while (x == a || x == b || x == c) {
        x++;
    }
    return x;
}

static bool conformance_check(cf_cmd_opts_t *o)
{
    if (o->list) {
        return true;
    }
    if (!medium_check(&o->med, "conformance")) {
        return false;
    }
    int media = (o->med.dev != NULL) + (o->med.bus != NULL) + o->card;
    if (media != 1) {
        cli_error("conformance: %s (--port DEV, --bus lcm:CHANNEL or --card)",
                  media == 0 ? "where is the slave?" : "one device under test at a time");
        return false;
    }
    if (!o->address_given || o->gsd_path == NULL) {
        cli_error("conformance: --address A and --gsd FILE are required");
        return false;
    }
    if (o->all_rates && !o->card) {
        cli_error("conformance: --baud all is for --card (a port or segment runs at one rate)");
        return false;
    }
    if (o->only != NULL && !only_matches(o->only)) {
        cli_error("conformance: --only '%s' matches no case (dfp-sim conformance --list)",
                  o->only);
        return false;
    }
    if (o->master == o->address) {
        cli_error("conformance: --master-address %u is the slave's address", o->master);
        return false;
    }
    cli_file_t files[CF_CMD_MAX_REPORTS + 1];
    size_t n = 0;
    files[n++] = (cli_file_t){"--gsd", o->gsd_path, true};
    for (size_t k = 0; k < o->n_reports; k++) {
        bool html = o->reports[k].kind == CF_REPORT_HTML;
        files[n++] = (cli_file_t){html ? "--report html" : "--report junit", o->reports[k].path,
                                  false};
    }
    return cli_files_distinct("conformance", files, n);
}

static void list_cases(void)
{
    static cf_case_t cases[CF_MAX_CASES];
    size_t n = cf_all_cases(cases, CF_MAX_CASES);
    for (size_t i = 0; i < n; i++) {
        printf("%s\t%s\t%s\t%s\n", cases[i].id, cases[i].group, cases[i].clause,
               cases[i].title);
    }
}

/* On a terminal, a line per case while the suite runs (the report comes at the end). */
static void progress(void *ctx, const cf_result_t *r, size_t index, size_t total)
{
    (void)ctx;
    fprintf(stderr, "\r[%3zu/%3zu] %-4s %-40s", index + 1u, total,
            r->verdict == CF_PASS ? "PASS" : r->verdict == CF_FAIL ? "FAIL" : "N/A", r->c->id);
    if (index + 1u == total) {
        fputc('\n', stderr);
    }
}

/* One run at one rate: results in *cf. Returns 0, or 2 when the medium or the GSD would not. */
static int run_at(cf_t *cf, const cf_cmd_opts_t *o, const gsd_t *g, uint32_t baud)
{
    static cf_rig_t cr;
    static cf_case_t cases[CF_MAX_CASES];
    cf_rig_cfg_t rc = {.baud = baud, .card_address = (uint8_t)o->address,
                       .echo_suppress = o->echo};
    if (o->card) {
        rc.medium = RIG_MEDIUM_MEMBUS;
    } else if (o->med.bus != NULL) {
        rc.medium = RIG_MEDIUM_LCM;
        rc.lcm_channel = o->med.bus + strlen("lcm:");
        rc.lcm_url = o->med.lcm_url;
        rc.lcm_key = medium_key(&o->med);
    } else {
        rc.medium = RIG_MEDIUM_TTY;
        rc.device = o->med.dev;
    }
    char err[300];
    if (cf_rig_open(&cr, &rc, err, sizeof err) != 0) {
        cli_error("conformance: %s", err);
        return 1;
    }
    static char name[300]; /* the link and the reports keep pointing at it */
    if (o->card) {
        snprintf(name, sizeof name, "the DFP21B card in process (in-memory bus)");
    } else {
        snprintf(name, sizeof name, "%s", o->med.bus != NULL ? o->med.bus : o->med.dev);
    }
    cf_link_t link = cf_rig_link(&cr, name);
    /* A wall-clock medium on a loaded host may keep the tester away longer than 200 ms: its
     * start-ups give the watchdog a second (dp.watchdog.expiry sets its own). */
    cf_options_t co = {.address = (uint8_t)o->address, .master = (uint8_t)o->master,
                       .module = -1, .only = o->only,
                       .watchdog_ms = o->card ? 200u : CF_WALL_CLOCK_WATCHDOG_MS};
    co.class2 = free_address(2u, co.master, co.address, 0xFFu);
    co.master_2 = free_address((uint8_t)(co.class2 + 1u), co.master, co.address, co.class2);
    for (size_t k = 0; k < o->n_modules; k++) {
        co.modules[k] = gsd_find_module(g, o->modules[k]);
        if (co.modules[k] < 0) {
            cli_error("conformance: the GSD file has no module \"%s\"", o->modules[k]);
            cf_rig_close(&cr);
            return EXIT_USAGE;
        }
    }
    co.n_modules = o->n_modules;
    if (cf_init(cf, &link, g, &co, err, sizeof err) != 0) {
        cli_error("conformance: %s", err);
        cf_rig_close(&cr);
        return EXIT_USAGE;
    }
    if (isatty(STDERR_FILENO)) {
        cf->hooks.case_done = progress;
    }
    size_t n = cf_all_cases(cases, CF_MAX_CASES);
    cf_run(cf, cases, n);
    cf_rig_close(&cr);
    return 0;
}

/* The report files, opened (created) before the run. 0, or 1 after reporting. */
static int open_reports(cf_cmd_opts_t *o)
{
    for (size_t k = 0; k < o->n_reports; k++) {
        o->report_files[k] = fopen(o->reports[k].path, "w");
        if (o->report_files[k] == NULL) {
            cli_error("conformance: cannot write %s: %s", o->reports[k].path, strerror(errno));
            return 1;
        }
    }
    return 0;
}

static int write_reports(cf_cmd_opts_t *o, const cf_report_run_t *runs, size_t n_runs,
                         const cf_report_info_t *info)
{
    int rc = 0;
    for (size_t k = 0; k < o->n_reports; k++) {
        FILE *f = o->report_files[k];
        o->report_files[k] = NULL;
        int w = o->reports[k].kind == CF_REPORT_HTML ? cf_report_html(f, runs, n_runs, info)
                                   : cf_report_junit(f, runs, n_runs, info);
        errno = 0;
        if (w != 0 || ferror(f) != 0) {
            w = -1;
        }
        if (fclose(f) != 0 || w != 0) {
            cli_error("conformance: cannot write %s%s%s", o->reports[k].path,
                      errno != 0 ? ": " : "", errno != 0 ? strerror(errno) : "");
            rc = 1;
        }
    }
    return rc;
}

static void close_reports(cf_cmd_opts_t *o)
{
    for (size_t k = 0; k < o->n_reports; k++) {
        if (o->report_files[k] != NULL) {
            (void)fclose(o->report_files[k]);
            o->report_files[k] = NULL;
        }
    }
}

static int conformance_run(cf_cmd_opts_t *o)
{
    static gsd_t g;
    char err[400];
    if (gsd_parse_file(o->gsd_path, &g, err, sizeof err) != 0) {
        cli_error("conformance: %s", err);
        return EXIT_USAGE;
    }
    uint32_t rates[GSD_RATE_COUNT];
    size_t n_rates = 0;
    if (o->all_rates) {
        for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
            if (gsd_supports_baud(&g, gsd_rate_baud(i))) {
                rates[n_rates++] = gsd_rate_baud(i);
            }
        }
        if (n_rates == 0u) {
            cli_error("conformance: the GSD file claims no rate (%s)", o->gsd_path);
            return EXIT_USAGE;
        }
    } else {
        rates[n_rates++] = o->baud;
    }
    if (open_reports(o) != 0) {
        close_reports(o);
        return 1;
    }
    cf_t *cfs = calloc(n_rates, sizeof *cfs);
    cf_report_run_t runs[GSD_RATE_COUNT];
    if (cfs == NULL) {
        cli_error("conformance: out of memory");
        return 1;
    }
    int rc = 0;
    size_t done = 0;
    for (size_t i = 0; i < n_rates && rc == 0; i++) {
        rc = run_at(&cfs[i], o, &g, rates[i]);
        if (rc == 0) {
            runs[done++] = (cf_report_run_t){.cf = &cfs[i], .baud = rates[i]};
        }
    }
    if (done > 0u) {
        char date[64];
        time_t now = time(NULL);
        struct tm tm;
        if (strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", gmtime_r(&now, &tm)) == 0u) {
            date[0] = '\0';
        }
        cf_report_info_t info = {.gsd_path = o->gsd_path, .date = date,
                                 .tool = "dfp-sim " DFP_SIM_VERSION};
        (void)cf_report_text(stdout, runs, done, &info);
        if (write_reports(o, runs, done, &info) != 0 && rc == 0) {
            rc = 1;
        }
    }
    for (size_t i = 0; rc == 0 && i < done; i++) {
        size_t pass;
        size_t fail;
        size_t na;
        cf_count(&cfs[i], &pass, &fail, &na);
        rc = fail > 0u ? 1 : 0;
    }
    close_reports(o);
    free(cfs);
    return rc;
}

int cmd_conformance(int argc, char **argv)
{
    static cf_cmd_opts_t o;
    memset(&o, 0, sizeof o);
    o.baud = 1500000u;
    o.master = 1u;
    int rc = cli_parse(&cli_conformance, argc, argv, &o);
    if (rc != 0) {
        return rc;
    }
    if (!conformance_check(&o)) {
        return EXIT_USAGE;
    }
    if (o.list) {
        list_cases();
        return 0;
    }
    return conformance_run(&o);
}
