/* SBus (movilink/sbus.h) at its edges, on a fake CAN that records frames and can refuse to send:
 * PD frames of odd lengths, frames too short for their identifier, send failures on both sides,
 * a card channel out of range, the default parameter timeout, callbacks left NULL, channel-2
 * identifiers when channel 2 is off, and the inverter's SBus timeout without a callback.
 * tests/sbus covers the normal traffic byte for byte on the in-memory bus. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "hal/hal_time.h"
#include "movilink/movilink_wire.h"
#include "movilink/sbus.h"

#define ADDR 5u

typedef struct fake_can {
    hal_can_frame_t sent[16];
    size_t n;
    bool refuse; /* send() fails (bus off) */
} fake_can_t;

static int fake_send(void *ctx, const hal_can_frame_t *f)
{
    fake_can_t *c = ctx;
    if (c->refuse) {
        return -1;
    }
    if (c->n < sizeof c->sent / sizeof c->sent[0]) {
        c->sent[c->n++] = *f;
    }
    return 0;
}

static const hal_can_ops_t fake_ops = {.send = fake_send};

static hal_can_frame_t frame(uint16_t id, uint8_t len, const uint8_t *data)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    if (len > 0u) {
        memcpy(f.data, data, len);
    }
    return f;
}

typedef struct card_probe {
    uint8_t rsp[4][ML_TELEGRAM_LEN];
    uint8_t channel[4];
    size_t n_rsp;
    uint16_t pi[SBUS_PD_WORDS];
    uint8_t n_pi;
    size_t pi_calls;
} card_probe_t;

static void on_response(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    card_probe_t *p = card;
    if (p->n_rsp < 4u) {
        memcpy(p->rsp[p->n_rsp], rsp, ML_TELEGRAM_LEN);
        p->channel[p->n_rsp] = channel;
    }
    p->n_rsp++;
}

static void on_inputs(void *card, const uint16_t *pi, uint8_t n)
{
    card_probe_t *p = card;
    memcpy(p->pi, pi, sizeof p->pi);
    p->n_pi = n;
    p->pi_calls++;
}

/* A MOVILINK read request of index idx (management: read service, byte 1 subindex). */
static void read_req(uint8_t t[ML_TELEGRAM_LEN], uint16_t idx)
{
    memset(t, 0, ML_TELEGRAM_LEN);
    t[ML_OFF_MANAGEMENT] = ML_SVC_READ;
    t[ML_OFF_INDEX_HIGH] = (uint8_t)(idx >> 8);
    t[ML_OFF_INDEX_LOW] = (uint8_t)(idx & 0xFFu);
}

static void test_pd_packing(void)
{
    hal_can_frame_t f;
    const uint16_t five[5] = {0x1122, 0x3344, 0x5566, 0x7788, 0x99AA};
    sbus_pack_pd(&f, sbus_id_po(ADDR), five, 5); /* n > 3 is cut */
    CHECK_EQ(f.len, 6);
    CHECK_BYTES(f.data, 8, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x00, 0x00);
    sbus_pack_pd(&f, sbus_id_po(ADDR), five, 1); /* n < 3 pads with 0 */
    CHECK_EQ(f.len, 6);
    CHECK_BYTES(f.data, 6, 0x11, 0x22, 0x00, 0x00, 0x00, 0x00);

    uint16_t w[SBUS_PD_WORDS];
    const uint8_t eight[8] = {0xA1, 0xA2, 0xB1, 0xB2, 0xC1, 0xC2, 0xD1, 0xD2};
    f = frame(sbus_id_pi(ADDR), 8, eight); /* 4 words on the wire: at most 3 */
    CHECK_EQ(sbus_unpack_pd(&f, w), 3);
    CHECK_EQ(w[0], 0xA1A2);
    CHECK_EQ(w[1], 0xB1B2);
    CHECK_EQ(w[2], 0xC1C2);
    f = frame(sbus_id_pi(ADDR), 3, eight); /* an odd octet is not a word */
    CHECK_EQ(sbus_unpack_pd(&f, w), 1);
    CHECK_EQ(w[0], 0xA1A2);
    CHECK_EQ(w[1], 0);
    CHECK_EQ(w[2], 0);
}

static void card_init(sbus_card_link_t *l, fake_can_t *can, card_probe_t *p, uint32_t timeout_us)
{
    memset(can, 0, sizeof *can);
    memset(p, 0, sizeof *p);
    sbus_card_link_cfg_t cfg = {.can = {.ops = &fake_ops, .ctx = can},
                                .address = ADDR,
                                .timeout_us = timeout_us,
                                .param_response = on_response,
                                .process_inputs = on_inputs,
                                .card = p};
    sbus_card_link_init(l, &cfg);
}

static void test_card_rejects(void)
{
    sbus_card_link_t l;
    fake_can_t can;
    card_probe_t p;
    card_init(&l, &can, &p, 0);
    ml_link_t link = sbus_card_link(&l);
    uint8_t req[ML_TELEGRAM_LEN];
    read_req(req, 8318);

    /* A card channel that does not exist. */
    CHECK(link.ops->param_request(link.ctx, (uint8_t)ML_MAX_CHANNELS, req) < 0);
    CHECK_EQ(can.n, 0);

    /* The CAN refuses: the request is refused at once and nothing is outstanding. */
    can.refuse = true;
    CHECK(link.ops->param_request(link.ctx, 0, req) < 0);
    CHECK_EQ(l.send_errors, 1);
    CHECK_EQ(l.requests_sent, 0);
    const uint16_t po[3] = {1, 2, 3};
    link.ops->process_outputs(link.ctx, po, 3);
    CHECK_EQ(l.send_errors, 2);
    CHECK_EQ(l.po_frames, 0);

    /* No CAN at all behaves the same. */
    sbus_card_link_cfg_t none = {.address = ADDR};
    sbus_card_link_init(&l, &none);
    link = sbus_card_link(&l);
    CHECK(link.ops->param_request(link.ctx, 0, req) < 0);
    CHECK_EQ(l.send_errors, 1);
}

static void test_card_default_timeout(void)
{
    sbus_card_link_t l;
    fake_can_t can;
    card_probe_t p;
    card_init(&l, &can, &p, 0); /* 0 = SBUS_PARAM_TIMEOUT_US */
    CHECK_EQ(l.cfg.timeout_us, SBUS_PARAM_TIMEOUT_US);
    ml_link_t link = sbus_card_link(&l);
    uint8_t req[ML_TELEGRAM_LEN];
    read_req(req, 8318);
    CHECK_EQ(link.ops->param_request(link.ctx, 0, req), 0);
    CHECK_EQ(can.n, 1);
    CHECK_EQ(can.sent[0].id, sbus_id_param_req(ADDR));
    /* The deadline starts at the first poll after sending. */
    CHECK_EQ(sbus_card_link_poll(&l, 1000), 1000u + SBUS_PARAM_TIMEOUT_US);
    CHECK_EQ(sbus_card_link_poll(&l, 1000u + SBUS_PARAM_TIMEOUT_US - 1u),
             1000u + SBUS_PARAM_TIMEOUT_US);
    CHECK_EQ(l.timeouts, 0);
    hal_time_us_t t = 1000u + SBUS_PARAM_TIMEOUT_US;
    CHECK_EQ(sbus_card_link_poll(&l, t), t + HAL_TIME_NO_DEADLINE_US);
    CHECK_EQ(l.timeouts, 1);
}

static void test_card_bad_frames(void)
{
    sbus_card_link_t l;
    fake_can_t can;
    card_probe_t p;
    card_init(&l, &can, &p, 50000);
    const uint8_t d[8] = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF0};

    hal_can_frame_t f = frame(sbus_id_pi(ADDR), 1, d); /* shorter than one word */
    sbus_card_link_rx(&l, &f, 0);
    CHECK_EQ(l.bad_frames, 1);
    CHECK_EQ(l.pi_frames, 0);
    CHECK_EQ(p.pi_calls, 0);

    f = frame(sbus_id_pi(ADDR), 8, d);
    sbus_card_link_rx(&l, &f, 0);
    CHECK_EQ(l.pi_frames, 1);
    CHECK_EQ(p.pi_calls, 1);
    CHECK_EQ(p.n_pi, 3);
    CHECK_EQ(p.pi[2], 0x9ABC);

    /* A parameter response of the wrong length. */
    f = frame(sbus_id_param_rsp(ADDR), 7, d);
    sbus_card_link_rx(&l, &f, 0);
    CHECK_EQ(l.bad_frames, 2);
    CHECK_EQ(p.n_rsp, 0);

    /* Channel 2 is off: its response identifier is somebody else's. */
    f = frame(sbus_id_param2_rsp(ADDR), 8, d);
    sbus_card_link_rx(&l, &f, 0);
    CHECK_EQ(l.bad_frames, 2);
    CHECK_EQ(l.stale_responses, 0);
    CHECK_EQ(p.n_rsp, 0);

    /* No process_inputs: the PI frame is counted and dropped. */
    l.cfg.process_inputs = NULL;
    f = frame(sbus_id_pi(ADDR), 6, d);
    sbus_card_link_rx(&l, &f, 0);
    CHECK_EQ(l.pi_frames, 2);
    CHECK_EQ(p.pi_calls, 1);
}

static void test_card_queued_send_fails(void)
{
    sbus_card_link_t l;
    fake_can_t can;
    card_probe_t p;
    card_init(&l, &can, &p, 50000);
    ml_link_t link = sbus_card_link(&l);
    uint8_t a[ML_TELEGRAM_LEN];
    uint8_t b[ML_TELEGRAM_LEN];
    read_req(a, 8318);
    read_req(b, 8319);
    CHECK_EQ(link.ops->param_request(link.ctx, 0, a), 0); /* on the wire */
    CHECK_EQ(link.ops->param_request(link.ctx, 1, b), 0); /* waits: same SBus channel */
    CHECK_EQ(can.n, 1);

    /* The answer to a arrives while the CAN is refusing: b cannot be sent and is answered
     * with class 6 code 2 (card <-> inverter communication), after a's answer is passed on. */
    can.refuse = true;
    uint8_t ans[ML_TELEGRAM_LEN];
    memcpy(ans, a, sizeof ans);
    ans[7] = 0x2A;
    hal_can_frame_t f = frame(sbus_id_param_rsp(ADDR), 8, ans);
    sbus_card_link_rx(&l, &f, 10);
    CHECK_EQ(l.responses, 1);
    CHECK_EQ(l.send_errors, 1);
    CHECK_EQ(p.n_rsp, 2);
    CHECK_EQ(p.channel[0], 1); /* b's refusal comes first: it happens inside send_next */
    CHECK_EQ(p.rsp[0][ML_OFF_MANAGEMENT] & ML_MGMT_ERROR, ML_MGMT_ERROR);
    CHECK_EQ(p.rsp[0][4], 6);
    CHECK_EQ(p.rsp[0][5], 2);
    CHECK_EQ(p.rsp[0][ML_OFF_INDEX_LOW], 8319u & 0xFFu);
    CHECK_EQ(p.channel[1], 0);
    CHECK_EQ(p.rsp[1][7], 0x2A);
    CHECK(!l.out[0].busy);

    /* Without a param_response callback, answers and refusals are dropped quietly. */
    can.refuse = false;
    l.cfg.param_response = NULL;
    CHECK_EQ(link.ops->param_request(link.ctx, 0, a), 0);
    CHECK_EQ(link.ops->param_request(link.ctx, 1, b), 0);
    can.refuse = true;
    sbus_card_link_rx(&l, &f, 20);
    CHECK_EQ(l.responses, 2);
    CHECK_EQ(l.send_errors, 2);
    CHECK_EQ(p.n_rsp, 2);
}

static void test_inverter_edges(void)
{
    fake_can_t can;
    memset(&can, 0, sizeof can);
    sbus_inverter_t inv;
    sbus_inverter_cfg_t cfg = {.can = {.ops = &fake_ops, .ctx = &can}, .address = ADDR,
                               .timeout_us = 0};
    sbus_inverter_init(&inv, &cfg);
    const uint8_t d[8] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08};

    /* No callbacks: the request is echoed, PO is answered with zero PI words. */
    hal_can_frame_t f = frame(sbus_id_param_req(ADDR), 8, d);
    sbus_inverter_rx(&inv, &f, 0);
    CHECK_EQ(inv.requests, 1);
    CHECK_EQ(can.n, 1);
    CHECK_EQ(can.sent[0].id, sbus_id_param_rsp(ADDR));
    CHECK_BYTES(can.sent[0].data, can.sent[0].len, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08);
    f = frame(sbus_id_po(ADDR), 6, d);
    sbus_inverter_rx(&inv, &f, 0);
    CHECK_EQ(inv.po_frames, 1);
    CHECK_EQ(can.n, 2);
    CHECK_EQ(can.sent[1].id, sbus_id_pi(ADDR));
    CHECK_BYTES(can.sent[1].data, can.sent[1].len, 0, 0, 0, 0, 0, 0);

    /* Frames too short or too long for their identifier; channel 2 when it is off. */
    f = frame(sbus_id_param_req(ADDR), 6, d);
    sbus_inverter_rx(&inv, &f, 0);
    f = frame(sbus_id_po(ADDR), 1, d);
    sbus_inverter_rx(&inv, &f, 0);
    CHECK_EQ(inv.bad_frames, 2);
    f = frame(sbus_id_param2_req(ADDR), 8, d);
    sbus_inverter_rx(&inv, &f, 0);
    CHECK_EQ(inv.requests, 1);
    CHECK_EQ(can.n, 2);

    /* Timeout off (P815 = 0): no deadline, ever. */
    CHECK_EQ(sbus_inverter_poll(&inv, 5000000), 5000000u + HAL_TIME_NO_DEADLINE_US);
    CHECK(!inv.timed_out);

    /* Send errors on both answers. */
    can.refuse = true;
    f = frame(sbus_id_param_req(ADDR), 8, d);
    sbus_inverter_rx(&inv, &f, 0);
    f = frame(sbus_id_po(ADDR), 6, d);
    sbus_inverter_rx(&inv, &f, 0);
    CHECK_EQ(inv.send_errors, 2);

    /* Timeout on, no timeout callback: the state still changes and recovers with PO. */
    inv.cfg.timeout_us = 100000;
    f = frame(sbus_id_po(ADDR), 6, d);
    sbus_inverter_rx(&inv, &f, 1000);
    CHECK_EQ(sbus_inverter_poll(&inv, 2000), 101000u);
    CHECK_EQ(sbus_inverter_poll(&inv, 101000), 101000u + HAL_TIME_NO_DEADLINE_US);
    CHECK(inv.timed_out);
    CHECK_EQ(sbus_inverter_poll(&inv, 200000), 200000u + HAL_TIME_NO_DEADLINE_US);
    sbus_inverter_rx(&inv, &f, 300000);
    CHECK(!inv.timed_out);
    CHECK_EQ(sbus_inverter_poll(&inv, 300000), 400000u);
}

int main(void)
{
    RUN_TEST(test_pd_packing);
    RUN_TEST(test_card_rejects);
    RUN_TEST(test_card_default_timeout);
    RUN_TEST(test_card_bad_frames);
    RUN_TEST(test_card_queued_send_fails);
    RUN_TEST(test_inverter_edges);
    return check_report();
}
