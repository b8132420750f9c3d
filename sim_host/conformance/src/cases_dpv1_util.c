/* The DP-V1 exchange and the MSAC2 connection the DP-V1 cases share (cases_dpv1_internal.h). */
#include <stdio.h>
#include <string.h>

#include "cases_dpv1_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "dpv1/dpv1_wire.h"

/* How an answer to a request or a poll reads. */
typedef enum v1_kind {
    K_PENDING = 0, /* taken, no response yet: SC, NR/OK without data, data of SAPs only */
    K_DATA,
    K_REFUSED,
    K_SILENT,
    K_BAD,
} v1_kind_t;

uint64_t v1_now_ms(const cf_t *cf)
{
    return cf->link.ops->now_ns(cf->link.ctx) / 1000000u;
}

uint32_t v1_key(const cf_t *cf, gsd_key_t k)
{
    uint32_t v = 0;
    (void)gsd_key(cf->gsd, k, &v);
    return v;
}

static uint32_t timeout_ms_of(const cf_t *cf, gsd_key_t k)
{
    uint32_t v = v1_key(cf, k); /* in 10 ms */
    return v == 0u ? V1_RESPONSE_TIMEOUT_DEFAULT_MS : v * 10u;
}

uint32_t v1_c1_timeout_ms(const cf_t *cf)
{
    return timeout_ms_of(cf, GSD_K_C1_RESPONSE_TIMEOUT);
}

uint32_t v1_c2_timeout_ms(const cf_t *cf)
{
    return timeout_ms_of(cf, GSD_K_C2_RESPONSE_TIMEOUT);
}

const char *v1_fdl_code_name(int code)
{
    return cf_rsp_name(code);
}

const char *v1_hex(const uint8_t *p, size_t n, char *buf, size_t cap)
{
    size_t shown = n > 12u ? 12u : n;
    size_t at = 0;
    buf[0] = '\0';
    /* cppcheck 2.10 concludes n == 0 from the callers it follows; n is any PDU's length. */
    // cppcheck-suppress knownConditionTrueFalse
    for (size_t i = 0; i < shown && at + 4u < cap; i++) {
        at += (size_t)snprintf(&buf[at], cap - at, i == 0u ? "%02X" : " %02X", p[i]);
    }
    // cppcheck-suppress knownConditionTrueFalse
    if (shown < n && at + 5u < cap) {
        snprintf(&buf[at], cap - at, " ...");
    }
    return buf;
}

bool v1_negative(const uint8_t *pdu, size_t len, uint8_t fn, uint8_t *code1)
{
    if (len != 4u || pdu[0] != (uint8_t)(fn | DPV1_FN_ERROR) || pdu[1] != DPV1_ERROR_DECODE) {
        return false;
    }
    *code1 = pdu[2];
    return true;
}

const char *v1_error_name(uint8_t code1)
{
    static const char *const access[16] = {
        "invalid index", "write length error", "invalid slot", "type conflict", "invalid area",
        "state conflict", "access denied", "invalid range", "invalid parameter", "invalid type",
        "user (access)", "user (access)", "user (access)", "user (access)", "user (access)",
        "user (access)",
    };
    switch (code1 >> 4) {
    case 0xA: return code1 == 0xA9u ? "feature not supported" : "application error";
    case 0xB: return access[code1 & 0x0Fu];
    case 0xC: return "resource error";
    default: return "user-specific error";
    }
}

/* An answer to a request (or a poll) on path p. */
static v1_kind_t classify(cf_t *cf, const v1_path_t *p, const cf_reply_t *r, bool poll,
                          v1_result_t *out)
{
    cf_answer_t a;
    if (r->len == 0u && !r->garbled) {
        return K_SILENT;
    }
    if (cf_is_sc(r)) {
        return K_PENDING;
    }
    if (!cf_answer(r, &a) || (a.fc & FDL_FC_REQUEST) != 0u) {
        char txt[64];
        (void)cf_fail(cf, "expected an answer to the SRD on SAP %u, got %s", p->dsap,
                      cf_reply_text(r, txt, sizeof txt));
        return K_BAD;
    }
    int code = (int)(a.fc & FDL_FC_CODE_MASK);
    bool data = code == FDL_RSP_DL || code == FDL_RSP_DH;
    if (code == FDL_RSP_NR || code == FDL_RSP_OK || (data && a.du_len == 0u) ||
        (poll && code == FDL_RSP_RR)) {
        return K_PENDING; /* no data: the response is not there yet (protocol.md §A10 item 1) */
    }
    if (!data) {
        out->fdl_code = code;
        return K_REFUSED;
    }
    if (!a.saps || a.dsap != p->ssap || a.ssap != p->dsap) {
        (void)cf_fail(cf, "expected the response from SAP %u to SAP %u (SAPs swapped), got %s",
                      p->dsap, p->ssap, a.saps ? "other SAPs" : "no SAPs");
        return K_BAD;
    }
    memcpy(out->pdu, a.du, a.du_len);
    out->len = a.du_len;
    return K_DATA;
}

static v1_status_t status_of(v1_kind_t k)
{
    switch (k) {
    case K_DATA: return V1_RESPONSE;
    case K_REFUSED: return V1_REFUSED;
    case K_SILENT: return V1_SILENT;
    case K_BAD: return V1_BROKEN;
    default: return V1_TIMEOUT;
    }
}

v1_status_t v1_call(cf_t *cf, const v1_path_t *p, const uint8_t *pdu, size_t len,
                    uint32_t timeout_ms, v1_result_t *out)
{
    cf_reply_t r;
    memset(out, 0, sizeof *out);
    out->fdl_code = -1;
    uint64_t deadline = v1_now_ms(cf) + timeout_ms;
    if (len > 0u) {
        if (!cf_request(cf, p->sa, FDL_REQ_SRD_HIGH, p->dsap, p->ssap, pdu, len, &r)) {
            return V1_BROKEN;
        }
        v1_kind_t k = classify(cf, p, &r, false, out);
        if (k != K_PENDING) {
            return status_of(k);
        }
    }
    while (v1_now_ms(cf) < deadline) {
        if (out->polls > 0u && !cf_pause_ms(cf, 1)) {
            return V1_BROKEN;
        }
        out->polls++;
        if (!cf_request(cf, p->sa, FDL_REQ_SRD_HIGH, p->dsap, p->ssap, NULL, 0, &r)) {
            return V1_BROKEN;
        }
        v1_kind_t k = classify(cf, p, &r, true, out);
        if (k != K_PENDING) {
            return status_of(k);
        }
    }
    return V1_TIMEOUT;
}

v1_status_t v1_write_read(cf_t *cf, const v1_path_t *p, const uint8_t *wpdu, size_t wlen,
                          uint32_t timeout_ms, v1_result_t *wres, v1_result_t *rres)
{
    uint64_t deadline = v1_now_ms(cf) + timeout_ms;
    v1_status_t st = v1_call(cf, p, wpdu, wlen, timeout_ms, wres);
    if (st != V1_RESPONSE || wres->pdu[0] != DPV1_FN_WRITE) {
        return st; /* the caller judges a refused or negative Write */
    }
    const uint8_t rpdu[DPV1_HEADER_LEN] = { DPV1_FN_READ, wpdu[1], wpdu[2], DPV1_MAX_DATA };
    uint8_t code1 = 0;
    do {
        uint64_t now = v1_now_ms(cf);
        uint32_t left = now < deadline ? (uint32_t)(deadline - now) : 1u;
        st = v1_call(cf, p, rpdu, sizeof rpdu, left, rres);
        if (st != V1_RESPONSE || !v1_negative(rres->pdu, rres->len, DPV1_FN_READ, &code1) ||
            code1 != DPV1_ERR_STATE_CONFLICT) {
            return st;
        }
    } while (v1_now_ms(cf) < deadline && cf_pause_ms(cf, 2));
    return cf->link_failed ? V1_BROKEN : V1_TIMEOUT;
}

bool v1_need_response(cf_t *cf, v1_status_t st, const v1_result_t *r, const char *what)
{
    switch (st) {
    case V1_RESPONSE: return true;
    case V1_REFUSED:
        return cf_fail(cf, "expected a response to %s, got the FDL refusal %s", what,
                       v1_fdl_code_name(r->fdl_code));
    case V1_SILENT: return cf_fail(cf, "expected a response to %s, got silence", what);
    case V1_TIMEOUT:
        return cf_fail(cf, "expected a response to %s, got none after %u polls", what,
                       (unsigned)r->polls);
    default: return false;
    }
}

size_t v1_probe_read(uint8_t *pdu)
{
    pdu[0] = DPV1_FN_READ;
    pdu[1] = 0;
    pdu[2] = DPV1_INDEX_IM;
    pdu[3] = DPV1_MAX_DATA;
    return DPV1_HEADER_LEN;
}

bool v1_is_read_response(const uint8_t *pdu, size_t len)
{
    uint8_t code1;
    if (v1_negative(pdu, len, DPV1_FN_READ, &code1)) {
        return true;
    }
    return len >= DPV1_HEADER_LEN && pdu[0] == DPV1_FN_READ && pdu[1] == 0u &&
           pdu[2] == DPV1_INDEX_IM && (size_t)pdu[3] == len - DPV1_HEADER_LEN;
}

/* ---- MSAC1 -------------------------------------------------------------------------------- */

bool v1_c1_ready(cf_t *cf)
{
    if (!cf->dpv1) {
        return cf_na(cf, "the GSD does not claim DPV1_Slave");
    }
    if (v1_key(cf, GSD_K_C1_READ_WRITE_SUPP) == 0u) {
        return cf_na(cf, "the GSD does not claim C1_Read_Write_supp");
    }
    if (cf->prm_len < DP_PRM_LEN_DPV1 ||
        (cf->prm[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_ENABLE) == 0u) {
        return cf_fail(cf, "the start-up Set_Prm has no DPV1_Enable (%u octets)",
                       (unsigned)cf->prm_len);
    }
    return cf_start_up(cf);
}

v1_path_t v1_c1_path(const cf_t *cf)
{
    v1_path_t p = { cf->opt.master, DPV1_SAP_C1, DPV1_SAP_C1 };
    return p;
}

/* ---- MSAC2 -------------------------------------------------------------------------------- */

bool v1_c2_claimed(cf_t *cf)
{
    if (!cf->dpv1) {
        return cf_na(cf, "the GSD does not claim DPV1_Slave");
    }
    if (v1_key(cf, GSD_K_C2_READ_WRITE_SUPP) == 0u) {
        return cf_na(cf, "the GSD does not claim C2_Read_Write_supp");
    }
    return true;
}

unsigned v1_c2_channels(const cf_t *cf)
{
    uint32_t n = v1_key(cf, GSD_K_C2_MAX_COUNT_CHANNELS);
    if (n == 0u) {
        n = 1u; /* C2_Read_Write_supp alone: one connection (the GSD default of the count) */
    }
    return n > V1_MAX_CONNS - 1u ? V1_MAX_CONNS - 1u : (unsigned)n;
}

static bool address_used(const cf_t *cf, uint8_t a)
{
    return a == cf->opt.address || a == cf->opt.master || a == cf->opt.master_2 ||
           a == cf->opt.class2;
}

uint8_t v1_c2_master(const cf_t *cf, unsigned i)
{
    if (i == 0u) {
        return cf->opt.class2;
    }
    unsigned seen = 0;
    for (uint8_t a = 5; a < 126u; a++) {
        if (!address_used(cf, a) && ++seen == i) {
            return a;
        }
    }
    return cf->opt.class2;
}

v1_path_t v1_conn_path(const v1_conn_t *c)
{
    v1_path_t p = { c->sa, c->sap, c->ssap };
    return p;
}

/* Initiate.req (protocol.md §A4.4): Features_Supported_1 DPV1_RW, no profile, source and
 * destination addresses of type 0 (API, SCL) only: the 20 octets of the smallest request. */
static size_t build_initiate(uint8_t *out, uint16_t send_timeout)
{
    const uint8_t pdu[DPV1_INITIATE_MIN] = {
        DPV1_FN_INITIATE, 0x00, 0x00, 0x00, (uint8_t)(send_timeout >> 8), (uint8_t)send_timeout,
        DPV1_FEATURES_1_DPV1_RW, 0x00, 0x00, 0x00, 0x00, 0x00,
        0x00, 0x02, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00,
    };
    memcpy(out, pdu, sizeof pdu);
    return sizeof pdu;
}

static void keep(v1_conn_t *c, const v1_result_t *r)
{
    memcpy(c->res, r->pdu, r->len);
    c->res_len = r->len;
}

static v1_open_t not_opened(v1_status_t st, const v1_result_t *r, const char *who, char *why,
                            size_t n)
{
    if (st == V1_BROKEN) {
        return V1_OPEN_BROKEN;
    }
    if (st == V1_REFUSED) {
        snprintf(why, n, "%s answered the FDL refusal %s", who, v1_fdl_code_name(r->fdl_code));
    } else {
        snprintf(why, n, "%s gave %s", who, st == V1_SILENT ? "silence" : "no response in time");
    }
    return V1_NOT_OPENED;
}

/* The PDU the connection's SAP gave to the polls after the resource manager's answer. */
static v1_open_t initiate_answer(cf_t *cf, v1_conn_t *c, const v1_result_t *r)
{
    keep(c, r);
    if (r->pdu[0] == DPV1_FN_ABORT) {
        return V1_ABORTED;
    }
    if (r->pdu[0] == (DPV1_FN_INITIATE | DPV1_FN_ERROR)) {
        return V1_NEGATIVE;
    }
    if (r->pdu[0] != DPV1_FN_INITIATE || r->len < DPV1_INITIATE_RES_HEAD_LEN) {
        char hex[64];
        (void)cf_fail(cf, "expected Initiate.res (57, at least 12 octets) on SAP %u, got %s",
                      c->sap, v1_hex(r->pdu, r->len, hex, sizeof hex));
        return V1_OPEN_BROKEN;
    }
    c->open = true;
    return V1_OPENED;
}

v1_open_t v1_c2_open(cf_t *cf, uint8_t sa, uint16_t send_timeout, v1_conn_t *c, char *why,
                     size_t why_len)
{
    char hex[64];
    uint8_t pdu[DPV1_INITIATE_MIN];
    v1_result_t r;
    memset(c, 0, sizeof *c);
    c->sa = sa;
    c->ssap = V1_C2_SSAP;
    const v1_path_t rm = { sa, DPV1_SAP_RM, V1_C2_SSAP };
    v1_status_t st = v1_call(cf, &rm, pdu, build_initiate(pdu, send_timeout),
                             v1_c2_timeout_ms(cf), &r);
    if (st != V1_RESPONSE) {
        return not_opened(st, &r, "the resource manager (SAP 49)", why, why_len);
    }
    keep(c, &r);
    if (r.pdu[0] == DPV1_FN_ABORT) {
        return V1_ABORTED;
    }
    /* The resource manager names a free SAP of 0..48 (protocol.md §A4.4). */
    if (r.len != 4u || r.pdu[0] != DPV1_FN_RM || r.pdu[1] > 48u) {
        (void)cf_fail(cf, "expected the resource manager's answer 56 SAP(0..48) TO TO, got %s",
                      v1_hex(r.pdu, r.len, hex, sizeof hex));
        return V1_OPEN_BROKEN;
    }
    c->sap = r.pdu[1];
    const v1_path_t cp = v1_conn_path(c);
    st = v1_call(cf, &cp, NULL, 0, v1_c2_timeout_ms(cf), &r);
    if (st != V1_RESPONSE) {
        snprintf(hex, sizeof hex, "the connection's SAP %u, polled for Initiate.res,", c->sap);
        return not_opened(st, &r, hex, why, why_len);
    }
    return initiate_answer(cf, c, &r);
}

bool v1_c2_abort(cf_t *cf, v1_conn_t *c)
{
    /* Subnet none; Instance user (0x20), reason 0 (protocol.md §A4.4). */
    const uint8_t pdu[4] = { DPV1_FN_ABORT, 0x00, 0x20, 0x00 };
    cf_reply_t r;
    c->open = false;
    return cf_request(cf, c->sa, FDL_REQ_SRD_HIGH, c->sap, c->ssap, pdu, sizeof pdu, &r);
}

void v1_c2_close_all(cf_t *cf, v1_conn_t *c, size_t n)
{
    for (size_t i = 0; i < n && !cf->link_failed; i++) {
        if (c[i].open) {
            (void)v1_c2_abort(cf, &c[i]);
        }
    }
}
