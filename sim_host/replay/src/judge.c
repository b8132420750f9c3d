/* Judging one request's answer (judge.h): exact octets, except those the mask leaves out. */
#include "judge.h"

#include <string.h>

/* Where PI1 begins in a Data_Exchange answer's data unit with the configuration the card holds
 * now (learnt from the capture's Chk_Cfg); -1 while it has none. */
static int pi_offset(const replay_t *r)
{
    const dfp21b_t *card = &r->cs->card;
    if (!card->pd.valid) {
        return -1;
    }
    return card->pd.param_channel ? 8 : 0;
}

/* Are the two answers the same? Octets the mask leaves out (bits) are not compared; *masked
 * says how many there were. */
static bool same_answer(replay_t *r, uint8_t *bits, size_t bits_len, unsigned *masked)
{
    memset(bits, 0, bits_len);
    *masked = 0;
    if (r->pend_expected != r->pend_actual) {
        return false;
    }
    if (!r->pend_expected) {
        return true; /* neither answered */
    }
    const replay_kept_t *e = &r->pend_expected_rec;
    const replay_kept_t *a = &r->pend_actual_rec;
    *masked = replay_mask_answer(r->opt.mask, r->pend_service, pi_offset(r), e->data, e->len,
                                 bits, bits_len);
    if (e->len != a->len) {
        return false;
    }
    for (size_t i = 0; i < e->len; i++) {
        if (e->data[i] != a->data[i] && !replay_bit(bits, i)) {
            return false;
        }
    }
    return true;
}

/* The mismatch as on_mismatch gets it. */
static void hand_over(replay_t *r, const uint8_t *bits, unsigned masked)
{
    if (r->opt.on_mismatch == NULL) {
        return;
    }
    replay_listed_t *l = &r->listed;
    memset(l, 0, offsetof(replay_listed_t, request));
    l->number = r->mismatches;
    l->service = r->pend_service;
    l->t_ns = r->pend_request.t_ns;
    l->record = r->pend_request.record;
    l->position = r->pend_request.position;
    l->request_len = (uint16_t)r->pend_request.len;
    memcpy(l->request, r->pend_request.data, r->pend_request.len);
    l->expected_present = r->pend_expected;
    if (r->pend_expected) {
        const replay_kept_t *e = &r->pend_expected_rec;
        replay_frame_t f;
        replay_frame_parse(e->data, e->len, &f);
        l->expected_record = e->record;
        l->expected_position = e->position;
        l->expected_len = (uint16_t)e->len;
        l->data_offset = f.du != NULL ? (uint16_t)(f.du - e->data) : 0u;
        memcpy(l->expected, e->data, e->len);
    }
    l->actual_present = r->pend_actual;
    if (r->pend_actual) {
        l->actual_len = (uint16_t)r->pend_actual_rec.len;
        memcpy(l->actual, r->pend_actual_rec.data, r->pend_actual_rec.len);
    }
    l->masked = (uint16_t)masked;
    memcpy(l->mask, bits, sizeof l->mask);
    r->opt.on_mismatch(r->opt.mismatch_ctx, l);
}

/* The first mismatch, kept whole for the report: the card's state and the telegrams before. */
static void keep_first(replay_t *r, const uint8_t *bits)
{
    replay_mismatch_t *m = &r->first;
    m->valid = true;
    m->service = r->pend_service;
    m->request = r->pend_request;
    snprintf(m->request_problem, sizeof m->request_problem, "%s", r->pend_request_problem);
    m->expected_present = r->pend_expected;
    m->expected = r->pend_expected_rec;
    snprintf(m->expected_problem, sizeof m->expected_problem, "%s", r->pend_expected_problem);
    m->actual_present = r->pend_actual;
    m->actual = r->pend_actual_rec;
    m->fcb_repeat = r->pend_fcb_repeat;
    m->card_state = r->pend_card_state;
    /* The rate as the request ended: still searching means the card did not take it. */
    m->baud_state = dp_slave_baud_state(&r->cs->card.dp);
    m->card_baud = dp_slave_baud(&r->cs->card.dp);
    m->set_prm_seen = r->set_prm_seen;
    const dfp21b_t *card = &r->cs->card;
    m->layout.known = card->pd.valid;
    m->layout.param_channel = card->pd.param_channel;
    memcpy(m->mask, bits, sizeof m->mask);
    /* The newest ring entries are the request and (if any) the card's answer. */
    unsigned skip = 1u + (r->pend_actual ? 1u : 0u);
    unsigned n = 0;
    if (r->ring_len > skip) {
        n = r->ring_len - skip;
    }
    if (n > REPLAY_CONTEXT) {
        n = REPLAY_CONTEXT;
    }
    for (unsigned i = 0; i < n; i++) {
        unsigned back = skip + n - i; /* 1 = newest */
        unsigned idx = (unsigned)((r->ring_next + RING_SIZE - back) % RING_SIZE);
        m->before[i] = r->ring[idx];
    }
    m->n_before = n;
}

void replay_judge(replay_t *r)
{
    if (!r->pending) {
        return;
    }
    r->pending = false;
    replay_counts_t *c = &r->svc[r->pend_service];
    c->requests++;
    if (!r->pend_expected) c->capture_silent++;
    if (!r->pend_actual) c->card_silent++;
    if (r->pend_expected && !r->pend_actual) c->missing++;
    if (!r->pend_expected && r->pend_actual) c->extra++;
    uint8_t bits[CAP_MAX_RECORD / 8u];
    unsigned masked = 0;
    bool same = same_answer(r, bits, sizeof bits, &masked);
    c->masked_octets += masked;
    r->masked_octets += masked;
    if (same) {
        c->matched++;
        return;
    }
    c->differ++;
    r->mismatches++;
    hand_over(r, bits, masked);
    if (!r->first.valid) {
        keep_first(r, bits);
    }
}
