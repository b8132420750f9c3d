/* Master and card on the in-memory bus with simulated time: start-up, cyclic data, watchdog,
 * wrong configuration, baud search. Each scenario asserts states, LED modes and data. */
#include <string.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
#include "rig/rig.h"

/* What the scenarios count from the card's and the master's events. */
typedef struct scn {
    unsigned restarts_seen;
    unsigned restarts_at_data_exch;
    unsigned wd_expiries;
} scn_t;

static void card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    (void)card;
    scn_t *s = ctx;
    if (ev->type == DP_EV_WD_EXPIRED) {
        s->wd_expiries++;
    }
}

static void master_event(void *ctx, const dp_master_event_t *ev)
{
    scn_t *s = ctx;
    if (ev->type == DP_MASTER_EV_FAULT) {
        s->restarts_seen++;
    }
    if (ev->type == DP_MASTER_EV_PHASE && ev->new_phase == DP_MASTER_PHASE_DATA_EXCH) {
        s->restarts_at_data_exch = s->restarts_seen;
    }
}

static rig_t rig; /* large: keep it off the stack */
static scn_t scn;

/* Card 4 first, then master 2: the order the bus polls them in, which the timings rest on. */
static void scn_setup(uint32_t master_baud, uint32_t card_fixed_baud, const uint8_t *cfg,
                      size_t cfg_len, uint32_t wd_ms)
{
    memset(&scn, 0, sizeof scn);
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS};
    rig_init(&rig, &rc);
    rig_tap_t tap = {.ctx = &scn, .card_event = card_event, .master_event = master_event};
    (void)rig_add_tap(&rig, &tap);
    card_options_t co = {.address = 4, .fixed_baud = card_fixed_baud, .strict_timing = true};
    char err[256] = "no room for the card on the bus"; /* rig_open overwrites it on failure */
    rig_card_t *card = rig_open(&rig, err, sizeof err) == 0 ? rig_add_card(&rig, &co, 0) : NULL;
    /* The note is empty unless card_station_init failed. */
    CHECK_STR(card != NULL ? card->nvm_note : err, "");
    dp_master_cfg_t mc = {.address = 2, .baud = master_baud, .strict_timing = true,
                          .cycle_us = 2000};
    (void)rig_add_master(&rig, &mc, 0);
    dp_master_slave_cfg_t sc = {.address = 4};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, wd_ms, dfp21b_user_prm_default,
                                        sizeof dfp21b_user_prm_default);
    memcpy(sc.cfg, cfg, cfg_len);
    sc.cfg_len = (uint8_t)cfg_len;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
}

static void test_startup_auto_baud_to_data_exchange(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    scn_setup(1500000, 0, cfg, sizeof cfg, 100);
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_RUN], HAL_LED_ON);
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_ON); /* searching */
    membus_run_for_us(&rig.bus, 200000);
    CHECK_EQ(dp_slave_baud_state(&rig.cards[0].cs.card.dp), DP_BAUD_CONTROL);
    CHECK_EQ(dfp21b_p092_baud(&rig.cards[0].cs.card), 1500000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    CHECK_EQ(dp_slave_master(&rig.cards[0].cs.card.dp), 2);
    CHECK_EQ(dfp21b_p819_timeout_ms(&rig.cards[0].cs.card), 100);
    char p090[16];
    dfp21b_p090_text(&rig.cards[0].cs.card.pd, p090, sizeof p090);
    CHECK_STR(p090, "3PD + PARAM");
    CHECK(rig.master.slaves[0].cycles > 50);

    /* PO words reach the card and come back as PI (loopback without an inverter). */
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0x00, 0x00};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(rig.cards[0].cs.card.po[0], 0x0006);
    CHECK_EQ(rig.cards[0].cs.card.po[1], 1500);
    CHECK_EQ(rig.master.slaves[0].inputs_len, 14);
    CHECK_BYTES(rig.master.slaves[0].inputs, rig.master.slaves[0].inputs_len, 0, 0, 0, 0, 0, 0,
                0, 0, 0x00, 0x06, 0x05, 0xDC, 0x00, 0x00);
    /* Only the polls while the card was still searching its rate went unanswered: none since. */
    CHECK(scn.restarts_seen > 0);
    CHECK_EQ(scn.restarts_seen, scn.restarts_at_data_exch);
}

static void test_watchdog_expiry_and_recovery(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    scn_setup(1500000, 1500000, cfg, sizeof cfg, 50);
    membus_run_for_us(&rig.bus, 50000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0, 0};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(rig.cards[0].cs.card.po[1], 1500);

    dp_master_stop(&rig.master);
    membus_run_for_us(&rig.bus, 45000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH); /* not yet: 50 ms */
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(scn.wd_expiries, 1);
    CHECK_EQ(rig.cards[0].cs.card.po[1], 0); /* outputs cleared */
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_ON);
    CHECK_EQ(dp_slave_master(&rig.cards[0].cs.card.dp), DP_MASTER_ADD_NONE);
    CHECK_EQ(dfp21b_p819_timeout_ms(&rig.cards[0].cs.card), 50);

    dp_master_start(&rig.master, membus_now_us(&rig.bus));
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_OFF);
}

static void test_wrong_configuration_gives_cfg_fault_and_backoff(void)
{
    /* Parameter channel + 3 PD out + 2 PD in: unequal lengths, refused by the card. */
    const uint8_t cfg[] = {0xF3, 0xE2, 0xD1};
    scn_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    membus_run_for_us(&rig.bus, 1000000);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(rig.cards[0].cs.leds.mode[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    char p090[16];
    dfp21b_p090_text(&rig.cards[0].cs.card.pd, p090, sizeof p090);
    CHECK_STR(p090, "0PD");
    uint8_t *d = rig.master.slaves[0].last_diag;
    CHECK_EQ(d[DP_DIAG_STATUS_1] & DP_DIAG1_CFG_FAULT, DP_DIAG1_CFG_FAULT);
    /* Back-off doubling from 10 ms: within 1 s at most 7 attempts, not thousands. */
    CHECK(scn.restarts_seen >= 4);
    CHECK(scn.restarts_seen <= 8);
}

static void test_inverter_fault_dh_and_diagnosis(void)
{
    /* User prm octet 8 = 00: inverter faults go to the master as external diagnosis. */
    const uint8_t cfg[] = {0xF3, 0xF2};
    scn_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    dp_master_slave_cfg_t sc = rig.master.slaves[0].cfg;
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 100, user, sizeof user);
    dp_master_reconfigure(&rig.master, 0, &sc, 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    uint32_t cycles = rig.master.slaves[0].cycles;

    dfp21b_set_inverter_fault(&rig.cards[0].cs.card, 0x11);
    membus_run_for_us(&rig.bus, 10000);
    /* DH made the master read the diagnosis, then it went back to cyclic exchange. */
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len,
                0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
    CHECK(rig.master.slaves[0].cycles > cycles + 2);
    CHECK_EQ(scn.restarts_seen, 0);

    dfp21b_set_inverter_fault(&rig.cards[0].cs.card, 0);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len,
                0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

static void test_master_global_control_clear_data(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    scn_setup(1500000, 1500000, cfg, sizeof cfg, 100);
    membus_run_for_us(&rig.bus, 20000);
    const uint8_t out[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0, 0};
    dp_master_set_outputs(&rig.master, 0, out, sizeof out);
    /* A long cycle time leaves a gap after the Global_Control before the next Data_Exchange. */
    rig.master.cfg.cycle_us = 20000;
    membus_run_for_us(&rig.bus, 30000);
    CHECK_EQ(rig.cards[0].cs.card.dp.outputs[9], 0x06);
    dp_master_global_control(&rig.master, DP_GC_CLEAR_DATA, 0);
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 500);
    /* Broadcast Clear_Data: the card cleared its outputs; the next Data_Exchange sets them. */
    CHECK_EQ(rig.cards[0].cs.card.dp.outputs[9], 0x00);
    CHECK_EQ(rig.cards[0].cs.card.dp.outputs[11], 0x00);
    membus_run_for_us(&rig.bus, 30000);
    CHECK_EQ(rig.cards[0].cs.card.dp.outputs[9], 0x06);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
}

static void test_card_finds_each_rate(void)
{
    const uint8_t cfg[] = {0xF1};
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        uint32_t baud = hal_uart_bauds[i];
        scn_setup(baud, 0, cfg, sizeof cfg, 0);
        membus_run_for_us(&rig.bus, 8000000);
        CHECK_EQ(dfp21b_p092_baud(&rig.cards[0].cs.card), baud);
        CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
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
