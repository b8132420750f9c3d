/* dfp-sim slave / master: the card or the built-in master on a real tty or a PTY, or on a
 * virtual segment over LCM (--bus lcm:CHANNEL), in wall-clock time. Timing on a PC is relaxed
 * (see fdl_rx.h): the OS delivers bytes in chunks. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "dfp_lcm_bridge/lcm_segment.h"
#include "lcm_cli.h"
#include "report.h"
#include "inverter_can.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

static volatile int stop_requested;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static void install_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

typedef struct tty_clock {
    uint64_t start_ns;
} tty_clock_t;

static uint64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

static uint64_t tty_clock_now(void *ctx)
{
    tty_clock_t *c = ctx;
    return mono_ns() - c->start_ns;
}

static bool open_capture(report_t *rep, const capture_opts_t *capture)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    rep->capture_direction = true;
    return report_open_capture(rep, capture,
                               (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec);
}

/* ---- one station on one tty, or on an LCM segment ---------------------------------------- */

static card_station_t card;
static tty_port_t port;
static dfp_lcm_segment_t segment;
static bool on_segment;
static tty_runner_t runner;
static dp_master_t master;
static report_t rep;
static tty_clock_t clk;
static lcm_cli_t telemetry; /* --lcm URL */

/* Where the station is: a tty (--port DEV) or a virtual segment (--bus lcm:CHANNEL with
 * --lcm-url URL). */
typedef struct medium_opts {
    const char *dev;
    const char *bus;
    const char *lcm_url;
} medium_opts_t;

/* --port / --bus / --lcm-url, shared by slave and master. Returns 1 when argv[*i] was one of
 * them, 0 when not, -1 on a usage error (reported). */
static int medium_option(medium_opts_t *m, int argc, char **argv, int *i)
{
    const char **slot = NULL;
    if (strcmp(argv[*i], "--port") == 0) {
        slot = &m->dev;
    } else if (strcmp(argv[*i], "--bus") == 0) {
        slot = &m->bus;
    } else if (strcmp(argv[*i], "--lcm-url") == 0) {
        slot = &m->lcm_url;
    } else {
        return 0;
    }
    return (*slot = cli_value(argc, argv, i)) != NULL ? 1 : -1;
}

/* Exactly one of --port and --bus; returns false after reporting. */
static bool medium_check(const medium_opts_t *m, const char *cmd)
{
    if (m->dev != NULL && m->bus != NULL) {
        cli_error("%s: --port and --bus exclude each other", cmd);
        return false;
    }
    if (m->bus != NULL && dfp_lcm_segment_channel(m->bus) == NULL) {
        cli_error("%s: --bus '%s': use lcm:CHANNEL (1..63 of A-Z a-z 0-9 _ . -)", cmd, m->bus);
        return false;
    }
    if (m->lcm_url != NULL && m->bus == NULL) {
        cli_error("%s: --lcm-url belongs to --bus lcm:CHANNEL", cmd);
        return false;
    }
    return true;
}

static const char *medium_name(const medium_opts_t *m)
{
    static char name[sizeof segment.url + sizeof segment.channel + 20];
    if (m->bus == NULL) {
        return m->dev;
    }
    snprintf(name, sizeof name, "LCM segment %s (%s)", dfp_lcm_segment_channel(m->bus),
             segment.url);
    return name;
}

static void session_close(void)
{
    if (on_segment) {
        dfp_lcm_segment_close(&segment);
    } else {
        tty_port_close(&port);
    }
}

/* Opens the port or the segment and the capture, and puts the station on it; the medium's tap
 * feeds the capture (session_tap_to adds --lcm telemetry). Returns false after reporting the
 * reason (nothing left open). */
static bool session_open(const medium_opts_t *m, int16_t station_address, uint32_t baud,
                         const capture_opts_t *capture, const sim_station_t *st)
{
    char err[320];
    on_segment = m->bus != NULL;
    if (on_segment) {
        if (dfp_lcm_segment_open(&segment, m->lcm_url, dfp_lcm_segment_channel(m->bus),
                                 station_address, baud, err, sizeof err) != 0) {
            cli_error("%s", err);
            return false;
        }
    } else if (tty_port_open(&port, m->dev, baud, err, sizeof err) != 0) {
        cli_error("%s", err);
        return false;
    }
    clk.start_ns = mono_ns();
    rep.now_ns = tty_clock_now;
    rep.now_ctx = &clk;
    if (!open_capture(&rep, capture)) {
        session_close();
        return false;
    }
    install_signals();
    tty_runner_init(&runner);
    if (on_segment) {
        dfp_lcm_segment_set_tap(&segment, report_tap, &rep);
        if (dfp_lcm_segment_attach(&segment, &runner, st) != 0) {
            cli_error("LCM segment: cannot wait on LCM's descriptor");
            session_close();
            return false;
        }
    } else {
        tty_runner_set_tap(&runner, report_tap, &rep);
        tty_runner_add(&runner, &port, st);
    }
    return true;
}

/* --lcm URL: the tap also publishes, with the medium's own time origin. */
static void session_tap_to(lcm_cli_t *l)
{
    if (on_segment) {
        l->tap_wall_us = lcm_cli_wall_of_mono(segment.t0_ns);
        dfp_lcm_segment_set_tap(&segment, lcm_cli_tap, l);
    } else {
        l->tap_wall_us = lcm_cli_wall_of_mono(runner.t0_ns);
        tty_runner_set_tap(&runner, lcm_cli_tap, l);
    }
}

static hal_uart_t session_uart(void)
{
    return on_segment ? dfp_lcm_segment_uart(&segment) : tty_port_uart(&port);
}

/* ---- slave ------------------------------------------------------------------------------ */

int cmd_slave(int argc, char **argv)
{
    medium_opts_t med = {0};
    const char *lcm_url = NULL;
    capture_opts_t capture = {.path = NULL};
    int copt;
    uint32_t address = 4;
    uint32_t baud = 0;
    uint32_t duration_s = 0;
    bool echo = false;
    const char *inverter = "sim";
    const char *eeprom = NULL;
    const char *card_nvm = NULL;
    for (int i = 2; i < argc; i++) {
        const char *v;
        int mo = medium_option(&med, argc, argv, &i);
        if (mo != 0) {
            if (mo < 0) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--lcm") == 0) {
            if ((lcm_url = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_u32("--address", v, 0, 127, &address)) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--baud") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_baud("--baud", v, true, &baud))
                return EXIT_USAGE;
        } else if ((copt = capture_option(argc, argv, &i, &capture)) != 0) {
            if (copt < 0) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--duration") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_u32("--duration", v, 1, 86400u * 365u, &duration_s)) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--echo-suppress") == 0) {
            echo = true;
        } else if (strcmp(argv[i], "--inverter") == 0) {
            if ((inverter = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--eeprom") == 0) {
            if ((eeprom = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--card-nvm") == 0) {
            if ((card_nvm = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else {
            cli_error("slave: unknown option '%s' (see dfp-sim --help)", argv[i]);
            return EXIT_USAGE;
        }
    }
    if (med.dev == NULL && med.bus == NULL) {
        cli_error("slave: --port DEV is required (a tty such as /dev/ttyUSB0, or a PTY), or --bus "
                  "lcm:CHANNEL");
        return EXIT_USAGE;
    }
    if (!medium_check(&med, "slave")) {
        return EXIT_USAGE;
    }
    card_inverter_t kind;
    if (strcmp(inverter, "sim") == 0) {
        kind = CARD_INVERTER_SIM;
    } else if (strcmp(inverter, "none") == 0) {
        kind = CARD_INVERTER_NONE;
    } else if (strncmp(inverter, "can:", 4) == 0) {
        kind = CARD_INVERTER_LINK;
    } else {
        cli_error("slave: --inverter '%s': use sim (emulated MOVIDRIVE), none (PI echoes PO) or "
                  "can:IFACE[:ADDR] (a MOVIDRIVE on SBus)", inverter);
        return EXIT_USAGE;
    }
    if (eeprom != NULL && kind != CARD_INVERTER_SIM) {
        cli_error("slave: --eeprom belongs to the emulated inverter (--inverter sim)");
        return EXIT_USAGE;
    }
    sim_station_t st = card_station(&card);
    if (!session_open(&med, (int16_t)address, baud != 0u ? baud : hal_uart_bauds[0], &capture,
                      &st)) {
        return 1;
    }
    port.echo_suppress = echo;
    rep.card = &card.card;
    if (lcm_url != NULL) {
        int64_t wall = lcm_cli_wall_of_mono(clk.start_ns);
        if (lcm_cli_open(&telemetry, lcm_url, &card.card, (uint8_t)address, &rep, wall, wall) !=
            0) {
            session_close();
            report_close_capture(&rep);
            return 1;
        }
        session_tap_to(&telemetry);
    }
    static inverter_can_t can_link;
    char err[256];
    ml_link_t external = {0};
    if (kind == CARD_INVERTER_LINK) {
        if (inverter_can_open(&can_link, inverter, card_station_param_response,
                              card_station_process_inputs, &card, &runner, err,
                              sizeof err) != 0) {
            cli_error("%s", err);
            lcm_cli_close(&telemetry);
            session_close();
            report_close_capture(&rep);
            return 1;
        }
        external = inverter_can_link(&can_link);
    }
    printf("dfp-sim slave: DFP21B on %s, DIP address %u, %s%s%s; inverter: %s%s%s\n",
           medium_name(&med), address, baud != 0u ? "fixed " : "automatic baud rate",
           baud != 0u ? report_baud_text(baud) : "",
           on_segment || port.parity_ok ? "" : " (device has no parity: a PTY)",
           kind == CARD_INVERTER_SIM ? "emulated MOVIDRIVE" : inverter,
           eeprom != NULL ? ", EEPROM " : "", eeprom != NULL ? eeprom : "");
    fflush(stdout);
    card_options_t co = {.address = (uint8_t)address, .fixed_baud = baud,
                         .strict_timing = false, .inverter = kind, .eeprom_path = eeprom,
                         .external_link = external, .card_nvm_path = card_nvm,
                         .event = report_card_event,
                         .led_change = report_led, .ctx = &rep};
    if (telemetry.open) {
        lcm_cli_observe_params(&telemetry, &co);
        tty_runner_add_timer(&runner, lcm_cli_timer, &telemetry);
    }
    if (card_station_init(&card, &co, session_uart(), tty_now_us(), err, sizeof err) != 0) {
        report_line(&rep, "card", "non-volatile storage: %s", err);
    }
    if (address > DFP21B_MAX_ADDRESS) {
        report_line(&rep, "card", "address %u is above 125: the card stays off the bus", address);
    }
    int rc = 0;
    uint64_t end_ns = duration_s != 0u ? mono_ns() + (uint64_t)duration_s * 1000000000ull : 0u;
    while (!stop_requested && (end_ns == 0u || mono_ns() < end_ns)) {
        if (tty_runner_run_until(&runner, tty_now_us() + 200000u, &stop_requested) < 0) {
            cli_error("%s", tty_runner_error(&runner));
            rc = 1;
            break;
        }
    }
    report_line(&rep, "card", "stopping (%s); state %s", stop_requested ? "signal" : "end",
                dp_state_name(dp_slave_state(&card.card.dp)));
    if (kind == CARD_INVERTER_LINK) {
        inverter_can_close(&can_link);
    }
    lcm_cli_close(&telemetry);
    session_close();
    return report_close_capture(&rep) != 0 ? 1 : rc;
}

/* ---- master ----------------------------------------------------------------------------- */

/* "4", "3-34", "3,5,7-9": distinct slave addresses 0..125, at most DPM_MAX_SLAVES. Returns
 * false after reporting. */
static bool parse_addresses(const char *text, uint8_t *out, size_t *n)
{
    bool seen[126] = {false};
    *n = 0;
    const char *p = text;
    for (;;) {
        char *end;
        unsigned long lo = strtoul(p, &end, 10);
        unsigned long hi = lo;
        bool ok = end != p && *p >= '0' && *p <= '9';
        if (ok && *end == '-') {
            const char *q = end + 1;
            hi = strtoul(q, &end, 10);
            ok = end != q && *q >= '0' && *q <= '9';
        }
        if (!ok || (*end != ',' && *end != '\0') || lo > 125u || hi > 125u || hi < lo) {
            cli_error("--address '%s': use addresses 0..125 as N, N-M or a comma list "
                      "(3-34, 3,5,7-9)", text);
            return false;
        }
        for (unsigned long a = lo; a <= hi; a++) {
            if (seen[a]) {
                cli_error("--address '%s': address %lu is given twice", text, a);
                return false;
            }
            if (*n >= DPM_MAX_SLAVES) {
                cli_error("--address '%s': more than %u slaves", text, DPM_MAX_SLAVES);
                return false;
            }
            seen[a] = true;
            out[(*n)++] = (uint8_t)a;
        }
        if (*end == '\0') {
            return true;
        }
        p = end + 1;
    }
}

static bool all_in_data_exchange(void)
{
    for (uint8_t i = 0; i < master.num_slaves; i++) {
        if (master.slaves[i].phase != DPM_PHASE_DATA_EXCH) {
            return false;
        }
    }
    return true;
}

static bool all_cycled(uint32_t cycles)
{
    for (uint8_t i = 0; i < master.num_slaves; i++) {
        if (master.slaves[i].cycles < cycles) {
            return false;
        }
    }
    return true;
}

static uint64_t total_cycles(void)
{
    uint64_t n = 0;
    for (uint8_t i = 0; i < master.num_slaves; i++) {
        n += master.slaves[i].cycles;
    }
    return n;
}

static void report_done(uint64_t t_start_ns, uint64_t t_all_ns, uint64_t cycles_at_all)
{
    if (master.num_slaves == 1u) {
        dpm_slave_t *s = &master.slaves[0];
        char in[3 * DPM_MAX_IO + 1];
        size_t n = 0;
        for (size_t i = 0; i < s->inputs_len; i++) {
            n += (size_t)snprintf(in + n, sizeof in - n, "%02X", s->inputs[i]);
        }
        in[n] = '\0';
        report_line(&rep, "master", "done: slave %u in data exchange, %u cycles, last inputs %s",
                    s->cfg.address, s->cycles, n > 0 ? in : "(none)");
        return;
    }
    uint64_t now = mono_ns();
    double span = (double)(now - t_all_ns) / 1e9;
    uint64_t dx = total_cycles() - cycles_at_all;
    report_line(&rep, "master",
                "done: %u slaves in data exchange, each at least the given cycles; all reached "
                "data exchange %.3f s after start; since then %llu Data_Exchange telegrams in "
                "%.3f s (%.0f/s, %.1f full bus cycles/s)",
                master.num_slaves, (double)(t_all_ns - t_start_ns) / 1e9,
                (unsigned long long)dx, span, span > 0 ? (double)dx / span : 0.0,
                span > 0 ? (double)dx / span / master.num_slaves : 0.0);
}

static void report_missing(uint32_t cycles, const char *why)
{
    if (master.num_slaves == 1u) {
        dpm_slave_t *s = &master.slaves[0];
        cli_error("master: slave %u did not complete %u Data_Exchange cycles (%s; reached %u, "
                  "phase %s)",
                  s->cfg.address, cycles, why, s->cycles, dpm_phase_name(s->phase));
        return;
    }
    char list[1024];
    size_t n = 0;
    unsigned missing = 0;
    for (uint8_t i = 0; i < master.num_slaves; i++) {
        dpm_slave_t *s = &master.slaves[i];
        if (s->cycles >= cycles) {
            continue;
        }
        missing++;
        if (n + 48u < sizeof list) {
            n += (size_t)snprintf(list + n, sizeof list - n, "%s%u (%u, %s)", n > 0 ? ", " : "",
                                  s->cfg.address, s->cycles, dpm_phase_name(s->phase));
        }
    }
    cli_error("master: %u of %u slaves did not complete %u Data_Exchange cycles (%s): %s",
              missing, master.num_slaves, cycles, why, list);
}

int cmd_master(int argc, char **argv)
{
    medium_opts_t med = {0};
    capture_opts_t capture = {.path = NULL};
    int copt;
    const char *addresses = NULL;
    uint32_t own = 2;
    uint32_t baud = 19200;
    uint32_t cycles = 100;
    uint32_t timeout_s = 10;
    uint32_t wd_ms = 1000;
    uint32_t slot_ms = 100;
    uint32_t ident = DFP21B_IDENT;
    uint8_t cfg[DPM_MAX_CFG];
    size_t cfg_len = 0;
    uint8_t user[DPM_MAX_PRM];
    size_t user_len = SIZE_MAX;
    uint8_t outputs[DPM_MAX_IO] = {0};
    size_t out_given = 0;
    bool verbose = false;
    for (int i = 2; i < argc; i++) {
        const char *v;
        const char *o = argv[i];
        int mo = medium_option(&med, argc, argv, &i);
        if (mo != 0) {
            if (mo < 0) return EXIT_USAGE;
        } else if (strcmp(o, "--address") == 0) {
            if ((addresses = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(o, "--master-address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 126, &own))
                return EXIT_USAGE;
        } else if (strcmp(o, "--config") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_hex(o, v, cfg, sizeof cfg, &cfg_len)) return EXIT_USAGE;
        } else if (strcmp(o, "--prm") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_hex(o, v, user, sizeof user - 7u, &user_len)) return EXIT_USAGE;
        } else if (strcmp(o, "--outputs") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL ||
                !cli_hex(o, v, outputs, sizeof outputs, &out_given)) return EXIT_USAGE;
        } else if (strcmp(o, "--ident") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 0xFFFF, &ident))
                return EXIT_USAGE;
        } else if (strcmp(o, "--baud") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_baud(o, v, false, &baud))
                return EXIT_USAGE;
        } else if (strcmp(o, "--cycles") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 1, 100000000u, &cycles))
                return EXIT_USAGE;
        } else if (strcmp(o, "--timeout") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 1, 86400u, &timeout_s))
                return EXIT_USAGE;
        } else if (strcmp(o, "--watchdog") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 650000u, &wd_ms))
                return EXIT_USAGE;
        } else if (strcmp(o, "--slot-time") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 1, 10000u, &slot_ms))
                return EXIT_USAGE;
        } else if ((copt = capture_option(argc, argv, &i, &capture)) != 0) {
            if (copt < 0) return EXIT_USAGE;
        } else if (strcmp(o, "--verbose") == 0) {
            verbose = true;
        } else {
            cli_error("master: unknown option '%s' (see dfp-sim --help)", o);
            return EXIT_USAGE;
        }
    }
    if ((med.dev == NULL && med.bus == NULL) || addresses == NULL || cfg_len == 0u) {
        cli_error("master: --port DEV (or --bus lcm:CHANNEL), --address N and --config HEX are "
                  "required");
        return EXIT_USAGE;
    }
    if (!medium_check(&med, "master")) {
        return EXIT_USAGE;
    }
    uint8_t slave_addr[DPM_MAX_SLAVES];
    size_t num_slaves = 0;
    if (!parse_addresses(addresses, slave_addr, &num_slaves)) {
        return EXIT_USAGE;
    }
    if (user_len == SIZE_MAX) {
        /* Without --prm: the DFP21B's user parameters for its ident, none for others. */
        user_len = ident == DFP21B_IDENT ? sizeof dfp21b_user_prm_default : 0u;
        memcpy(user, dfp21b_user_prm_default, user_len);
    }
    dpm_slave_cfg_t sc = {0};
    sc.prm_len = (uint8_t)dpm_build_prm(sc.prm, (uint16_t)ident, wd_ms, user, user_len);
    memcpy(sc.cfg, cfg, cfg_len);
    sc.cfg_len = (uint8_t)cfg_len;

    sim_station_t st = master_station(&master);
    if (!session_open(&med, (int16_t)own, baud, &capture, &st)) {
        return 1;
    }
    rep.show_inputs = verbose;
    dp_master_cfg_t mc = {.address = (uint8_t)own, .baud = baud, .strict_timing = false,
                          .slot_time_us = slot_ms * 1000u, .uart = session_uart(),
                          .event = report_master_event, .event_ctx = &rep};
    dp_master_init(&master, &mc, tty_now_us());
    for (size_t i = 0; i < num_slaves; i++) {
        sc.address = slave_addr[i];
        if (dp_master_add_slave(&master, &sc) < 0) {
            cli_error("master: configuration %s... cannot be decoded into I/O lengths",
                      "--config");
            session_close();
            return EXIT_USAGE;
        }
        dp_master_set_outputs(&master, (unsigned)i, outputs, out_given);
    }
    printf("dfp-sim master: address %u on %s at %s; %s %s, ident 0x%04X, %zu cfg octets, "
           "%u out / %u in octets\n",
           own, medium_name(&med), report_baud_text(baud), num_slaves == 1u ? "slave" : "slaves",
           addresses, ident, cfg_len, master.slaves[0].out_len, master.slaves[0].in_len);
    fflush(stdout);
    uint64_t t_start = mono_ns();
    uint64_t end_ns = t_start + (uint64_t)timeout_s * 1000000000ull;
    uint64_t t_all = 0;
    uint64_t cycles_at_all = 0;
    int rc = 1;
    const char *why = "timeout";
    while (!stop_requested && mono_ns() < end_ns) {
        if (tty_runner_run_until(&runner, tty_now_us() + 20000u, &stop_requested) < 0) {
            why = tty_runner_error(&runner);
            break;
        }
        if (t_all == 0u && all_in_data_exchange()) {
            t_all = mono_ns();
            cycles_at_all = total_cycles();
            if (num_slaves > 1u) {
                report_line(&rep, "master", "all %zu slaves in data exchange", num_slaves);
            }
        }
        if (all_cycled(cycles)) {
            rc = 0;
            break;
        }
    }
    if (rc == 0) {
        report_done(t_start, t_all != 0u ? t_all : mono_ns(), cycles_at_all);
    } else {
        report_missing(cycles, stop_requested ? "interrupted" : why);
    }
    session_close();
    return report_close_capture(&rep) != 0 ? 1 : rc;
}
