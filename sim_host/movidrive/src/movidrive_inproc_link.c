/* The card's inverter link, in process: requests run on the emulated MOVIDRIVE at once, their
 * responses come back delay_us later from movidrive_inproc_link_poll(), so the card sees the same
 * asynchronous behaviour as over SBus. */
#include <string.h>

#include "movidrive/movidrive.h"

static void push_inputs(movidrive_inproc_link_t *l)
{
    if (l->process_inputs == NULL || l->pd_words == 0) {
        return;
    }
    uint16_t pi[ML_MAX_PD];
    movidrive_process_inputs(l->md, pi, l->pd_words);
    size_t bytes = (size_t)l->pd_words * sizeof pi[0];
    if (l->pushed_valid && l->pushed_words == l->pd_words && memcmp(l->pushed, pi, bytes) == 0) {
        return;
    }
    memcpy(l->pushed, pi, bytes);
    l->pushed_words = l->pd_words;
    l->pushed_valid = true;
    l->process_inputs(l->card, pi, l->pd_words);
}

static int link_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    movidrive_inproc_link_t *l = ctx;
    if (channel >= ML_MAX_CHANNELS || l->ch[channel].pending) {
        return -1;
    }
    movidrive_param(l->md, req, l->ch[channel].rsp);
    l->ch[channel].due = l->now + l->delay_us;
    l->ch[channel].pending = true;
    return 0;
}

static void link_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    movidrive_inproc_link_t *l = ctx;
    if (n > ML_MAX_PD) {
        n = ML_MAX_PD;
    }
    movidrive_process_outputs(l->md, po, n);
    l->pd_words = n;
    if (!l->pi_on_poll_only) {
        push_inputs(l);
    }
}

static void link_fieldbus_status(void *ctx, const ml_fieldbus_status_t *status)
{
    movidrive_inproc_link_t *l = ctx;
    movidrive_fieldbus_status(l->md, status);
}

static const ml_link_ops_t inproc_ops = {
    .param_request = link_param_request,
    .process_outputs = link_process_outputs,
    .fieldbus_status = link_fieldbus_status,
};

ml_link_t movidrive_inproc_link(movidrive_inproc_link_t *l)
{
    return (ml_link_t){.ops = &inproc_ops, .ctx = l};
}

hal_time_us_t movidrive_inproc_link_advance(movidrive_inproc_link_t *l, hal_time_us_t now)
{
    l->now = now;
    hal_time_us_t next = movidrive_tick(l->md, now);
    for (uint8_t c = 0; c < ML_MAX_CHANNELS; c++) {
        if (!l->ch[c].pending) {
            continue;
        }
        if (hal_time_reached(now, l->ch[c].due)) {
            /* Cleared first: the completion may start the next request on this channel. */
            uint8_t rsp[ML_TELEGRAM_LEN];
            memcpy(rsp, l->ch[c].rsp, sizeof rsp);
            l->ch[c].pending = false;
            if (l->param_response != NULL) {
                l->param_response(l->card, c, rsp);
            }
        }
        if (l->ch[c].pending) {
            next = hal_time_earlier(next, l->ch[c].due);
        }
    }
    return next;
}

hal_time_us_t movidrive_inproc_link_poll(movidrive_inproc_link_t *l, hal_time_us_t now)
{
    hal_time_us_t next = movidrive_inproc_link_advance(l, now);
    push_inputs(l);
    return next;
}

void movidrive_inproc_link_card_restarted(movidrive_inproc_link_t *l)
{
    l->pushed_valid = false;
}
