/* dfp-sim demo: the card, its emulated MOVIDRIVE and a DP master on the in-memory bus, told as
 * a timeline: start-up, commissioning through the parameter channel as the manual's §4.3 does it,
 * a drive that ramps up, a fieldbus timeout and its fault reset, a wrong configuration. Everything
 * runs in simulated time, so the run takes milliseconds and is the same every time. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "commands.h"
#include "dp_master/param_channel.h"
#include "instrument.h"
#include "lcm_cli.h"
#include "report.h"
#include "rig/rig.h"

#define DEMO_ADDRESS 4u
#define DEMO_MASTER 2u
#define DEMO_BAUD 1500000u
#define DEMO_WATCHDOG_MS 100u
#define DEMO_INVERTER_DELAY_US 3000u /* each parameter service takes a few bus cycles */

typedef struct demo {
    rig_t rig;
    card_station_t *card;
    dp_master_t *master;
    instrument_t in;
    report_t rep; /* --capture */
    uint8_t out[14]; /* parameter channel + PO1..PO3 */
    dp_master_param_t param;
    bool ok;
    lcm_cli_t lcm; /* --lcm URL */
    bool paced;    /* --http: simulated time follows the wall clock, so a person can watch */
    uint64_t wall_start_ns;
} demo_t;

static demo_t demo; /* several kB of telegram buffers: not on the stack */
static uint64_t demo_now_ns(void *ctx)
{
    return ((demo_t *)ctx)->rig.bus.now_ns;
}

static uint64_t wall_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

#define say(who, ...) rig_log(&demo.in.log, RIG_LOG_INFO, who, "demo", __VA_ARGS__)

/* One 0.5 ms step of simulated time; with --http it also waits for the wall clock to catch up
 * and lets the control API act between steps. */
static void step(void)
{
    membus_run_for_us(&demo.rig.bus, 500u);
    lcm_cli_poll_state(&demo.lcm);
    lcm_cli_pace(&demo.lcm, demo.rig.bus.now_ns);
    if (demo.paced) {
        instrument_service(&demo.in);
        uint64_t due = demo.wall_start_ns + demo.rig.bus.now_ns;
        uint64_t now = wall_ns();
        if (due > now) {
            struct timespec d = {.tv_sec = (time_t)((due - now) / 1000000000u),
                                 .tv_nsec = (long)((due - now) % 1000000000u)};
            nanosleep(&d, NULL);
        }
    }
}

static void scene(const char *title)
{
    printf("\n--- %s\n", title);
}

/* Runs the bus until cond holds (checked every 0.5 ms) or limit_us passes. */
static bool run_until(bool (*cond)(void), uint64_t limit_us)
{
    for (uint64_t t = 0; t < limit_us; t += 500u) {
        if (cond != NULL && cond()) {
            return true;
        }
        step();
    }
    return cond != NULL && cond();
}

static void expect(bool cond, const char *what)
{
    if (!cond) {
        rig_log(&demo.in.log, RIG_LOG_ERROR, "demo", "demo", "UNEXPECTED: %s", what);
        demo.ok = false;
    }
}

static bool card_in_data_exchange(void)
{
    return dp_slave_state(&demo.card->card.dp) == DP_STATE_DATA_EXCH &&
           demo.master->slaves[0].phase == DP_MASTER_PHASE_DATA_EXCH;
}

static bool card_in_wait_prm(void)
{
    return dp_slave_state(&demo.card->card.dp) == DP_STATE_WAIT_PRM;
}

static void slave_cfg(dp_master_slave_cfg_t *sc, const uint8_t *cfg, size_t len)
{
    /* User prm octet 8 = 00: inverter faults reach the master as external diagnosis. */
    static const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    memset(sc, 0, sizeof *sc);
    sc->address = DEMO_ADDRESS;
    sc->prm_len = (uint8_t)dp_master_build_prm(sc->prm, DFP21B_IDENT, DEMO_WATCHDOG_MS, user,
                                         sizeof user);
    memcpy(sc->cfg, cfg, len);
    sc->cfg_len = (uint8_t)len;
}

static void set_po(uint16_t cw, uint16_t speed)
{
    demo.out[8] = (uint8_t)(cw >> 8);
    demo.out[9] = (uint8_t)cw;
    demo.out[10] = (uint8_t)(speed >> 8);
    demo.out[11] = (uint8_t)speed;
    dp_master_set_outputs(demo.master, 0, demo.out, sizeof demo.out);
}

static bool param_done(void)
{
    return dp_master_param_done(&demo.param, demo.master->slaves[0].inputs);
}

/* One MOVILINK service through the cyclic channel, the way a PLC program does it: toggle the
 * handshake, keep sending, wait for the reply with the same handshake. */
static bool param(uint8_t service, uint16_t index, uint32_t value, const char *what,
                  uint32_t *result)
{
    dp_master_param_start(&demo.param, service, index, value, demo.out);
    dp_master_set_outputs(demo.master, 0, demo.out, sizeof demo.out);
    uint32_t cycles0 = demo.master->slaves[0].cycles;
    if (!run_until(param_done, 1000000u)) {
        say("master", "%s: no answer in the parameter channel", what);
        demo.ok = false;
        return false;
    }
    const uint8_t *rsp = demo.master->slaves[0].inputs;
    uint32_t cycles = demo.master->slaves[0].cycles - cycles0;
    if ((rsp[0] & ML_MGMT_ERROR) != 0u) {
        char text[128];
        ml_error_text(rsp, text, sizeof text);
        say("master", "%s -> error: %s (%u bus cycles)", what, text, cycles);
        return false;
    }
    uint32_t v = ml_data(rsp);
    if (result != NULL) {
        *result = v;
    }
    if (service == ML_SVC_READ) {
        say("master", "%s -> %u (0x%08X) (%u bus cycles)", what, v, v, cycles);
    } else {
        say("master", "%s -> done (%u bus cycles)", what, cycles);
    }
    return true;
}

static void show_pi(const char *label)
{
    const uint8_t *in = demo.master->slaves[0].inputs;
    uint16_t sw = (uint16_t)((in[8] << 8) | in[9]);
    int16_t speed = (int16_t)((in[10] << 8) | in[11]);
    uint16_t cur = (uint16_t)((in[12] << 8) | in[13]);
    say("master",
                "%s PI1 status %04X (%s%s%s%s, %s %u) PI2 %5.1f rpm PI3 %4.1f %% I_N", label, sw,
                (sw & 0x01u) ? "enabled" : "not enabled", (sw & 0x02u) ? ", ready" : "",
                (sw & 0x04u) ? ", PO enabled" : "", (sw & 0x20u) ? ", FAULT" : "",
                (sw & 0x20u) ? "fault" : "unit status", sw >> 8, speed * 0.2, cur * 0.1);
}

static bool drive_at_300_rpm(void)
{
    const uint8_t *in = demo.master->slaves[0].inputs;
    return (int16_t)((in[10] << 8) | in[11]) >= 1500;
}

static bool status_shows_fault(void)
{
    return (demo.master->slaves[0].inputs[9] & 0x20u) != 0u;
}

static void print_monitor(void)
{
    const dfp21b_t *c = &demo.card->card;
    char p090[16];
    dfp21b_p090_text(&c->pd, p090, sizeof p090);
    printf("    fieldbus monitor as the inverter shows it:\n");
    printf("      P090 PD configuration  %s\n", p090);
    printf("      P091 fieldbus type     PROFIBUS DP\n");
    printf("      P092 baud rate         %s\n",
           dfp21b_p092_baud(c) ? report_baud_text(dfp21b_p092_baud(c)) : "none");
    printf("      P093 address           %u\n", dfp21b_p093_address(c));
    printf("      P094..P096 PO1..PO3    %04X %04X %04X hex\n", c->po[0], c->po[1], c->po[2]);
    printf("      P097..P099 PI1..PI3    %04X %04X %04X hex\n", c->pi[0], c->pi[1], c->pi[2]);
    printf("      P819 fieldbus timeout  %u ms\n", dfp21b_p819_timeout_ms(c));
}

static void lcm_param(void *ctx, unsigned card, uint8_t channel,
                      const uint8_t req[ML_TELEGRAM_LEN], const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)card;
    dfp_lcm_bridge_param_observer(&((lcm_cli_t *)ctx)->bridge, channel, req, rsp);
}

static hal_uart_t lcm_wrap(void *ctx, hal_uart_t inner)
{
    return lcm_cli_card_uart(ctx, inner);
}

static void setup(const instrument_opts_t *io)
{
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS};
    if (demo.lcm.open) {
        rc.wrap_card_uart = lcm_wrap;
        rc.wrap_ctx = &demo.lcm;
    }
    rig_init(&demo.rig, &rc);
    instrument_attach_log(&demo.in, &demo.rig, io);
    rig_tap_t capture = {.ctx = &demo.rep, .frame = report_tap};
    if (demo.lcm.open) {
        capture = (rig_tap_t){.ctx = &demo.lcm, .frame = lcm_cli_tap, .param = lcm_param};
    }
    rig_add_tap(&demo.rig, &capture);
    char err[256];
    rig_open(&demo.rig, err, sizeof err);
    card_options_t co = {.address = DEMO_ADDRESS, .fixed_baud = 0, .strict_timing = true,
                         .inverter = CARD_INVERTER_SIM,
                         .inverter_delay_us = DEMO_INVERTER_DELAY_US};
    demo.card = &rig_add_card(&demo.rig, &co, 0)->cs;
    dp_master_cfg_t mc = {.address = DEMO_MASTER, .baud = DEMO_BAUD, .strict_timing = true,
                          .cycle_us = 2000, .token_ring = true};
    demo.master = rig_add_master(&demo.rig, &mc, 0);
}

static void reconfigure(const uint8_t *cfg, size_t len)
{
    dp_master_slave_cfg_t sc;
    slave_cfg(&sc, cfg, len);
    dp_master_reconfigure(demo.master, 0, &sc, membus_now_us(&demo.rig.bus));
    rig_wake(&demo.rig);
}

typedef struct demo_opts {
    capture_opts_t capture;
    const char *lcm_url;
    instrument_opts_t io;
} demo_opts_t;

static const cli_opt_t demo_options[] = {
    {CLI_OPT("--lcm", "URL", CLI_TEXT, offsetof(demo_opts_t, lcm_url))},
};

static const cli_group_t demo_groups[] = {
    {capture_options, CLI_COUNT(capture_options), offsetof(demo_opts_t, capture)},
    {demo_options, CLI_COUNT(demo_options), 0},
    {instrument_options, CLI_COUNT(instrument_options), offsetof(demo_opts_t, io)},
    {instrument_http_options, CLI_COUNT(instrument_http_options), offsetof(demo_opts_t, io.web)},
};

const cli_command_t cli_demo = {.name = "demo", .groups = demo_groups,
                                .n_groups = CLI_COUNT(demo_groups)};

/* The command line into o: 0, or EXIT_USAGE after reporting. */
static int demo_parse(demo_opts_t *o, int argc, char **argv)
{
    *o = (demo_opts_t){.capture = {.path = NULL}};
    instrument_defaults(&o->io, RIG_LOG_TIME_BUS);
    if (cli_parse(&cli_demo, argc, argv, o) != 0) {
        return EXIT_USAGE;
    }
    char lcm_log[512];
    const cli_file_t files[] = {{"--capture", o->capture.path, false},
                                {"--lcm", cli_lcm_log_written(o->lcm_url, lcm_log,
                                                              sizeof lcm_log),
                                 false}};
    return cli_files_distinct("demo", files, 2u) ? 0 : EXIT_USAGE;
}

/* The capture and the LCM telemetry. False after reporting. */
static bool demo_open(demo_opts_t *o)
{
    memset(&demo, 0, sizeof demo);
    demo.ok = true;
    demo.rep.now_ns = demo_now_ns;
    demo.rep.now_ctx = &demo;
    demo.rep.card = &demo.rig.cards[0].cs.card;
    o->capture.w.baud = DEMO_BAUD;
    struct timespec wall;
    (void)clock_gettime(CLOCK_REALTIME, &wall);
    if (!report_open_capture(&demo.rep, &o->capture, (uint64_t)wall.tv_sec * 1000000000ull)) {
        return false;
    }
    if (o->lcm_url != NULL) {
        /* Simulated time 0 is now: utime = wall clock at start + simulated time. */
        int64_t start = dfp_lcm_wall_us();
        if (lcm_cli_open(&demo.lcm, o->lcm_url, &demo.rig.cards[0].cs.card, DEMO_ADDRESS,
                         &demo.rep, start, start) != 0) {
            return false;
        }
    }
    return true;
}

static const uint8_t param_3pd[] = {0xF3, 0xF2};

/* Scene 1, with the control API when asked. Returns 0, or instrument_start_http's code. */
static int scene_startup(const demo_opts_t *o)
{
    scene("1. Power-up, baud search and start-up with \"Param + 3 PD\" (F3 F2)");
    setup(&o->io);
    if (o->io.http != NULL) {
        if (demo.lcm.open) {
            demo.in.api_event = lcm_cli_api_event;
            demo.in.api_event_ctx = &demo.lcm;
        }
        int rc = instrument_start_http(&demo.in, &demo.rig, &o->io, "demo", false);
        if (rc != 0) {
            return rc;
        }
        cli_catch_stop_signals();
        demo.paced = true;
        demo.wall_start_ns = wall_ns();
    }
    dp_master_slave_cfg_t sc;
    slave_cfg(&sc, param_3pd, sizeof param_3pd);
    dp_master_add_slave(demo.master, &sc);
    expect(run_until(card_in_data_exchange, 2000000u), "start-up reaches Data_Exch");
    run_until(NULL, 10000u);
    show_pi("drive as delivered:");
    return 0;
}

static void scene_commissioning(void)
{
    scene("2. Commissioning through the parameter channel (manual 4.3)");
    uint32_t v = 0;
    expect(param(ML_SVC_READ, 8300, 0, "read index 8300 (P076 firmware)", &v) &&
               v == 0x311C7289u,
           "index 8300 reads 0x311C7289");
    expect(param(ML_SVC_WRITE, 8461, 3, "write P100 setpoint source = 3 FIELDBUS", NULL),
           "P100 written");
    expect(param(ML_SVC_WRITE, 8462, 2, "write P101 control signal source = 2 FIELDBUS", NULL),
           "P101 written");
    expect(!param(ML_SVC_WRITE_VOLATILE, 8517, 99000000u,
                  "write volatile P302 maximum speed = 99000 rpm", NULL),
           "P302 refuses 99000 rpm");
    param(ML_SVC_READ, 8318, 0, "read P000 speed (0.001 rpm)", NULL);
    run_until(NULL, 10000u);
    show_pi("after P100/P101:");
}

static void scene_enable(void)
{
    scene("3. Enable: control word 0006, PO2 = 1500 (300 rpm at 0.2 rpm/digit), ramp P130");
    set_po(0x0006, 1500);
    for (int i = 0; i < 4; i++) {
        run_until(NULL, 50000u);
        show_pi("ramping:");
    }
    expect(run_until(drive_at_300_rpm, 1000000u), "the drive reaches 300 rpm");
    show_pi("at speed:");
    print_monitor();
}

static void scene_watchdog(void)
{
    scene("4. The master stops (PLC in STOP, cable pulled): DP watchdog, P831 reaction");
    dp_master_stop(demo.master);
    say("master", "stopped sending");
    expect(run_until(card_in_wait_prm, 500000u), "watchdog expiry");
    run_until(NULL, 300000u);
    say("master", "running again");
    dp_master_start(demo.master, membus_now_us(&demo.rig.bus));
    rig_wake(&demo.rig);
    expect(run_until(card_in_data_exchange, 500000u), "back in Data_Exch");
    expect(run_until(status_shows_fault, 500000u), "status word 1 shows the fault");
    run_until(NULL, 250000u); /* the card's status poll turns the fault into Ext_Diag */
    show_pi("after the timeout:");
    say("master", "reset: control word bit 6 rising edge (0046, then 0006)");
    set_po(0x0046, 1500);
    run_until(NULL, 10000u);
    set_po(0x0006, 1500);
    run_until(NULL, 400000u);
    expect(!status_shows_fault(), "fault reset");
    show_pi("after the reset:");
}

static void scene_configuration(void)
{
    scene("5. A wrong configuration: F3 E2 D1 (parameter channel, 3 PD out but 2 PD in)");
    reconfigure((const uint8_t[]){0xF3, 0xE2, 0xD1}, 3);
    run_until(NULL, 100000u);
    expect(!card_in_data_exchange(), "the card refuses F3 E2 D1");
    print_monitor();

    scene("6. Configuration corrected to F3 F2 (Param + 3 PD)");
    reconfigure(param_3pd, sizeof param_3pd);
    expect(run_until(card_in_data_exchange, 2000000u), "Data_Exch again");
    set_po(0x0006, 1500);
    run_until(NULL, 300000u);
    show_pi("running:");
}

/* The summary; 0 when every scene behaved, 1 when not or the capture could not be finished. */
static int demo_summary(const demo_opts_t *o)
{
    printf("\n--- Summary\n");
    printf("    %llu telegrams on the bus, %u Data_Exchange cycles, %u master timeouts, "
           "simulated %.1f ms\n",
           (unsigned long long)demo.rig.bus.frames_sent, demo.master->slaves[0].cycles,
           demo.master->timeouts, (double)demo.rig.bus.now_ns / 1e6);
    if (demo.rep.capturing) {
        cap_writer_options_t w = demo.rep.capture.opt;
        if (report_close_capture(&demo.rep) != 0) {
            return 1;
        }
        printf("    capture: %llu telegrams written to %s (%s, link type %u)\n",
               (unsigned long long)demo.rep.frames_captured, o->capture.path,
               cap_format_name(w.format), w.linktype);
    }
    printf("    result: %s\n", demo.ok ? "every scene behaved as the manual describes"
                                       : "UNEXPECTED: a scene did not reach its expected state");
    return demo.ok ? 0 : 1;
}

int cmd_demo(int argc, char **argv)
{
    static demo_opts_t o;
    int rc = demo_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    if (!demo_open(&o)) {
        return 1;
    }
    printf("dfp-sim demo: a DFP21B (DIP address %u, automatic baud rate) in an emulated MOVIDRIVE,\n"
           "and a DP master (address %u, %s, watchdog %u ms) on a simulated RS-485 segment.\n"
           "Times are simulated bus time%s.\n",
           DEMO_ADDRESS, DEMO_MASTER, report_baud_text(DEMO_BAUD), DEMO_WATCHDOG_MS,
           o.io.http != NULL ? ", running at wall-clock speed while the panel is open" : "");
    rc = scene_startup(&o);
    if (rc != 0) {
        (void)report_close_capture(&demo.rep);
        return rc;
    }
    scene_commissioning();
    scene_enable();
    scene_watchdog();
    scene_configuration();
    if (demo.paced) {
        scene("The simulation goes on at wall-clock speed: the front panel stays up until Ctrl-C");
        while (!cli_stop) {
            step();
        }
        say("sim", "stopping (signal)");
        instrument_stop(&demo.in);
    }
    if (demo.lcm.open) {
        lcm_cli_close(&demo.lcm);
    }
    return demo_summary(&o);
}
