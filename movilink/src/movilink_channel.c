#include "movilink/movilink_channel.h"

#include <string.h>

void ml_channel_init(ml_channel_t *ch, ml_client_t *client, uint8_t channel)
{
    memset(ch, 0, sizeof *ch);
    ch->client = client;
    ch->channel = channel;
}

static void finish(ml_channel_t *ch, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    memcpy(ch->reply, rsp, ML_TELEGRAM_LEN);
    ch->reply[ML_OFF_MANAGEMENT] =
        (uint8_t)((rsp[ML_OFF_MANAGEMENT] & (uint8_t)~ML_MGMT_HANDSHAKE) | ch->running_handshake);
    ch->handshake = ch->running_handshake;
    ch->busy = false;
}

static void on_done(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)channel;
    finish(ctx, rsp);
}

/* Errors the card detects itself, without asking the inverter. */
static void card_error(ml_channel_t *ch, const uint8_t req[ML_TELEGRAM_LEN], uint8_t err_class,
                       uint8_t code)
{
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, req, sizeof rsp);
    rsp[ML_OFF_MANAGEMENT] &= (uint8_t)~ML_MGMT_ERROR;
    ml_put_error(rsp, err_class, code, 0);
    finish(ch, rsp);
}

void ml_channel_request(ml_channel_t *ch, const uint8_t req[ML_TELEGRAM_LEN], hal_time_us_t now)
{
    uint8_t mgmt = req[ML_OFF_MANAGEMENT];
    uint8_t hs = (uint8_t)(mgmt & ML_MGMT_HANDSHAKE);
    if (ch->busy || hs == ch->handshake) {
        return; /* no edge, or the previous service still runs: keep the last reply */
    }
    if (ml_client_busy(ch->client, ch->channel)) {
        return; /* the link still drains a timed-out service: take the edge next cycle */
    }
    ch->running_handshake = hs;
    ch->busy = true;
    ch->services++;
    uint8_t svc = (uint8_t)(mgmt & ML_MGMT_SERVICE_MASK);
    if (svc > ML_SVC_LAST || (mgmt & ML_MGMT_ERROR) != 0u || req[ML_OFF_RESERVED] != 0u) {
        card_error(ch, req, ML_CLASS_SERVICE, ML_CODE_ILLEGAL_PARAMETER);
        return;
    }
    bool is_write = svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE;
    if (is_write && (mgmt & ML_MGMT_LENGTH_MASK) != ML_MGMT_LENGTH_4) {
        card_error(ch, req, ML_CLASS_ACCESS, ML_CODE_TYPE_CONFLICT);
        return;
    }
    if (svc == ML_SVC_NONE) {
        uint8_t rsp[ML_TELEGRAM_LEN];
        memcpy(rsp, req, sizeof rsp);
        finish(ch, rsp); /* nothing to do: acknowledge the new handshake */
        return;
    }
    if (ml_client_request(ch->client, ch->channel, req, on_done, ch, now) != 0) {
        /* The client channel is ours alone, so this only happens on a programming error;
         * answer rather than hang the master's handshake. */
        card_error(ch, req, ML_CLASS_ACCESS, ML_CODE_HARDWARE_FAULT);
    }
}
