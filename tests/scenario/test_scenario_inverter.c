/* Master, card and emulated MOVIDRIVE on the in-memory bus: the cyclic parameter channel end to
 * end (exactly once, many bus cycles, inverter timeout), process data and the status word, the
 * fieldbus timeout reaction and its reset, external diagnosis on and off. */
#include <string.h>

#include "check.h"
#include "dp_master/param_channel.h"
#include "dp_slave/dp_wire.h"
#include "rig/rig.h"

/* The master's side of the parameter channel, and what the card's events counted. */
typedef struct scn {
    uint8_t out[14];
    dp_master_param_t param;
    unsigned gc_events;
} scn_t;

static rig_t rig; /* large: keep it off the stack */
static scn_t scn;
/* Where simulated time starts: 0, or a wall-clock-like instant past 2^31 us (35.8 min uptime). */
static uint64_t start_ns;

static const uint8_t cfg_param_3pd[] = {0xF3, 0xF2};

static void on_card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    (void)card;
    if (ev->type == DP_EV_GLOBAL_CONTROL) {
        ((scn_t *)ctx)->gc_events++;
    }
}

/* A rig with card co on the in-memory bus from t_ns; the check stands for card_station_init's
 * result (the note is empty unless it failed). */
static void rig_with_card(const card_options_t *co, uint64_t t_ns)
{
    memset(&scn, 0, sizeof scn);
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .start_ns = t_ns};
    rig_init(&rig, &rc);
    rig_tap_t tap = {.ctx = &scn, .card_event = on_card_event};
    (void)rig_add_tap(&rig, &tap);
    char err[256] = "no room for the card on the bus"; /* rig_open overwrites it on failure */
    rig_card_t *card = rig_open(&rig, err, sizeof err) == 0
                           ? rig_add_card(&rig, co, membus_now_us(&rig.bus))
                           : NULL;
    CHECK_STR(card != NULL ? card->nvm_note : err, "");
}

/* Card 4 first, then master 2: the order the bus polls them in, which the timings rest on. */
static void setup(uint32_t inverter_delay_us, uint8_t diag_alarm_octet)
{
    card_options_t co = {.address = 4, .fixed_baud = 1500000, .strict_timing = true,
                         .inverter = CARD_INVERTER_SIM, .inverter_delay_us = inverter_delay_us};
    rig_with_card(&co, start_ns);
    dp_master_cfg_t mc = {.address = 2, .baud = 1500000, .strict_timing = true, .cycle_us = 2000};
    (void)rig_add_master(&rig, &mc, membus_now_us(&rig.bus));
    const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, diag_alarm_octet};
    dp_master_slave_cfg_t sc = {.address = 4};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 50, user, sizeof user);
    memcpy(sc.cfg, cfg_param_3pd, sizeof cfg_param_3pd);
    sc.cfg_len = sizeof cfg_param_3pd;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
}

static const uint8_t *inputs(void)
{
    return rig.master.slaves[0].inputs;
}

static void start(uint8_t service, uint16_t index, uint32_t value)
{
    dp_master_param_start(&scn.param, service, index, value, scn.out);
    dp_master_set_outputs(&rig.master, 0, scn.out, sizeof scn.out);
}

/* Runs until the reply to the running service is in the inputs; returns the cycles it took. */
static uint32_t finish(uint32_t limit_us)
{
    uint32_t c0 = rig.master.slaves[0].cycles;
    for (uint32_t t = 0; t < limit_us; t += 500u) {
        if (dp_master_param_done(&scn.param, inputs())) {
            return rig.master.slaves[0].cycles - c0;
        }
        membus_run_for_us(&rig.bus, 500u);
    }
    return UINT32_MAX;
}

static void set_po(uint16_t cw, uint16_t speed)
{
    scn.out[8] = (uint8_t)(cw >> 8);
    scn.out[9] = (uint8_t)cw;
    scn.out[10] = (uint8_t)(speed >> 8);
    scn.out[11] = (uint8_t)speed;
    dp_master_set_outputs(&rig.master, 0, scn.out, sizeof scn.out);
}

static uint16_t pi_word(unsigned i)
{
    return (uint16_t)((inputs()[8u + 2u * i] << 8) | inputs()[9u + 2u * i]);
}

static void test_read_8300_through_the_cyclic_channel(void)
{
    setup(0, 0x01);
    start(ML_SVC_READ, 8300, 0);
    CHECK(finish(100000) != UINT32_MAX);
    CHECK_BYTES(inputs(), 8, 0x71, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
}

static void test_slow_inverter_keeps_old_reply_and_exchange_running(void)
{
    setup(20000, 0x01); /* each service takes 20 ms: about ten bus cycles */
    start(ML_SVC_READ, 8300, 0);
    uint32_t cycles = finish(100000);
    CHECK(cycles != UINT32_MAX);
    CHECK(cycles >= 8);
    uint8_t first[8];
    memcpy(first, inputs(), 8);
    /* The next service: until it completes every reply repeats the previous one exactly. */
    start(ML_SVC_READ, 8489, 0);
    bool same_until_done = true;
    uint32_t c0 = rig.master.slaves[0].cycles;
    for (int i = 0; i < 200 && !dp_master_param_done(&scn.param, inputs()); i++) {
        same_until_done = same_until_done && memcmp(inputs(), first, 8) == 0;
        membus_run_for_us(&rig.bus, 500);
    }
    CHECK(same_until_done);
    CHECK(rig.master.slaves[0].cycles - c0 >= 8);
    CHECK_BYTES(inputs(), 8, 0x31, 0x00, 0x21, 0x29, 0x00, 0x02, 0x49, 0xF0); /* 150000 */
}

static void test_write_executes_exactly_once(void)
{
    setup(5000, 0x01);
    uint32_t writes0 = rig.cards[0].cs.md.eeprom_writes;
    uint32_t services0 = rig.cards[0].cs.card.param.services;
    start(ML_SVC_WRITE, 8489, 300000);
    CHECK(finish(100000) != UINT32_MAX);
    /* The same request keeps arriving with an unchanged handshake for 100 more cycles. */
    uint32_t c0 = rig.master.slaves[0].cycles;
    while (rig.master.slaves[0].cycles - c0 < 100u) {
        membus_run_for_us(&rig.bus, 1000);
    }
    CHECK_EQ(rig.cards[0].cs.card.param.services - services0, 1);
    CHECK_EQ(rig.cards[0].cs.md.eeprom_writes - writes0, 0); /* no EEPROM file in this rig */
    int32_t v = 0;
    CHECK(movidrive_read_value(&rig.cards[0].cs.md, 8489, &v));
    CHECK_EQ(v, 300000);
    CHECK_BYTES(inputs(), 8, 0x72, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0);
}

static void test_inverter_error_and_card_error(void)
{
    setup(0, 0x01);
    start(ML_SVC_WRITE_VOLATILE, 8517, 99000000u); /* P302 above its maximum */
    CHECK(finish(100000) != UINT32_MAX);
    CHECK_BYTES(inputs(), 8, 0xF3, 0x00, 0x21, 0x45, 0x08, 0x00, 0x00, 0x15);
    /* Reserved octet not 0: the card answers class 5 code 5 without asking the inverter. */
    dp_master_param_start(&scn.param, ML_SVC_READ, 8300, 0, scn.out);
    scn.out[1] = 0x01;
    dp_master_set_outputs(&rig.master, 0, scn.out, sizeof scn.out);
    CHECK(finish(100000) != UINT32_MAX);
    CHECK_BYTES(inputs(), 8, 0xB1, 0x01, 0x20, 0x6C, 0x05, 0x05, 0x00, 0x00);
}

static void test_inverter_not_answering_gives_6_2(void)
{
    setup(500000, 0x01); /* slower than the card's 200 ms limit */
    start(ML_SVC_READ, 8300, 0);
    uint32_t cycles = finish(400000);
    CHECK(cycles != UINT32_MAX);
    CHECK_BYTES(inputs(), 8, 0xF1, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    membus_run_for_us(&rig.bus, 400000); /* the late answer arrives and must change nothing */
    CHECK_BYTES(inputs(), 8, 0xF1, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(rig.cards[0].cs.card.ml.stale_responses, 1);
}

static void commission(void)
{
    start(ML_SVC_WRITE, 8461, 3);
    CHECK(finish(100000) != UINT32_MAX);
    start(ML_SVC_WRITE, 8462, 2);
    CHECK(finish(100000) != UINT32_MAX);
    CHECK_EQ(inputs()[0] & ML_MGMT_ERROR, 0);
}

static void test_process_data_ramp_and_status_word(void)
{
    setup(0, 0x01);
    membus_run_for_us(&rig.bus, 5000);
    CHECK_EQ(pi_word(0) & 0x0007u, 0x0002u); /* ready, PO data not enabled yet */
    commission();
    membus_run_for_us(&rig.bus, 5000);
    CHECK_EQ(pi_word(0) & 0x0007u, 0x0006u); /* PO data enabled, not enabled */
    set_po(0x0006, 1500);
    membus_run_for_us(&rig.bus, 100000);
    CHECK_EQ(pi_word(0) & 0x0007u, 0x0007u);
    int16_t speed = (int16_t)pi_word(1);
    CHECK(speed > 600 && speed < 900); /* 150 rpm after 100 ms with P130 = 2 s per 3000 rpm */
    membus_run_for_us(&rig.bus, 200000);
    CHECK_EQ(pi_word(1), 1500);
    CHECK_EQ(rig.cards[0].cs.card.po[0], 0x0006);
    CHECK_EQ(rig.cards[0].cs.card.po[1], 1500);
}

static void test_fieldbus_timeout_fault_ext_diag_and_reset(void)
{
    setup(0, 0x00); /* diagnostic alarm on */
    commission();
    set_po(0x0006, 1500);
    membus_run_for_us(&rig.bus, 400000);
    CHECK_EQ(pi_word(1), 1500);
    dp_master_stop(&rig.master);
    membus_run_for_us(&rig.bus, 100000); /* 50 ms watchdog */
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(rig.cards[0].cs.md.fault, 28); /* P831 default 4: rapid stop with fault */
    dp_master_start(&rig.master, membus_now_us(&rig.bus));
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 300000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    CHECK_EQ(pi_word(0), 0x1C24); /* fault 28 in the high byte, fault bit, PO enabled */
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len, 0x08, 0x0C,
                0x00, 0x02, 0x60, 0x03, 0x02, 0x1C);
    set_po(0x0046, 1500); /* rising edge of bit 6 */
    membus_run_for_us(&rig.bus, 10000);
    set_po(0x0006, 1500);
    membus_run_for_us(&rig.bus, 300000);
    CHECK_EQ(rig.cards[0].cs.md.fault, 0);
    CHECK_EQ(pi_word(0) & 0x0027u, 0x0007u);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len, 0x00, 0x0C,
                0x00, 0x02, 0x60, 0x03);
}

static void test_no_ext_diag_with_alarm_off(void)
{
    setup(0, 0x01); /* factory setting: no diagnostic alarm */
    commission();
    set_po(0x0006, 1500);
    membus_run_for_us(&rig.bus, 50000);
    dp_master_stop(&rig.master);
    membus_run_for_us(&rig.bus, 100000);
    dp_master_start(&rig.master, membus_now_us(&rig.bus));
    membus_wake(rig.master_port);
    membus_run_for_us(&rig.bus, 300000);
    CHECK_EQ(rig.cards[0].cs.md.fault, 28);
    CHECK_EQ(pi_word(0) & 0x0020u, 0x0020u);
    CHECK_BYTES(rig.master.slaves[0].last_diag, rig.master.slaves[0].last_diag_len, 0x00, 0x0C,
                0x00, 0x02, 0x60, 0x03);
}

/* A parameter of the emulated drive behind the card, -1 if it cannot be read. */
static int32_t drive_value(uint16_t index)
{
    int32_t v = -1;
    CHECK(movidrive_read_value(&rig.cards[0].cs.md, index, &v));
    return v;
}

static int32_t p819(void) { return drive_value(MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT); }

/* protocol.md §B5: P819 shows the master's watchdog time; written through another interface it is
 * shown until the next parameterisation. Global_Control and the other DP events in between also
 * reach the drive as fieldbus status (P090..P093) and must not bring the old value back. */
static void test_p819_written_elsewhere_stays_until_next_set_prm(void)
{
    setup(0, 0x01);
    CHECK_EQ(p819(), 50);
    start(ML_SVC_WRITE_VOLATILE, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT, 300);
    CHECK(finish(100000) != UINT32_MAX);
    CHECK_EQ(inputs()[0] & ML_MGMT_ERROR, 0);
    CHECK_EQ(p819(), 300);
    unsigned gc_before = scn.gc_events;
    dp_master_global_control(&rig.master, DP_GC_CLEAR_DATA, 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(scn.gc_events, gc_before + 1u);
    CHECK_EQ(p819(), 300);
    /* The master parameterises again with the same 50 ms: that overwrites it. */
    dp_master_slave_cfg_t sc = rig.master.slaves[0].cfg;
    CHECK_EQ(dp_master_reconfigure(&rig.master, 0, &sc, membus_now_us(&rig.bus)), 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    CHECK_EQ(p819(), 50);
}

/* protocol.md §B9: with the DIP switches above 125 the card stays off the bus, and the manual's
 * first diagnosis step is to read P093 on the drive: it must show that address. */
static void test_address_above_125_shown_in_p093(void)
{
    card_options_t co = {.address = 126, .fixed_baud = 1500000, .inverter = CARD_INVERTER_SIM};
    rig_with_card(&co, 0);
    membus_run_for_us(&rig.bus, 10000);
    CHECK(!rig.cards[0].cs.card.on_bus);
    CHECK_EQ(drive_value(8454), 126); /* P093 */
    CHECK_EQ(drive_value(8452), 5);   /* P091: PROFIBUS DP */
    CHECK_EQ(drive_value(8453), 0);   /* P092: no rate heard */
    /* No master ever parameterised the card: the drive keeps its own P819 (CSV default). */
    CHECK_EQ(p819(), 500);
}

/* A power cycle restarts the card with an empty input image while its drive runs on: once the
 * master has it in Data_Exch again, the PI words are the drive's, even though the drive's
 * words did not change meanwhile (the in-process link hands over only changed words, and must
 * hand over all of them to a card that forgot them). */
static void test_power_cycled_card_gets_the_drives_pi_again(void)
{
    setup(0, 0x01);
    membus_run_for_us(&rig.bus, 5000);
    uint16_t before[3];
    movidrive_process_inputs(&rig.cards[0].cs.md, before, 3);
    CHECK(before[0] != 0u);
    CHECK_EQ(pi_word(0), before[0]);
    rig_card_power_cycle(&rig.cards[0], rig_now_us(&rig));
    CHECK_EQ(rig.cards[0].cs.card.pi[0], 0u); /* the restarted card has forgotten them */
    membus_run_for_us(&rig.bus, 50000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    uint16_t after[3];
    movidrive_process_inputs(&rig.cards[0].cs.md, after, 3);
    CHECK_EQ(after[0], before[0]);
    for (unsigned i = 0; i < 3u; i++) {
        CHECK_EQ(pi_word(i), after[i]);
    }
}

/* Regression: deadlines that started at 0 never came due once the clock was past 2^31 us. */
static void test_everything_works_after_35_minutes_of_uptime(void)
{
    start_ns = 0x90000000ull * 1000u; /* 2415 s */
    test_read_8300_through_the_cyclic_channel();
    test_fieldbus_timeout_fault_ext_diag_and_reset();
    start_ns = 0;
}

int main(void)
{
    RUN_TEST(test_read_8300_through_the_cyclic_channel);
    RUN_TEST(test_slow_inverter_keeps_old_reply_and_exchange_running);
    RUN_TEST(test_write_executes_exactly_once);
    RUN_TEST(test_inverter_error_and_card_error);
    RUN_TEST(test_inverter_not_answering_gives_6_2);
    RUN_TEST(test_process_data_ramp_and_status_word);
    RUN_TEST(test_fieldbus_timeout_fault_ext_diag_and_reset);
    RUN_TEST(test_no_ext_diag_with_alarm_off);
    RUN_TEST(test_p819_written_elsewhere_stays_until_next_set_prm);
    RUN_TEST(test_address_above_125_shown_in_p093);
    RUN_TEST(test_power_cycled_card_gets_the_drives_pi_again);
    RUN_TEST(test_everything_works_after_35_minutes_of_uptime);
    return check_report();
}
