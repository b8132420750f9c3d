/* dfp-sim slave / master: the card or the built-in master on a real tty or a PTY, in wall-clock
 * time. Timing on a PC is relaxed (see fdl_rx.h): the OS delivers bytes in chunks. */
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
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

/* ---- one station on one tty ------------------------------------------------------------ */

static card_station_t card;
static tty_port_t port;
static tty_runner_t runner;
static dp_master_t master;
static report_t rep;
static tty_clock_t clk;

/* Opens the port and the capture, and puts the station on the port. Returns false after
 * reporting the reason (nothing left open). */
static bool session_open(const char *dev, uint32_t baud, const capture_opts_t *capture,
                         const sim_station_t *st)
{
    char err[256];
    if (tty_port_open(&port, dev, baud, err, sizeof err) != 0) {
        cli_error("%s", err);
        return false;
    }
    clk.start_ns = mono_ns();
    rep.now_ns = tty_clock_now;
    rep.now_ctx = &clk;
    if (!open_capture(&rep, capture)) {
        tty_port_close(&port);
        return false;
    }
    install_signals();
    tty_runner_init(&runner);
    tty_runner_set_tap(&runner, report_tap, &rep);
    tty_runner_add(&runner, &port, st);
    return true;
}

/* ---- slave ------------------------------------------------------------------------------ */

int cmd_slave(int argc, char **argv)
{
    const char *dev = NULL;
    capture_opts_t capture = {.path = NULL};
    uint32_t address = 4;
    uint32_t baud = 0;
    uint32_t duration_s = 0;
    bool echo = false;
    const char *inverter = "sim";
    const char *eeprom = NULL;
    const char *card_nvm = NULL;
    int copt;
    for (int i = 2; i < argc; i++) {
        const char *v;
        if (strcmp(argv[i], "--port") == 0) {
            if ((dev = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
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
    if (dev == NULL) {
        cli_error("slave: --port DEV is required (a tty such as /dev/ttyUSB0, or a PTY)");
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
    if (!session_open(dev, baud != 0u ? baud : hal_uart_bauds[0], &capture, &st)) {
        return 1;
    }
    port.echo_suppress = echo;
    rep.card = &card.card;
    static inverter_can_t can_link;
    char err[256];
    ml_link_t external = {0};
    if (kind == CARD_INVERTER_LINK) {
        if (inverter_can_open(&can_link, inverter, card_station_param_response,
                              card_station_process_inputs, &card, &runner, err,
                              sizeof err) != 0) {
            cli_error("%s", err);
            tty_port_close(&port);
            report_close_capture(&rep);
            return 1;
        }
        external = inverter_can_link(&can_link);
    }
    printf("dfp-sim slave: DFP21B on %s, DIP address %u, %s%s%s; inverter: %s%s%s\n", dev,
           address, baud != 0u ? "fixed " : "automatic baud rate",
           baud != 0u ? report_baud_text(baud) : "",
           port.parity_ok ? "" : " (device has no parity: a PTY)",
           kind == CARD_INVERTER_SIM ? "emulated MOVIDRIVE" : inverter,
           eeprom != NULL ? ", EEPROM " : "", eeprom != NULL ? eeprom : "");
    fflush(stdout);
    card_options_t co = {.address = (uint8_t)address, .fixed_baud = baud,
                         .strict_timing = false, .inverter = kind, .eeprom_path = eeprom,
                         .external_link = external, .card_nvm_path = card_nvm,
                         .event = report_card_event,
                         .led_change = report_led, .ctx = &rep};
    if (card_station_init(&card, &co, tty_port_uart(&port), tty_now_us(), err, sizeof err) != 0) {
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
    tty_port_close(&port);
    return report_close_capture(&rep) != 0 ? 1 : rc;
}

/* ---- master ----------------------------------------------------------------------------- */

int cmd_master(int argc, char **argv)
{
    const char *dev = NULL;
    capture_opts_t capture = {.path = NULL};
    uint32_t address = 0;
    bool have_address = false;
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
    int copt;
    for (int i = 2; i < argc; i++) {
        const char *v;
        const char *o = argv[i];
        if (strcmp(o, "--port") == 0) {
            if ((dev = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(o, "--address") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 125, &address))
                return EXIT_USAGE;
            have_address = true;
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
    if (dev == NULL || !have_address || cfg_len == 0u) {
        cli_error("master: --port DEV, --address N and --config HEX are required");
        return EXIT_USAGE;
    }
    if (user_len == SIZE_MAX) {
        /* Without --prm: the DFP21B's user parameters for its ident, none for others. */
        user_len = ident == DFP21B_IDENT ? sizeof dfp21b_user_prm_default : 0u;
        memcpy(user, dfp21b_user_prm_default, user_len);
    }
    dpm_slave_cfg_t sc = {.address = (uint8_t)address};
    sc.prm_len = (uint8_t)dpm_build_prm(sc.prm, (uint16_t)ident, wd_ms, user, user_len);
    memcpy(sc.cfg, cfg, cfg_len);
    sc.cfg_len = (uint8_t)cfg_len;

    sim_station_t st = master_station(&master);
    if (!session_open(dev, baud, &capture, &st)) {
        return 1;
    }
    rep.show_inputs = verbose;
    dp_master_cfg_t mc = {.address = (uint8_t)own, .baud = baud, .strict_timing = false,
                          .slot_time_us = slot_ms * 1000u, .uart = tty_port_uart(&port),
                          .event = report_master_event, .event_ctx = &rep};
    dp_master_init(&master, &mc, tty_now_us());
    if (dp_master_add_slave(&master, &sc) < 0) {
        cli_error("master: configuration %s... cannot be decoded into I/O lengths", "--config");
        tty_port_close(&port);
        return EXIT_USAGE;
    }
    dp_master_set_outputs(&master, 0, outputs, out_given);
    printf("dfp-sim master: address %u on %s at %s; slave %u, ident 0x%04X, %zu cfg octets, "
           "%u out / %u in octets\n",
           own, dev, report_baud_text(baud), address, ident, cfg_len, master.slaves[0].out_len,
           master.slaves[0].in_len);
    fflush(stdout);
    uint64_t end_ns = mono_ns() + (uint64_t)timeout_s * 1000000000ull;
    int rc = 1;
    const char *why = "timeout";
    while (!stop_requested && mono_ns() < end_ns) {
        if (tty_runner_run_until(&runner, tty_now_us() + 20000u, &stop_requested) < 0) {
            why = tty_runner_error(&runner);
            break;
        }
        if (master.slaves[0].cycles >= cycles) {
            rc = 0;
            break;
        }
    }
    dpm_slave_t *s = &master.slaves[0];
    if (rc == 0) {
        char in[3 * DPM_MAX_IO + 1];
        size_t n = 0;
        for (size_t i = 0; i < s->inputs_len; i++) {
            n += (size_t)snprintf(in + n, sizeof in - n, "%02X", s->inputs[i]);
        }
        in[n] = '\0';
        report_line(&rep, "master", "done: slave %u in data exchange, %u cycles, last inputs %s",
                    address, s->cycles, n > 0 ? in : "(none)");
    } else {
        cli_error("master: slave %u did not complete %u Data_Exchange cycles (%s; reached %u, "
                  "phase %s)",
                  address, cycles, stop_requested ? "interrupted" : why, s->cycles,
                  dpm_phase_name(s->phase));
    }
    tty_port_close(&port);
    return report_close_capture(&rep) != 0 ? 1 : rc;
}
