/* Master and card on the in-memory bus with simulated time: start-up, cyclic data, watchdog,
 * wrong configuration, baud search. Each scenario asserts states, LED modes and data. */
#include <string.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
#include "sim_hal/membus.h"
#include "sim_stations/stations.h"

typedef struct rig {
    membus_t bus;
    card_station_t card;
    dp_master_t master;
    membus_port_t *master_port;
    unsigned restarts_seen;
    unsigned restarts_at_data_exch;
    unsigned wd_expiries;
} rig_t;

static void card_event(void *ctx, const dp_event_t *ev)
{
    rig_t *r = ctx;
    if (ev->type == DP_EV_WD_EXPIRED) {
        r->wd_expiries++;
    }
}

static void master_event(void *ctx, const dpm_event_t *ev)
{
    rig_t *r = ctx;
    if (ev->type == DPM_EV_FAULT) {
        r->restarts_seen++;
    }
    if (ev->type == DPM_EV_PHASE && ev->new_phase == DPM_PHASE_DATA_EXCH) {
        r->restarts_at_data_exch = r->restarts_seen;
    }
}

static rig_t rig; /* large: keep it off the stack */

static void rig_setup(uint32_t master_baud, uint32_t card_fixed_baud, const uint8_t *cfg,
                      size_t cfg_len, uint32_t wd_ms)
{
    memset(&rig, 0, sizeof rig);
    membus_init(&rig.bus);
    hal_uart_t card_uart;
    hal_uart_t master_uart;
    sim_station_t cs = card_station(&rig.card);
    sim_station_t ms = master_station(&rig.master);
    membus_attach(&rig.bus, &cs, &card_uart);
    rig.master_port = membus_attach(&rig.bus, &ms, &master_uart);
    card_options_t co = {.address = 4, .fixed_baud = card_fixed_baud, .strict_timing = true,
                         .event = card_event, .ctx = &rig};
    char err[256];
    CHECK_EQ(card_station_init(&rig.card, &co, card_uart, 0, err, sizeof err), 0);
    dp_master_cfg_t mc = {.address = 2, .baud = master_baud, .strict_timing = true,
                          .cycle_us = 2000, .uart = master_uart, .event = master_event,
                          .event_ctx = &rig};
    dp_master_init(&rig.master, &mc, 0);
    dpm_slave_cfg_t sc = {.address = 4};
    sc.prm_len = (uint8_t)dpm_build_prm(sc.prm, DFP21B_IDENT, wd_ms, dfp21b_user_prm_default,
                                        sizeof dfp21b_user_prm_default);
    memcpy(sc.cfg, cfg, cfg_len);
    sc.cfg_len = (uint8_t)cfg_len;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
}

static void test_startup_auto_baud_to_data_exchange(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    rig_setup(1500000, 0, cfg, sizeof cfg, 100);
    CHECK_EQ(rig.card.leds.mode[HAL_LED_RUN], HAL_LED_ON);
    CHECK_EQ(rig.card.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_ON); /* searching */
    membus_run_for_us(&rig.bus, 200000);
    CHECK_EQ(dp_slave_baud_state(&rig.card.card.dp), DP_BAUD_CONTROL);
    CHECK_EQ(dfp21b_p092_baud(&rig.card.card), 1500000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(rig.master.slaves[0].phase, DPM_PHASE_DATA_EXCH);
    CHECK_EQ(rig.card.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    CHECK_EQ(dp_slave_master(&rig.card.card.dp), 2);
    CHECK_EQ(dfp21b_p819_timeout_ms(&rig.card.card), 100);
    char p090[16];
    dfp21b_p090_text(&rig.card.card.pd, p090, sizeof p090);
    CHECK_STR(p090, "3PD + PARAM");
    CHECK(rig.master.slaves[0].cycles > 50);

    /* PO words reach the card and come back as PI (loopback without an inverter). */
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0x00, 0x00};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(rig.card.card.po[0], 0x0006);
    CHECK_EQ(rig.card.card.po[1], 1500);
    CHECK_EQ(rig.master.slaves[0].inputs_len, 14);
    CHECK_BYTES(rig.master.slaves[0].inputs, rig.master.slaves[0].inputs_len, 0, 0, 0, 0, 0, 0,
                0, 0, 0x00, 0x06, 0x05, 0xDC, 0x00, 0x00);
    /* Only the polls while the card was still searching its rate went unanswered: none since. */
    CHECK(rig.restarts_seen > 0);
    CHECK_EQ(rig.restarts_seen, rig.restarts_at_data_exch);
}

static void test_watchdog_expiry_and_recovery(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    rig_setup(1500000, 1500000, cfg, sizeof cfg, 50);
    membus_run_for_us(&rig.bus, 50000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH);
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0, 0};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(rig.card.card.po[1], 1500);

    dp_master_stop(&rig.master);
    membus_run_for_us(&rig.bus, 45000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH); /* not yet: 50 ms */
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(rig.wd_expiries, 1);
    CHECK_EQ(rig.card.card.po[1], 0); /* outputs cleared */
    CHECK_EQ(rig.card.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_ON);
    CHECK_EQ(dp_slave_master(&rig.card.card.dp), DP_MASTER_ADD_NONE);
    CHECK_EQ(dfp21b_p819_timeout_ms(&rig.card.card), 50);

    dp_master_start(&rig.master, membus_now_us(&rig.bus));
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(rig.card.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_OFF);
}

static void test_wrong_configuration_gives_cfg_fault_and_backoff(void)
{
    /* Parameter channel + 3 PD out + 2 PD in: unequal lengths, refused by the card. */
    const uint8_t cfg[] = {0xF3, 0xE2, 0xD1};
    rig_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    membus_run_for_us(&rig.bus, 1000000);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(rig.card.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    char p090[16];
    dfp21b_p090_text(&rig.card.card.pd, p090, sizeof p090);
    CHECK_STR(p090, "0PD");
    uint8_t *d = rig.master.slaves[0].last_diag;
    CHECK_EQ(d[DP_DIAG_STATUS_1] & DP_DIAG1_CFG_FAULT, DP_DIAG1_CFG_FAULT);
    /* Back-off doubling from 10 ms: within 1 s at most 7 attempts, not thousands. */
    CHECK(rig.restarts_seen >= 4);
    CHECK(rig.restarts_seen <= 8);
}

static void test_inverter_fault_dh_and_diagnosis(void)
{
    /* User prm octet 8 = 00: inverter faults go to the master as external diagnosis. */
    const uint8_t cfg[] = {0xF3, 0xF2};
    rig_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    dpm_slave_cfg_t sc = rig.master.slaves[0].cfg;
    sc.prm_len = (uint8_t)dpm_build_prm(sc.prm, DFP21B_IDENT, 100, user, sizeof user);
    dp_master_reconfigure(&rig.master, 0, &sc, 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DPM_PHASE_DATA_EXCH);
    uint32_t cycles = rig.master.slaves[0].cycles;

    dfp21b_set_inverter_fault(&rig.card.card, 0x11);
    membus_run_for_us(&rig.bus, 10000);
    /* DH made the master read the diagnosis, then it went back to cyclic exchange. */
    CHECK_EQ(rig.master.slaves[0].phase, DPM_PHASE_DATA_EXCH);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len,
                0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
    CHECK(rig.master.slaves[0].cycles > cycles + 2);
    CHECK_EQ(rig.restarts_seen, 0);

    dfp21b_set_inverter_fault(&rig.card.card, 0);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len,
                0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

static void test_master_global_control_clear_data(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    rig_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    membus_run_for_us(&rig.bus, 20000);
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0, 0};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    /* A long cycle time leaves a gap after the Global_Control before the next Data_Exchange. */
    rig.master.cfg.cycle_us = 20000;
    membus_run_for_us(&rig.bus, 30000);
    CHECK_EQ(rig.card.card.dp.outputs[9], 0x06);
    dp_master_global_control(&rig.master, DP_GC_CLEAR_DATA, 0);
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 500);
    /* Broadcast Clear_Data: the card cleared its outputs; the next Data_Exchange sets them. */
    CHECK_EQ(rig.card.card.dp.outputs[9], 0x00);
    CHECK_EQ(rig.card.card.dp.outputs[11], 0x00);
    membus_run_for_us(&rig.bus, 30000);
    CHECK_EQ(rig.card.card.dp.outputs[9], 0x06);
    CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH);
}

static void test_card_finds_each_rate(void)
{
    const uint8_t cfg[] = {0xF1};
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        uint32_t baud = hal_uart_bauds[i];
        rig_setup(baud, 0, cfg, sizeof cfg, 0);
        membus_run_for_us(&rig.bus, 8000000);
        CHECK_EQ(dfp21b_p092_baud(&rig.card.card), baud);
        CHECK_EQ(dp_slave_state(&rig.card.card.dp), DP_STATE_DATA_EXCH);
    }
}

int main(void)
{
    RUN_TEST(test_startup_auto_baud_to_data_exchange);
    RUN_TEST(test_watchdog_expiry_and_recovery);
    RUN_TEST(test_wrong_configuration_gives_cfg_fault_and_backoff);
    RUN_TEST(test_inverter_fault_dh_and_diagnosis);
    RUN_TEST(test_master_global_control_clear_data);
    RUN_TEST(test_card_finds_each_rate);
    return check_report();
}
