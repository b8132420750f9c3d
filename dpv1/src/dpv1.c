#include "dpv1/dpv1.h"

#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "dpv1/dpv1_wire.h"
#include "hal/hal_byte_order.h"

static void conn_close(dpv1_conn_t *c)
{
    c->open = false;
    c->mailbox = DPV1_MB_EMPTY;
    c->seq++;
    c->pdu_len = 0;
    c->im_selected = IM_INDEX_0;
    ds47_reset(&c->ds47);
}

void dpv1_init(dpv1_t *d, const dpv1_cfg_t *cfg)
{
    memset(d, 0, sizeof *d);
    ds47_init(&d->c1.ds47, cfg->ml, cfg->ch_c1);
    d->c1.im_selected = IM_INDEX_0;
    for (uint8_t i = 0; i < DPV1_C2_CONNECTIONS; i++) {
        ds47_init(&d->c2[i].ds47, cfg->ml, cfg->ch_c2[i]);
        d->c2[i].im_selected = IM_INDEX_0;
    }
    im_init(&d->im, &cfg->identity, cfg->nvm, cfg->nvm_offset);
    d->preempt = cfg->preempt;
    d->preempt_ctx = cfg->preempt_ctx;
}

void dpv1_dp_state(dpv1_t *d, bool data_exch, bool dpv1_mode, uint8_t master)
{
    bool want = data_exch && dpv1_mode;
    if (want && (!d->c1.open || d->c1.master != master)) {
        conn_close(&d->c1);
        d->c1.open = true;
        d->c1.master = master;
    } else if (!want && d->c1.open) {
        conn_close(&d->c1); /* left Data_Exch or re-parameterised: MSAC1 closes */
    }
}

/* ---- receive path ------------------------------------------------------------------------- */

/* A poll hands out a ready response; a PDU goes into the mailbox. Either way: no work here. */
static dp_sap_answer_t mailbox_request(dpv1_conn_t *c, const uint8_t *data, size_t len,
                                       dp_sap_reply_t *reply)
{
    if (len == 0u) {
        if (c->mailbox != DPV1_MB_RESPONSE) {
            return DP_SAP_ANSWER_SC;
        }
        reply->buf = c->frame;
        reply->len = c->pdu_len;
        reply->sum_known = true;
        reply->sum = c->pdu_sum;
        reply->guard = &c->seq;
        reply->guard_value = c->seq;
        c->mailbox = DPV1_MB_EMPTY;
        return DP_SAP_ANSWER_DATA;
    }
    if (len > DPV1_MAX_PDU) {
        len = DPV1_MAX_PDU;
    }
    memcpy(dpv1_pdu(c), data, len);
    c->pdu_len = (uint8_t)len;
    c->seq++;
    c->mailbox = DPV1_MB_REQUEST; /* replaces an unfetched response */
    return DP_SAP_ANSWER_SC;
}

static dp_sap_answer_t abort_reply(uint8_t reason, dp_sap_reply_t *reply)
{
    uint8_t *du = &reply->buf[FDL_TX_HEADROOM];
    du[0] = DPV1_FN_ABORT;
    du[1] = 0; /* subnet: none */
    du[2] = (uint8_t)(DPV1_ABORT_INSTANCE_C2 | reason);
    du[3] = 0;
    reply->len = 4;
    return DP_SAP_ANSWER_DATA;
}

static dp_sap_answer_t resource_manager(dpv1_t *d, uint8_t master, uint8_t ssap,
                                        const uint8_t *data, size_t len, dp_sap_reply_t *reply,
                                        hal_time_us_t t)
{
    if (len < DPV1_INITIATE_MIN || data[0] != DPV1_FN_INITIATE) {
        return abort_reply(DPV1_ABORT_REASON_FE, reply);
    }
    int free_slot = -1;
    for (uint8_t i = 0; i < DPV1_C2_CONNECTIONS; i++) {
        dpv1_conn_t *c = &d->c2[i];
        if (c->open && c->master == master && c->ssap == ssap) {
            conn_close(c); /* the same master initiates again: its old connection is gone */
        }
        if (!c->open && free_slot < 0) {
            free_slot = (int)i;
        }
    }
    if (free_slot < 0) {
        d->c2_refused++;
        return abort_reply(DPV1_ABORT_REASON_RESOURCE, reply);
    }
    dpv1_conn_t *c = &d->c2[free_slot];
    conn_close(c);
    c->open = true;
    c->master = master;
    c->ssap = ssap;
    uint32_t timeout_10ms = hal_get_be16(&data[DPV1_INITIATE_SEND_TIMEOUT]);
    c->send_timeout_us = (timeout_10ms == 0u ? 1u : timeout_10ms) * DPV1_SEND_TIMEOUT_UNIT_US;
    c->last_rx = t;
    (void)mailbox_request(c, data, len, reply); /* Initiate.res comes from poll */
    uint8_t *du = &reply->buf[FDL_TX_HEADROOM];
    du[0] = DPV1_FN_RM;
    du[1] = (uint8_t)(DPV1_C2_FIRST_SAP + (uint8_t)free_slot);
    du[2] = 0;
    du[3] = 0;
    reply->len = 4;
    return DP_SAP_ANSWER_DATA;
}

dp_sap_answer_t dpv1_sap_request(dpv1_t *d, uint8_t master, uint8_t dsap, uint8_t ssap,
                                 const uint8_t *data, size_t len, dp_sap_reply_t *reply,
                                 hal_time_us_t t)
{
    if (dsap == DPV1_SAP_C1) {
        if (!d->c1.open || d->c1.master != master || ssap != DPV1_SAP_C1) {
            return DP_SAP_NOT_SERVED;
        }
        return mailbox_request(&d->c1, data, len, reply);
    }
    if (dsap == DPV1_SAP_RM) {
        return resource_manager(d, master, ssap, data, len, reply, t);
    }
    if (dsap < DPV1_C2_FIRST_SAP + DPV1_C2_CONNECTIONS) {
        dpv1_conn_t *c = &d->c2[dsap - DPV1_C2_FIRST_SAP];
        if (!c->open || c->master != master || c->ssap != ssap) {
            return DP_SAP_NOT_SERVED;
        }
        if (hal_time_diff(t, c->last_rx) > (int32_t)c->send_timeout_us) {
            /* Silent for longer than its Send_Timeout: gone, even if the main loop has not
             * noticed yet. */
            conn_close(c);
            d->c2_timeouts++;
            return DP_SAP_NOT_SERVED;
        }
        c->last_rx = t;
        if (len > 0u && data[0] == DPV1_FN_ABORT) {
            conn_close(c);
            d->c2_aborts++;
            return DP_SAP_ANSWER_SC;
        }
        if (len > 0u && data[0] == DPV1_FN_IDLE) {
            size_t n = len < DPV1_HEADER_LEN ? len : DPV1_HEADER_LEN;
            /* keep-alive: echoed, the mailbox is left alone */
            memcpy(&reply->buf[FDL_TX_HEADROOM], data, n);
            reply->len = n;
            return DP_SAP_ANSWER_DATA;
        }
        return mailbox_request(c, data, len, reply);
    }
    return DP_SAP_NOT_SERVED;
}

/* ---- main loop ---------------------------------------------------------------------------- */

static size_t negative(uint8_t *rsp, uint8_t fn, uint8_t code)
{
    rsp[0] = (uint8_t)(fn | DPV1_FN_ERROR);
    rsp[1] = DPV1_ERROR_DECODE;
    rsp[2] = code;
    rsp[3] = 0;
    return 4;
}

static void preempt(const dpv1_t *d)
{
    if (d->preempt != NULL) {
        d->preempt(d->preempt_ctx);
    }
}

/* Data set 47's response, written into pdu from the parameters in bounded steps with the
 * caller's chance to reply in between; false when the Read was replaced or the connection closed
 * meanwhile (the response then stays unread). */
static bool read_ds47(dpv1_t *d, dpv1_conn_t *c, uint8_t seq, uint8_t *out, uint8_t want,
                      size_t *n, uint8_t *sum, uint8_t *err)
{
    ds47_read_cursor_t cur;
    *err = ds47_read_begin(&c->ds47, out, want, &cur);
    if (*err != 0u) {
        return true;
    }
    while (ds47_read_step(&c->ds47, out, &cur)) {
        preempt(d);
        if (c->seq != seq) {
            return false;
        }
    }
    ds47_read_done(&c->ds47);
    *n = cur.len;
    *sum = cur.sum;
    return true;
}

/* The response is written over the request in pdu: function, slot and index stay in place.
 * *data_sum: the octet sum of the data after the header. 0 when the request was dropped. */
static size_t do_read(dpv1_t *d, dpv1_conn_t *c, uint8_t *pdu, size_t len, uint8_t seq,
                      uint8_t *data_sum)
{
    *data_sum = 0;
    if (len < DPV1_HEADER_LEN) {
        return negative(pdu, DPV1_FN_READ, DPV1_ERR_INVALID_RANGE);
    }
    uint8_t index = pdu[2];
    uint8_t want = pdu[3];
    if (want == 0u || want > DPV1_MAX_DATA) {
        return negative(pdu, DPV1_FN_READ, DPV1_ERR_INVALID_RANGE);
    }
    size_t n = 0;
    uint8_t err;
    if (index == DPV1_INDEX_DS47) {
        if (!read_ds47(d, c, seq, &pdu[DPV1_HEADER_LEN], want, &n, data_sum, &err)) {
            return 0;
        }
    } else if (index == DPV1_INDEX_IM) {
        err = im_read(&d->im, c->im_selected, &pdu[DPV1_HEADER_LEN], want, &n);
        *data_sum = fdl_fcs(&pdu[DPV1_HEADER_LEN], n);
    } else {
        err = DPV1_ERR_INVALID_INDEX;
    }
    if (err != 0u) {
        return negative(pdu, DPV1_FN_READ, err);
    }
    pdu[3] = (uint8_t)n;
    return DPV1_HEADER_LEN + n;
}

/* Data set 47 in bounded steps with the caller's chance to reply in between; false when the
 * request was replaced or the connection closed meanwhile (then nothing is answered). */
static bool write_ds47(dpv1_t *d, dpv1_conn_t *c, uint8_t seq, const uint8_t *data, size_t n,
                       hal_time_us_t now, uint8_t *err)
{
    *err = ds47_write_step(&c->ds47, data, n, now);
    while (*err == DS47_IN_PROGRESS) {
        preempt(d);
        if (c->seq != seq) {
            if (c->ds47.state == DS47_PARSING) {
                ds47_reset(&c->ds47);
            }
            return false;
        }
        *err = ds47_write_step(&c->ds47, data, n, now);
    }
    return true;
}

/* The response (the request's header, or a negative one) over the request in pdu; 0 when the
 * request was dropped meanwhile. */
static size_t do_write(dpv1_t *d, dpv1_conn_t *c, uint8_t *pdu, size_t len, uint8_t seq,
                       hal_time_us_t now)
{
    if (len < DPV1_HEADER_LEN) {
        return negative(pdu, DPV1_FN_WRITE, DPV1_ERR_WRITE_LENGTH);
    }
    uint8_t index = pdu[2];
    uint8_t n = pdu[3];
    if (n == 0u || n > DPV1_MAX_DATA || (size_t)n != len - DPV1_HEADER_LEN) {
        return negative(pdu, DPV1_FN_WRITE, DPV1_ERR_WRITE_LENGTH);
    }
    uint8_t err;
    if (index == DPV1_INDEX_DS47) {
        if (!write_ds47(d, c, seq, &pdu[DPV1_HEADER_LEN], n, now, &err)) {
            return 0;
        }
    } else if (index == DPV1_INDEX_IM) {
        err = im_write(&d->im, &pdu[DPV1_HEADER_LEN], n, &c->im_selected);
    } else {
        err = DPV1_ERR_INVALID_INDEX;
    }
    if (err != 0u) {
        return negative(pdu, DPV1_FN_WRITE, err);
    }
    return DPV1_HEADER_LEN;
}

/* Initiate.res: our limits. A slave mirrors the Profile_Ident_Number only if it supports the
 * requested profile (protocol.md §A4.4); the DFP21B's profile ident is 0 (manual §6.5), so a
 * master asking for PROFIdrive (3A 00) must not be told it is there: ident and profile features
 * are answered 0 whatever was asked. */
static size_t do_initiate(uint8_t *rsp)
{
    rsp[0] = DPV1_FN_INITIATE;
    rsp[1] = DPV1_MAX_DATA;
    rsp[2] = DPV1_FEATURES_1_DPV1_RW;
    rsp[3] = 0x00; /* Features_Supported_2 */
    memset(&rsp[4], 0, DPV1_INITIATE_RES_HEAD_LEN - 4u); /* profile features and ident: 0 */
    return DPV1_INITIATE_RES_HEAD_LEN;
}

static void serve(dpv1_t *d, dpv1_conn_t *c, bool class2, hal_time_us_t now)
{
    if (c->ds47.state == DS47_BUSY) {
        ds47_poll(&c->ds47, now);
        preempt(d);
    }
    if (c->mailbox != DPV1_MB_REQUEST) {
        return;
    }
    uint8_t seq = c->seq;
    uint8_t *pdu = dpv1_pdu(c);
    size_t len = c->pdu_len;
    size_t n;
    uint8_t data_sum = 0;
    switch (pdu[0]) {
    case DPV1_FN_READ:
        n = do_read(d, c, pdu, len, seq, &data_sum);
        if (n == 0u) {
            return; /* replaced or closed while being answered: the next pass serves what is new */
        }
        break;
    case DPV1_FN_WRITE:
        n = do_write(d, c, pdu, len, seq, now);
        if (n == 0u) {
            return; /* replaced or closed while being parsed: the next pass serves what is new */
        }
        break;
    case DPV1_FN_INITIATE:
        n = class2 ? do_initiate(pdu) : negative(pdu, pdu[0], DPV1_ERR_NOT_SUPPORTED);
        break;
    default:
        n = negative(pdu, pdu[0], DPV1_ERR_NOT_SUPPORTED);
        break;
    }
    c->pdu_len = (uint8_t)n;
    /* The reply path frames the response without adding it up; a read's data was summed where it
     * was made. Every other response is a header of a few octets. */
    size_t summed = n > DPV1_HEADER_LEN && pdu[0] == DPV1_FN_READ ? DPV1_HEADER_LEN : n;
    c->pdu_sum = (uint8_t)(fdl_fcs(pdu, summed) + (summed < n ? data_sum : 0u));
    c->mailbox = DPV1_MB_RESPONSE;
}

/* Work is left when a request waits (one that replaced another during a parse). */
static bool request_waiting(const dpv1_t *d)
{
    if (d->c1.open && d->c1.mailbox == DPV1_MB_REQUEST) {
        return true;
    }
    for (uint8_t i = 0; i < DPV1_C2_CONNECTIONS; i++) {
        if (d->c2[i].open && d->c2[i].mailbox == DPV1_MB_REQUEST) {
            return true;
        }
    }
    return false;
}

hal_time_us_t dpv1_poll(dpv1_t *d, hal_time_us_t now)
{
    hal_time_us_t next = now + HAL_TIME_NO_DEADLINE_US;
    if (d->c1.open) {
        serve(d, &d->c1, false, now);
    }
    for (uint8_t i = 0; i < DPV1_C2_CONNECTIONS; i++) {
        dpv1_conn_t *c = &d->c2[i];
        preempt(d);
        if (!c->open) {
            continue;
        }
        hal_time_us_t deadline = c->last_rx + c->send_timeout_us;
        if (hal_time_reached(now, deadline)) {
            conn_close(c); /* the master fell silent: the connection is free again */
            d->c2_timeouts++;
            continue;
        }
        next = hal_time_earlier(next, deadline);
        serve(d, c, true, now);
    }
    return request_waiting(d) ? now : next;
}
