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

typedef struct cf_cmd_report {
    bool html;
    const char *path;
} cf_cmd_report_t;

typedef struct cf_cmd_opts {
    medium_opts_t med;
    bool card;
    uint32_t address;
    bool address_given;
    const char *gsd_path;
    const char *module;
    uint32_t baud;
    bool all_rates;
    const char *only;
    uint32_t master;
    bool echo;
    bool list;
    cf_cmd_report_t reports[CF_CMD_MAX_REPORTS];
    size_t n_reports;
} cf_cmd_opts_t;

#define CF_OPT(field) offsetof(cf_cmd_opts_t, field)

static const cli_choice_t report_kinds[] = {
    {"junit", 0, false},
    {"html", 1, false},
    {NULL, 0, false},
};

/* --report junit|html FILE: two values. */
static bool set_report(void *base, const cli_opt_t *opt, const char *kind, cli_args_t *args)
{
    (void)opt;
    cf_cmd_opts_t *o = base;
    if (strcmp(kind, "junit") != 0 && strcmp(kind, "html") != 0) {
        cli_error("conformance: --report '%s': use junit FILE or html FILE", kind);
        return false;
    }
    if (args->i + 1 >= args->argc) {
        cli_error("conformance: --report %s: which file? --report %s FILE", kind, kind);
        return false;
    }
    if (o->n_reports == CF_CMD_MAX_REPORTS) {
        cli_error("conformance: --report: at most %u report files", CF_CMD_MAX_REPORTS);
        return false;
    }
    args->i++;
    o->reports[o->n_reports].html = strcmp(kind, "html") == 0;
    o->reports[o->n_reports].path = args->argv[args->i];
    o->n_reports++;
    return true;
}

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
    {CLI_OPT("--module", "NAME", CLI_TEXT, CF_OPT(module))},
    {CLI_OPT("--baud", "RATE|all", CLI_CALL, 0), .choices = baud_words, .set = set_baud},
    {CLI_OPT("--only", "PREFIX", CLI_TEXT, CF_OPT(only))},
    {CLI_OPT("--master-address", "N", CLI_U32, CF_OPT(master)), .min = 0, .max = 125},
    {CLI_OPT("--report", "junit|html FILE", CLI_CALL, 0), .choices = report_kinds,
     .set = set_report},
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
    if (o->master == o->address) {
        cli_error("conformance: --master-address %u is the slave's address", o->master);
        return false;
    }
    cli_file_t files[CF_CMD_MAX_REPORTS + 1];
    size_t n = 0;
    files[n++] = (cli_file_t){"--gsd", o->gsd_path, true};
    for (size_t k = 0; k < o->n_reports; k++) {
        files[n++] = (cli_file_t){o->reports[k].html ? "--report html" : "--report junit",
                                  o->reports[k].path, false};
    }
    return cli_files_distinct("conformance", files, n);
}

static void list_cases(void)
{
    static cf_case_t cases[CF_MAX_CASES];
    size_t n = cf_all_cases(cases, CF_MAX_CASES);
    for (size_t i = 0; i < n; i++) {
        printf("%-34s %-17s %s\n", cases[i].id, cases[i].group, cases[i].title);
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
    cf_options_t co = {.address = (uint8_t)o->address, .master = (uint8_t)o->master,
                       .class2 = 2, .master_2 = 3, .module = -1, .only = o->only};
    if (o->module != NULL && (co.module = gsd_find_module(g, o->module)) < 0) {
        cli_error("conformance: the GSD file has no module \"%s\"", o->module);
        cf_rig_close(&cr);
        return EXIT_USAGE;
    }
    if (co.master == co.class2 || co.master == co.master_2) {
        co.class2 = co.master == 2u ? 4u : 2u;
        co.master_2 = co.master == 3u ? 5u : 3u;
    }
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

static int write_reports(const cf_cmd_opts_t *o, const cf_report_run_t *runs, size_t n_runs,
                         const cf_report_info_t *info)
{
    int rc = 0;
    for (size_t k = 0; k < o->n_reports; k++) {
        const char *path = o->reports[k].path;
        FILE *f = fopen(path, "w");
        int w = -1;
        if (f != NULL) {
            w = o->reports[k].html ? cf_report_html(f, runs, n_runs, info)
                                   : cf_report_junit(f, runs, n_runs, info);
            if (fclose(f) != 0) {
                w = -1;
            }
        }
        if (w != 0) {
            cli_error("conformance: cannot write %s: %s", path, strerror(errno));
            rc = 1;
        }
    }
    return rc;
}

static int conformance_run(const cf_cmd_opts_t *o)
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
        strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", gmtime_r(&now, &tm));
        cf_report_info_t info = {.gsd_path = o->gsd_path, .date = date,
                                 .tool = "dfp-sim " DFP_SIM_VERSION};
        (void)cf_report_text(stdout, runs, done, &info);
        if (write_reports(o, runs, done, &info) != 0 && rc == 0) {
            rc = 1;
        }
    }
    for (size_t i = 0; rc == 0 && i < done; i++) {
        size_t pass, fail, na;
        cf_count(&cfs[i], &pass, &fail, &na);
        rc = fail > 0u ? 1 : 0;
    }
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
