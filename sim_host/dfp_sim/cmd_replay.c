/* dfp-sim replay: a bus capture played against the emulated card, optionally checking every
 * reply (docs/replay.md). The command line is replay_args.c's. */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"
#include "lcm_bridge/lcm_bridge.h"
#include "instrument.h"
#include "progress.h"
#include "replay/infer.h"
#include "replay/param_text.h"
#include "replay/replay.h"
#include "replay_args.h"
#include "report.h"
#include "sim_hal/path.h"

/* ---- replay -------------------------------------------------------------------------------- */

typedef struct replay_cli {
    replay_t replay; /* the bus, the card and the inverter: not on the stack */
    bool verbose;
    report_t rep; /* card events in --verbose, as dfp-sim demo prints them */
    replay_param_ctx_t param_ctx; /* names a data set 47 answer after its request (--verbose) */
    bool lcm_open;
    dfp_lcm_bridge_t lcm; /* --lcm URL */
    instrument_t in;      /* --http: the read-only control API */
    replay_inferred_t inferred; /* the first pass's findings and the command line */
    replay_list_t list;   /* the mismatches listed in the reports */
} replay_cli_t;

static replay_cli_t rc_state;

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

/* First pass over a regular file: which station answers, what rate the recorded timing needs,
 * whether the times are a line's or a tty's, whether the card had its rate already. A pipe
 * cannot be read twice: then everything comes from the command line (replay_args.c made sure
 * the address and rate are there). Returns 0, or the exit status after reporting. */
static int first_pass(const replay_args_t *a, replay_inferred_t *inf)
{
    static replay_scan_t scan;
    replay_file_status_t st;
    memset(&st, 0, sizeof st);
    const replay_scan_t *found = NULL;
    struct stat fst;
    if (stat(a->file, &fst) != 0 || S_ISREG(fst.st_mode)) {
        progress_t prog;
        replay_scan_init(&scan);
        progress_begin(&prog, "looking at the capture");
        replay_input_t src = {.path = a->file, .format = a->format,
                              .lcm_channel = a->lcm_channel};
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
        found = &scan;
    }
    char err[1400];
    if (replay_infer(found, &st, &a->given, inf, err, sizeof err) != 0) {
        cli_error("replay: %s", err);
        return EXIT_USAGE;
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
    replay_list_close(&rc_state.list);
}

/* The read-only control API: the card under test as the panel shows it, every action refused.
 * The log goes to the API's event list (and stderr from warnings on): stdout is the report's. */
static int start_http(const replay_args_t *a)
{
    instrument_opts_t io;
    instrument_defaults(&io, RIG_LOG_TIME_BUS);
    io.http = a->http;
    io.web = a->web;
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
    const replay_inferred_t *inf = &rc_state.inferred;
    replay_options_t ro = {.address = inf->address, .check = a->check, .baud = inf->baud,
                           .baud_override = inf->baud_override,
                           .fixed_card_baud = inf->fixed_baud, .inverter = a->inverter,
                           .inverter_delay_us = inf->delay_us, .speed = a->speed,
                           .stop = &cli_stop, .on_telegram = on_telegram,
                           .on_card_event = on_card_event, .ctx = &rc_state,
                           .mask = a->mask.any ? &a->mask : NULL,
                           .on_mismatch = replay_list_add, .mismatch_ctx = &rc_state.list};
    replay_list_init(&rc_state.list, a->max_listed);
    char err[400];
    if (a->lcm_url != NULL) {
        if (dfp_lcm_bridge_open(&rc_state.lcm, a->lcm_url, (int16_t)inf->address, err,
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

/* --report json|junit FILE. Returns 0, or 1 after saying which file could not be written. */
static int write_report_files(const replay_args_t *a, const replay_report_info_t *info)
{
    int status = 0;
    for (size_t i = 0; i < a->n_reports; i++) {
        const cli_kind_file_t *rf = &a->reports[i];
        bool junit = rf->kind == REPLAY_REPORT_JUNIT;
        char why[160];
        FILE *f = sim_fopen_write(rf->path, why, sizeof why);
        if (f == NULL) {
            cli_error("replay: --report %s: cannot write %s: %s", junit ? "junit" : "json",
                      rf->path, why);
            status = 1;
            continue;
        }
        int rc = junit ? replay_report_junit(&rc_state.replay, info, f)
                           : replay_report_json(&rc_state.replay, info, f);
        if (fclose(f) != 0 || rc != 0) {
            cli_error("replay: --report %s: could not write all of %s",
                      junit ? "junit" : "json", rf->path);
            status = 1;
        }
    }
    return status;
}

/* The report, the report files, and what --lcm published. Returns the report's exit status (1
 * also when a report file could not be written). */
static int finish_replay(const replay_args_t *a, const replay_file_status_t *st)
{
    replay_report_info_t info = {
        .file = a->file,
        .format = cap_format_name(st->format),
        .position_unit = replay_position_unit(st->format),
        .address_source = rc_state.inferred.address_source,
        .baud_source = rc_state.inferred.baud_source,
        .file_error = st->read_error ? st->error : NULL,
        .source_note = st->note,
        .interrupted = st->interrupted,
        .inferred = &rc_state.inferred,
        .list = &rc_state.list,
    };
    int status = replay_report(&rc_state.replay, &info, stdout);
    fflush(stdout);
    if (write_report_files(a, &info) != 0) {
        status = 1;
    }
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

/* The replay set up from rc_state.inferred, through the file once (with scan: the first pass
 * along with it). Returns 0, or the exit status after reporting. */
static int replay_pass(const replay_args_t *a, replay_scan_t *scan, replay_file_status_t *st)
{
    int rc = start_replay(a);
    if (rc != 0) {
        return rc;
    }
    progress_t prog;
    progress_begin(&prog, "replay");
    if (rc_state.verbose) {
        prog.on = false; /* the trace is on stdout; keep the terminal readable */
    }
    replay_input_t src = {.path = a->file, .format = a->format, .lcm_channel = a->lcm_channel};
    rc = scan != NULL
             ? replay_scan_run_file(scan, &rc_state.replay, &src, &cli_stop, progress_show,
                                    &prog, st)
             : replay_run_file(&rc_state.replay, &src, &cli_stop, progress_show, &prog, st);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("%s", st->error);
        close_outputs();
        return EXIT_USAGE;
    }
    return 0;
}

/* Records the first pass looks at before the replay starts, when it goes along with the
 * replay: enough for the card's first request and its answer, and the kind of timing, in
 * any capture seen so far. */
#define GUESS_RECORDS 4096u

/* The first pass along with the replay saves reading the file twice. It needs a file that can
 * be read again should the guess be wrong, and nothing that shows the replay while it runs
 * (a wrong guess replays again). */
static bool one_pass_possible(const replay_args_t *a)
{
    struct stat fst;
    return a->speed == REPLAY_SPEED_MAX && !a->verbose && a->lcm_url == NULL &&
           a->http == NULL && stat(a->file, &fst) == 0 && S_ISREG(fst.st_mode);
}

/* What the replay is set up from: the options replay_init gets from replay_inferred_t. */
static bool same_setup(const replay_inferred_t *x, const replay_inferred_t *y)
{
    return x->address == y->address && x->baud == y->baud &&
           x->baud_override == y->baud_override && x->fixed_baud == y->fixed_baud &&
           x->delay_us == y->delay_us;
}

/* The guess from the first records of the file: 1 when they do not settle the address (the
 * two passes then), else 0 with the guess in rc_state.inferred, or the exit status. */
static int guess_setup(const replay_args_t *a, replay_scan_t *scan)
{
    replay_file_status_t st;
    replay_input_t src = {.path = a->file, .format = a->format, .lcm_channel = a->lcm_channel};
    replay_scan_init(scan);
    if (replay_scan_file_head(scan, &src, GUESS_RECORDS, &cli_stop, &st) != 0) {
        cli_error("%s", st.error);
        return EXIT_USAGE;
    }
    if (st.interrupted) {
        cli_error("replay: interrupted");
        return 1;
    }
    char err[1400];
    return replay_infer(scan, &st, &a->given, &rc_state.inferred, err, sizeof err) == 0 ? 0
                                                                                          : -1;
}

/* The replay with the first pass along with it; once more when the whole file says otherwise
 * than its first records (the replay then is the one the two passes would give). */
static int replay_one_pass(const replay_args_t *a, replay_file_status_t *st)
{
    static replay_scan_t scan;
    int rc = guess_setup(a, &scan);
    if (rc < 0) {
        rc = first_pass(a, &rc_state.inferred);
        return rc != 0 ? rc : replay_pass(a, NULL, st);
    }
    if (rc != 0) {
        return rc;
    }
    replay_scan_init(&scan);
    if ((rc = replay_pass(a, &scan, st)) != 0 || st->interrupted) {
        return rc; /* interrupted: reported as replayed, with what it was set up from */
    }
    replay_inferred_t found;
    char err[1400];
    if (replay_infer(&scan, st, &a->given, &found, err, sizeof err) != 0) {
        cli_error("replay: %s", err);
        close_outputs();
        return EXIT_USAGE;
    }
    bool same = same_setup(&found, &rc_state.inferred);
    rc_state.inferred = found;
    if (same) {
        return 0;
    }
    close_outputs();
    return replay_pass(a, NULL, st);
}

int cmd_replay(int argc, char **argv)
{
    static replay_args_t a;
    memset(&rc_state, 0, sizeof rc_state);
    int rc = replay_parse_args(argc, argv, &a);
    if (rc != 0) {
        return rc;
    }
    rc_state.verbose = a.verbose;
    cli_catch_stop_signals();
    replay_file_status_t st;
    if (one_pass_possible(&a)) {
        rc = replay_one_pass(&a, &st);
    } else if ((rc = first_pass(&a, &rc_state.inferred)) == 0) {
        rc = replay_pass(&a, NULL, &st);
    }
    return rc != 0 ? rc : finish_replay(&a, &st);
}
