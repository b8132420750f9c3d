/* The LCM telemetry bridge over memq:// (messages are delivered in lcm_handle on this thread):
 * every field of each message type as a subscriber decodes it, the card-state throttle, and the
 * parameter-service observer of card_station with master, card and emulated MOVIDRIVE on the
 * in-memory bus (a write through the cyclic channel is exactly one message). */
#include <lcm/lcm.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dfp_lcm/dfp_lcm_card_state_t.h"
#include "dfp_lcm/dfp_lcm_param_service_t.h"
#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "lcm_bridge/lcm_bridge.h"
#include "lcm_bridge/telegram_decode.h"
#include "dp_master/param_channel.h"
#include "rig/rig.h"

/* ---- what the subscriber received ---------------------------------------------------------- */

#define MAX_GOT 64

static struct {
    int telegrams;
    dfp_lcm_telegram_t telegram; /* the last one, data copied below */
    uint8_t telegram_data[64];
    int states;
    dfp_lcm_card_state_t state;
    char state_strings[5][32];
    int32_t po[10];
    int32_t pi[10];
    int params;
    dfp_lcm_param_service_t param[MAX_GOT];
    char param_strings[MAX_GOT][3][96];
} got;

static void on_telegram(const lcm_recv_buf_t *rbuf, const char *channel,
                        const dfp_lcm_telegram_t *msg, void *user)
{
    (void)rbuf;
    (void)user;
    CHECK_STR(channel, DFP_LCM_CH_TELEGRAM);
    got.telegrams++;
    got.telegram = *msg;
    size_t n = msg->length > 0 && (size_t)msg->length <= sizeof got.telegram_data
                   ? (size_t)msg->length
                   : 0u;
    memcpy(got.telegram_data, msg->data, n);
    got.telegram.data = got.telegram_data;
}

static void keep(char *dst, const char *src)
{
    snprintf(dst, 32, "%s", src);
}

static void on_state(const lcm_recv_buf_t *rbuf, const char *channel,
                     const dfp_lcm_card_state_t *msg, void *user)
{
    (void)rbuf;
    (void)user;
    CHECK_STR(channel, DFP_LCM_CH_CARD_STATE);
    got.states++;
    got.state = *msg;
    keep(got.state_strings[0], msg->dp_state);
    keep(got.state_strings[1], msg->led_run);
    keep(got.state_strings[2], msg->led_bus_fault);
    keep(got.state_strings[3], msg->p090_pd_config);
    keep(got.state_strings[4], msg->p091_fieldbus_type);
    got.state.dp_state = got.state_strings[0];
    got.state.led_run = got.state_strings[1];
    got.state.led_bus_fault = got.state_strings[2];
    got.state.p090_pd_config = got.state_strings[3];
    got.state.p091_fieldbus_type = got.state_strings[4];
    for (int i = 0; i < msg->pd_words && i < 10; i++) {
        got.po[i] = msg->po[i];
        got.pi[i] = msg->pi[i];
    }
    got.state.po = got.po;
    got.state.pi = got.pi;
}

static void on_param(const lcm_recv_buf_t *rbuf, const char *channel,
                     const dfp_lcm_param_service_t *msg, void *user)
{
    (void)rbuf;
    (void)user;
    CHECK_STR(channel, DFP_LCM_CH_PARAM);
    if (got.params >= MAX_GOT) {
        got.params++;
        return;
    }
    int k = got.params++;
    got.param[k] = *msg;
    snprintf(got.param_strings[k][0], 96, "%s", msg->path);
    snprintf(got.param_strings[k][1], 96, "%s", msg->service);
    snprintf(got.param_strings[k][2], 96, "%s", msg->result_text);
    got.param[k].path = got.param_strings[k][0];
    got.param[k].service = got.param_strings[k][1];
    got.param[k].result_text = got.param_strings[k][2];
}

static dfp_lcm_bridge_t bridge;
static dfp_lcm_telegram_t_subscription_t *sub_telegram;
static dfp_lcm_card_state_t_subscription_t *sub_state;
static dfp_lcm_param_service_t_subscription_t *sub_param;

static void open_bridge(int16_t station)
{
    memset(&got, 0, sizeof got);
    char err[320];
    CHECK_EQ(dfp_lcm_bridge_open(&bridge, "memq://", station, err, sizeof err), 0);
    CHECK(bridge.lcm != NULL);
    CHECK(bridge.source_id > 0);
    sub_telegram = dfp_lcm_telegram_t_subscribe(bridge.lcm, DFP_LCM_CH_TELEGRAM, on_telegram,
                                                NULL);
    sub_state = dfp_lcm_card_state_t_subscribe(bridge.lcm, DFP_LCM_CH_CARD_STATE, on_state, NULL);
    sub_param = dfp_lcm_param_service_t_subscribe(bridge.lcm, DFP_LCM_CH_PARAM, on_param, NULL);
}

static void close_bridge(void)
{
    dfp_lcm_telegram_t_unsubscribe(bridge.lcm, sub_telegram);
    dfp_lcm_card_state_t_unsubscribe(bridge.lcm, sub_state);
    dfp_lcm_param_service_t_unsubscribe(bridge.lcm, sub_param);
    dfp_lcm_bridge_close(&bridge);
    CHECK(bridge.lcm == NULL);
}

static void deliver(void)
{
    while (lcm_handle_timeout(bridge.lcm, 0) > 0) {
    }
}

/* ---- telegram_t ------------------------------------------------------------------------------ */

static void test_telegram_fields(void)
{
    open_bridge(4);
    const uint8_t req[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
    CHECK_EQ(dfp_lcm_bridge_telegram(&bridge, 1700000000123456LL, req, sizeof req, false, 1500000,
                                     HAL_UART_RX_PARITY_ERR),
             0);
    deliver();
    CHECK_EQ(got.telegrams, 1);
    CHECK_EQ(got.telegram.utime, 1700000000123456LL);
    CHECK_EQ(got.telegram.source_id, bridge.source_id);
    CHECK_EQ(got.telegram.process_id, getpid());
    CHECK_EQ(got.telegram.station, 4);
    CHECK_EQ(got.telegram.direction, DFP_LCM_TELEGRAM_T_DIR_RX);
    CHECK_EQ(got.telegram.baud, 1500000);
    CHECK_EQ(got.telegram.error_flags, DFP_LCM_TELEGRAM_T_ERR_PARITY);
    CHECK_BYTES(got.telegram.data, got.telegram.length, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);

    const uint8_t sc[] = {0xE5};
    CHECK_EQ(dfp_lcm_bridge_telegram(&bridge, 1700000000123789LL, sc, 1, true, 19200, 0), 0);
    deliver();
    CHECK_EQ(got.telegrams, 2);
    CHECK_EQ(got.telegram.direction, DFP_LCM_TELEGRAM_T_DIR_TX);
    CHECK_EQ(got.telegram.baud, 19200);
    CHECK_EQ(got.telegram.error_flags, 0);
    CHECK_BYTES(got.telegram.data, got.telegram.length, 0xE5);
    CHECK_EQ(bridge.messages, 2);
    CHECK_EQ(bridge.failures, 0);
    close_bridge();
}

/* The encoded layout the log reader relies on (DFP_LCM_TELEGRAM_FIXED), and the checked
 * decoder refusing what lcm-gen's decoder would copy gigabytes for. */
static void test_telegram_layout_and_checked_decode(void)
{
    uint8_t data[6] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
    dfp_lcm_telegram_t m = {.utime = 1, .source_id = 2, .process_id = 3, .station = 4,
                            .direction = 1, .baud = 9600, .error_flags = 0, .length = 6,
                            .data = data};
    uint8_t buf[128];
    int n = dfp_lcm_telegram_t_encode(buf, 0, sizeof buf, &m);
    CHECK_EQ(n, DFP_LCM_TELEGRAM_FIXED + 6);
    CHECK_EQ(buf[DFP_LCM_TELEGRAM_FIXED - 2u], 0x00); /* length, big-endian */
    CHECK_EQ(buf[DFP_LCM_TELEGRAM_FIXED - 1u], 0x06);
    CHECK_EQ(buf[DFP_LCM_TELEGRAM_FIXED], 0x10);
    dfp_lcm_telegram_t out;
    char why[96];
    CHECK_EQ(dfp_lcm_telegram_decode_checked(buf, (size_t)n, &out, why, sizeof why), 0);
    CHECK_EQ(out.baud, 9600);
    CHECK_BYTES(out.data, out.length, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    dfp_lcm_telegram_t_decode_cleanup(&out);

    buf[DFP_LCM_TELEGRAM_FIXED - 2u] = 0xFF; /* length -3 */
    buf[DFP_LCM_TELEGRAM_FIXED - 1u] = 0xFD;
    CHECK_EQ(dfp_lcm_telegram_decode_checked(buf, (size_t)n, &out, why, sizeof why), -1);
    CHECK_STR(why, "telegram_t length field -3");
    buf[DFP_LCM_TELEGRAM_FIXED - 2u] = 0x00;
    buf[DFP_LCM_TELEGRAM_FIXED - 1u] = 0x07; /* one more than there is */
    CHECK_EQ(dfp_lcm_telegram_decode_checked(buf, (size_t)n, &out, why, sizeof why), -1);
    CHECK_STR(why, "telegram_t of 45 octets, its length field 7 needs 46");
    CHECK_EQ(dfp_lcm_telegram_decode_checked(buf, 20, &out, why, sizeof why), -1);
    CHECK_STR(why, "telegram_t cut short: 20 of at least 39 octets");
    buf[0] ^= 1u;
    CHECK_EQ(dfp_lcm_telegram_decode_checked(buf, (size_t)n, &out, why, sizeof why), -1);
    CHECK_STR(why, "not a dfp_lcm.telegram_t (other fingerprint)");
}

/* ---- the card on the in-memory bus ----------------------------------------------------------- */

/* What the test drives the master with; the bus, the card and the master are in the rig. */
static struct {
    uint8_t out[14];
    dp_master_param_t param;
} drv;

static rig_t rig; /* large: keep it off the stack */
#define RIG_EPOCH_US 1700000000000000LL

static int64_t rig_clock(void *ctx)
{
    (void)ctx;
    return RIG_EPOCH_US + (int64_t)(rig.bus.now_ns / 1000u);
}

static void observe_param(void *ctx, unsigned card, uint8_t channel,
                          const uint8_t req[ML_TELEGRAM_LEN], const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)card;
    dfp_lcm_bridge_param_observer(ctx, channel, req, rsp);
}

/* Card 4 first, then master 2: the order the bus polls them in, which the timings rest on. */
static void setup(card_inverter_t inverter)
{
    memset(&drv, 0, sizeof drv);
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS};
    rig_init(&rig, &rc);
    rig_tap_t tap = {.ctx = &bridge, .param = observe_param};
    (void)rig_add_tap(&rig, &tap);
    card_options_t co = {.address = 4, .fixed_baud = 1500000, .strict_timing = true,
                         .inverter = inverter};
    bridge.clock = rig_clock;
    char err[256] = "no room for the card on the bus"; /* rig_open overwrites it on failure */
    rig_card_t *card = rig_open(&rig, err, sizeof err) == 0
                           ? rig_add_card(&rig, &co, membus_now_us(&rig.bus))
                           : NULL;
    /* The note is empty unless card_station_init failed. */
    CHECK_STR(card != NULL ? card->nvm_note : err, "");
    dp_master_cfg_t mc = {.address = 2, .baud = 1500000, .strict_timing = true,
                          .cycle_us = 2000};
    (void)rig_add_master(&rig, &mc, membus_now_us(&rig.bus));
    dp_master_slave_cfg_t sc = {.address = 4};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 50, dfp21b_user_prm_default,
                                        sizeof dfp21b_user_prm_default);
    sc.cfg[0] = 0xF3; /* Param + 3 PD */
    sc.cfg[1] = 0xF2;
    sc.cfg_len = 2;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
}

static void set_po(uint16_t a, uint16_t b, uint16_t c)
{
    const uint16_t w[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        drv.out[8 + 2 * i] = (uint8_t)(w[i] >> 8);
        drv.out[9 + 2 * i] = (uint8_t)w[i];
    }
    dp_master_set_outputs(&rig.master, 0, drv.out, sizeof drv.out);
}

static void test_card_state_fields_and_throttle(void)
{
    open_bridge(4);
    setup(CARD_INVERTER_NONE); /* PI words echo the PO words */
    set_po(0x0006, 0x05DC, 0xFFFF);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(dfp_lcm_bridge_card_state(&bridge, rig_clock(NULL), &rig.cards[0].cs.card), 1);
    deliver();
    CHECK_EQ(got.states, 1);
    const dfp_lcm_card_state_t *s = &got.state;
    CHECK_EQ(s->utime, rig_clock(NULL));
    CHECK_EQ(s->source_id, bridge.source_id);
    CHECK_EQ(s->address, 4);
    CHECK_STR(s->dp_state, "Data_Exch");
    CHECK_EQ(s->dp_state_num, DFP_LCM_CARD_STATE_T_DP_DATA_EXCH);
    CHECK_STR(s->led_run, "on");
    CHECK_EQ(s->led_run_mode, DFP_LCM_CARD_STATE_T_LED_ON);
    CHECK_STR(s->led_bus_fault, "off");
    CHECK_EQ(s->led_bus_fault_mode, DFP_LCM_CARD_STATE_T_LED_OFF);
    CHECK_EQ(s->baud, 1500000);
    CHECK_STR(s->p090_pd_config, "3PD + PARAM");
    CHECK_STR(s->p091_fieldbus_type, "PROFIBUS DP");
    CHECK_EQ(s->p092_baud, 1500000);
    CHECK_EQ(s->p093_address, 4);
    CHECK_EQ(s->p094_po1, 0x0006);
    CHECK_EQ(s->p095_po2, 0x05DC);
    CHECK_EQ(s->p096_po3, 0xFFFF);
    CHECK_EQ(s->p097_pi1, 0x0006);
    CHECK_EQ(s->p098_pi2, 0x05DC);
    CHECK_EQ(s->p099_pi3, 0xFFFF);
    CHECK_EQ(s->p819_timeout_ms, 50);
    CHECK_EQ(s->param_channel, 1);
    CHECK_EQ(s->pd_words, 3);
    CHECK_EQ(s->po[0], 0x0006);
    CHECK_EQ(s->po[2], 0xFFFF);
    CHECK_EQ(s->pi[1], 0x05DC);

    /* Unchanged: nothing. Changed within 100 ms: held back, then published. */
    membus_run_for_us(&rig.bus, 5000);
    CHECK_EQ(dfp_lcm_bridge_card_state(&bridge, rig_clock(NULL), &rig.cards[0].cs.card), 0);
    CHECK(!bridge.state_pending);
    set_po(0x0007, 0x05DC, 0xFFFF);
    membus_run_for_us(&rig.bus, 10000);
    CHECK_EQ(dfp_lcm_bridge_card_state(&bridge, rig_clock(NULL), &rig.cards[0].cs.card), 0);
    CHECK(bridge.state_pending);
    membus_run_for_us(&rig.bus, 90000);
    CHECK_EQ(dfp_lcm_bridge_card_state(&bridge, rig_clock(NULL), &rig.cards[0].cs.card), 1);
    CHECK(!bridge.state_pending);
    deliver();
    CHECK_EQ(got.states, 2);
    CHECK_EQ(got.state.p094_po1, 0x0007);
    CHECK_EQ(got.state.p097_pi1, 0x0007);
    close_bridge();
}

static uint32_t run_service(uint8_t service, uint16_t index, uint32_t value)
{
    dp_master_param_start(&drv.param, service, index, value, drv.out);
    dp_master_set_outputs(&rig.master, 0, drv.out, sizeof drv.out);
    for (uint32_t t = 0; t < 200000u; t += 500u) {
        if (dp_master_param_done(&drv.param, rig.master.slaves[0].inputs)) {
            return t;
        }
        membus_run_for_us(&rig.bus, 500u);
    }
    return UINT32_MAX;
}

static void test_param_observer_one_message_per_service(void)
{
    open_bridge(4);
    setup(CARD_INVERTER_SIM);
    deliver();
    got.params = 0; /* nothing ran yet; the card's status poll is off (user prm octet 8 = 01) */

    CHECK(run_service(ML_SVC_WRITE, 8489, 300000) != UINT32_MAX);
    /* The request keeps arriving with the same handshake: still one service. */
    membus_run_for_us(&rig.bus, 100000);
    deliver();
    CHECK_EQ(got.params, 1);
    const dfp_lcm_param_service_t *p = &got.param[0];
    CHECK_EQ(p->source_id, bridge.source_id);
    CHECK_EQ(p->address, 4);
    CHECK_STR(p->path, "channel");
    CHECK_EQ(p->link_channel, 0);
    CHECK_EQ(p->index, 8489);
    CHECK_EQ(p->subindex, 0);
    CHECK_STR(p->service, "write");
    CHECK_EQ(p->service_num, ML_SVC_WRITE);
    CHECK_EQ(p->value, 300000);
    CHECK_EQ(p->ok, 1);
    CHECK_EQ(p->result, 0);
    CHECK_STR(p->result_text, "");
    /* The handshake bit is cleared towards the inverter (it would select sync mode on SBus). */
    CHECK_BYTES(p->request, 8, 0x32, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0);
    CHECK_BYTES(p->response, 8, 0x32, 0x00, 0x21, 0x29, 0x00, 0x04, 0x93, 0xE0);
    CHECK(p->utime > RIG_EPOCH_US + 20000 && p->utime <= rig_clock(NULL));

    CHECK(run_service(ML_SVC_WRITE_VOLATILE, 8517, 99000000u) != UINT32_MAX);
    CHECK(run_service(ML_SVC_READ, 8300, 0) != UINT32_MAX);
    deliver();
    CHECK_EQ(got.params, 3);
    p = &got.param[1];
    CHECK_STR(p->service, "write volatile");
    CHECK_EQ(p->index, 8517);
    CHECK_EQ(p->value, 99000000);
    CHECK_EQ(p->ok, 0);
    CHECK_EQ(p->result, 0x08000015);
    CHECK_STR(p->result_text, "class 8, additional code 0x15: value too high");
    CHECK_BYTES(p->response, 8, 0xB3, 0x00, 0x21, 0x45, 0x08, 0x00, 0x00, 0x15);
    p = &got.param[2];
    CHECK_STR(p->service, "read");
    CHECK_EQ(p->index, 8300);
    CHECK_EQ(p->value, 0x311C7289); /* P076 firmware, the value read */
    CHECK_EQ(p->ok, 1);

    /* A request the card answers itself (reserved octet not 0) never reaches the inverter. */
    dp_master_param_start(&drv.param, ML_SVC_READ, 8300, 0, drv.out);
    drv.out[1] = 0x01;
    dp_master_set_outputs(&rig.master, 0, drv.out, sizeof drv.out);
    membus_run_for_us(&rig.bus, 50000);
    CHECK(dp_master_param_done(&drv.param, rig.master.slaves[0].inputs));
    deliver();
    CHECK_EQ(got.params, 3);
    CHECK_EQ(bridge.failures, 0);
    close_bridge();
}

static void test_paths_and_bad_url(void)
{
    CHECK_STR(dfp_lcm_param_path(0), "channel");
    CHECK_STR(dfp_lcm_param_path(1), "c1-ds47");
    CHECK_STR(dfp_lcm_param_path(2), "c2-ds47-1");
    CHECK_STR(dfp_lcm_param_path(3), "c2-ds47-2");
    CHECK_STR(dfp_lcm_param_path(4), "status-poll");
    CHECK_STR(dfp_lcm_param_path(5), "?");
    dfp_lcm_bridge_t b;
    char err[320];
    CHECK_EQ(dfp_lcm_bridge_open(&b, "nosuchprovider://x", 4, err, sizeof err), -1);
    CHECK_STR(err, "cannot open LCM URL 'nosuchprovider://x'");
    /* A closed bridge refuses quietly instead of crashing the card's loop. */
    CHECK_EQ(dfp_lcm_bridge_telegram(&b, 0, (const uint8_t[]){0xE5}, 1, true, 9600, 0), -1);
}

int main(void)
{
    RUN_TEST(test_telegram_fields);
    RUN_TEST(test_telegram_layout_and_checked_decode);
    RUN_TEST(test_card_state_fields_and_throttle);
    RUN_TEST(test_param_observer_one_message_per_service);
    RUN_TEST(test_paths_and_bad_url);
    return check_report();
}
