/* dfp-sim replay: a bus capture played against the emulated card, optionally checking every
 * reply (docs/replay.md); dfp-sim record: a capture made on the simulated bus. */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"
#include "dfp_lcm_bridge/lcm_bridge.h"
#include "instrument.h"
#include "replay/generator.h"
#include "replay/param_text.h"
#include "replay/replay.h"
#include "report.h"
#include "sim_hal/host_clock.h"

/* ---- progress on a terminal ---------------------------------------------------------------- */

typedef struct progress {
    bool on; /* stderr is a terminal */
    const char *what;
    uint64_t t0;
    uint64_t last;
    bool shown;
} progress_t;

static void progress_show(void *ctx, uint64_t records, uint64_t pos, uint64_t size)
{
    progress_t *p = ctx;
    if (!p->on) {
        return;
    }
    uint64_t now = host_clock_mono_ns();
    if (p->shown && now - p->last < 200000000u) {
        return; /* the first call shows at once, then five times a second */
    }
    p->last = now;
    double s = (double)(now - p->t0) / 1e9;
    if (size > 0u) {
        fprintf(stderr, "\r%s: %llu records (%.0f %%), %.0f telegrams/s\033[K", p->what,
                (unsigned long long)records, 100.0 * (double)pos / (double)size,
                s > 0 ? (double)records / s : 0.0);
    } else {
        fprintf(stderr, "\r%s: %llu records, %.0f telegrams/s\033[K", p->what,
                (unsigned long long)records, s > 0 ? (double)records / s : 0.0);
    }
    p->shown = true;
}

static void progress_end(progress_t *p)
{
    if (p->shown) {
        fputs("\r\033[K", stderr);
        p->shown = false;
    }
}

static void progress_begin(progress_t *p, const char *what)
{
    p->on = isatty(STDERR_FILENO) != 0;
    p->what = what;
    p->t0 = host_clock_mono_ns();
    p->last = p->t0;
    p->shown = false;
}

/* ---- replay -------------------------------------------------------------------------------- */

typedef struct replay_cli {
    replay_t replay; /* the bus, the card and the inverter: not on the stack */
    bool verbose;
    report_t rep; /* card events in --verbose, as dfp-sim demo prints them */
    replay_param_ctx_t param_ctx; /* names a data set 47 answer after its request (--verbose) */
    bool lcm_open;
    dfp_lcm_bridge_t lcm; /* --lcm URL */
    instrument_t in;      /* --http: the read-only control API */
} replay_cli_t;

static replay_cli_t rc_state;

/* The command line of dfp-sim replay. */
typedef struct replay_args {
    const char *file;
    uint32_t address;
    bool have_address;
    bool check;
    bool fixed;
    uint32_t baud;
    bool baud_given;
    uint32_t delay_us;
    cap_format_t format;
    const char *lcm_channel;
    card_inverter_t inverter;
    replay_speed_t speed;
    const char *lcm_url;
    const char *http;
    char address_source[160];
    char baud_source[640];
} replay_args_t;

static const dfp21b_t *replay_card(void)
{
    return &rc_state.replay.rig.cards[0].cs.card;
}

static uint64_t replay_now_ns(void *ctx)
{
    return ((replay_t *)ctx)->rig.bus.now_ns;
}

/* LCM's utime of a bus instant: the capture's own clock (the first record's time, shortened
 * gaps counted in full), so the telemetry of a replay carries the times of the plant, not of the
 * replay. It never runs backwards (the bridge's state rate limit relies on that). */
static int64_t capture_utime(uint64_t bus_ns)
{
    return (int64_t)(replay_capture_ns(&rc_state.replay, bus_ns) / 1000u);
}

static int64_t replay_lcm_clock(void *ctx)
{
    (void)ctx;
    return capture_utime(rc_state.replay.rig.bus.now_ns);
}

/* --verbose: one line per telegram, and the parameter service it carries named below it. */
static void print_telegram(replay_cli_t *c, const replay_telegram_t *t)
{
    char hex[3u * CAP_MAX_RECORD + 8u];
    char text[512];
    replay_hex(t->data, t->len, hex, sizeof hex);
    const dfp21b_pd_cfg_t *pd = &replay_card()->pd;
    replay_dx_layout_t lay = {.known = pd->valid, .param_channel = pd->param_channel};
    replay_describe(t->data, t->len, &lay, text, sizeof text);
    if (t->source == REPLAY_FROM_CARD) {
        printf("%10.3f ms  card    > %s  | %s\n", (double)t->t_ns / 1e6, hex, text);
    } else {
        printf("%10.3f ms  #%-6llu < %s  | %s%s%s\n", (double)t->t_ns / 1e6,
               (unsigned long long)t->record, hex, text, t->problem[0] != '\0' ? "  DAMAGED: " : "",
               t->problem);
    }
    if (replay_param_text(t->data, t->len, &lay, &c->param_ctx, text, sizeof text) > 0u) {
        printf("%22s %s\n", "", text);
    }
}

/* Every telegram on the replay bus: --lcm publishes it (the card's own as TX, the capture's as
 * RX, as the card saw them) and the card's state with it; --verbose prints it. */
static void on_telegram(void *ctx, const replay_telegram_t *t)
{
    replay_cli_t *c = ctx;
    if (c->lcm_open) {
        int64_t utime = capture_utime(t->t_ns);
        (void)dfp_lcm_bridge_telegram(&c->lcm, utime, t->data, t->len,
                                      t->source == REPLAY_FROM_CARD, t->baud, 0);
        (void)dfp_lcm_bridge_card_state(&c->lcm, utime, replay_card());
    }
    if (c->verbose) {
        print_telegram(c, t);
    }
}

static void on_card_event(void *ctx, uint64_t t_ns, const dp_event_t *ev)
{
    (void)t_ns;
    replay_cli_t *c = ctx;
    if (c->verbose) {
        report_card_event(&c->rep, ev);
    }
}

static void on_service(void *ctx)
{
    instrument_service(ctx);
}

static const char replay_usage_hint[] = "(see dfp-sim --help)";

/* --speed, --inverter, --format: a word each. */
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
    if (!cap_format_parse(v, &a->format)) {
        cli_error("replay: --format '%s': use pcap, pcapng, text or lcm", v);
        return false;
    }
    return true;
}

/* An option with a value. 1: consumed, 0: not one of these, -1: reported. */
static int parse_value_option(int argc, char **argv, int *i, replay_args_t *a)
{
    const char *o = argv[*i];
    bool word = strcmp(o, "--speed") == 0 || strcmp(o, "--inverter") == 0 ||
                strcmp(o, "--format") == 0;
    bool known = word || strcmp(o, "--address") == 0 || strcmp(o, "--baud") == 0 ||
                 strcmp(o, "--lcm") == 0 || strcmp(o, "--inverter-delay") == 0 ||
                 strcmp(o, "--http") == 0 || strcmp(o, "--channel") == 0;
    if (!known) {
        return 0;
    }
    const char *v = cli_value(argc, argv, i);
    if (v == NULL) {
        return -1;
    }
    bool ok = true;
    if (word) {
        ok = parse_word_option(o, v, a);
    } else if (strcmp(o, "--address") == 0) {
        ok = cli_u32(o, v, 0, 125, &a->address);
        a->have_address = true;
    } else if (strcmp(o, "--baud") == 0) {
        ok = cli_baud(o, v, false, &a->baud);
    } else if (strcmp(o, "--inverter-delay") == 0) {
        ok = cli_u32(o, v, 0, 10000000u, &a->delay_us);
    } else if (strcmp(o, "--lcm") == 0) {
        a->lcm_url = v;
    } else if (strcmp(o, "--channel") == 0) {
        a->lcm_channel = v;
    } else {
        a->http = v;
    }
    return ok ? 1 : -1;
}

static int parse_args(int argc, char **argv, replay_args_t *a)
{
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i];
        int c = parse_value_option(argc, argv, &i, a);
        if (c < 0) {
            return EXIT_USAGE;
        }
        if (c > 0) {
            continue;
        }
        if (strcmp(o, "--check") == 0) {
            a->check = true;
        } else if (strcmp(o, "--verbose") == 0) {
            rc_state.verbose = true;
        } else if (strcmp(o, "--fixed-baud") == 0) {
            a->fixed = true;
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

static int check_args(replay_args_t *a)
{
    if (a->file == NULL) {
        cli_error("replay: which capture? dfp-sim replay FILE [--check] ... %s",
                  replay_usage_hint);
        return EXIT_USAGE;
    }
    if (a->inverter != CARD_INVERTER_SIM && a->delay_us != REPLAY_INVERTER_DELAY_US_DEFAULT) {
        cli_error("replay: --inverter-delay belongs to the emulated inverter (--inverter sim)");
        return EXIT_USAGE;
    }
    if (a->have_address) {
        (void)snprintf(a->address_source, sizeof a->address_source, "given with --address");
    }
    a->baud_given = a->baud != 0u;
    if (a->baud_given) {
        (void)snprintf(a->baud_source, sizeof a->baud_source, "given with --baud");
    }
    struct stat fst;
    if ((!a->have_address || a->baud == 0u) && stat(a->file, &fst) == 0 &&
        !S_ISREG(fst.st_mode)) {
        /* The first pass would consume a pipe, leaving nothing to replay. */
        cli_error("replay: %s is not a regular file (a pipe?) and can be read only once: give "
                  "--address and --baud, or save it to a file first", a->file);
        return EXIT_USAGE;
    }
    return 0;
}

/* The card's address from the first pass: the one slave that answers. */
static int address_from_scan(replay_args_t *a, const replay_scan_t *scan,
                             const replay_file_status_t *st)
{
    uint8_t found[REPLAY_SCAN_MAX];
    unsigned n = replay_scan_result(scan, found, REPLAY_SCAN_MAX);
    if (n == 0u) {
        cli_error("replay: no slave answers in %s (%llu records%s%s): nothing tells which "
                  "station is the card; give --address N", a->file,
                  (unsigned long long)st->records, st->read_error ? "; " : "",
                  st->read_error ? st->error : "");
        return EXIT_USAGE;
    }
    if (n > 1u) {
        char list[1024];
        size_t k = 0;
        for (unsigned i = 0; i < n && k + 40u < sizeof list; i++) {
            k += (size_t)snprintf(list + k, sizeof list - k, "%s%u (%llu answers)",
                                  i > 0u ? ", " : "", found[i],
                                  (unsigned long long)scan->answers[found[i]]);
        }
        cli_error("replay: %u slaves answer in %s: %s; say which one is the card with "
                  "--address N", n, a->file, list);
        return EXIT_USAGE;
    }
    a->address = found[0];
    (void)snprintf(a->address_source, sizeof a->address_source,
                   "from the capture: the only slave that answers, %llu answers",
                   (unsigned long long)scan->answers[a->address]);
    return 0;
}

/* Appends to the baud source text; *used stays within its size. */
static void baud_source_add(replay_args_t *a, size_t *used, int k)
{
    *used += k > 0 && (size_t)k < sizeof a->baud_source - *used ? (size_t)k : 0u;
}

/* The rate the recorded timing needs, with why. */
static void baud_from_timing(replay_args_t *a, const replay_scan_t *scan)
{
    replay_scan_rate_t why;
    uint32_t inferred = replay_scan_rate(scan, &why);
    if (inferred == 0u) {
        (void)snprintf(a->baud_source, sizeof a->baud_source,
                       "the capture records no rate and no timed request with its answer: "
                       "the default, the rate of dfp-sim demo and record; --baud to change");
        return;
    }
    a->baud = inferred;
    size_t used = 0;
    baud_source_add(a, &used, snprintf(a->baud_source, sizeof a->baud_source,
                    "the capture records no rate; the lowest rate its timing allows: record "
                    "%llu begins %.1f us after record %llu, which needs %u bit times in that gap",
                    (unsigned long long)why.decided.record, (double)why.decided.gap_ns / 1e3,
                    (unsigned long long)why.decided.prev_record, why.decided.bits));
    if (why.outlier) {
        baud_source_add(a, &used, snprintf(a->baud_source + used, sizeof a->baud_source - used,
                        "; left out: record %llu, %.1f us after record %llu, alone needs a rate "
                        "four times higher (a bad timestamp?)",
                        (unsigned long long)why.ignored.record,
                        (double)why.ignored.gap_ns / 1e3,
                        (unsigned long long)why.ignored.prev_record));
    }
    if (scan->backward_pairs > 0u) {
        baud_source_add(a, &used, snprintf(a->baud_source + used, sizeof a->baud_source - used,
                        "; %llu records earlier than the one before left out",
                        (unsigned long long)scan->backward_pairs));
    }
    (void)snprintf(a->baud_source + used, sizeof a->baud_source - used, "; --baud to override");
}

/* First pass: which station answers, and what rate the recorded timing needs. Returns 0, or the
 * exit status after reporting. */
static int first_pass(replay_args_t *a)
{
    static replay_scan_t scan;
    progress_t prog;
    replay_file_status_t st;
    replay_scan_init(&scan);
    progress_begin(&prog, "looking at the capture");
    replay_input_t src = {.path = a->file, .format = a->format, .lcm_channel = a->lcm_channel};
    int rc = replay_scan_file(&scan, &src, &cli_stop, progress_show, &prog, &st);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("%s", st.error);
        return EXIT_USAGE;
    }
    if (st.interrupted) {
        cli_error("replay: interrupted");
        return 1;
    }
    if (!a->have_address && (rc = address_from_scan(a, &scan, &st)) != 0) {
        return rc;
    }
    if (a->baud == 0u && scan.recorded_baud != 0u) {
        a->baud = scan.recorded_baud; /* also the rate a --fixed-baud card starts at */
        (void)snprintf(a->baud_source, sizeof a->baud_source, "recorded in the capture");
    } else if (a->baud == 0u) {
        baud_from_timing(a, &scan);
    }
    return 0;
}

/* --lcm and --http around the replay. */
static void close_outputs(void)
{
    if (rc_state.lcm_open) {
        dfp_lcm_bridge_close(&rc_state.lcm);
        rc_state.lcm_open = false;
    }
    instrument_stop(&rc_state.in);
}

/* The read-only control API: the card under test as the panel shows it, every action refused.
 * The log goes to the API's event list (and stderr from warnings on): stdout is the report's. */
static int start_http(const replay_args_t *a)
{
    instrument_opts_t io;
    instrument_defaults(&io, RIG_LOG_TIME_BUS);
    io.http = a->http;
    rig_t *rig = &rc_state.replay.rig;
    memset(&rc_state.in, 0, sizeof rc_state.in);
    rig_log_init(&rc_state.in.log, rig, stderr);
    rc_state.in.log.level = RIG_LOG_WARN;
    rc_state.in.log.time = io.time;
    rig_tap_t tap = rig_log_tap(&rc_state.in.log);
    (void)rig_add_tap(rig, &tap);
    int rc = instrument_start_http(&rc_state.in, rig, &io, "replay", true);
    if (rc == 0) {
        /* The log's own line about the server is below its level here. */
        (void)fprintf(stderr, "replay: control API on port %u (read-only) while the replay "
                              "runs\n", http_server_port(rc_state.in.http));
    }
    return rc;
}

/* Sets up the engine with --lcm and --http. Returns 0, or the exit status after reporting. */
static int start_replay(const replay_args_t *a)
{
    rc_state.rep.now_ns = replay_now_ns;
    rc_state.rep.now_ctx = &rc_state.replay;
    rc_state.rep.card = &rc_state.replay.rig.cards[0].cs.card;
    replay_options_t ro = {.address = (uint8_t)a->address, .check = a->check, .baud = a->baud,
                           .baud_override = a->baud_given, .fixed_card_baud = a->fixed,
                           .inverter = a->inverter, .inverter_delay_us = a->delay_us,
                           .speed = a->speed, .stop = &cli_stop, .on_telegram = on_telegram,
                           .on_card_event = on_card_event, .ctx = &rc_state};
    char err[400];
    if (a->lcm_url != NULL) {
        if (dfp_lcm_bridge_open(&rc_state.lcm, a->lcm_url, (int16_t)a->address, err,
                                sizeof err) != 0) {
            cli_error("replay: --lcm: %s", err);
            return 1;
        }
        rc_state.lcm_open = true;
        rc_state.lcm.clock = replay_lcm_clock;
        ro.param_observer = dfp_lcm_bridge_param_observer;
        ro.param_observer_ctx = &rc_state.lcm;
    }
    if (a->http != NULL) {
        ro.service = on_service;
        ro.service_ctx = &rc_state.in;
    }
    if (replay_init(&rc_state.replay, &ro, err, sizeof err) != 0) {
        cli_error("replay: %s", err);
        close_outputs();
        return 1;
    }
    int rc = a->http != NULL ? start_http(a) : 0;
    if (rc != 0) {
        close_outputs();
    }
    return rc;
}

/* The report, and what --lcm published. Returns the report's exit status. */
static int finish_replay(const replay_args_t *a, const replay_file_status_t *st)
{
    replay_report_info_t info = {
        .file = a->file,
        .format = cap_format_name(st->format),
        .position_unit = replay_position_unit(st->format),
        .address_source = a->address_source,
        .baud_source = a->baud_source,
        .file_error = st->read_error ? st->error : NULL,
        .source_note = st->note,
        .interrupted = st->interrupted,
    };
    int status = replay_report(&rc_state.replay, &info, stdout);
    if (rc_state.lcm_open) {
        /* Telemetry never changes the verdict: failures are reported, not counted against it. */
        (void)dfp_lcm_bridge_card_state(&rc_state.lcm, capture_utime(rc_state.replay.rig.bus.now_ns),
                                        replay_card());
        printf("lcm: %llu messages published to %s", (unsigned long long)rc_state.lcm.messages,
               a->lcm_url);
        if (rc_state.lcm.failures > 0u) {
            printf(", %llu failed (first: %s)", (unsigned long long)rc_state.lcm.failures,
                   rc_state.lcm.error);
        }
        printf("\n");
    }
    close_outputs();
    fflush(stdout);
    return status;
}

int cmd_replay(int argc, char **argv)
{
    memset(&rc_state, 0, sizeof rc_state);
    replay_args_t a = {.delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT, .format = CAP_FORMAT_AUTO,
                       .inverter = CARD_INVERTER_SIM, .speed = REPLAY_SPEED_MAX};
    int rc = parse_args(argc, argv, &a);
    if (rc == 0) {
        rc = check_args(&a);
    }
    if (rc != 0) {
        return rc;
    }
    cli_catch_stop_signals();
    if ((!a.have_address || a.baud == 0u) && (rc = first_pass(&a)) != 0) {
        return rc;
    }
    if ((rc = start_replay(&a)) != 0) {
        return rc;
    }
    progress_t prog;
    progress_begin(&prog, "replay");
    if (rc_state.verbose) {
        prog.on = false; /* the trace is on stdout; keep the terminal readable */
    }
    replay_file_status_t st;
    replay_input_t src = {.path = a.file, .format = a.format, .lcm_channel = a.lcm_channel};
    rc = replay_run_file(&rc_state.replay, &src, &cli_stop, progress_show, &prog, &st);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("%s", st.error);
        close_outputs();
        return EXIT_USAGE;
    }
    return finish_replay(&a, &st);
}

/* ---- record -------------------------------------------------------------------------------- */

static void record_progress(void *ctx, uint32_t cycles, uint64_t telegrams)
{
    progress_t *p = ctx;
    if (!p->on) {
        return;
    }
    uint64_t now = host_clock_mono_ns();
    if (now - p->last < 200000000u) {
        return;
    }
    p->last = now;
    fprintf(stderr, "\rrecord: %u cycles, %llu telegrams\033[K", cycles,
            (unsigned long long)telegrams);
    p->shown = true;
}

/* One option of dfp-sim record that is not a capture option. 1: consumed, 0: unknown, -1:
 * reported. */
static int record_option(int argc, char **argv, int *i, gen_options_t *o, uint32_t *address,
                         bool *have_cycles)
{
    const char *opt = argv[*i];
    const char *v;
    if (strcmp(opt, "--dpv1") == 0 || strcmp(opt, "--faults") == 0 ||
        strcmp(opt, "--foreign") == 0) {
        o->dpv1 = o->dpv1 || strcmp(opt, "--dpv1") == 0;
        o->faults = o->faults || strcmp(opt, "--faults") == 0;
        o->foreign = o->foreign || strcmp(opt, "--foreign") == 0;
        return 1;
    }
    if (strcmp(opt, "--cycles") == 0) {
        *have_cycles = true;
        return (v = cli_value(argc, argv, i)) != NULL &&
               cli_u32(opt, v, 1, 100000000u, &o->cycles) ? 1 : -1;
    }
    if (strcmp(opt, "--baud") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL && cli_baud(opt, v, false, &o->baud) ? 1
                                                                                           : -1;
    }
    if (strcmp(opt, "--address") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL && cli_u32(opt, v, 0, 125, address) ? 1
                                                                                           : -1;
    }
    if (strcmp(opt, "--param-every") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL &&
               cli_u32(opt, v, 0, 100000000u, &o->param_every) ? 1 : -1;
    }
    if (strcmp(opt, "--inverter") != 0) {
        return 0;
    }
    if ((v = cli_value(argc, argv, i)) == NULL) return -1;
    if (strcmp(v, "sim") == 0 || strcmp(v, "none") == 0) {
        o->inverter = strcmp(v, "sim") == 0 ? CARD_INVERTER_SIM : CARD_INVERTER_NONE;
        return 1;
    }
    cli_error("record: --inverter '%s': use sim or none", v);
    return -1;
}

static int parse_record_args(int argc, char **argv, gen_options_t *o, uint32_t *address)
{
    bool have_cycles = false;
    for (int i = 2; i < argc; i++) {
        capture_opts_t co = {.path = o->path, .w = o->writer};
        int c = capture_option(argc, argv, &i, &co);
        if (c > 0) {
            o->path = co.path;
            o->writer = co.w;
            continue;
        }
        if (c == 0) {
            c = record_option(argc, argv, &i, o, address, &have_cycles);
        }
        if (c < 0) {
            return EXIT_USAGE;
        }
        if (c == 0) {
            cli_error("record: unknown option '%s' (see dfp-sim --help)", argv[i]);
            return EXIT_USAGE;
        }
    }
    if (o->path == NULL || !have_cycles) {
        cli_error("record: --capture FILE and --cycles N are required");
        return EXIT_USAGE;
    }
    if (o->foreign && *address > 114u) {
        cli_error("record: --foreign puts stations at --address + 1 and + 10: the address must "
                  "be 114 or lower");
        return EXIT_USAGE;
    }
    return 0;
}

int cmd_record(int argc, char **argv)
{
    gen_options_t o = {.address = 4, .param_every = 10, .inverter = CARD_INVERTER_SIM,
                       .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT};
    uint32_t address = 4;
    int rc = parse_record_args(argc, argv, &o, &address);
    if (rc != 0) {
        return rc;
    }
    o.address = (uint8_t)address;
    progress_t prog;
    progress_begin(&prog, "record");
    o.progress = record_progress;
    o.ctx = &prog;
    gen_result_t res;
    char err[256];
    rc = gen_run(&o, &res, err, sizeof err);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("record: %s", err);
        return 1;
    }
    printf("record: %llu telegrams (%llu octets) in %.3f s of bus time at %s -> %s\n"
           "  %u Data_Exchange cycles of the card at address %u, %u parameter-channel services "
           "(%u answered with an error), %u data set 47 calls, %u class-2 connections, "
           "%u turns of master %u, %u watchdog expiries\n",
           (unsigned long long)res.telegrams, (unsigned long long)res.octets,
           (double)res.bus_ns / 1e9, report_baud_text(o.baud != 0u ? o.baud : 1500000u), o.path,
           res.cycles, address, res.param_services, res.param_errors, res.ds47_calls,
           res.c2_connections, res.foreign_bursts, GEN_FOREIGN_MASTER_ADDRESS,
           res.watchdog_expiries);
    return 0;
}
