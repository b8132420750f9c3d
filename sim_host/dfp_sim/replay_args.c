/* The command line of dfp-sim replay (replay_args.h). */
#include "replay_args.h"

#include <string.h>
#include <sys/stat.h>

#include "cli.h"

static const char replay_usage_hint[] = "(see dfp-sim --help)";

/* --speed, --inverter, --format, --timing: a word each. */
static bool parse_word_option(const char *o, const char *v, replay_args_t *a)
{
    if (strcmp(o, "--speed") == 0) {
        if (strcmp(v, "real") == 0 || strcmp(v, "max") == 0) {
            a->speed = strcmp(v, "real") == 0 ? REPLAY_SPEED_REAL : REPLAY_SPEED_MAX;
            return true;
        }
        cli_error("replay: --speed '%s': use real (the capture's pace) or max", v);
        return false;
    }
    if (strcmp(o, "--inverter") == 0) {
        if (strcmp(v, "sim") == 0 || strcmp(v, "none") == 0) {
            a->inverter = strcmp(v, "sim") == 0 ? CARD_INVERTER_SIM : CARD_INVERTER_NONE;
            return true;
        }
        cli_error("replay: --inverter '%s': use sim (emulated MOVIDRIVE) or none (PI echoes PO)",
                  v);
        return false;
    }
    if (strcmp(o, "--timing") == 0) {
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
    if (!cap_format_parse(v, &a->format)) {
        cli_error("replay: --format '%s': use pcap, pcapng, text or lcm", v);
        return false;
    }
    return true;
}

/* --report json|junit FILE: two values. */
static bool parse_report(int argc, char **argv, int *i, replay_args_t *a)
{
    const char *kind = cli_value(argc, argv, i);
    if (kind == NULL) {
        return false;
    }
    if (strcmp(kind, "json") != 0 && strcmp(kind, "junit") != 0) {
        cli_error("replay: --report '%s': use json FILE or junit FILE", kind);
        return false;
    }
    if (*i + 1 >= argc) {
        cli_error("replay: --report %s: which file? --report %s FILE", kind, kind);
        return false;
    }
    const char *path = argv[++*i];
    if (a->n_reports == REPLAY_MAX_REPORTS) {
        cli_error("replay: --report: at most %u report files", REPLAY_MAX_REPORTS);
        return false;
    }
    a->reports[a->n_reports].junit = strcmp(kind, "junit") == 0;
    a->reports[a->n_reports].path = path;
    a->n_reports++;
    return true;
}

/* The options of the check: --ignore, --max-mismatches. */
static bool parse_check_option(const char *o, const char *v, replay_args_t *a)
{
    if (strcmp(o, "--ignore") == 0) {
        char err[400];
        if (!replay_mask_add(&a->mask, v, err, sizeof err)) {
            cli_error("replay: --ignore %s", err);
            return false;
        }
        return true;
    }
    uint32_t n = 0;
    if (!cli_u32(o, v, 0, 1000000000u, &n)) {
        return false;
    }
    a->max_listed = n == 0u ? REPLAY_LIST_ALL : n;
    return true;
}

static bool is_value_option(const char *o, bool *word)
{
    static const char *const words[] = {"--speed", "--inverter", "--format", "--timing"};
    static const char *const others[] = {"--address", "--baud", "--lcm", "--inverter-delay",
                                         "--http", "--channel", "--ignore", "--max-mismatches"};
    *word = false;
    for (size_t k = 0; k < sizeof words / sizeof words[0]; k++) {
        *word = *word || strcmp(o, words[k]) == 0;
    }
    bool known = *word;
    for (size_t k = 0; k < sizeof others / sizeof others[0]; k++) {
        known = known || strcmp(o, others[k]) == 0;
    }
    return known;
}

/* An option with a value. 1: consumed, 0: not one of these, -1: reported. */
static int parse_value_option(int argc, char **argv, int *i, replay_args_t *a)
{
    const char *o = argv[*i];
    if (strcmp(o, "--report") == 0) {
        return parse_report(argc, argv, i, a) ? 1 : -1;
    }
    bool word = false;
    if (!is_value_option(o, &word)) {
        return 0;
    }
    const char *v = cli_value(argc, argv, i);
    if (v == NULL) {
        return -1;
    }
    bool ok = true;
    uint32_t n = 0;
    if (word) {
        ok = parse_word_option(o, v, a);
    } else if (strcmp(o, "--address") == 0) {
        ok = cli_u32(o, v, 0, 125, &n);
        a->given.address = (uint8_t)n;
        a->given.have_address = true;
    } else if (strcmp(o, "--baud") == 0) {
        ok = cli_baud(o, v, false, &a->given.baud);
    } else if (strcmp(o, "--inverter-delay") == 0) {
        ok = cli_u32(o, v, 0, 10000000u, &a->given.delay_us);
        a->given.have_delay = true;
    } else if (strcmp(o, "--lcm") == 0) {
        a->lcm_url = v;
    } else if (strcmp(o, "--channel") == 0) {
        a->lcm_channel = v;
    } else if (strcmp(o, "--http") == 0) {
        a->http = v;
    } else {
        ok = parse_check_option(o, v, a);
    }
    return ok ? 1 : -1;
}

static int parse_flags(int argc, char **argv, replay_args_t *a, bool *check_only)
{
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i];
        *check_only = *check_only || strcmp(o, "--report") == 0 ||
                      strcmp(o, "--ignore") == 0 || strcmp(o, "--max-mismatches") == 0;
        int c = parse_value_option(argc, argv, &i, a);
        c = c == 0 ? instrument_http_option(argc, argv, &i, &a->web) : c;
        if (c < 0) {
            return EXIT_USAGE;
        }
        if (c > 0) {
            continue;
        }
        if (strcmp(o, "--check") == 0) {
            a->check = true;
        } else if (strcmp(o, "--verbose") == 0) {
            a->verbose = true;
        } else if (strcmp(o, "--fixed-baud") == 0) {
            a->given.fixed_baud = true;
        } else if (o[0] == '-' && o[1] != '\0') {
            cli_error("replay: unknown option '%s' %s", o, replay_usage_hint);
            return EXIT_USAGE;
        } else if (a->file == NULL) {
            a->file = o;
        } else {
            cli_error("replay: one capture file only ('%s' and '%s')", a->file, o);
            return EXIT_USAGE;
        }
    }
    return 0;
}

/* The capture, the report files and an LCM log --lcm writes: no two may be one file (a report
 * written over the capture would destroy what may be the only copy of a field recording). */
static bool files_distinct(const replay_args_t *a)
{
    cli_file_t files[2u + REPLAY_MAX_REPORTS];
    char lcm_log[512];
    size_t n = 0;
    files[n++] = (cli_file_t){"FILE", a->file};
    files[n++] = (cli_file_t){"--lcm", cli_lcm_log_written(a->lcm_url, lcm_log, sizeof lcm_log)};
    for (unsigned k = 0; k < a->n_reports; k++) {
        files[n++] = (cli_file_t){a->reports[k].junit ? "--report junit" : "--report json",
                                  a->reports[k].path};
    }
    return cli_files_distinct("replay", files, n);
}

static int check_args(replay_args_t *a, bool check_only)
{
    if (a->file == NULL) {
        cli_error("replay: which capture? dfp-sim replay FILE [--check] ... %s",
                  replay_usage_hint);
        return EXIT_USAGE;
    }
    if (check_only && !a->check) {
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
    bool check_only = false;
    int rc = parse_flags(argc, argv, a, &check_only);
    if (rc == 0) {
        rc = check_args(a, check_only);
    }
    a->given.file = a->file;
    return rc;
}
