/* dfp-sim inverter: the emulated MOVIDRIVE on SBus (SocketCAN) until SIGINT/SIGTERM.
 *
 * The drive answers parameter requests 8·A+512+3 with responses 8·A+512+4 (and SBus channel 2,
 * 8·A+512+5 -> +7), and every PO frame 8·A+3 with a PI frame 8·A+4 (movilink/sbus.h). Each
 * parameter service and each change of the drive state is printed as one line.
 *
 * SBus timeout: the emulated MOVIDRIVE has no P815/P836 of its own, so this command watches
 * P815 (index 8602, ms; 0 = off) itself: once PO frames have started and then stop for that
 * long, the drive gets the card's fieldbus-timeout signal (movidrive_fieldbus_status with
 * timeout set), i.e. it reacts with P831 instead of P836; the next PO frame clears it. This is
 * what happens when the DFP21B's DP watchdog expires: the card stops sending PO frames. */
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "dp_master/param_channel.h"
#include "movidrive/movidrive.h"
#include "movilink/sbus.h"
#include "sim_hal/file_nvm.h"
#include "sim_hal/socketcan.h"
#include "sim_hal/tty_port.h"

#define IDX_P815_SBUS_TIMEOUT 8602u

static struct {
    movidrive_t md;
    file_nvm_t nvm;
    socketcan_t sock;
    sbus_inverter_t sbus;
    tty_runner_t runner;
    uint64_t t0_ms;
    bool quiet;
    /* last reported state */
    uint16_t status;
    int32_t setpoint;
    uint8_t fault;
    bool reported;
    hal_time_us_t next_speed_report;
    int32_t reported_speed;
    uint32_t services;
    uint32_t service_errors;
} inv;

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static void line(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static void line(const char *fmt, ...)
{
    double t = (double)(mono_ms() - inv.t0_ms) / 1e3;
    printf("%9.3f s  ", t);
    va_list ap;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    fflush(stdout);
}

static void on_param(void *ctx, const uint8_t req[ML_TELEGRAM_LEN], uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    movidrive_param(&inv.md, req, rsp);
    inv.services++;
    uint8_t svc = req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK;
    bool write = svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE;
    char what[96];
    if (write) {
        (void)snprintf(what, sizeof what, "%s %u = %ld", ml_service_name(svc), ml_index(req),
                       (long)(int32_t)ml_data(req));
    } else {
        (void)snprintf(what, sizeof what, "%s %u", ml_service_name(svc), ml_index(req));
    }
    if ((rsp[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        char err[96];
        (void)ml_error_text(rsp, err, sizeof err);
        inv.service_errors++;
        line("param  %s -> error: %s", what, err);
    } else if (write) {
        line("param  %s -> ok", what);
    } else {
        line("param  %s -> 0x%08lX (%ld)", what, (unsigned long)ml_data(rsp),
             (long)(int32_t)ml_data(rsp));
    }
}

static void on_po(void *ctx, const uint16_t *po, uint8_t n)
{
    (void)ctx;
    movidrive_process_outputs(&inv.md, po, n);
}

static void on_pi(void *ctx, uint16_t *pi, uint8_t n)
{
    (void)ctx;
    movidrive_process_inputs(&inv.md, pi, n);
}

static void on_sbus_timeout(void *ctx, bool active)
{
    (void)ctx;
    ml_fieldbus_status_t st = inv.md.fieldbus;
    st.timeout = active;
    st.data_exchange = !active;
    movidrive_fieldbus_status(&inv.md, &st);
    if (active) {
        line("state  SBus timeout: no PO frame for %lu ms (P815); the drive reacts as to a "
             "fieldbus timeout (P831)", (unsigned long)(inv.sbus.cfg.timeout_us / 1000u));
    } else {
        line("state  PO frames again: SBus timeout over");
    }
}

static void on_rx(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    sbus_inverter_rx(&inv.sbus, f, tty_now_us());
}

static void report_state(hal_time_us_t now)
{
    uint16_t sw = movidrive_status_word(&inv.md);
    if (!inv.reported || sw != inv.status || inv.md.fault != inv.fault) {
        char fault[32] = "";
        if (inv.md.fault != 0u) {
            (void)snprintf(fault, sizeof fault, ", fault F%02u", inv.md.fault);
        }
        line("state  status word 0x%04X: %s%s%s%s, unit status %u%s", sw,
             (sw & MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED) ? "output stage enabled" : "output stage off",
             (sw & MOVIDRIVE_SW_READY) ? ", ready" : "",
             (sw & MOVIDRIVE_SW_PO_DATA_ENABLED) ? ", PO data enabled" : "",
             (sw & MOVIDRIVE_SW_FAULT) ? ", fault/warning" : "", (unsigned)(sw >> 8), fault);
        inv.status = sw;
        inv.fault = inv.md.fault;
    }
    if (!inv.reported || inv.md.speed_setpoint_mrpm != inv.setpoint) {
        line("state  speed setpoint %.1f rpm", inv.md.speed_setpoint_mrpm / 1000.0);
        inv.setpoint = inv.md.speed_setpoint_mrpm;
    }
    /* The actual speed while it changes, at most twice a second. */
    if (inv.md.speed_actual_mrpm != inv.reported_speed && hal_time_reached(now, inv.next_speed_report)) {
        line("state  speed %.1f rpm", inv.md.speed_actual_mrpm / 1000.0);
        inv.reported_speed = inv.md.speed_actual_mrpm;
        inv.next_speed_report = now + 500000u;
    }
    inv.reported = true;
}

static hal_time_us_t on_timer(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    int32_t p815 = 0;
    if (movidrive_read_value(&inv.md, IDX_P815_SBUS_TIMEOUT, &p815)) {
        inv.sbus.cfg.timeout_us = (p815 > 0 && p815 < 650000) ? (uint32_t)p815 * 1000u : 0u;
    }
    hal_time_us_t next = movidrive_tick(&inv.md, now);
    hal_time_us_t t = sbus_inverter_poll(&inv.sbus, now);
    next = hal_time_earlier(next, t);
    if (!inv.quiet) {
        report_state(now);
    }
    /* Ramps are integrated in ticks: at least every 10 ms while the drive moves. */
    if (inv.md.speed_actual_mrpm != inv.md.speed_setpoint_mrpm && hal_time_diff(next, now + 10000u) > 0) {
        next = now + 10000u;
    }
    return next;
}

typedef struct inverter_opts {
    const char *ifname;
    const char *eeprom;
    uint32_t address;
    uint32_t duration_s;
    bool channel2;
    bool quiet;
} inverter_opts_t;

/* --eeprom FILE, refused at once when it can be no EEPROM file. */
static bool set_eeprom(void *base, const cli_opt_t *opt, const char *value, cli_args_t *args)
{
    (void)opt;
    (void)args;
    inverter_opts_t *o = base;
    o->eeprom = value;
    char why[300];
    int rc = file_nvm_check_path(o->eeprom, why, sizeof why);
    if (rc != 0) {
        cli_error("inverter: --eeprom %s: refused%s", why,
                  rc == FILE_NVM_NOT_FILE ? " (give a regular file, or a path where "
                                            "one can be created)" : "");
        return false;
    }
    return true;
}

#define INVERTER(field) offsetof(inverter_opts_t, field)

static const cli_opt_t inverter_options[] = {
    {CLI_OPT("--can", "IFACE", CLI_TEXT, INVERTER(ifname))},
    {CLI_OPT("--sbus-address", "N", CLI_U32, INVERTER(address)),
     .min = 0, .max = SBUS_MAX_ADDRESS},
    {CLI_OPT("--eeprom", "FILE", CLI_CALL, 0), .set = set_eeprom},
    {CLI_OPT("--duration", "S", CLI_U32, INVERTER(duration_s)), .min = 1, .max = 86400u * 365u},
    {CLI_OPT("--channel2", NULL, CLI_FLAG, INVERTER(channel2))},
    {CLI_OPT("--quiet", NULL, CLI_FLAG, INVERTER(quiet))},
};

static const cli_group_t inverter_groups[] = {
    {inverter_options, CLI_COUNT(inverter_options), 0},
};

const cli_command_t cli_inverter = {.name = "inverter", .groups = inverter_groups,
                                    .n_groups = CLI_COUNT(inverter_groups)};

/* The command line into o (and --quiet into inv): 0, or EXIT_USAGE after reporting. */
static int inverter_parse(inverter_opts_t *o, int argc, char **argv)
{
    *o = (inverter_opts_t){.ifname = NULL};
    if (cli_parse(&cli_inverter, argc, argv, o) != 0) {
        return EXIT_USAGE;
    }
    inv.quiet = o->quiet;
    if (o->ifname == NULL) {
        cli_error("inverter: --can IFACE is required (a SocketCAN interface such as can0 or vcan0)");
        return EXIT_USAGE;
    }
    return 0;
}

/* The emulated drive with its EEPROM; problems with either are reported, not fatal, but for a
 * file another process took since the command line was checked: EXIT_USAGE, as that check. */
static int drive_init(const inverter_opts_t *o)
{
    char err[256] = "";
    movidrive_cfg_t cfg = {.sbus_address = (uint8_t)o->address, .terminal_enable = true};
    if (o->eeprom != NULL) {
        /* A missing file is a blank EEPROM; a damaged one is reported and replaced by the
         * previous generation or the factory settings (file_nvm.h). */
        if (file_nvm_open(&inv.nvm, o->eeprom, movidrive_eeprom_size(), err, sizeof err) != 0) {
            (void)fprintf(stderr, "dfp-sim inverter: %s\n", err); /* err names the file */
        }
        if (inv.nvm.loaded == FILE_NVM_IMAGE_IN_USE) {
            return EXIT_USAGE;
        }
        cfg.eeprom = file_nvm_hal(&inv.nvm);
    }
    if (movidrive_init(&inv.md, &cfg, err, sizeof err) != 0) {
        (void)fprintf(stderr, "dfp-sim inverter: %s (factory settings in use)\n", err);
    }
    return 0;
}

/* The SBus side on the interface, in the runner. Returns 0, or 1 after reporting. */
static int sbus_open(const inverter_opts_t *o)
{
    char err[256] = "";
    if (socketcan_open(&inv.sock, o->ifname, on_rx, NULL, err, sizeof err) != 0) {
        cli_error("%s", err);
        return 1;
    }
    sbus_inverter_cfg_t sc = {
        .can = socketcan_can(&inv.sock), .address = (uint8_t)o->address,
        .channel2 = o->channel2, .param = on_param, .process_outputs = on_po,
        .process_inputs = on_pi, .timeout = on_sbus_timeout,
    };
    sbus_inverter_init(&inv.sbus, &sc);
    tty_runner_init(&inv.runner);
    if (socketcan_attach(&inv.sock, &inv.runner) != 0 ||
        tty_runner_add_timer(&inv.runner, on_timer, NULL) != 0) {
        cli_error("inverter: cannot wait on %s", o->ifname);
        socketcan_close(&inv.sock);
        return 1;
    }
    return 0;
}

/* Until SIGINT/SIGTERM or --duration: 0, or 1 when the interface failed. */
static int inverter_run(uint32_t duration_s)
{
    /* The duration on a 64-bit clock: hal_time_us_t wraps after 71 minutes. */
    uint64_t end_ms = mono_ms() + (uint64_t)duration_s * 1000u;
    while (!cli_stop && (duration_s == 0u || mono_ms() < end_ms)) {
        hal_time_us_t until = tty_now_us() + 200000u;
        if (duration_s != 0u && end_ms - mono_ms() < 200u) {
            until = tty_now_us() + (hal_time_us_t)((end_ms - mono_ms()) * 1000u);
        }
        if (tty_runner_run_until(&inv.runner, until, &cli_stop) < 0) {
            cli_error("%s", tty_runner_error(&inv.runner));
            return 1;
        }
    }
    return 0;
}

int cmd_inverter(int argc, char **argv)
{
    inverter_opts_t o;
    int rc = inverter_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    (void)setvbuf(stdout, NULL, _IOLBF, 0);
    if (drive_init(&o) != 0) {
        return EXIT_USAGE;
    }
    if (sbus_open(&o) != 0) {
        return 1;
    }
    cli_catch_stop_signals();

    uint8_t a = (uint8_t)o.address;
    inv.t0_ms = mono_ms();
    inv.next_speed_report = tty_now_us(); /* not 0: on the wall clock 0 may lie in the future */
    printf("dfp-sim inverter: emulated MOVIDRIVE at SBus address %u on %s: PO %u -> PI %u, "
           "parameters %u -> %u%s; EEPROM %s\n",
           a, o.ifname, sbus_id_po(a), sbus_id_pi(a), sbus_id_param_req(a), sbus_id_param_rsp(a),
           o.channel2 ? " and channel 2" : "", o.eeprom != NULL ? o.eeprom : "none (RAM only)");
    rc = inverter_run(o.duration_s);
    line("stopping (%s): %lu parameter services (%lu refused), %lu PO frames, %lu frames "
         "received, %lu send errors", cli_stop ? "signal" : rc != 0 ? "error" : "end",
         (unsigned long)inv.services, (unsigned long)inv.service_errors,
         (unsigned long)inv.sbus.po_frames, (unsigned long)inv.sock.frames_received,
         (unsigned long)(inv.sock.send_errors + inv.sbus.send_errors));
    socketcan_close(&inv.sock);
    return rc;
}
