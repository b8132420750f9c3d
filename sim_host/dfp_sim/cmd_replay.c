/* dfp-sim replay: a bus capture played against the emulated card, optionally checking every
 * reply (docs/replay.md); dfp-sim record: a capture made on the simulated bus. */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "capture/capture.h"
#include "cli.h"
#include "dfp_lcm_bridge/lcm_bridge.h"
#include "commands.h"
#include "replay/generator.h"
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

static replay_t replay; /* the bus, the card and the inverter: not on the stack */

typedef struct replay_cli {
    bool verbose;
    report_t rep; /* card events in --verbose, as dfp-sim demo prints them */
    bool lcm_open;
    dfp_lcm_bridge_t lcm; /* --lcm URL */
} replay_cli_t;

static replay_cli_t rc_state;

static uint64_t replay_now_ns(void *ctx)
{
    return ((replay_t *)ctx)->bus.now_ns;
}

/* LCM's utime of a bus instant: the capture's own clock (the first record's time, shortened
 * gaps counted in full), so the telemetry of a replay carries the times of the plant, not of the
 * replay. It never runs backwards (the bridge's state rate limit relies on that). */
static int64_t capture_utime(uint64_t bus_ns)
{
    return (int64_t)(replay_capture_ns(&replay, bus_ns) / 1000u);
}

static int64_t replay_lcm_clock(void *ctx)
{
    (void)ctx;
    return capture_utime(replay.bus.now_ns);
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
        (void)dfp_lcm_bridge_card_state(&c->lcm, utime, &replay.card.card);
    }
    if (!c->verbose) {
        return;
    }
    char hex[3u * CAP_MAX_RECORD + 8u];
    char text[512];
    replay_hex(t->data, t->len, hex, sizeof hex);
    const dfp21b_pd_cfg_t *pd = &replay.card.card.pd;
    replay_dx_layout_t lay = {.known = pd->valid, .param_channel = pd->param_channel};
    replay_describe(t->data, t->len, &lay, text, sizeof text);
    if (t->source == REPLAY_FROM_CARD) {
        printf("%10.3f ms  card    > %s  | %s\n", (double)t->t_ns / 1e6, hex, text);
    } else {
        printf("%10.3f ms  #%-6llu < %s  | %s%s%s\n", (double)t->t_ns / 1e6,
               (unsigned long long)t->record, hex, text, t->problem[0] != '\0' ? "  DAMAGED: " : "",
               t->problem);
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

static const char replay_usage_hint[] = "(see dfp-sim --help)";

int cmd_replay(int argc, char **argv)
{
    const char *file = NULL;
    uint32_t address = 0;
    bool have_address = false;
    bool check = false;
    bool fixed = false;
    uint32_t baud = 0;
    uint32_t delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT;
    cap_format_t format = CAP_FORMAT_AUTO;
    card_inverter_t inverter = CARD_INVERTER_SIM;
    replay_speed_t speed = REPLAY_SPEED_MAX;
    const char *lcm_url = NULL;
    memset(&rc_state, 0, sizeof rc_state);
    for (int i = 2; i < argc; i++) {
        const char *o = argv[i];
        const char *v;
        if (strcmp(o, "--address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 125, &address))
                return EXIT_USAGE;
            have_address = true;
        } else if (strcmp(o, "--check") == 0) {
            check = true;
        } else if (strcmp(o, "--verbose") == 0) {
            rc_state.verbose = true;
        } else if (strcmp(o, "--fixed-baud") == 0) {
            fixed = true;
        } else if (strcmp(o, "--speed") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
            if (strcmp(v, "real") == 0) {
                speed = REPLAY_SPEED_REAL;
            } else if (strcmp(v, "max") == 0) {
                speed = REPLAY_SPEED_MAX;
            } else {
                cli_error("replay: --speed '%s': use real (the capture's pace) or max", v);
                return EXIT_USAGE;
            }
        } else if (strcmp(o, "--baud") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_baud(o, v, false, &baud))
                return EXIT_USAGE;
        } else if (strcmp(o, "--format") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
            if (!cap_format_parse(v, &format)) {
                cli_error("replay: --format '%s': use pcap, pcapng, text or lcm", v);
                return EXIT_USAGE;
            }
        } else if (strcmp(o, "--inverter") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
            if (strcmp(v, "sim") == 0) {
                inverter = CARD_INVERTER_SIM;
            } else if (strcmp(v, "none") == 0) {
                inverter = CARD_INVERTER_NONE;
            } else {
                cli_error("replay: --inverter '%s': use sim (emulated MOVIDRIVE) or none (PI "
                          "echoes PO)", v);
                return EXIT_USAGE;
            }
        } else if (strcmp(o, "--lcm") == 0) {
            if ((lcm_url = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(o, "--inverter-delay") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 10000000u, &delay_us))
                return EXIT_USAGE;
        } else if (o[0] == '-' && o[1] != '\0') {
            cli_error("replay: unknown option '%s' %s", o, replay_usage_hint);
            return EXIT_USAGE;
        } else if (file == NULL) {
            file = o;
        } else {
            cli_error("replay: one capture file only ('%s' and '%s')", file, o);
            return EXIT_USAGE;
        }
    }
    if (file == NULL) {
        cli_error("replay: which capture? dfp-sim replay FILE [--check] ... %s",
                  replay_usage_hint);
        return EXIT_USAGE;
    }
    if (inverter != CARD_INVERTER_SIM && delay_us != REPLAY_INVERTER_DELAY_US_DEFAULT) {
        cli_error("replay: --inverter-delay belongs to the emulated inverter (--inverter sim)");
        return EXIT_USAGE;
    }
    cli_catch_stop_signals();

    progress_t prog;
    replay_file_status_t st;
    char address_source[160];
    char baud_source[640];
    if (have_address) {
        snprintf(address_source, sizeof address_source, "given with --address");
    }
    bool baud_given = baud != 0u;
    if (baud_given) {
        snprintf(baud_source, sizeof baud_source, "given with --baud");
    }
    struct stat fst;
    if ((!have_address || baud == 0u) && stat(file, &fst) == 0 && !S_ISREG(fst.st_mode)) {
        /* The first pass would consume a pipe, leaving nothing to replay. */
        cli_error("replay: %s is not a regular file (a pipe?) and can be read only once: give "
                  "--address and --baud, or save it to a file first", file);
        return EXIT_USAGE;
    }
    if (!have_address || baud == 0u) {
        /* First pass: which station answers, and what rate the recorded timing needs. */
        static replay_scan_t scan;
        replay_scan_init(&scan);
        progress_begin(&prog, "looking at the capture");
        int rc = replay_scan_file(&scan, file, format, &cli_stop, progress_show, &prog,
                                  &st);
        progress_end(&prog);
        if (rc != 0) {
            cli_error("%s", st.error);
            return EXIT_USAGE;
        }
        if (st.interrupted) {
            cli_error("replay: interrupted");
            return 1;
        }
        if (!have_address) {
            uint8_t found[REPLAY_SCAN_MAX];
            unsigned n = replay_scan_result(&scan, found, REPLAY_SCAN_MAX);
            if (n == 0u) {
                cli_error("replay: no slave answers in %s (%llu records%s%s): nothing tells "
                          "which station is the card; give --address N", file,
                          (unsigned long long)st.records, st.read_error ? "; " : "",
                          st.read_error ? st.error : "");
                return EXIT_USAGE;
            }
            if (n > 1u) {
                char list[1024];
                size_t k = 0;
                for (unsigned i = 0; i < n && k + 40u < sizeof list; i++) {
                    k += (size_t)snprintf(list + k, sizeof list - k, "%s%u (%llu answers)",
                                          i > 0u ? ", " : "", found[i],
                                          (unsigned long long)scan.answers[found[i]]);
                }
                cli_error("replay: %u slaves answer in %s: %s; say which one is the card with "
                          "--address N", n, file, list);
                return EXIT_USAGE;
            }
            address = found[0];
            snprintf(address_source, sizeof address_source,
                     "from the capture: the only slave that answers, %llu answers",
                     (unsigned long long)scan.answers[address]);
        }
        if (baud == 0u && scan.recorded_baud != 0u) {
            baud = scan.recorded_baud; /* also the rate a --fixed-baud card starts at */
            snprintf(baud_source, sizeof baud_source, "recorded in the capture");
        } else if (baud == 0u) {
            replay_scan_rate_t why;
            uint32_t inferred = replay_scan_rate(&scan, &why);
            if (inferred != 0u) {
                baud = inferred;
                int k = snprintf(baud_source, sizeof baud_source,
                                 "the capture records no rate; the lowest rate its timing "
                                 "allows: record %llu begins %.1f us after record %llu, which "
                                 "needs %u bit times in that gap",
                                 (unsigned long long)why.decided.record,
                                 (double)why.decided.gap_ns / 1e3,
                                 (unsigned long long)why.decided.prev_record, why.decided.bits);
                size_t used = k > 0 && (size_t)k < sizeof baud_source ? (size_t)k : 0u;
                if (why.outlier) {
                    k = snprintf(baud_source + used, sizeof baud_source - used,
                                 "; left out: record %llu, %.1f us after record %llu, alone "
                                 "needs a rate four times higher (a bad timestamp?)",
                                 (unsigned long long)why.ignored.record,
                                 (double)why.ignored.gap_ns / 1e3,
                                 (unsigned long long)why.ignored.prev_record);
                    used += k > 0 && (size_t)k < sizeof baud_source - used ? (size_t)k : 0u;
                }
                if (scan.backward_pairs > 0u) {
                    k = snprintf(baud_source + used, sizeof baud_source - used,
                                 "; %llu records earlier than the one before left out",
                                 (unsigned long long)scan.backward_pairs);
                    used += k > 0 && (size_t)k < sizeof baud_source - used ? (size_t)k : 0u;
                }
                (void)snprintf(baud_source + used, sizeof baud_source - used,
                               "; --baud to override");
            } else {
                snprintf(baud_source, sizeof baud_source,
                         "the capture records no rate and no timed request with its answer: "
                         "the default, the rate of dfp-sim demo and record; --baud to change");
            }
        }
    }

    rc_state.rep.now_ns = replay_now_ns;
    rc_state.rep.now_ctx = &replay;
    rc_state.rep.card = &replay.card.card;
    replay_options_t ro = {.address = (uint8_t)address, .check = check, .baud = baud,
                           .baud_override = baud_given, .fixed_card_baud = fixed, .inverter = inverter,
                           .inverter_delay_us = delay_us, .speed = speed,
                           .stop = &cli_stop,
                           .on_telegram = on_telegram, .on_card_event = on_card_event,
                           .ctx = &rc_state};
    char err[400];
    if (lcm_url != NULL) {
        if (dfp_lcm_bridge_open(&rc_state.lcm, lcm_url, (int16_t)address, err, sizeof err) != 0) {
            cli_error("replay: --lcm: %s", err);
            return 1;
        }
        rc_state.lcm_open = true;
        rc_state.lcm.clock = replay_lcm_clock;
        ro.param_observer = dfp_lcm_bridge_param_observer;
        ro.param_observer_ctx = &rc_state.lcm;
    }
    if (replay_init(&replay, &ro, err, sizeof err) != 0) {
        cli_error("replay: %s", err);
        if (rc_state.lcm_open) {
            dfp_lcm_bridge_close(&rc_state.lcm);
        }
        return 1;
    }
    progress_begin(&prog, "replay");
    if (rc_state.verbose) {
        prog.on = false; /* the trace is on stdout; keep the terminal readable */
    }
    int rc = replay_run_file(&replay, file, format, &cli_stop, progress_show, &prog, &st);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("%s", st.error);
        if (rc_state.lcm_open) {
            dfp_lcm_bridge_close(&rc_state.lcm);
        }
        return EXIT_USAGE;
    }
    replay_report_info_t info = {
        .file = file,
        .format = cap_format_name(st.format),
        .position_unit = replay_position_unit(st.format),
        .address_source = address_source,
        .baud_source = baud_source,
        .file_error = st.read_error ? st.error : NULL,
        .interrupted = st.interrupted,
    };
    int status = replay_report(&replay, &info, stdout);
    if (rc_state.lcm_open) {
        /* Telemetry never changes the verdict: failures are reported, not counted against it. */
        (void)dfp_lcm_bridge_card_state(&rc_state.lcm, capture_utime(replay.bus.now_ns),
                                        &replay.card.card);
        printf("lcm: %llu messages published to %s", (unsigned long long)rc_state.lcm.messages,
               lcm_url);
        if (rc_state.lcm.failures > 0u) {
            printf(", %llu failed (first: %s)", (unsigned long long)rc_state.lcm.failures,
                   rc_state.lcm.error);
        }
        printf("\n");
        dfp_lcm_bridge_close(&rc_state.lcm);
    }
    fflush(stdout);
    return status;
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

int cmd_record(int argc, char **argv)
{
    gen_options_t o = {.address = 4, .param_every = 10, .inverter = CARD_INVERTER_SIM,
                       .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT};
    uint32_t address = 4;
    bool have_cycles = false;
    for (int i = 2; i < argc; i++) {
        const char *opt = argv[i];
        const char *v;
        capture_opts_t co = {.path = o.path, .w = o.writer};
        int c = capture_option(argc, argv, &i, &co);
        if (c < 0) {
            return EXIT_USAGE;
        }
        if (c > 0) {
            o.path = co.path;
            o.writer = co.w;
        } else if (strcmp(opt, "--cycles") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_u32(opt, v, 1, 100000000u, &o.cycles)) return EXIT_USAGE;
            have_cycles = true;
        } else if (strcmp(opt, "--baud") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_baud(opt, v, false, &o.baud))
                return EXIT_USAGE;
        } else if (strcmp(opt, "--address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(opt, v, 0, 125, &address))
                return EXIT_USAGE;
        } else if (strcmp(opt, "--param-every") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_u32(opt, v, 0, 100000000u, &o.param_every)) return EXIT_USAGE;
        } else if (strcmp(opt, "--dpv1") == 0) {
            o.dpv1 = true;
        } else if (strcmp(opt, "--faults") == 0) {
            o.faults = true;
        } else if (strcmp(opt, "--foreign") == 0) {
            o.foreign = true;
        } else if (strcmp(opt, "--inverter") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
            if (strcmp(v, "sim") == 0) {
                o.inverter = CARD_INVERTER_SIM;
            } else if (strcmp(v, "none") == 0) {
                o.inverter = CARD_INVERTER_NONE;
            } else {
                cli_error("record: --inverter '%s': use sim or none", v);
                return EXIT_USAGE;
            }
        } else {
            cli_error("record: unknown option '%s' (see dfp-sim --help)", opt);
            return EXIT_USAGE;
        }
    }
    if (o.path == NULL || !have_cycles) {
        cli_error("record: --capture FILE and --cycles N are required");
        return EXIT_USAGE;
    }
    if (o.foreign && address > 114u) {
        cli_error("record: --foreign puts stations at --address + 1 and + 10: the address must "
                  "be 114 or lower");
        return EXIT_USAGE;
    }
    o.address = (uint8_t)address;
    progress_t prog;
    progress_begin(&prog, "record");
    o.progress = record_progress;
    o.ctx = &prog;
    gen_result_t res;
    char err[256];
    int rc = gen_run(&o, &res, err, sizeof err);
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
