/* The command line of dfp-sim replay (replay_args.h). */
#include "replay_args.h"

#include <stddef.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "commands.h"

static const char replay_usage_hint[] = "(see dfp-sim --help)";

/* --timing auto|line|relaxed: auto leaves it to the capture. */
static bool set_timing(void *base, const cli_opt_t *opt, const char *v, cli_args_t *args)
{
    (void)opt;
    (void)args;
    replay_args_t *a = base;
    bool line = strcmp(v, "line") == 0;
    a->given.have_timing = line || strcmp(v, "relaxed") == 0;
    a->given.timing = line ? REPLAY_TIMING_LINE : REPLAY_TIMING_RELAXED;
    if (a->given.have_timing || strcmp(v, "auto") == 0) {
        return true;
    }
    cli_error("replay: --timing '%s': use auto (from the capture), line or relaxed (a "
              "tty/PTY capture)", v);
    return false;
}

static bool set_address(void *base, const cli_opt_t *opt, const char *v, cli_args_t *args)
{
    (void)args;
    replay_args_t *a = base;
    uint32_t n = 0;
    bool ok = cli_u32(opt->name, v, 0, 125, &n);
    a->given.address = (uint8_t)n;
    a->given.have_address = true;
    return ok;
}

static bool set_ignore(void *base, const cli_opt_t *opt, const char *v, cli_args_t *args)
{
    (void)opt;
    (void)args;
    char err[400];
    if (!replay_mask_add(&((replay_args_t *)base)->mask, v, err, sizeof err)) {
        cli_error("replay: --ignore %s", err);
        return false;
    }
    return true;
}

static bool set_max_listed(void *base, const cli_opt_t *opt, const char *v, cli_args_t *args)
{
    (void)args;
    uint32_t n = 0;
    if (!cli_u32(opt->name, v, 0, 1000000000u, &n)) {
        return false;
    }
    ((replay_args_t *)base)->max_listed = n == 0u ? REPLAY_LIST_ALL : n;
    return true;
}

static bool replay_operand(void *opts, const char *word)
{
    replay_args_t *a = opts;
    if (a->file != NULL) {
        cli_error("replay: one capture file only ('%s' and '%s')", a->file, word);
        return false;
    }
    a->file = word;
    return true;
}

static const cli_choice_t speeds[] = {
    {"real", REPLAY_SPEED_REAL, false}, {"max", REPLAY_SPEED_MAX, false}, {NULL, 0, false}};
static const cli_choice_t formats[] = {
    {"pcap", CAP_FORMAT_PCAP, false}, {"pcapng", CAP_FORMAT_PCAPNG, false},
    {"text", CAP_FORMAT_TEXT, false}, {"lcm", CAP_FORMAT_LCM, false},
    {"auto", CAP_FORMAT_AUTO, true},  {NULL, 0, false}};
static const cli_choice_t inverters[] = {
    {"sim", CARD_INVERTER_SIM, false}, {"none", CARD_INVERTER_NONE, false}, {NULL, 0, false}};
static const cli_choice_t timings[] = {
    {"auto", 0, false}, {"line", 0, false}, {"relaxed", 0, false}, {NULL, 0, false}};
static const cli_choice_t report_kinds[] = {
    {"json", REPLAY_REPORT_JSON, false}, {"junit", REPLAY_REPORT_JUNIT, false}, {NULL, 0, false}};

#define ARGS(field) offsetof(replay_args_t, field)
#define CHECK_OPTION CLI_SEEN(replay_args_t, check_options)

static const cli_opt_t replay_options[] = {
    {CLI_OPT("--address", "N", CLI_CALL, 0), .set = set_address},
    {CLI_OPT("--check", NULL, CLI_FLAG, ARGS(check))},
    {CLI_OPT("--speed", "real|max", CLI_CHOICE, ARGS(speed)), .choices = speeds,
     .bad = "replay: --speed '%s': use real (the capture's pace) or max"},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, ARGS(given.baud))},
    {CLI_OPT("--format", "pcap|pcapng|text|lcm", CLI_CHOICE, ARGS(format)), .choices = formats,
     .bad = "replay: --format '%s': use pcap, pcapng, text or lcm"},
    {CLI_OPT("--inverter", "sim|none", CLI_CHOICE, ARGS(inverter)), .choices = inverters,
     .bad = "replay: --inverter '%s': use sim (emulated MOVIDRIVE) or none (PI echoes PO)"},
    {CLI_OPT("--inverter-delay", "US", CLI_U32, ARGS(given.delay_us)), .min = 0,
     .max = 10000000u, .seen = CLI_SEEN(replay_args_t, given.have_delay)},
    {CLI_OPT("--fixed-baud", NULL, CLI_FLAG, ARGS(given.fixed_baud))},
    {CLI_OPT("--timing", "auto|line|relaxed", CLI_CALL, 0), .choices = timings,
     .set = set_timing},
    {CLI_OPT("--verbose", NULL, CLI_FLAG, ARGS(verbose))},
    {CLI_OPT("--lcm", "URL", CLI_TEXT, ARGS(lcm_url))},
    {CLI_OPT("--channel", "NAME", CLI_TEXT, ARGS(lcm_channel))},
    {CLI_OPT("--http", "[ADDR:]PORT", CLI_TEXT, ARGS(http))},
    {CLI_OPT("--max-mismatches", "N", CLI_CALL, 0), .set = set_max_listed,
     .seen = CHECK_OPTION},
    {CLI_OPT("--ignore", "MASK", CLI_CALL, 0), .set = set_ignore, .seen = CHECK_OPTION},
    {CLI_OPT("--report", "json|junit FILE", CLI_KIND_FILE, ARGS(reports)),
     .aux = ARGS(n_reports), .max = REPLAY_MAX_REPORTS, .choices = report_kinds,
     .seen = CHECK_OPTION},
};

static const cli_group_t replay_groups[] = {
    {replay_options, CLI_COUNT(replay_options), 0},
    {instrument_http_options, CLI_COUNT(instrument_http_options), ARGS(web)},
};

const cli_command_t cli_replay = {.name = "replay", .groups = replay_groups,
                                  .n_groups = CLI_COUNT(replay_groups),
                                  .operands = CLI_OPERANDS, .operand = replay_operand};

/* The capture, the report files and an LCM log --lcm writes: no two may be one file (a report
 * written over the capture would destroy what may be the only copy of a field recording). */
static bool files_distinct(const replay_args_t *a)
{
    cli_file_t files[2u + REPLAY_MAX_REPORTS];
    char lcm_log[512];
    size_t n = 0;
    files[n++] = (cli_file_t){"FILE", a->file, .input = true};
    files[n++] = (cli_file_t){"--lcm", cli_lcm_log_written(a->lcm_url, lcm_log, sizeof lcm_log),
                              false};
    for (size_t k = 0; k < a->n_reports; k++) {
        bool junit = a->reports[k].kind == REPLAY_REPORT_JUNIT;
        files[n++] = (cli_file_t){junit ? "--report junit" : "--report json", a->reports[k].path,
                                  false};
    }
    return cli_files_distinct("replay", files, n);
}

static int check_args(replay_args_t *a)
{
    if (a->file == NULL) {
        cli_error("replay: which capture? dfp-sim replay FILE [--check] ... %s",
                  replay_usage_hint);
        return EXIT_USAGE;
    }
    if (a->check_options && !a->check) {
        cli_error("replay: --report, --ignore and --max-mismatches belong to the check: add "
                  "--check");
        return EXIT_USAGE;
    }
    if (!files_distinct(a)) {
        return EXIT_USAGE;
    }
    if (a->inverter != CARD_INVERTER_SIM && a->given.have_delay) {
        cli_error("replay: --inverter-delay belongs to the emulated inverter (--inverter sim)");
        return EXIT_USAGE;
    }
    struct stat fst;
    if ((!a->given.have_address || a->given.baud == 0u) && stat(a->file, &fst) == 0 &&
        !S_ISREG(fst.st_mode)) {
        /* The first pass would consume a pipe, leaving nothing to replay. */
        cli_error("replay: %s is not a regular file (a pipe?) and can be read only once: give "
                  "--address and --baud, or save it to a file first", a->file);
        return EXIT_USAGE;
    }
    return 0;
}

int replay_parse_args(int argc, char **argv, replay_args_t *a)
{
    memset(a, 0, sizeof *a);
    a->format = CAP_FORMAT_AUTO;
    a->inverter = CARD_INVERTER_SIM;
    a->speed = REPLAY_SPEED_MAX;
    a->max_listed = REPLAY_LIST_DEFAULT;
    int rc = cli_parse(&cli_replay, argc, argv, a);
    if (rc == 0) {
        rc = check_args(a);
    }
    a->given.file = a->file;
    return rc;
}
