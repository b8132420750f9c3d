/* The MSAC2 cases of the "DP-V1" group: class-2 connections through the resource manager on
 * SAP 49 (IEC 61158-6-3 MSAC_C2; protocol.md §A4.4). Each case aborts what it opened, whatever
 * its verdict, so the next one finds the slave's connections free. */
#include <stdio.h>
#include <string.h>

#include "cases_dpv1_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "dpv1/dpv1_wire.h"

/* Send_Timeout of the cases' connections (10 ms units): 3 s, beyond any response timeout. */
#define C2_SEND_TIMEOUT 300u
/* Abort reasons of the MSAC_C2 instance (protocol.md §A4.4). */
#define ABORT_REASON_MASK 0x0Fu
#define ABORT_REASON_STO 0x06u

/* Fails the case unless the connection opened. */
static bool opened(cf_t *cf, v1_open_t o, const v1_conn_t *c, const char *why)
{
    char g[64];
    switch (o) {
    case V1_OPENED: return true;
    case V1_ABORTED:
    case V1_NEGATIVE:
        return cf_fail(cf, "Initiate from master %u: expected Initiate.res (57 ...), got %s %s",
                       c->sa, o == V1_ABORTED ? "Abort" : "negative Initiate",
                       v1_hex(c->res, c->res_len, g, sizeof g));
    case V1_NOT_OPENED:
        return cf_fail(cf, "Initiate from master %u: expected Initiate.res, but %s", c->sa, why);
    default: return false;
    }
}

/* Opens n connections from the cases' class-2 masters 0..n-1. */
static bool open_n(cf_t *cf, v1_conn_t *c, unsigned n)
{
    char why[96];
    for (unsigned i = 0; i < n; i++) {
        v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, i), C2_SEND_TIMEOUT, &c[i], why,
                                 sizeof why);
        if (!opened(cf, o, &c[i], why)) {
            return false;
        }
    }
    return true;
}

/* The connection answers a Read.req with a Read response. */
static bool serves(cf_t *cf, const v1_conn_t *c)
{
    uint8_t pdu[DPV1_HEADER_LEN];
    v1_result_t r;
    char g[64], what[64];
    v1_path_t p = v1_conn_path(c);
    snprintf(what, sizeof what, "Read.req on SAP %u from master %u", c->sap, c->sa);
    v1_status_t st = v1_call(cf, &p, pdu, v1_probe_read(pdu), v1_c2_timeout_ms(cf), &r);
    return v1_need_response(cf, st, &r, what) &&
           cf_check(cf, v1_is_read_response(r.pdu, r.len), "%s: expected a Read response "
                    "(5E 00 FF n ... or DE 80 xx xx), got %s", what,
                    v1_hex(r.pdu, r.len, g, sizeof g));
}

/* A Read.req from p's master to p's SAP must not be served: the FDL refuses it (RS: the SAP is
 * not activated for this master) or an Abort PDU comes. */
static bool not_served(cf_t *cf, const v1_path_t *p, const char *why)
{
    uint8_t pdu[DPV1_HEADER_LEN];
    v1_result_t r;
    char g[64];
    v1_status_t st = v1_call(cf, p, pdu, v1_probe_read(pdu), v1_c2_timeout_ms(cf), &r);
    if (st == V1_REFUSED) {
        cf_info(cf, "SAP %u %s: %s", p->dsap, why, v1_fdl_code_name(r.fdl_code));
        return true;
    }
    if (st == V1_RESPONSE && r.len >= 3u && r.pdu[0] == DPV1_FN_ABORT) {
        cf_info(cf, "SAP %u %s: Abort %s", p->dsap, why, v1_hex(r.pdu, r.len, g, sizeof g));
        return true;
    }
    if (st == V1_BROKEN) {
        return false;
    }
    return cf_fail(cf, "Read.req from master %u on SAP %u %s: expected RS (SAP not activated) "
                   "or an Abort, got %s", p->sa, p->dsap, why,
                   st == V1_SILENT    ? "silence"
                   : st == V1_TIMEOUT ? "the request taken (SC)"
                                      : v1_hex(r.pdu, r.len, g, sizeof g));
}

/* The Initiate.res head (protocol.md §A4.4): DPV1_RW is mandatory, the addresses fit. */
static void judge_initiate_res(cf_t *cf, const v1_conn_t *c)
{
    const uint8_t *res = c->res;
    size_t need = DPV1_INITIATE_RES_HEAD_LEN + (size_t)res[9] + res[11];
    if (!cf_check(cf, (res[2] & DPV1_FEATURES_1_DPV1_RW) != 0u, "Initiate.res "
                  "Features_Supported_1: expected DPV1_RW (bit 0) set, got 0x%02X", res[2]) ||
        !cf_check(cf, c->res_len >= need, "Initiate.res: S_Len %u and D_Len %u need %zu "
                  "octets, got %zu", res[9], res[11], need, c->res_len)) {
        return;
    }
    cf_info(cf, "RM named SAP %u; Initiate.res Max_Len_Data_Unit %u, Features 0x%02X 0x%02X, "
            "Profile_Ident 0x%02X%02X", c->sap, res[1], res[2], res[3], res[6], res[7]);
}

void v1_case_c2_initiate(cf_t *cf)
{
    v1_conn_t c;
    char why[96];
    if (!v1_c2_claimed(cf)) {
        return;
    }
    v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, 0), C2_SEND_TIMEOUT, &c, why, sizeof why);
    if (opened(cf, o, &c, why)) {
        judge_initiate_res(cf, &c);
        if (!cf_decided(cf)) {
            (void)serves(cf, &c);
        }
    }
    v1_c2_close_all(cf, &c, 1);
}

void v1_case_c2_abort(cf_t *cf)
{
    v1_conn_t c[V1_MAX_CONNS];
    char why[96];
    memset(c, 0, sizeof c);
    if (!v1_c2_claimed(cf)) {
        return;
    }
    unsigned n = v1_c2_channels(cf);
    /* Every channel taken, one aborted: a new master must then get it. */
    if (open_n(cf, c, n) && v1_c2_abort(cf, &c[0])) {
        v1_path_t p = v1_conn_path(&c[0]);
        if (not_served(cf, &p, "after Abort")) {
            v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, n), C2_SEND_TIMEOUT, &c[n], why,
                                     sizeof why);
            if (opened(cf, o, &c[n], why)) {
                cf_info(cf, "the freed channel went to master %u on SAP %u", c[n].sa, c[n].sap);
            }
        }
    }
    v1_c2_close_all(cf, c, n + 1u);
}

/* How long one exchange of the connection may take on this link (ms): idle, slot and two
 * telegrams of 30 characters. Send_Timeout has to leave room for several. */
static uint32_t exchange_ms(const cf_t *cf)
{
    uint64_t us = (uint64_t)cf->link.idle_us + cf->link.slot_us;
    if (cf->link.baud > 0u) {
        us += (uint64_t)2u * 30u * FDL_CHAR_BITS * 1000000u / cf->link.baud;
    }
    return (uint32_t)(us / 1000u) + 1u;
}

/* Opens a connection with the shortest Send_Timeout of 100 ms, 1 s and 4 s that leaves room
 * for five exchanges and that the slave takes (it may refuse one too small with Abort STO). */
static bool open_short(cf_t *cf, v1_conn_t *c, uint32_t *t_ms)
{
    static const uint16_t tries[] = { 10u, 100u, 400u };
    char why[96];
    for (size_t i = 0; i < sizeof tries / sizeof tries[0]; i++) {
        *t_ms = tries[i] * 10u;
        if (*t_ms < 5u * exchange_ms(cf) && i + 1u < sizeof tries / sizeof tries[0]) {
            continue;
        }
        v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, 0), tries[i], c, why, sizeof why);
        if (o != V1_ABORTED || c->res_len < 3u ||
            (c->res[2] & ABORT_REASON_MASK) != ABORT_REASON_STO) {
            return opened(cf, o, c, why);
        }
        cf_info(cf, "Send_Timeout %u ms refused (STO)", *t_ms);
    }
    return cf_fail(cf, "every Send_Timeout up to 4 s refused with Abort STO");
}

/* ms pass without a telegram on the connection; Slave_Diag from the class-1 master goes on
 * every 50 ms, since a slave that hears nothing addressed to it for its baud control time
 * starts the baud search again (protocol.md §A2.3) and would then be deaf to the next request. */
static bool connection_silent(cf_t *cf, uint32_t ms)
{
    uint64_t end = v1_now_ms(cf) + ms;
    cf_reply_t r;
    for (uint64_t now = v1_now_ms(cf); now < end; now = v1_now_ms(cf)) {
        uint64_t step = end - now < 50u ? end - now : 50u;
        if (!cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r) || !cf_pause_ms(cf, (uint32_t)step)) {
            return false;
        }
    }
    return true;
}

/* An Idle.req at most every 0.6 Send_Timeout (from one request's start to the next), three
 * times: 1.8 times the timeout in all, and the connection stays alive. */
static bool kept_alive(cf_t *cf, const v1_conn_t *c, uint32_t t_ms)
{
    const uint8_t idle[4] = { DPV1_FN_IDLE, 0, 0, 0 };
    uint32_t gap = t_ms * 6u / 10u, ex = exchange_ms(cf);
    cf_reply_t r;
    cf_answer_t a;
    char g[64];
    for (int i = 0; i < 3; i++) {
        if (!connection_silent(cf, gap > 3u * ex ? gap - 3u * ex : 1u) ||
            !cf_request(cf, c->sa, FDL_REQ_SRD_HIGH, c->sap, c->ssap, idle, sizeof idle, &r)) {
            return false;
        }
        bool ok = cf_is_sc(&r) || (cf_answer(&r, &a) && (a.fc & FDL_FC_REQUEST) == 0u &&
                                   ((a.fc & FDL_FC_CODE_MASK) == FDL_RSP_DL ||
                                    (a.fc & FDL_FC_CODE_MASK) == FDL_RSP_DH ||
                                    (a.fc & FDL_FC_CODE_MASK) == FDL_RSP_NR) &&
                                   (a.du_len == 0u || a.du[0] != DPV1_FN_ABORT));
        if (!cf_check(cf, ok, "Idle.req %d (about %u ms apart, Send_Timeout %u ms): expected "
                      "the connection alive (SC or Idle), got %s", i + 1, gap, t_ms,
                      cf_reply_text(&r, g, sizeof g))) {
            return false;
        }
    }
    return true;
}

void v1_case_c2_idle_timeout(cf_t *cf)
{
    v1_conn_t c;
    uint32_t t_ms = 0;
    char why[64];
    memset(&c, 0, sizeof c);
    if (!v1_c2_claimed(cf)) {
        return;
    }
    if (open_short(cf, &c, &t_ms) && kept_alive(cf, &c, t_ms) &&
        connection_silent(cf, t_ms + t_ms / 2u + 20u)) {
        v1_path_t p = v1_conn_path(&c);
        snprintf(why, sizeof why, "after %u ms of silence (Send_Timeout %u ms)",
                 t_ms + t_ms / 2u + 20u, t_ms);
        if (not_served(cf, &p, why)) {
            c.open = false; /* the slave closed it: nothing to abort */
        }
    }
    v1_c2_close_all(cf, &c, 1);
}

void v1_case_c2_two_connections(cf_t *cf)
{
    v1_conn_t c[2];
    memset(c, 0, sizeof c);
    if (!v1_c2_claimed(cf)) {
        return;
    }
    if (v1_key(cf, GSD_K_C2_MAX_COUNT_CHANNELS) < 2u) {
        return (void)cf_na(cf, "the GSD claims C2_Max_Count_Channels %u (fewer than two)",
                           (unsigned)v1_key(cf, GSD_K_C2_MAX_COUNT_CHANNELS));
    }
    if (open_n(cf, c, 2) &&
        cf_check(cf, c[0].sap != c[1].sap, "two connections: expected two SAPs, got SAP %u "
                 "for both", c[0].sap) &&
        serves(cf, &c[0]) && serves(cf, &c[1]) && serves(cf, &c[0])) {
        /* A connection's SAP serves only its master (SA and SSAP). */
        v1_path_t cross = { c[0].sa, c[1].sap, c[0].ssap };
        if (not_served(cf, &cross, "of the other master's connection")) {
            (void)serves(cf, &c[1]);
        }
    }
    v1_c2_close_all(cf, c, 2);
}

void v1_case_c2_third_refused(cf_t *cf)
{
    v1_conn_t c[V1_MAX_CONNS];
    char why[96], g[64];
    memset(c, 0, sizeof c);
    if (!v1_c2_claimed(cf)) {
        return;
    }
    unsigned n = v1_c2_channels(cf);
    if (v1_key(cf, GSD_K_C2_MAX_COUNT_CHANNELS) > n) {
        return (void)cf_na(cf, "C2_Max_Count_Channels %u: more connections than the suite "
                           "opens (%u)", (unsigned)v1_key(cf, GSD_K_C2_MAX_COUNT_CHANNELS), n);
    }
    if (open_n(cf, c, n)) {
        v1_open_t o = v1_c2_open(cf, v1_c2_master(cf, n), C2_SEND_TIMEOUT, &c[n], why,
                                 sizeof why);
        const uint8_t *res = c[n].res;
        if (o == V1_ABORTED && c[n].res_len >= 3u &&
            (res[2] & ABORT_REASON_MASK) == DPV1_ABORT_REASON_RESOURCE) {
            cf_info(cf, "connection %u of %u refused: Abort %s", n + 1u, n,
                    v1_hex(res, c[n].res_len, g, sizeof g));
            (void)serves(cf, &c[0]);
        } else if (o != V1_OPEN_BROKEN) {
            (void)cf_fail(cf, "Initiate %u with C2_Max_Count_Channels %u: expected Abort with "
                          "reason RES (58 xx 1F 00), got %s", n + 1u, n,
                          o == V1_NOT_OPENED ? why
                          : o == V1_OPENED   ? "the connection opened"
                                             : v1_hex(res, c[n].res_len, g, sizeof g));
        }
    }
    v1_c2_close_all(cf, c, n + 1u);
}
