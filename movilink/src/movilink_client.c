#include "movilink/movilink_client.h"

#include <string.h>

void ml_client_init(ml_client_t *c, ml_link_t link, uint32_t timeout_us)
{
    memset(c, 0, sizeof *c);
    c->link = link;
    c->timeout_us = timeout_us != 0u ? timeout_us : ML_RESPONSE_TIMEOUT_US;
}

bool ml_client_busy(const ml_client_t *c, uint8_t channel)
{
    return channel < ML_MAX_CHANNELS && (c->ch[channel].busy || c->ch[channel].quarantine);
}

/* The card's own answer when the inverter cannot be asked or does not answer. */
static void fail_hardware(ml_client_t *c, uint8_t channel)
{
    ml_pending_t *p = &c->ch[channel];
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, p->req, sizeof rsp);
    ml_put_error(rsp, ML_CLASS_ACCESS, ML_CODE_HARDWARE_FAULT, 0);
    p->busy = false;
    if (p->done != NULL) {
        p->done(p->done_ctx, channel, rsp);
    }
}

int ml_client_request(ml_client_t *c, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                      ml_done_fn done, void *done_ctx, hal_time_us_t now)
{
    if (channel >= ML_MAX_CHANNELS || ml_client_busy(c, channel)) {
        return -1;
    }
    ml_pending_t *p = &c->ch[channel];
    memcpy(p->req, req, ML_TELEGRAM_LEN);
    p->req[ML_OFF_MANAGEMENT] &= (uint8_t)~(ML_MGMT_HANDSHAKE | ML_MGMT_ERROR);
    p->done = done;
    p->done_ctx = done_ctx;
    p->deadline = now + c->timeout_us;
    p->busy = true;
    if (c->link.ops == NULL || c->link.ops->param_request == NULL ||
        c->link.ops->param_request(c->link.ctx, channel, p->req) != 0) {
        fail_hardware(c, channel);
    }
    return 0;
}

void ml_client_response(ml_client_t *c, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    if (channel >= ML_MAX_CHANNELS) {
        c->stale_responses++;
        return;
    }
    ml_pending_t *p = &c->ch[channel];
    if (p->quarantine) {
        p->quarantine = false; /* the late answer of a timed-out request: the channel is free */
        c->stale_responses++;
        return;
    }
    if (!p->busy) {
        c->stale_responses++;
        return;
    }
    uint8_t want_svc = (uint8_t)(p->req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK);
    uint8_t got_svc = (uint8_t)(rsp[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK);
    if (got_svc != want_svc || ml_index(rsp) != ml_index(p->req)) {
        c->stale_responses++; /* an answer to an earlier, timed-out request */
        return;
    }
    p->busy = false;
    if (p->done != NULL) {
        p->done(p->done_ctx, channel, rsp);
    }
}

hal_time_us_t ml_client_poll(ml_client_t *c, hal_time_us_t now)
{
    hal_time_us_t next = now + HAL_TIME_NO_DEADLINE_US;
    for (uint8_t i = 0; i < ML_MAX_CHANNELS; i++) {
        ml_pending_t *p = &c->ch[i];
        if (!p->busy && !p->quarantine) {
            continue;
        }
        if (hal_time_reached(now, p->deadline)) {
            if (p->quarantine) {
                p->quarantine = false; /* no late answer came: the channel is free */
                continue;
            }
            c->timeouts++;
            p->quarantine = true;
            p->deadline = now + c->timeout_us;
            if (c->link.ops != NULL && c->link.ops->param_cancel != NULL) {
                c->link.ops->param_cancel(c->link.ctx, i);
            }
            fail_hardware(c, i);
        }
        next = hal_time_earlier(next, p->deadline);
    }
    return next;
}
