/* SBus framing, card and inverter side. See movilink/sbus.h. */
#include "movilink/sbus.h"

#include <string.h>

void sbus_pack_pd(hal_can_frame_t *f, uint16_t id, const uint16_t *words, uint8_t n)
{
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = SBUS_PD_LEN;
    for (uint8_t i = 0; i < SBUS_PD_WORDS && i < n; i++) {
        size_t at = 2u * (size_t)i;
        f->data[at] = (uint8_t)(words[i] >> 8);
        f->data[at + 1u] = (uint8_t)(words[i] & 0xFFu);
    }
}

uint8_t sbus_unpack_pd(const hal_can_frame_t *f, uint16_t words[SBUS_PD_WORDS])
{
    uint8_t n = (uint8_t)(f->len / 2u);
    if (n > SBUS_PD_WORDS) {
        n = SBUS_PD_WORDS;
    }
    for (uint8_t i = 0; i < SBUS_PD_WORDS; i++) {
        uint16_t w = 0u;
        if (i < n) {
            size_t at = 2u * (size_t)i;
            w = (uint16_t)((f->data[at] << 8) | f->data[at + 1u]);
        }
        words[i] = w;
    }
    return n;
}

static int send_frame(hal_can_t can, const hal_can_frame_t *f)
{
    if (can.ops == NULL || can.ops->send == NULL) {
        return -1;
    }
    return can.ops->send(can.ctx, f);
}

static void param_frame(hal_can_frame_t *f, uint16_t id, const uint8_t t[ML_TELEGRAM_LEN])
{
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = ML_TELEGRAM_LEN;
    memcpy(f->data, t, ML_TELEGRAM_LEN);
}

/* ---------------------------------------------------------------------------------------------
 * Card side */

uint8_t sbus_card_link_sbus_channel(const sbus_card_link_t *l, uint8_t channel)
{
    return (l->cfg.use_channel2 && channel >= 2u) ? 2u : 1u;
}

static uint16_t request_id(const sbus_card_link_t *l, uint8_t sbus_ch)
{
    return sbus_ch == 2u ? sbus_id_param2_req(l->cfg.address) : sbus_id_param_req(l->cfg.address);
}

/* Put a request on the wire for SBus channel sc (1 or 2). */
static int transmit_request(sbus_card_link_t *l, uint8_t sc, uint8_t channel,
                            const uint8_t req[ML_TELEGRAM_LEN])
{
    hal_can_frame_t f;
    param_frame(&f, request_id(l, sc), req);
    if (send_frame(l->cfg.can, &f) != 0) {
        l->send_errors++;
        return -1;
    }
    sbus_outstanding_t *o = &l->out[sc - 1u];
    o->busy = true;
    o->armed = false;
    o->given_up = false;
    o->channel = channel;
    memcpy(o->req, req, ML_TELEGRAM_LEN);
    l->requests_sent++;
    return 0;
}

/* The card's answer for a request that could not be sent after waiting (class 6 code 2, as the
 * service client answers when the link refuses at once). */
static void fail_request(sbus_card_link_t *l, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, req, sizeof rsp);
    ml_put_error(rsp, ML_CLASS_ACCESS, ML_CODE_HARDWARE_FAULT, 0);
    if (l->cfg.param_response != NULL) {
        l->cfg.param_response(l->cfg.card, channel, rsp);
    }
}

/* SBus channel sc is free: send the oldest waiting request for it. */
static void send_next(sbus_card_link_t *l, uint8_t sc)
{
    while (!l->out[sc - 1u].busy) {
        int best = -1;
        for (uint8_t c = 0; c < ML_MAX_CHANNELS; c++) {
            if (l->queue[c].waiting && sbus_card_link_sbus_channel(l, c) == sc &&
                (best < 0 || (int32_t)(l->queue[c].seq - l->queue[best].seq) < 0)) {
                best = c;
            }
        }
        if (best < 0) {
            return;
        }
        uint8_t req[ML_TELEGRAM_LEN];
        memcpy(req, l->queue[best].req, sizeof req);
        l->queue[best].waiting = false;
        if (transmit_request(l, sc, (uint8_t)best, req) != 0) {
            fail_request(l, (uint8_t)best, req); /* may queue or send a new request: re-scan */
        }
    }
}

static int card_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    sbus_card_link_t *l = ctx;
    if (channel >= ML_MAX_CHANNELS) {
        return -1;
    }
    uint8_t sc = sbus_card_link_sbus_channel(l, channel);
    if (l->out[sc - 1u].busy) {
        sbus_queued_t *q = &l->queue[channel];
        q->waiting = true; /* a newer request of the same card channel replaces the older */
        q->seq = l->seq++;
        memcpy(q->req, req, ML_TELEGRAM_LEN);
        return 0;
    }
    return transmit_request(l, sc, channel, req);
}

static void card_param_cancel(void *ctx, uint8_t channel)
{
    sbus_card_link_t *l = ctx;
    if (channel >= ML_MAX_CHANNELS) {
        return;
    }
    l->queue[channel].waiting = false;
    for (uint8_t i = 0; i < 2u; i++) {
        if (l->out[i].busy && l->out[i].channel == channel) {
            l->out[i].given_up = true;
        }
    }
}

static void card_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    sbus_card_link_t *l = ctx;
    if (l->po_stopped) {
        l->po_withheld++;
        return;
    }
    hal_can_frame_t f;
    sbus_pack_pd(&f, sbus_id_po(l->cfg.address), po, n);
    if (send_frame(l->cfg.can, &f) != 0) {
        l->send_errors++;
        return;
    }
    l->po_frames++;
}

static void card_fieldbus_status(void *ctx, const ml_fieldbus_status_t *st)
{
    sbus_card_link_t *l = ctx;
    l->po_stopped = st->timeout;
}

static const ml_link_ops_t sbus_card_ops = {
    .param_request = card_param_request,
    .process_outputs = card_process_outputs,
    .fieldbus_status = card_fieldbus_status,
    .param_cancel = card_param_cancel,
};

void sbus_card_link_init(sbus_card_link_t *l, const sbus_card_link_cfg_t *cfg)
{
    memset(l, 0, sizeof *l);
    l->cfg = *cfg;
    l->cfg.address &= SBUS_ADDRESS_MASK;
    if (l->cfg.timeout_us == 0u) {
        l->cfg.timeout_us = SBUS_PARAM_TIMEOUT_US;
    }
}

ml_link_t sbus_card_link(sbus_card_link_t *l)
{
    return (ml_link_t){.ops = &sbus_card_ops, .ctx = l};
}

static void arm(sbus_card_link_t *l, hal_time_us_t now)
{
    for (uint8_t i = 0; i < 2u; i++) {
        if (l->out[i].busy && !l->out[i].armed) {
            l->out[i].armed = true;
            l->out[i].deadline = now + l->cfg.timeout_us;
        }
    }
}

/* A response for SBus channel sc: it must answer the outstanding request (same service, same
 * index), else it is a late answer to one given up on. */
static void card_response(sbus_card_link_t *l, uint8_t sc, const hal_can_frame_t *f)
{
    sbus_outstanding_t *o = &l->out[sc - 1u];
    if (f->len != ML_TELEGRAM_LEN) {
        l->bad_frames++;
        return;
    }
    if (!o->busy ||
        (f->data[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK) !=
            (o->req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK) ||
        ml_index(f->data) != ml_index(o->req)) {
        l->stale_responses++;
        return;
    }
    uint8_t channel = o->channel;
    bool given_up = o->given_up;
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, f->data, sizeof rsp);
    o->busy = false;
    l->responses++;
    send_next(l, sc); /* whoever waited goes first */
    if (given_up) {
        l->stale_responses++;
        return;
    }
    if (l->cfg.param_response != NULL) {
        l->cfg.param_response(l->cfg.card, channel, rsp);
    }
}

void sbus_card_link_rx(sbus_card_link_t *l, const hal_can_frame_t *f, hal_time_us_t now)
{
    arm(l, now);
    uint8_t a = l->cfg.address;
    if (f->id == sbus_id_pi(a)) {
        uint16_t pi[SBUS_PD_WORDS];
        if (f->len < 2u) {
            l->bad_frames++;
            return;
        }
        uint8_t n = sbus_unpack_pd(f, pi);
        l->pi_frames++;
        if (l->cfg.process_inputs != NULL) {
            l->cfg.process_inputs(l->cfg.card, pi, n);
        }
    } else if (f->id == sbus_id_param_rsp(a)) {
        card_response(l, 1u, f);
    } else if (f->id == sbus_id_param2_rsp(a) && l->cfg.use_channel2) {
        card_response(l, 2u, f);
    }
}

hal_time_us_t sbus_card_link_poll(sbus_card_link_t *l, hal_time_us_t now)
{
    hal_time_us_t next = now + HAL_TIME_NO_DEADLINE_US;
    arm(l, now);
    for (uint8_t i = 0; i < 2u; i++) {
        sbus_outstanding_t *o = &l->out[i];
        if (o->busy && hal_time_reached(now, o->deadline)) {
            o->busy = false; /* the service client has answered 6/2 and waited out a late answer */
            l->timeouts++;
            send_next(l, (uint8_t)(i + 1u));
            arm(l, now);
        }
        if (o->busy) {
            next = hal_time_earlier(next, o->deadline);
        }
    }
    return next;
}

/* ---------------------------------------------------------------------------------------------
 * Inverter side */

void sbus_inverter_init(sbus_inverter_t *inv, const sbus_inverter_cfg_t *cfg)
{
    memset(inv, 0, sizeof *inv);
    inv->cfg = *cfg;
    inv->cfg.address &= SBUS_ADDRESS_MASK;
}

static void inverter_param(sbus_inverter_t *inv, uint16_t rsp_id, const hal_can_frame_t *f)
{
    if (f->len != ML_TELEGRAM_LEN) {
        inv->bad_frames++;
        return;
    }
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, f->data, sizeof rsp);
    inv->requests++;
    if (inv->cfg.param != NULL) {
        inv->cfg.param(inv->cfg.ctx, f->data, rsp);
    }
    hal_can_frame_t out;
    param_frame(&out, rsp_id, rsp);
    if (send_frame(inv->cfg.can, &out) != 0) {
        inv->send_errors++;
    }
}

static void inverter_po(sbus_inverter_t *inv, const hal_can_frame_t *f, hal_time_us_t now)
{
    uint16_t po[SBUS_PD_WORDS];
    if (f->len < 2u) {
        inv->bad_frames++;
        return;
    }
    uint8_t n = sbus_unpack_pd(f, po);
    inv->po_frames++;
    inv->po_seen = true;
    inv->po_deadline = now + inv->cfg.timeout_us;
    if (inv->timed_out) {
        inv->timed_out = false;
        if (inv->cfg.timeout != NULL) {
            inv->cfg.timeout(inv->cfg.ctx, false);
        }
    }
    if (inv->cfg.process_outputs != NULL) {
        inv->cfg.process_outputs(inv->cfg.ctx, po, n);
    }
    uint16_t pi[SBUS_PD_WORDS] = {0, 0, 0};
    if (inv->cfg.process_inputs != NULL) {
        inv->cfg.process_inputs(inv->cfg.ctx, pi, SBUS_PD_WORDS);
    }
    hal_can_frame_t out;
    sbus_pack_pd(&out, sbus_id_pi(inv->cfg.address), pi, SBUS_PD_WORDS);
    if (send_frame(inv->cfg.can, &out) != 0) {
        inv->send_errors++;
    }
}

void sbus_inverter_rx(sbus_inverter_t *inv, const hal_can_frame_t *f, hal_time_us_t now)
{
    uint8_t a = inv->cfg.address;
    if (f->id == sbus_id_po(a)) {
        inverter_po(inv, f, now);
    } else if (f->id == sbus_id_param_req(a)) {
        inverter_param(inv, sbus_id_param_rsp(a), f);
    } else if (f->id == sbus_id_param2_req(a) && inv->cfg.channel2) {
        inverter_param(inv, sbus_id_param2_rsp(a), f);
    }
}

hal_time_us_t sbus_inverter_poll(sbus_inverter_t *inv, hal_time_us_t now)
{
    if (inv->cfg.timeout_us == 0u || !inv->po_seen || inv->timed_out) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    if (!hal_time_reached(now, inv->po_deadline)) {
        return inv->po_deadline;
    }
    inv->timed_out = true;
    if (inv->cfg.timeout != NULL) {
        inv->cfg.timeout(inv->cfg.ctx, true);
    }
    return now + HAL_TIME_NO_DEADLINE_US;
}
