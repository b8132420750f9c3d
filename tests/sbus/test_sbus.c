/* SBus framing (movilink/sbus.h) on the in-memory CAN bus, byte-exact.
 *
 * Three nodes: the card link, an inverter (sbus_inverter_t with scripted callbacks, or nothing
 * when a test plays the inverter by hand) and a monitor that records every frame on the wire. */
#include <stdbool.h>
#include <string.h>

#include "check.h"
#include "movilink/movilink_client.h"
#include "movilink/sbus.h"
#include "sim_hal/memcan.h"

#define MON_MAX 256u

typedef struct monitor {
    hal_can_t can;
    hal_can_frame_t got[MON_MAX];
    size_t n;
} monitor_t;

typedef struct card_probe {
    uint8_t rsp[8][ML_TELEGRAM_LEN];
    uint8_t rsp_channel[8];
    size_t n_rsp;
    uint16_t pi[SBUS_PD_WORDS];
    uint8_t n_pi;
    size_t pi_calls;
    ml_client_t *client; /* when set, responses go to the service client */
} card_probe_t;

typedef struct inv_probe {
    uint8_t last_req[ML_TELEGRAM_LEN];
    size_t params;
    uint16_t po[SBUS_PD_WORDS];
    uint8_t n_po;
    size_t po_calls;
    uint16_t pi[SBUS_PD_WORDS];
    int timeout_events[4];
    size_t n_timeout_events;
} inv_probe_t;

static struct {
    memcan_t bus;
    sbus_card_link_t link;
    sbus_inverter_t inv;
    hal_can_t card_can;
    hal_can_t inv_can;
    monitor_t mon;
    card_probe_t card;
    inv_probe_t ip;
    hal_time_us_t now;
    bool inverter_on;
} t;

static void mon_rx(void *ctx, const hal_can_frame_t *f)
{
    monitor_t *m = ctx;
    if (m->n < MON_MAX) {
        m->got[m->n++] = *f;
    }
}

static void card_rx(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    sbus_card_link_rx(&t.link, f, t.now);
}

static void inv_rx(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    if (t.inverter_on) {
        sbus_inverter_rx(&t.inv, f, t.now);
    }
}

static void on_param_response(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    card_probe_t *c = card;
    if (c->client != NULL) {
        ml_client_response(c->client, channel, rsp);
    }
    if (c->n_rsp < 8u) {
        memcpy(c->rsp[c->n_rsp], rsp, ML_TELEGRAM_LEN);
        c->rsp_channel[c->n_rsp] = channel;
        c->n_rsp++;
    }
}

static void on_process_inputs(void *card, const uint16_t *pi, uint8_t n)
{
    card_probe_t *c = card;
    memcpy(c->pi, pi, n * sizeof pi[0]);
    c->n_pi = n;
    c->pi_calls++;
}

/* A tiny inverter: index 8300 reads 0x311C7289, 11000 (H0) is read/write, others class 8 0x10. */
static int32_t h0;

static void inv_param(void *ctx, const uint8_t req[ML_TELEGRAM_LEN], uint8_t rsp[ML_TELEGRAM_LEN])
{
    inv_probe_t *p = ctx;
    memcpy(p->last_req, req, ML_TELEGRAM_LEN);
    p->params++;
    memcpy(rsp, req, ML_TELEGRAM_LEN);
    uint8_t svc = req[0] & ML_MGMT_SERVICE_MASK;
    uint16_t idx = ml_index(req);
    if (idx == 8300u && svc == ML_SVC_READ) {
        ml_put_data(rsp, 0x311C7289u);
    } else if (idx == 11000u && svc == ML_SVC_READ) {
        ml_put_data(rsp, (uint32_t)h0);
    } else if (idx == 11000u && (svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE)) {
        h0 = (int32_t)ml_data(req);
    } else {
        ml_put_error(rsp, ML_CLASS_OTHER, 0, ML_ADD_ILLEGAL_INDEX);
    }
}

static void inv_po(void *ctx, const uint16_t *po, uint8_t n)
{
    inv_probe_t *p = ctx;
    memcpy(p->po, po, n * sizeof po[0]);
    p->n_po = n;
    p->po_calls++;
}

static void inv_pi(void *ctx, uint16_t *pi, uint8_t n)
{
    inv_probe_t *p = ctx;
    memcpy(pi, p->pi, n * sizeof pi[0]);
}

static void inv_timeout(void *ctx, bool active)
{
    inv_probe_t *p = ctx;
    if (p->n_timeout_events < 4u) {
        p->timeout_events[p->n_timeout_events++] = active ? 1 : 0;
    }
}

static void setup(uint8_t card_addr, uint8_t inv_addr, bool channel2, bool inverter_on)
{
    memset(&t, 0, sizeof t);
    memcan_init(&t.bus);
    (void)memcan_attach(&t.bus, card_rx, NULL, &t.card_can);
    (void)memcan_attach(&t.bus, inv_rx, NULL, &t.inv_can);
    (void)memcan_attach(&t.bus, mon_rx, &t.mon, &t.mon.can);
    sbus_card_link_cfg_t cc = {
        .can = t.card_can, .address = card_addr, .use_channel2 = channel2, .timeout_us = 50000u,
        .param_response = on_param_response, .process_inputs = on_process_inputs,
        .card = &t.card,
    };
    sbus_card_link_init(&t.link, &cc);
    sbus_inverter_cfg_t ic = {
        .can = t.inv_can, .address = inv_addr, .channel2 = channel2, .timeout_us = 100000u,
        .ctx = &t.ip, .param = inv_param, .process_outputs = inv_po, .process_inputs = inv_pi,
        .timeout = inv_timeout,
    };
    sbus_inverter_init(&t.inv, &ic);
    t.inverter_on = inverter_on;
    t.now = 1000u;
    h0 = 0;
}

static void deliver(void)
{
    (void)memcan_deliver(&t.bus, 1000u);
}

static int request(uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    ml_link_t l = sbus_card_link(&t.link);
    return l.ops->param_request(l.ctx, channel, req);
}

static const uint8_t read_fw[8] = {0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00};
static const uint8_t read_h0[8] = {0x01, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x00, 0x00};

/* ------------------------------------------------------------------------------------------- */

static void test_identifiers(void)
{
    /* protocol.md §C2.1 worked examples: PO, PI, PO sync, parameter request, response. */
    static const uint16_t ex[][6] = {
        {33, 267, 268, 269, 779, 780}, {17, 139, 140, 141, 651, 652},
        {11, 91, 92, 93, 603, 604},    {7, 59, 60, 61, 571, 572},
        {1, 11, 12, 13, 523, 524},
    };
    for (size_t i = 0; i < sizeof ex / sizeof ex[0]; i++) {
        uint8_t a = (uint8_t)ex[i][0];
        CHECK_EQ(sbus_id_po(a), ex[i][1]);
        CHECK_EQ(sbus_id_pi(a), ex[i][2]);
        CHECK_EQ(sbus_id_po_sync(a), ex[i][3]);
        CHECK_EQ(sbus_id_param_req(a), ex[i][4]);
        CHECK_EQ(sbus_id_param_rsp(a), ex[i][5]);
        CHECK_EQ(sbus_id_address(ex[i][4]), a);
        CHECK_EQ(sbus_id_address(ex[i][1]), a);
    }
    CHECK_EQ(sbus_id_param2_req(1), 525);
    CHECK_EQ(sbus_id_param2_rsp(1), 527);
    CHECK_EQ(sbus_id_group_po(5), 46);
    CHECK_EQ(sbus_id_group_param(5), 558);
    CHECK_EQ(sbus_id_param_rsp(63), 1020); /* "ID range 3-1020" */
    CHECK_EQ(sbus_id_po(0), 3);
    CHECK(sbus_id_is_param(779));
    CHECK(!sbus_id_is_param(267));
    CHECK_EQ(sbus_id_function(780), SBUS_FN_PARAM_RSP);
    CHECK_EQ(sbus_id_function(269), SBUS_FN_PO_SYNC);
    CHECK(sbus_id_param_rsp(63) <= HAL_CAN_ID_MASK);
}

/* protocol.md §C7: ID 523 01 00 20 6C 00 00 00 00 -> ID 524 01 00 20 6C 31 1C 72 89, both on the wire. */
static void test_worked_parameter_read(void)
{
    setup(1, 1, false, true);
    CHECK_EQ(request(0, read_fw), 0);
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_EQ(t.mon.got[0].id, 523);
    CHECK_BYTES(t.mon.got[0].data, t.mon.got[0].len, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
                0x00);
    CHECK_EQ(t.mon.got[1].id, 524);
    CHECK_BYTES(t.mon.got[1].data, t.mon.got[1].len, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72,
                0x89);
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_EQ(t.card.rsp_channel[0], 0);
    CHECK_BYTES(t.card.rsp[0], 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    CHECK_EQ(t.link.requests_sent, 1);
    CHECK_EQ(t.link.responses, 1);
}

/* The same read answered by hand (no inverter object): the card link alone. */
static void test_card_link_by_hand(void)
{
    setup(1, 1, false, false);
    CHECK_EQ(request(0, read_fw), 0);
    deliver();
    CHECK_EQ(t.mon.n, 1);
    hal_can_frame_t rsp = {.id = 524, .len = 8, .data = {0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89}};
    CHECK_EQ(t.inv_can.ops->send(t.inv_can.ctx, &rsp), 0);
    /* Frames for other addresses and the PI of another inverter are not ours. */
    hal_can_frame_t other = {.id = 532, .len = 8, .data = {0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 1}};
    CHECK_EQ(t.inv_can.ops->send(t.inv_can.ctx, &other), 0);
    hal_can_frame_t other_pi = {.id = 20, .len = 6, .data = {1, 2, 3, 4, 5, 6}};
    CHECK_EQ(t.inv_can.ops->send(t.inv_can.ctx, &other_pi), 0);
    deliver();
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_BYTES(t.card.rsp[0], 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    CHECK_EQ(t.card.pi_calls, 0);
}

/* protocol.md §C7: ID 11 00 06 05 DC 00 00 -> ID 12 with PI1..PI3; big-endian words. */
static void test_worked_process_data(void)
{
    setup(1, 1, false, true);
    t.ip.pi[0] = 0x0007;
    t.ip.pi[1] = 1499;
    t.ip.pi[2] = 0xFEDC;
    ml_link_t l = sbus_card_link(&t.link);
    const uint16_t po[3] = {0x0006, 1500, 0};
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_EQ(t.mon.got[0].id, 11);
    CHECK_BYTES(t.mon.got[0].data, t.mon.got[0].len, 0x00, 0x06, 0x05, 0xDC, 0x00, 0x00);
    CHECK_EQ(t.mon.got[1].id, 12);
    CHECK_BYTES(t.mon.got[1].data, t.mon.got[1].len, 0x00, 0x07, 0x05, 0xDB, 0xFE, 0xDC);
    CHECK_EQ(t.ip.n_po, 3);
    CHECK_EQ(t.ip.po[0], 0x0006);
    CHECK_EQ(t.ip.po[1], 1500);
    CHECK_EQ(t.ip.po[2], 0);
    CHECK_EQ(t.card.pi_calls, 1);
    CHECK_EQ(t.card.n_pi, 3);
    CHECK_EQ(t.card.pi[0], 7);
    CHECK_EQ(t.card.pi[1], 1499);
    CHECK_EQ(t.card.pi[2], 0xFEDC);

    /* SBus carries 3 PD: fewer are padded with 0, more are cut. */
    t.mon.n = 0;
    const uint16_t one[1] = {0x1234};
    l.ops->process_outputs(l.ctx, one, 1);
    const uint16_t ten[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    l.ops->process_outputs(l.ctx, ten, 10);
    l.ops->process_outputs(l.ctx, ten, 0);
    deliver();
    CHECK_EQ(t.mon.n, 6); /* three PO frames, then the three PI answers */
    CHECK_BYTES(t.mon.got[0].data, t.mon.got[0].len, 0x12, 0x34, 0x00, 0x00, 0x00, 0x00);
    CHECK_BYTES(t.mon.got[1].data, t.mon.got[1].len, 0x00, 0x01, 0x00, 0x02, 0x00, 0x03);
    CHECK_BYTES(t.mon.got[2].data, t.mon.got[2].len, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00);
    CHECK_EQ(t.mon.got[3].id, 12);
    CHECK_EQ(t.link.po_frames, 4);
}

/* Address 33: the card talks to 779/267 and listens on 780/268 only. */
static void test_address_33(void)
{
    setup(33, 33, false, true);
    t.ip.pi[0] = 0x0102;
    CHECK_EQ(request(1, read_h0), 0);
    ml_link_t l = sbus_card_link(&t.link);
    const uint16_t po[3] = {6, 0, 0};
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.mon.n, 4);
    CHECK_EQ(t.mon.got[0].id, 779);
    CHECK_EQ(t.mon.got[1].id, 267);
    CHECK_EQ(t.mon.got[2].id, 780);
    CHECK_EQ(t.mon.got[3].id, 268);
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_EQ(t.card.rsp_channel[0], 1);
    CHECK_EQ(t.card.pi[0], 0x0102);
    /* An inverter at another address stays silent. */
    setup(33, 34, false, true);
    CHECK_EQ(request(0, read_fw), 0);
    l = sbus_card_link(&t.link);
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_EQ(t.ip.params, 0);
    CHECK_EQ(t.ip.po_calls, 0);
}

/* One outstanding request per SBus channel: channels 0..3 queue behind each other in arrival
 * order; each response goes to the channel that asked. */
static void test_queueing_on_channel_1(void)
{
    setup(1, 1, false, false);
    const uint8_t w_h0[8] = {0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8};
    CHECK_EQ(request(3, read_fw), 0);
    CHECK_EQ(request(0, w_h0), 0);
    CHECK_EQ(request(1, read_h0), 0);
    deliver();
    CHECK_EQ(t.mon.n, 1); /* only the first is on the wire */
    CHECK_BYTES(t.mon.got[0].data, 8, 0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0);
    CHECK_EQ(sbus_card_link_sbus_channel(&t.link, 3), 1);
    t.inverter_on = true; /* let it answer the rest */
    hal_can_frame_t rsp = {.id = 524, .len = 8, .data = {0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89}};
    CHECK_EQ(t.inv_can.ops->send(t.inv_can.ctx, &rsp), 0);
    deliver();
    CHECK_EQ(t.card.n_rsp, 3);
    CHECK_EQ(t.card.rsp_channel[0], 3);
    CHECK_EQ(t.card.rsp_channel[1], 0);
    CHECK_BYTES(t.card.rsp[1], 8, 0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    CHECK_EQ(t.card.rsp_channel[2], 1);
    CHECK_BYTES(t.card.rsp[2], 8, 0x01, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    /* On the wire: request, response, request, response, request, response, in that order. */
    CHECK_EQ(t.mon.n, 6);
    static const uint16_t ids[6] = {523, 524, 523, 524, 523, 524};
    for (size_t i = 0; i < 6u && i < t.mon.n; i++) {
        CHECK_EQ(t.mon.got[i].id, ids[i]);
    }
}

/* use_channel2: card channels 2, 3 on SBus channel 2 (525 -> 527), in parallel with channel 1. */
static void answer_by_hand(uint16_t id, const uint8_t req[ML_TELEGRAM_LEN], uint32_t value)
{
    hal_can_frame_t f = {.id = id, .len = 8};
    memcpy(f.data, req, 8);
    ml_put_data(f.data, value);
    (void)t.inv_can.ops->send(t.inv_can.ctx, &f);
    deliver();
}

static void test_channel_2(void)
{
    setup(1, 1, true, false);
    CHECK_EQ(sbus_card_link_sbus_channel(&t.link, 0), 1);
    CHECK_EQ(sbus_card_link_sbus_channel(&t.link, 1), 1);
    CHECK_EQ(sbus_card_link_sbus_channel(&t.link, 2), 2);
    CHECK_EQ(sbus_card_link_sbus_channel(&t.link, 3), 2);
    CHECK_EQ(request(0, read_fw), 0);
    CHECK_EQ(request(3, read_h0), 0);
    CHECK_EQ(request(2, read_fw), 0); /* waits behind channel 3 */
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_EQ(t.mon.got[0].id, 523);
    CHECK_EQ(t.mon.got[1].id, 525);
    CHECK_BYTES(t.mon.got[1].data, 8, 0x01, 0x00, 0x2A, 0xF8, 0, 0, 0, 0);
    answer_by_hand(527, read_h0, 77);
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_EQ(t.card.rsp_channel[0], 3);
    CHECK_EQ(ml_data(t.card.rsp[0]), 77);
    CHECK_EQ(t.mon.n, 4); /* 527, then channel 2's read on 525 */
    CHECK_EQ(t.mon.got[3].id, 525);
    CHECK_BYTES(t.mon.got[3].data, 8, 0x01, 0x00, 0x20, 0x6C, 0, 0, 0, 0);
    answer_by_hand(524, read_fw, 1);
    answer_by_hand(527, read_fw, 2);
    CHECK_EQ(t.card.n_rsp, 3);
    CHECK_EQ(t.card.rsp_channel[1], 0);
    CHECK_EQ(ml_data(t.card.rsp[1]), 1);
    CHECK_EQ(t.card.rsp_channel[2], 2);
    CHECK_EQ(ml_data(t.card.rsp[2]), 2);
    /* An inverter serving channel 2 answers 525 on 527. */
    setup(1, 1, true, true);
    CHECK_EQ(request(2, read_fw), 0);
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_EQ(t.mon.got[0].id, 525);
    CHECK_EQ(t.mon.got[1].id, 527);
    CHECK_BYTES(t.mon.got[1].data, 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
    CHECK_EQ(t.card.rsp_channel[0], 2);
}

/* A response for another index or service is not the answer: dropped, the request still waits. */
static void test_stale_response(void)
{
    setup(1, 1, false, false);
    CHECK_EQ(request(0, read_fw), 0);
    hal_can_frame_t wrong_idx = {.id = 524, .len = 8, .data = {0x01, 0x00, 0x20, 0x6D, 0, 0, 0, 1}};
    hal_can_frame_t wrong_svc = {.id = 524, .len = 8, .data = {0x02, 0x00, 0x20, 0x6C, 0, 0, 0, 1}};
    hal_can_frame_t short_rsp = {.id = 524, .len = 7, .data = {0x01, 0x00, 0x20, 0x6C, 0, 0, 0}};
    (void)t.inv_can.ops->send(t.inv_can.ctx, &wrong_idx);
    (void)t.inv_can.ops->send(t.inv_can.ctx, &wrong_svc);
    (void)t.inv_can.ops->send(t.inv_can.ctx, &short_rsp);
    deliver();
    CHECK_EQ(t.card.n_rsp, 0);
    CHECK_EQ(t.link.stale_responses, 2);
    CHECK_EQ(t.link.bad_frames, 1);
    /* An error answer (same service and index, error bit) is the answer. */
    hal_can_frame_t err = {.id = 524, .len = 8, .data = {0x81, 0x00, 0x20, 0x6C, 0x08, 0x00, 0x00, 0x12}};
    (void)t.inv_can.ops->send(t.inv_can.ctx, &err);
    deliver();
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_BYTES(t.card.rsp[0], 8, 0x81, 0x00, 0x20, 0x6C, 0x08, 0x00, 0x00, 0x12);
    /* Nothing outstanding any more: another copy is stale. */
    (void)t.inv_can.ops->send(t.inv_can.ctx, &err);
    deliver();
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_EQ(t.link.stale_responses, 3);
}

/* No answer: the SBus channel is given up after timeout_us (counted from the first poll after
 * sending) and the next request goes out; a late answer to the old one is stale. */
static void test_timeout_frees_channel(void)
{
    setup(1, 1, false, false);
    CHECK_EQ(request(0, read_fw), 0);
    CHECK_EQ(request(1, read_h0), 0);
    deliver();
    CHECK_EQ(t.mon.n, 1);
    hal_time_us_t next = sbus_card_link_poll(&t.link, 10000u);
    CHECK_EQ(next, 10000u + 50000u);
    CHECK_EQ(sbus_card_link_poll(&t.link, 59999u), 60000u);
    deliver();
    CHECK_EQ(t.mon.n, 1);
    t.now = 60000u;
    next = sbus_card_link_poll(&t.link, 60000u);
    CHECK_EQ(t.link.timeouts, 1);
    CHECK_EQ(next, 110000u); /* the next request is armed at once */
    deliver();
    CHECK_EQ(t.mon.n, 2);
    CHECK_BYTES(t.mon.got[1].data, 8, 0x01, 0x00, 0x2A, 0xF8, 0, 0, 0, 0);
    CHECK_EQ(t.card.n_rsp, 0); /* the service client's own deadline answers the master */
    hal_can_frame_t late = {.id = 524, .len = 8, .data = {0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89}};
    (void)t.inv_can.ops->send(t.inv_can.ctx, &late);
    deliver();
    CHECK_EQ(t.card.n_rsp, 0);
    CHECK_EQ(t.link.stale_responses, 1);
    CHECK_EQ(sbus_card_link_poll(&t.link, 200000u), 200000u + HAL_TIME_NO_DEADLINE_US);
    CHECK_EQ(t.link.timeouts, 2);
}

/* The same near the wrap of the 32-bit microsecond clock and past 2^31 (a wall clock after 36
 * minutes of uptime): no instant is taken for "long ago" or "never". */
static void test_timeouts_across_wrap(void)
{
    static const hal_time_us_t bases[2] = {0xFFFFFF00u, 0x80000010u};
    for (int b = 0; b < 2; b++) {
        hal_time_us_t t0 = bases[b];
        setup(1, 1, false, false);
        CHECK_EQ(request(0, read_fw), 0);
        CHECK_EQ(request(1, read_h0), 0);
        deliver();
        CHECK_EQ(sbus_card_link_poll(&t.link, t0), t0 + 50000u);
        CHECK_EQ(sbus_card_link_poll(&t.link, t0 + 49999u), t0 + 50000u);
        CHECK_EQ(t.link.timeouts, 0);
        (void)sbus_card_link_poll(&t.link, t0 + 50000u);
        CHECK_EQ(t.link.timeouts, 1);
        deliver();
        CHECK_EQ(t.mon.n, 2);
        /* The inverter's P815 timeout from a PO received at t0. */
        setup(1, 1, false, true);
        t.now = t0;
        ml_link_t l = sbus_card_link(&t.link);
        const uint16_t po[3] = {6, 0, 0};
        l.ops->process_outputs(l.ctx, po, 3);
        deliver();
        CHECK_EQ(sbus_inverter_poll(&t.inv, t0 + 99999u), t0 + 100000u);
        CHECK_EQ(t.ip.n_timeout_events, 0);
        (void)sbus_inverter_poll(&t.inv, t0 + 100000u);
        CHECK_EQ(t.ip.n_timeout_events, 1);
    }
}

/* The link cannot send: the request is refused at once (the client answers 6/2); a queued
 * request whose turn comes while the bus refuses gets the card's 6/2 answer from the link. */
static int refuse_count;
static int refusing_send(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    (void)f;
    refuse_count++;
    return -1;
}
static const hal_can_ops_t refusing_ops = {.send = refusing_send};

static void test_send_failure(void)
{
    setup(1, 1, false, false);
    CHECK_EQ(request(0, read_fw), 0);
    t.link.cfg.can = (hal_can_t){.ops = &refusing_ops, .ctx = NULL};
    CHECK_EQ(request(1, read_h0), 0); /* queued behind channel 0 */
    hal_can_frame_t rsp = {.id = 524, .len = 8, .data = {0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89}};
    (void)t.inv_can.ops->send(t.inv_can.ctx, &rsp);
    deliver();
    CHECK_EQ(t.card.n_rsp, 2);
    CHECK_EQ(t.card.rsp_channel[0], 1); /* the link's own answer for the one it could not send */
    CHECK_BYTES(t.card.rsp[0], 8, 0x81, 0x00, 0x2A, 0xF8, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(t.card.rsp_channel[1], 0);
    CHECK_EQ(request(2, read_fw), -1);
    CHECK_EQ(t.link.send_errors, 2);
    ml_link_t l = sbus_card_link(&t.link);
    const uint16_t po[3] = {1, 2, 3};
    l.ops->process_outputs(l.ctx, po, 3);
    CHECK_EQ(t.link.send_errors, 3);
    CHECK_EQ(refuse_count, 3);
}

/* DP watchdog expired: no PO frames until it clears; the inverter's SBus timeout then reacts. */
static void test_fieldbus_timeout_stops_po(void)
{
    setup(1, 1, false, true);
    ml_link_t l = sbus_card_link(&t.link);
    const uint16_t po[3] = {6, 1500, 0};
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.ip.po_calls, 1);
    CHECK_EQ(sbus_inverter_poll(&t.inv, t.now), t.now + 100000u);
    ml_fieldbus_status_t st = {.timeout = true};
    l.ops->fieldbus_status(l.ctx, &st);
    deliver();
    CHECK_EQ(t.mon.n, 2); /* the status itself puts nothing on the wire */
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.ip.po_calls, 1);
    CHECK_EQ(t.link.po_withheld, 1);
    CHECK_EQ(sbus_inverter_poll(&t.inv, t.now + 99999u), t.now + 100000u);
    CHECK_EQ(t.ip.n_timeout_events, 0);
    (void)sbus_inverter_poll(&t.inv, t.now + 100000u);
    CHECK_EQ(t.ip.n_timeout_events, 1);
    CHECK_EQ(t.ip.timeout_events[0], 1);
    st.timeout = false;
    st.data_exchange = true;
    l.ops->fieldbus_status(l.ctx, &st);
    t.now += 150000u;
    l.ops->process_outputs(l.ctx, po, 3);
    deliver();
    CHECK_EQ(t.ip.po_calls, 2);
    CHECK_EQ(t.ip.n_timeout_events, 2);
    CHECK_EQ(t.ip.timeout_events[1], 0);
}

/* The inverter side alone: wrong lengths ignored, handshake (synchronous) requests answered. */
static void test_inverter_side(void)
{
    setup(1, 1, false, true);
    hal_can_frame_t bad = {.id = 523, .len = 6, .data = {1, 0, 0x20, 0x6C, 0, 0}};
    hal_can_frame_t bad_po = {.id = 11, .len = 1, .data = {6}};
    hal_can_frame_t sync = {.id = 523, .len = 8, .data = {0x41, 0, 0x20, 0x6C, 0, 0, 0, 0}};
    hal_can_frame_t ch2 = {.id = 525, .len = 8, .data = {0x01, 0, 0x20, 0x6C, 0, 0, 0, 0}};
    (void)t.mon.can.ops->send(t.mon.can.ctx, &bad);
    (void)t.mon.can.ops->send(t.mon.can.ctx, &bad_po);
    (void)t.mon.can.ops->send(t.mon.can.ctx, &sync);
    (void)t.mon.can.ops->send(t.mon.can.ctx, &ch2); /* channel 2 not enabled: ignored */
    deliver();
    CHECK_EQ(t.inv.bad_frames, 2);
    CHECK_EQ(t.ip.params, 1);
    /* the card link (node 0) also hears the 524 answer: stale for it, nothing outstanding */
    CHECK_EQ(t.link.stale_responses, 1);
    CHECK_EQ(t.inv.requests, 1);
    /* Unknown index: class 8 code 0x10 comes back as the inverter made it. */
    setup(1, 1, false, true);
    const uint8_t unknown[8] = {0x01, 0x00, 0x12, 0x34, 0, 0, 0, 0};
    CHECK_EQ(request(0, unknown), 0);
    deliver();
    CHECK_EQ(t.card.n_rsp, 1);
    CHECK_BYTES(t.card.rsp[0], 8, 0x81, 0x00, 0x12, 0x34, 0x08, 0x00, 0x00, 0x10);
    /* No SBus timeout before the first PO ("t" on the display), none when P815 = 0. */
    CHECK_EQ(sbus_inverter_poll(&t.inv, 5000000u), 5000000u + HAL_TIME_NO_DEADLINE_US);
}

/* With the service client on top: a write then a read over the bus; a lost request ends with
 * the client's 6/2 and the next service still works. */
typedef struct done_rec {
    uint8_t rsp[ML_TELEGRAM_LEN];
    int calls;
} done_rec_t;

static void on_done(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)channel;
    done_rec_t *d = ctx;
    memcpy(d->rsp, rsp, ML_TELEGRAM_LEN);
    d->calls++;
}

static void test_with_service_client(void)
{
    static ml_client_t client;
    setup(1, 1, false, true);
    ml_client_init(&client, sbus_card_link(&t.link), 200000u);
    t.card.client = &client;
    done_rec_t d = {0};
    const uint8_t w[8] = {0x73, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8}; /* handshake set */
    CHECK_EQ(ml_client_request(&client, 0, w, on_done, &d, t.now), 0);
    deliver();
    CHECK_EQ(d.calls, 1);
    /* The client cleared the handshake bit on the way out: asynchronous mode on SBus. */
    CHECK_EQ(t.mon.got[0].data[0], 0x33);
    CHECK_BYTES(d.rsp, 8, 0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);
    CHECK_EQ(h0, 3000);
    CHECK_EQ(ml_client_request(&client, 0, read_h0, on_done, &d, t.now), 0);
    deliver();
    CHECK_EQ(d.calls, 2);
    CHECK_BYTES(d.rsp, 8, 0x01, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x0B, 0xB8);

    /* Lose the next request frame. */
    memcan_drop_next(&t.bus, 1);
    CHECK_EQ(ml_client_request(&client, 0, read_fw, on_done, &d, t.now), 0);
    deliver();
    CHECK_EQ(d.calls, 2);
    (void)sbus_card_link_poll(&t.link, t.now);
    (void)ml_client_poll(&client, t.now + 199999u);
    CHECK_EQ(d.calls, 2);
    t.now += 200000u;
    (void)ml_client_poll(&client, t.now);
    (void)sbus_card_link_poll(&t.link, t.now);
    CHECK_EQ(d.calls, 3);
    CHECK_BYTES(d.rsp, 8, 0x81, 0x00, 0x20, 0x6C, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(t.link.timeouts, 1);
    /* The channel stays quarantined for one more timeout, waiting for a late answer. */
    CHECK_EQ(ml_client_request(&client, 0, read_fw, on_done, &d, t.now), -1);
    t.now += 200000u;
    (void)ml_client_poll(&client, t.now);
    CHECK_EQ(ml_client_request(&client, 0, read_fw, on_done, &d, t.now), 0);
    deliver();
    CHECK_EQ(d.calls, 4);
    CHECK_BYTES(d.rsp, 8, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89);
}

/* Random loss on the bus: every service ends (answer or 6/2), none ends twice, the card never
 * takes a wrong answer. */
static void test_lossy_bus(void)
{
    static ml_client_t client;
    setup(1, 1, false, true);
    memcan_set_loss(&t.bus, 200, 4711);
    ml_client_init(&client, sbus_card_link(&t.link), 200000u);
    t.card.client = &client;
    int answered = 0;
    int failed = 0;
    int wrong = 0;
    for (uint32_t i = 0; i < 300u; i++) {
        done_rec_t d = {0};
        uint8_t w[8] = {0x32, 0x00, 0x2A, 0xF8, 0, 0, (uint8_t)(i >> 8), (uint8_t)i};
        /* After a timeout the channel is quarantined until the late answer or a second
         * timeout: keep the bus running until it takes the request. */
        int tries = 0;
        while (ml_client_request(&client, 0, w, on_done, &d, t.now) != 0 && tries++ < 20) {
            deliver();
            (void)sbus_card_link_poll(&t.link, t.now);
            (void)ml_client_poll(&client, t.now);
            t.now += 50000u;
        }
        CHECK(tries <= 20);
        for (int step = 0; step < 10 && d.calls == 0; step++) {
            deliver();
            (void)sbus_card_link_poll(&t.link, t.now);
            (void)ml_client_poll(&client, t.now);
            t.now += 50000u;
        }
        if (d.calls != 1) {
            wrong++;
        } else if ((d.rsp[0] & ML_MGMT_ERROR) != 0u) {
            failed += d.rsp[4] == ML_CLASS_ACCESS && d.rsp[5] == ML_CODE_HARDWARE_FAULT;
        } else {
            answered++;
            wrong += ml_data(d.rsp) != i || ml_index(d.rsp) != 11000u;
        }
    }
    CHECK_EQ(wrong, 0);
    CHECK_EQ(answered + failed, 300);
    CHECK(answered > 150 && failed > 40); /* about 64 % of round trips survive 20 % loss */
    printf("lossy bus (20 %% frame loss): %d answered, %d ended with 6/2\n", answered, failed);
}

/* ---- The link under the service client with the production timeouts ----------------------
 * One SBus parameter channel for every card channel (the reference board), the link's default
 * SBUS_PARAM_TIMEOUT_US and the client's ML_RESPONSE_TIMEOUT_US. The telegram has no tag, so
 * the channel must stay closed while an answer may still come for a request the client gave
 * up on; a request the client gave up on before it was sent must never go out. */

typedef struct wire {
    hal_can_frame_t f[16];
    unsigned n;
} wire_t;

static int wire_send(void *ctx, const hal_can_frame_t *f)
{
    wire_t *w = ctx;
    if (w->n < 16u) {
        w->f[w->n++] = *f;
    }
    return 0;
}

static const hal_can_ops_t wire_ops = {.send = wire_send};

static struct {
    wire_t wire;
    sbus_card_link_t link;
    ml_client_t client;
} P;

static void p_to_client(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)card;
    ml_client_response(&P.client, channel, rsp);
}

static void p_setup(void)
{
    memset(&P, 0, sizeof P);
    sbus_card_link_cfg_t cfg = {.can = {.ops = &wire_ops, .ctx = &P.wire}, .address = 1,
                                .param_response = p_to_client};
    sbus_card_link_init(&P.link, &cfg);
    ml_client_init(&P.client, sbus_card_link(&P.link), 0);
}

static void p_run(hal_time_us_t from, hal_time_us_t to)
{
    for (hal_time_us_t now = from; now <= to; now += 1000u) {
        (void)sbus_card_link_poll(&P.link, now);
        (void)ml_client_poll(&P.client, now);
    }
}

static void p_inverter_answers(const uint8_t rsp[ML_TELEGRAM_LEN], hal_time_us_t now)
{
    hal_can_frame_t f = {.id = sbus_id_param_rsp(1), .len = 8};
    memcpy(f.data, rsp, 8);
    sbus_card_link_rx(&P.link, &f, now);
}

static void test_link_holds_channel_while_client_waits(void)
{
    p_setup();
    done_rec_t d1 = {0};
    done_rec_t d0 = {0};
    const uint8_t p302_5[8] = {0x33, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x05};
    const uint8_t p302_max[8] = {0x33, 0x00, 0x21, 0x45, 0x7F, 0xFF, 0xFF, 0xFF};
    CHECK_EQ(ml_client_request(&P.client, 1, p302_5, on_done, &d1, 0), 0); /* MSAC1 */
    p_run(0, 110000u);
    CHECK_EQ(ml_client_request(&P.client, 0, p302_max, on_done, &d0, 110000u), 0); /* cyclic */
    CHECK_EQ(P.wire.n, 1); /* waits: the first request still holds the SBus channel */
    /* Inside the client's 200 ms: the answer is the first request's, as it should be. */
    p_inverter_answers(p302_5, 120000u);
    CHECK_EQ(d1.calls, 1);
    CHECK_BYTES(d1.rsp, 8, 0x33, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x05);
    CHECK_EQ(P.wire.n, 2); /* now the cyclic channel's request goes out */
    CHECK_BYTES(P.wire.f[1].data, 8, 0x33, 0x00, 0x21, 0x45, 0x7F, 0xFF, 0xFF, 0xFF);
    const uint8_t too_high[8] = {0xB3, 0x00, 0x21, 0x45, 0x08, 0x00, 0x00, 0x15};
    p_inverter_answers(too_high, 125000u);
    CHECK_EQ(d0.calls, 1);
    CHECK_BYTES(d0.rsp, 8, 0xB3, 0x00, 0x21, 0x45, 0x08, 0x00, 0x00, 0x15);
}

static void test_late_answer_goes_to_its_own_channel(void)
{
    p_setup();
    done_rec_t d1 = {0};
    done_rec_t d0 = {0};
    const uint8_t p302_5[8] = {0x33, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x05};
    const uint8_t read_p302[8] = {0x31, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x00};
    CHECK_EQ(ml_client_request(&P.client, 1, p302_5, on_done, &d1, 0), 0);
    p_run(0, 210000u); /* the client answers 6/2 at 200 ms */
    CHECK_EQ(d1.calls, 1);
    CHECK_BYTES(d1.rsp, 8, 0xB3, 0x00, 0x21, 0x45, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(ml_client_request(&P.client, 0, read_p302, on_done, &d0, 210000u), 0);
    CHECK_EQ(P.wire.n, 1); /* still held for the late answer */
    /* The late answer to the write: the link drops it (the client gave the write up), not taken
     * as the read's. */
    p_inverter_answers(p302_5, 250000u);
    CHECK_EQ(d0.calls, 0);
    CHECK_EQ(d1.calls, 1);
    CHECK_EQ(P.link.stale_responses, 1);
    CHECK_EQ(P.wire.n, 2);
    CHECK_BYTES(P.wire.f[1].data, 8, 0x31, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x00);
    const uint8_t value[8] = {0x31, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x05};
    p_inverter_answers(value, 260000u);
    CHECK_EQ(d0.calls, 1);
    CHECK_BYTES(d0.rsp, 8, 0x31, 0x00, 0x21, 0x45, 0x00, 0x00, 0x00, 0x05);
}

/* A request sent late (it waited behind another) is given up by the client at 200 ms after it
 * asked; the client's quarantine ends before the link's hold does, and the master's repetition
 * waits in the link. The first request's late answer must not complete the repetition, which
 * then goes out and gets its own answer. */
static void test_late_answer_never_completes_the_repetition(void)
{
    p_setup();
    done_rec_t dx = {0};
    done_rec_t da = {0};
    done_rec_t db = {0};
    const uint8_t read_fw_[8] = {0x31, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00};
    const uint8_t h0_5[8] = {0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x00, 0x05};
    CHECK_EQ(ml_client_request(&P.client, 0, read_fw_, on_done, &dx, 0), 0);
    p_run(0, 10000u);
    CHECK_EQ(ml_client_request(&P.client, 1, h0_5, on_done, &da, 10000u), 0); /* waits */
    p_run(10000u, 50000u);
    const uint8_t fw[8] = {0x31, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89};
    p_inverter_answers(fw, 50000u); /* the write goes out at 50 ms */
    CHECK_EQ(P.wire.n, 2);
    p_run(50000u, 415000u); /* 6/2 at 210 ms, quarantine over at 410 ms, link holds to 450 */
    CHECK_BYTES(da.rsp, 8, 0xB3, 0x00, 0x2A, 0xF8, 0x06, 0x02, 0x00, 0x00);
    CHECK_EQ(ml_client_request(&P.client, 1, h0_5, on_done, &db, 415000u), 0); /* repeated */
    CHECK_EQ(P.wire.n, 2);
    const uint8_t done_ok[8] = {0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x00, 0x05};
    p_inverter_answers(done_ok, 420000u); /* the first write's late answer */
    CHECK_EQ(db.calls, 0);
    CHECK_EQ(P.wire.n, 3); /* the repetition went out */
    p_inverter_answers(done_ok, 425000u);
    CHECK_EQ(db.calls, 1);
    CHECK_BYTES(db.rsp, 8, 0x33, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x00, 0x05);
}

static void test_request_given_up_unsent_never_goes_out(void)
{
    p_setup();
    done_rec_t d1 = {0};
    done_rec_t d0 = {0};
    const uint8_t read_h0_[8] = {0x31, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x00, 0x00};
    const uint8_t h0_9[8] = {0x33, 0x00, 0x2A, 0xF9, 0x00, 0x00, 0x00, 0x09};
    CHECK_EQ(ml_client_request(&P.client, 1, read_h0_, on_done, &d1, 0), 0);
    p_run(0, 5000u);
    CHECK_EQ(ml_client_request(&P.client, 0, h0_9, on_done, &d0, 5000u), 0); /* waits */
    p_run(5000u, 300000u); /* no answer at all: both clients give up, the write while waiting */
    CHECK_EQ(d0.calls, 1);
    CHECK_BYTES(d0.rsp, 8, 0xB3, 0x00, 0x2A, 0xF9, 0x06, 0x02, 0x00, 0x00);
    p_run(300000u, 900000u); /* the link gives the channel up too */
    CHECK_EQ(P.link.timeouts, 1);
    CHECK_EQ(P.wire.n, 1); /* the write the master was told to repeat never reached the drive */
}

int main(void)
{
    RUN_TEST(test_identifiers);
    RUN_TEST(test_worked_parameter_read);
    RUN_TEST(test_card_link_by_hand);
    RUN_TEST(test_worked_process_data);
    RUN_TEST(test_address_33);
    RUN_TEST(test_queueing_on_channel_1);
    RUN_TEST(test_channel_2);
    RUN_TEST(test_stale_response);
    RUN_TEST(test_timeout_frees_channel);
    RUN_TEST(test_timeouts_across_wrap);
    RUN_TEST(test_send_failure);
    RUN_TEST(test_fieldbus_timeout_stops_po);
    RUN_TEST(test_inverter_side);
    RUN_TEST(test_with_service_client);
    RUN_TEST(test_lossy_bus);
    RUN_TEST(test_link_holds_channel_while_client_waits);
    RUN_TEST(test_late_answer_goes_to_its_own_channel);
    RUN_TEST(test_request_given_up_unsent_never_goes_out);
    RUN_TEST(test_late_answer_never_completes_the_repetition);
    return check_report();
}
