/* A fake inverter link for the fuzz targets: it holds every parameter request it was given (per
 * channel, oldest first) and answers when the input says so, correctly, with an error, with
 * another index or service, with garbage, twice, or never. Every request gets a tag so a
 * target can tell which request an answer belonged to. */
#ifndef TESTS_FUZZ_FUZZ_LINK_H
#define TESTS_FUZZ_FUZZ_LINK_H

#include "fuzz_common.h"
#include "movilink/movilink_link.h"
#include "movilink/movilink_wire.h"

#define FL_HELD_MAX 8u

typedef struct fl_held {
    uint8_t req[ML_TELEGRAM_LEN];
    uint32_t tag;
} fl_held_t;

typedef struct fake_link {
    fl_held_t held[ML_MAX_CHANNELS][FL_HELD_MAX];
    uint8_t n_held[ML_MAX_CHANNELS];
    bool refuse;
    uint32_t next_tag;
    uint32_t requests[ML_MAX_CHANNELS];
    /* Optional observer of every request the link accepted. */
    void (*on_request)(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                       uint32_t tag);
    void *ctx;
    /* Where answers go (ml_client_response or the card's entry point). */
    void (*deliver)(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN]);
    void *deliver_ctx;
    /* Set while an answer is being delivered: the tag of the request it answers. */
    uint32_t delivering_tag;
    bool delivering;
    uint32_t n_fieldbus_status;
    ml_fieldbus_status_t fieldbus;
    uint16_t po[ML_MAX_PD];
    uint8_t po_n;
    uint32_t po_count;
} fake_link_t;

static int fl_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    fake_link_t *l = ctx;
    PROPERTY(channel < ML_MAX_CHANNELS, "request on channel %u", channel);
    PROPERTY((req[ML_OFF_MANAGEMENT] & (ML_MGMT_HANDSHAKE | ML_MGMT_ERROR)) == 0u,
             "handshake or error bit sent to the inverter: %02X", req[ML_OFF_MANAGEMENT]);
    if (l->refuse) {
        return -1;
    }
    uint32_t tag = ++l->next_tag;
    l->requests[channel]++;
    if (l->n_held[channel] < FL_HELD_MAX) {
        fl_held_t *h = &l->held[channel][l->n_held[channel]++];
        memcpy(h->req, req, ML_TELEGRAM_LEN);
        h->tag = tag;
    }
    if (l->on_request != NULL) {
        l->on_request(l->ctx, channel, req, tag);
    }
    return 0;
}

static void fl_process_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    fake_link_t *l = ctx;
    PROPERTY(n <= ML_MAX_PD, "%u PO words", n);
    memcpy(l->po, po, n * sizeof po[0]);
    l->po_n = n;
    l->po_count++;
}

static void fl_fieldbus_status(void *ctx, const ml_fieldbus_status_t *st)
{
    fake_link_t *l = ctx;
    l->fieldbus = *st;
    l->n_fieldbus_status++;
}

static const ml_link_ops_t fl_ops = {
    .param_request = fl_param_request,
    .process_outputs = fl_process_outputs,
    .fieldbus_status = fl_fieldbus_status,
};

static inline ml_link_t fl_link(fake_link_t *l) { return (ml_link_t){.ops = &fl_ops, .ctx = l}; }

/* The answer a MOVIDRIVE might give to req: a value (read) or an echo (write), or a class-8
 * error, chosen by the input. */
static inline void fl_good_answer(fz_t *f, const uint8_t req[ML_TELEGRAM_LEN],
                                  uint8_t rsp[ML_TELEGRAM_LEN])
{
    memcpy(rsp, req, ML_TELEGRAM_LEN);
    uint8_t how = fz_u8(f);
    if ((how & 3u) == 3u) {
        ml_put_error(rsp, ML_CLASS_OTHER, 0, (uint16_t)(0x10u + (how >> 2) % 0x11u));
    } else {
        uint8_t svc = (uint8_t)(req[0] & ML_MGMT_SERVICE_MASK);
        if (svc != ML_SVC_WRITE && svc != ML_SVC_WRITE_VOLATILE) {
            ml_put_data(rsp, fz_u32(f));
        }
    }
}

/* Answers the oldest request held on a channel. mode: 0 correct, 1 another index, 2 another
 * service, 3 garbage; keep: the request stays held (a duplicate answer may follow). Returns
 * false when nothing was held there. */
static inline bool fl_answer(fake_link_t *l, fz_t *f, uint8_t channel, uint8_t mode, bool keep)
{
    channel = (uint8_t)(channel % ML_MAX_CHANNELS);
    if (l->n_held[channel] == 0u) {
        return false;
    }
    fl_held_t h = l->held[channel][0];
    if (!keep) {
        memmove(&l->held[channel][0], &l->held[channel][1],
                (size_t)(l->n_held[channel] - 1u) * sizeof h);
        l->n_held[channel]--;
    }
    uint8_t rsp[ML_TELEGRAM_LEN];
    switch (mode & 3u) {
    case 0: fl_good_answer(f, h.req, rsp); break;
    case 1:
        memcpy(rsp, h.req, sizeof rsp);
        rsp[3] = (uint8_t)(rsp[3] + 1u + fz_u8(f) % 200u);
        break;
    case 2:
        memcpy(rsp, h.req, sizeof rsp);
        rsp[0] = (uint8_t)((rsp[0] & 0xF0u) | ((rsp[0] + 1u) & 0x0Fu));
        break;
    default: fz_bytes(f, rsp, sizeof rsp); break;
    }
    l->delivering = true;
    l->delivering_tag = h.tag;
    l->deliver(l->deliver_ctx, channel, rsp);
    l->delivering = false;
    l->delivering_tag = 0;
    return true;
}

/* The properties of the findings fixed in the core (docs/quality.md) are checked by default;
 * FUZZ_KNOWN=none switches them off, e.g. to fuzz an older tree. */
static inline bool fz_known(const char *name)
{
    const char *k = getenv("FUZZ_KNOWN");
    if (k == NULL) {
        /* ml_late_answer in its strict form (an answer may come any time later) cannot hold
         * without a tag in the 8-byte telegram: the core bounds it (quarantine of two timeouts,
         * docs/quality.md), so it stays opt-in. */
        return strcmp(name, "ml_late_answer") != 0;
    }
    if (strcmp(k, "all") == 0) {
        return true;
    }
    return strcmp(k, "none") != 0 && strstr(k, name) != NULL;
}

#endif
