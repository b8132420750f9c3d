/* dfp-sim slave / master: the card or the built-in master on a real tty or a PTY, or on a
 * virtual segment over LCM (--bus lcm:CHANNEL), in wall-clock time. Timing on a PC is relaxed
 * (see fdl_rx.h): the OS delivers bytes in chunks. */
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
#include "instrument.h"
#include "rig/rig.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"
#include <sys/stat.h>
#include "sim_hal/host_clock.h"

static bool open_capture(report_t *rep, const capture_opts_t *capture)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    rep->capture_direction = true;
    return report_open_capture(rep, capture,
                               (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec);
}

/* ---- the rig on one tty, or on an LCM segment ---------------------------------------------- */

static rig_t rig;
static instrument_t in;
static report_t rep;
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
    static char name[sizeof rig.segment.url + sizeof rig.segment.channel + 20];
    if (m->bus == NULL) {
        return m->dev;
    }
    snprintf(name, sizeof name, "LCM segment %s (%s)", dfp_lcm_segment_channel(m->bus),
             rig.segment.url);
    return name;
}

static void session_close(void)
{
    instrument_stop(&in);
    rig_close(&rig);
}

/* Telegrams go to the capture, or through the LCM telemetry, which writes the capture first. */
static void session_frame(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                          uint32_t baud)
{
    (void)ctx;
    if (telemetry.open) {
        lcm_cli_tap(&telemetry, t_ns, frame, len, local, baud);
    } else {
        report_tap(&rep, t_ns, frame, len, local, baud);
    }
}

static void session_param(void *ctx, unsigned card, uint8_t channel,
                          const uint8_t req[ML_TELEGRAM_LEN], const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    (void)card;
    if (telemetry.open) {
        dfp_lcm_bridge_param_observer(&telemetry.bridge, channel, req, rsp);
    }
}

static uint64_t session_now_ns(void *ctx)
{
    (void)ctx;
    return rig_elapsed_ns(&rig);
}

/* Builds the rig on the port or the segment with the log, capture and telemetry taps. Returns
 * false after reporting the reason (nothing left open). */
static bool session_open(const medium_opts_t *m, int16_t station_address, uint32_t baud,
                         const capture_opts_t *capture, const instrument_opts_t *io, bool echo)
{
    char err[320];
    rig_cfg_t rc = {.medium = m->bus != NULL ? RIG_MEDIUM_LCM : RIG_MEDIUM_TTY,
                    .device = m->dev,
                    .lcm_channel = m->bus != NULL ? dfp_lcm_segment_channel(m->bus) : NULL,
                    .lcm_url = m->lcm_url,
                    .lcm_station_address = station_address,
                    .baud = baud,
                    .echo_suppress = echo};
    rig_init(&rig, &rc);
    instrument_attach_log(&in, &rig, io);
    rig_tap_t taps = {.frame = session_frame, .param = session_param};
    rig_add_tap(&rig, &taps);
    if (rig_open(&rig, err, sizeof err) != 0) {
        cli_error("%s", err);
        return false;
    }
    rep.now_ns = session_now_ns;
    if (!open_capture(&rep, capture)) {
        session_close();
        return false;
    }
    cli_catch_stop_signals();
    return true;
}

/* --lcm URL: the telemetry, with the medium's own time origin. */
static int session_telemetry(const char *url, const dfp21b_t *card, uint8_t address)
{
    int64_t wall = lcm_cli_wall_of_mono(rig.cfg.medium == RIG_MEDIUM_LCM ? rig.segment.t0_ns
                                                                         : rig.runner.t0_ns);
    if (lcm_cli_open(&telemetry, url, card, address, &rep, wall, wall) != 0) {
        return -1;
    }
    rig_add_timer(&rig, lcm_cli_timer, &telemetry);
    return 0;
}

/* ---- slave ------------------------------------------------------------------------------ */

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

/* Several cards (--address 4-9) keep their drives' EEPROMs and their own NVM in a directory. */
static const char *per_card_path(const char *dir, const char *stem, uint8_t address, char *buf,
                                 size_t n)
{
    if (dir == NULL) {
        return NULL;
    }
    snprintf(buf, n, "%s/%s%u.%s", dir, stem, address, strcmp(stem, "drive") == 0 ? "ee" : "nvm");
    return buf;
}

static bool is_directory(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

int cmd_slave(int argc, char **argv)
{
    medium_opts_t med = {0};
    const char *lcm_url = NULL;
    capture_opts_t capture = {.path = NULL};
    instrument_opts_t io;
    instrument_defaults(&io, RIG_LOG_TIME_BUS);
    int copt;
    const char *address_text = "4";
    uint32_t baud = 0;
    uint32_t duration_s = 0;
    bool echo = false;
    const char *inverter = "sim";
    const char *eeprom = NULL;
    const char *card_nvm = NULL;
    for (int i = 2; i < argc; i++) {
        const char *v;
        int mo = medium_option(&med, argc, argv, &i);
        if (mo == 0) {
            mo = instrument_option(argc, argv, &i, &io);
        }
        if (mo != 0) {
            if (mo < 0) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--lcm") == 0) {
            if ((lcm_url = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
        } else if (strcmp(argv[i], "--address") == 0) {
            if ((address_text = cli_value(argc, argv, &i)) == NULL) return EXIT_USAGE;
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
    /* One address (0..127, above 125 the card stays off the bus) or a line of cards. */
    uint8_t addresses[DPM_MAX_SLAVES];
    size_t num_cards = 1;
    uint32_t single = 0;
    bool is_list = strpbrk(address_text, "-,") != NULL;
    if (is_list) {
        if (!parse_addresses(address_text, addresses, &num_cards)) return EXIT_USAGE;
    } else {
        if (!cli_u32("--address", address_text, 0, 127, &single)) return EXIT_USAGE;
        addresses[0] = (uint8_t)single;
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
    if (num_cards > 1u) {
        if (kind == CARD_INVERTER_LINK) {
            cli_error("slave: a line of cards (--address %s) needs emulated drives, not SBus",
                      address_text);
            return EXIT_USAGE;
        }
        const char *dirs[2] = {eeprom, card_nvm};
        for (unsigned k = 0; k < 2u; k++) {
            if (dirs[k] != NULL && !is_directory(dirs[k])) {
                cli_error("slave: with several addresses, %s names a directory (one file per "
                          "card in it): '%s' is not one", k == 0u ? "--eeprom" : "--card-nvm",
                          dirs[k]);
                return EXIT_USAGE;
            }
        }
    }
    int16_t station = -1; /* several cards: no single station address on an LCM segment */
    if (num_cards == 1u) {
        station = (int16_t)addresses[0];
    }
    if (!session_open(&med, station, baud != 0u ? baud : hal_uart_bauds[0], &capture, &io,
                      echo)) {
        return 1;
    }
    card_station_t *first = &rig.cards[0].cs;
    rep.card = &first->card;
    if (lcm_url != NULL && session_telemetry(lcm_url, &first->card, addresses[0]) != 0) {
        session_close();
        report_close_capture(&rep);
        return 1;
    }
    static inverter_can_t can_link;
    ml_link_t external = {0};
    if (kind == CARD_INVERTER_LINK) {
        char err[256];
        if (inverter_can_open(&can_link, inverter, card_station_param_response,
                              card_station_process_inputs, first, &rig.runner, err,
                              sizeof err) != 0) {
            cli_error("%s", err);
            lcm_cli_close(&telemetry);
            session_close();
            report_close_capture(&rep);
            return 1;
        }
        external = inverter_can_link(&can_link);
    }
    printf("dfp-sim slave: DFP21B on %s, DIP address %s, %s%s%s; inverter: %s%s%s\n",
           medium_name(&med), address_text, baud != 0u ? "fixed " : "automatic baud rate",
           baud != 0u ? report_baud_text(baud) : "",
           med.bus != NULL || rig.port.parity_ok ? "" : " (device has no parity: a PTY)",
           kind == CARD_INVERTER_SIM ? "emulated MOVIDRIVE" : inverter,
           eeprom != NULL ? ", EEPROM " : "", eeprom != NULL ? eeprom : "");
    fflush(stdout);
    for (size_t k = 0; k < num_cards; k++) {
        char ee_buf[512];
        char nvm_buf[512];
        card_options_t co = {.address = addresses[k], .fixed_baud = baud,
                             .strict_timing = false, .inverter = kind,
                             .eeprom_path = num_cards > 1u ? per_card_path(eeprom, "drive",
                                            addresses[k], ee_buf, sizeof ee_buf) : eeprom,
                             .external_link = external,
                             .card_nvm_path = num_cards > 1u ? per_card_path(card_nvm, "card",
                                            addresses[k], nvm_buf, sizeof nvm_buf) : card_nvm};
        rig_card_t *rc = rig_add_card(&rig, &co, tty_now_us());
        if (rc == NULL) {
            cli_error("slave: cannot add card %u", addresses[k]);
            session_close();
            return 1;
        }
        if (rc->nvm_note[0] != '\0') {
            rig_log(&in.log, RIG_LOG_WARN, num_cards > 1u ? "card *" : "card", "nvm",
                    "non-volatile storage: %s", rc->nvm_note);
        }
        if (addresses[k] > DFP21B_MAX_ADDRESS) {
            rig_log(&in.log, RIG_LOG_WARN, "card", "dp_state",
                    "address %u is above 125: the card stays off the bus", addresses[k]);
        }
    }
    int rc = instrument_start_http(&in, &rig, &io, "slave", false);
    if (rc != 0) {
        session_close();
        report_close_capture(&rep);
        return rc;
    }
    uint64_t end_ns = duration_s != 0u ? host_clock_mono_ns() + (uint64_t)duration_s * 1000000000ull : 0u;
    while (!cli_stop && (end_ns == 0u || host_clock_mono_ns() < end_ns)) {
        if (rig_run_until(&rig, tty_now_us() + 200000u, &cli_stop) < 0) {
            cli_error("%s", rig_error(&rig));
            rc = 1;
            break;
        }
    }
    for (size_t k = 0; k < num_cards; k++) {
        rig_log(&in.log, RIG_LOG_INFO, num_cards > 1u ? "sim" : "card", "dp_state",
                "stopping (%s); card %u state %s", cli_stop ? "signal" : "end",
                rig.cards[k].cs.card.address,
                dp_state_name(dp_slave_state(&rig.cards[k].cs.card.dp)));
    }
    if (kind == CARD_INVERTER_LINK) {
        inverter_can_close(&can_link);
    }
    lcm_cli_close(&telemetry);
    session_close();
    return report_close_capture(&rep) != 0 ? 1 : rc;
}

/* ---- master ----------------------------------------------------------------------------- */

static bool all_in_data_exchange(void)
{
    for (uint8_t i = 0; i < rig.master.num_slaves; i++) {
        if (rig.master.slaves[i].phase != DPM_PHASE_DATA_EXCH) {
            return false;
        }
    }
    return true;
}

static bool all_cycled(uint32_t cycles)
{
    for (uint8_t i = 0; i < rig.master.num_slaves; i++) {
        if (rig.master.slaves[i].cycles < cycles) {
            return false;
        }
    }
    return true;
}

static uint64_t total_cycles(void)
{
    uint64_t n = 0;
    for (uint8_t i = 0; i < rig.master.num_slaves; i++) {
        n += rig.master.slaves[i].cycles;
    }
    return n;
}

static void report_done(uint64_t t_start_ns, uint64_t t_all_ns, uint64_t cycles_at_all)
{
    if (rig.master.num_slaves == 1u) {
        dpm_slave_t *s = &rig.master.slaves[0];
        char hex[3 * DPM_MAX_IO + 1];
        size_t n = 0;
        for (size_t i = 0; i < s->inputs_len; i++) {
            n += (size_t)snprintf(hex + n, sizeof hex - n, "%02X", s->inputs[i]);
        }
        hex[n] = '\0';
        rig_log(&in.log, RIG_LOG_INFO, "master", "master",
                "done: slave %u in data exchange, %u cycles, last inputs %s", s->cfg.address,
                s->cycles, n > 0 ? hex : "(none)");
        return;
    }
    uint64_t now = host_clock_mono_ns();
    double span = (double)(now - t_all_ns) / 1e9;
    uint64_t dx = total_cycles() - cycles_at_all;
    rig_log(&in.log, RIG_LOG_INFO, "master", "master",
                "done: %u slaves in data exchange, each at least the given cycles; all reached "
                "data exchange %.3f s after start; since then %llu Data_Exchange telegrams in "
                "%.3f s (%.0f/s, %.1f full bus cycles/s)",
                rig.master.num_slaves, (double)(t_all_ns - t_start_ns) / 1e9,
                (unsigned long long)dx, span, span > 0 ? (double)dx / span : 0.0,
                span > 0 ? (double)dx / span / rig.master.num_slaves : 0.0);
}

static void report_missing(uint32_t cycles, const char *why)
{
    if (rig.master.num_slaves == 1u) {
        dpm_slave_t *s = &rig.master.slaves[0];
        cli_error("master: slave %u did not complete %u Data_Exchange cycles (%s; reached %u, "
                  "phase %s)",
                  s->cfg.address, cycles, why, s->cycles, dpm_phase_name(s->phase));
        return;
    }
    char list[1024];
    size_t n = 0;
    unsigned missing = 0;
    for (uint8_t i = 0; i < rig.master.num_slaves; i++) {
        dpm_slave_t *s = &rig.master.slaves[i];
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
              missing, rig.master.num_slaves, cycles, why, list);
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
    bool timeout_given = false;
    instrument_opts_t io;
    instrument_defaults(&io, RIG_LOG_TIME_BUS);
    for (int i = 2; i < argc; i++) {
        const char *v;
        const char *o = argv[i];
        int mo = medium_option(&med, argc, argv, &i);
        if (mo == 0) {
            mo = instrument_option(argc, argv, &i, &io);
        }
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
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 0, 100000000u, &cycles))
                return EXIT_USAGE;
        } else if (strcmp(o, "--timeout") == 0) {
            if ((v = cli_value(argc, argv, &i)) == NULL || !cli_u32(o, v, 1, 86400u, &timeout_s))
                return EXIT_USAGE;
            timeout_given = true;
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

    if (!session_open(&med, (int16_t)own, baud, &capture, &io, false)) {
        return 1;
    }
    in.log.show_inputs = verbose;
    dp_master_cfg_t mc = {.address = (uint8_t)own, .baud = baud, .strict_timing = false,
                          .slot_time_us = slot_ms * 1000u};
    dp_master_t *master = rig_add_master(&rig, &mc, tty_now_us());
    for (size_t i = 0; master != NULL && i < num_slaves; i++) {
        sc.address = slave_addr[i];
        if (dp_master_add_slave(master, &sc) < 0) {
            cli_error("master: configuration %s... cannot be decoded into I/O lengths",
                      "--config");
            session_close();
            return EXIT_USAGE;
        }
        dp_master_set_outputs(master, (unsigned)i, outputs, out_given);
    }
    printf("dfp-sim master: address %u on %s at %s; %s %s, ident 0x%04X, %zu cfg octets, "
           "%u out / %u in octets%s\n",
           own, medium_name(&med), report_baud_text(baud), num_slaves == 1u ? "slave" : "slaves",
           addresses, ident, cfg_len, rig.master.slaves[0].out_len, rig.master.slaves[0].in_len,
           cycles == 0u ? "; runs until stopped" : "");
    fflush(stdout);
    int rc = instrument_start_http(&in, &rig, &io, "master", false);
    if (rc != 0) {
        session_close();
        report_close_capture(&rep);
        return rc;
    }
    uint64_t t_start = host_clock_mono_ns();
    uint64_t end_ns = timeout_given || cycles != 0u
                          ? t_start + (uint64_t)timeout_s * 1000000000ull
                          : UINT64_MAX;
    uint64_t t_all = 0;
    uint64_t cycles_at_all = 0;
    rc = 1;
    const char *why = "timeout";
    while (!cli_stop && host_clock_mono_ns() < end_ns) {
        if (rig_run_until(&rig, tty_now_us() + 20000u, &cli_stop) < 0) {
            why = rig_error(&rig);
            break;
        }
        if (t_all == 0u && all_in_data_exchange()) {
            t_all = host_clock_mono_ns();
            cycles_at_all = total_cycles();
            if (num_slaves > 1u) {
                rig_log(&in.log, RIG_LOG_INFO, "master", "master", "all %zu slaves in data "
                        "exchange", num_slaves);
            }
        }
        if (cycles != 0u && all_cycled(cycles)) {
            rc = 0;
            break;
        }
    }
    if (cycles == 0u && cli_stop) {
        rig_log(&in.log, RIG_LOG_INFO, "master", "master", "stopping (signal)");
        rc = 0;
        session_close();
        return report_close_capture(&rep) != 0 ? 1 : rc;
    }
    if (rc == 0) {
        report_done(t_start, t_all != 0u ? t_all : host_clock_mono_ns(), cycles_at_all);
    } else {
        report_missing(cycles, cli_stop ? "interrupted" : why);
    }
    session_close();
    return report_close_capture(&rep) != 0 ? 1 : rc;
}
