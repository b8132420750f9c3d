/* The suite's run, verdicts, evidence and wire helpers (cf.h). */
#include "conformance/cf.h"

#include <stdio.h>
#include <string.h>

#include "dp_master/dp_master.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"

#define CF_DEFAULT_MASTER 1u
#define CF_DEFAULT_CLASS2 2u
#define CF_DEFAULT_MASTER_2 3u
#define CF_DEFAULT_WATCHDOG_MS 200u
/* How often cf_start_up asks for a ready diagnosis before it gives up (a slave may need some
 * cycles after Chk_Cfg, e.g. to reach its application). */
#define CF_START_UP_DIAG_POLLS 50u
#define CF_START_UP_POLL_MS 10u

/* ---- the run ------------------------------------------------------------------------------ */

static void default_options(cf_options_t *o)
{
    if (o->master == 0u && o->master_2 == 0u && o->class2 == 0u) {
        o->master = CF_DEFAULT_MASTER;
        o->class2 = CF_DEFAULT_CLASS2;
        o->master_2 = CF_DEFAULT_MASTER_2;
    }
    if (o->watchdog_ms == 0u) {
        o->watchdog_ms = CF_DEFAULT_WATCHDOG_MS;
    }
}

/* The configuration start-ups use: the chosen modules' identifiers one after the other (the
 * first module when none is chosen). A GSD without modules cannot be configured. */
static int choose_modules(cf_t *cf, char *err, size_t errlen)
{
    const gsd_t *g = cf->gsd;
    if (g->n_modules == 0u) {
        snprintf(err, errlen, "the GSD file has no module: no configuration to send");
        return -1;
    }
    if (cf->opt.n_modules == 0u) {
        cf->opt.modules[0] = cf->opt.module < 0 ? 0 : cf->opt.module;
        cf->opt.n_modules = 1;
    }
    cf->cfg_len = 0;
    cf->in_len = cf->out_len = 0;
    for (size_t k = 0; k < cf->opt.n_modules && k < CF_MAX_MODULES; k++) {
        int m = cf->opt.modules[k];
        if (m < 0 || (size_t)m >= g->n_modules) {
            snprintf(err, errlen, "the GSD file has %zu modules: no module %d", g->n_modules, m);
            return -1;
        }
        const gsd_module_t *mod = &g->modules[m];
        uint16_t in = 0;
        uint16_t out = 0;
        if (mod->cfg_len == 0u || cf->cfg_len + mod->cfg_len > sizeof cf->cfg ||
            !gsd_module_io(g, (size_t)m, &in, &out) || cf->in_len + in > DP_IO_LEN_LIMIT ||
            cf->out_len + out > DP_IO_LEN_LIMIT) {
            snprintf(err, errlen, "module \"%s\" has no usable configuration identifiers, or "
                     "the configuration grows beyond 244 octets", gsd_chars(g, mod->name));
            return -1;
        }
        memcpy(&cf->cfg[cf->cfg_len], gsd_module_cfg(g, (size_t)m), mod->cfg_len);
        cf->cfg_len = (uint8_t)(cf->cfg_len + mod->cfg_len);
        cf->in_len = (uint16_t)(cf->in_len + in);
        cf->out_len = (uint16_t)(cf->out_len + out);
    }
    cf->opt.module = cf->opt.modules[0];
    return 0;
}

int cf_init(cf_t *cf, const cf_link_t *link, const gsd_t *gsd, const cf_options_t *opt,
            char *err, size_t errlen)
{
    memset(cf, 0, sizeof *cf);
    cf->link = *link;
    cf->gsd = gsd;
    cf->opt = *opt;
    default_options(&cf->opt);
    uint32_t v = 0;
    if (!gsd_key(gsd, GSD_K_IDENT_NUMBER, &v) || v > 0xFFFFu) {
        snprintf(err, errlen, "the GSD file gives no Ident_Number");
        return -1;
    }
    cf->ident = (uint16_t)v;
    cf->dpv1 = gsd_key(gsd, GSD_K_DPV1_SLAVE, &v) && v == 1u;
    if (choose_modules(cf, err, errlen) != 0) {
        return -1;
    }
    size_t n = cf_default_prm(cf, cf->opt.watchdog_ms, cf->prm, sizeof cf->prm);
    if (n == 0u) {
        snprintf(err, errlen, "the GSD's user parameters for module %d do not fit in Set_Prm",
                 cf->opt.module);
        return -1;
    }
    cf->prm_len = (uint8_t)n;
    return 0;
}

static bool id_selected(const cf_t *cf, const char *id)
{
    return cf->opt.only == NULL || strncmp(id, cf->opt.only, strlen(cf->opt.only)) == 0;
}

static bool request(cf_t *cf, uint8_t sa, uint8_t fc_code, int dsap, int ssap, const uint8_t *du,
                    size_t du_len, uint32_t wait_us, uint8_t retries, cf_reply_t *out);

/* A slave searching for the rate answers only once it has found the tester's: ask until it
 * does, as a master's start-up does, before any case is judged. */
static void find_slave(cf_t *cf)
{
    uint64_t t0 = cf->link.ops->now_ns(cf->link.ctx);
    uint64_t limit = (uint64_t)CF_FIND_SLAVE_MS * 1000000u;
    /* A slave searching the rate stays only some ms on each (20 ms at the fast rates,
     * DP_BAUD_SEARCH_DWELL_MIN_US): on a wall-clock medium, where the slot time is long, the
     * tester asks every few ms, unrepeated, so that a request falls within the dwell on its
     * rate. Answers that come later than that are settled once the slave is found. */
    uint32_t wait_us = cf->link.slot_us;
    if (!cf->link.timing && wait_us > CF_FIND_SLAVE_WAIT_US) {
        wait_us = CF_FIND_SLAVE_WAIT_US;
    }
    uint32_t asked = 1;
    for (;;) {
        cf_reply_t r;
        if (!request(cf, cf->opt.master, FDL_REQ_SRD_HIGH, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, NULL,
                     0, wait_us, 0, &r)) {
            return;
        }
        cf_answer_t a;
        if (cf_answer(&r, &a) && a.sa == cf->opt.address && (a.fc & FDL_FC_REQUEST) == 0u) {
            cf->found = true;
            cf->found_after_ns = cf->link.ops->now_ns(cf->link.ctx) - t0;
            /* A slave that started late may find the requests it missed queued in its
             * receiver (a PTY keeps what was written to it) and answer each of them. */
            if (!cf->link.timing && asked > 1u) {
                (void)cf_settle(cf);
            }
            return;
        }
        asked++;
        if (cf->link.ops->now_ns(cf->link.ctx) - t0 > limit || !cf_pause_ms(cf, 1u)) {
            return;
        }
    }
}

void cf_run(cf_t *cf, const cf_case_t *cases, size_t n)
{
    find_slave(cf);
    size_t total = 0;
    for (size_t i = 0; i < n; i++) {
        total += id_selected(cf, cases[i].id) ? 1u : 0u;
    }
    for (size_t i = 0; i < n && cf->n_results < CF_MAX_CASES; i++) {
        if (!id_selected(cf, cases[i].id)) {
            continue;
        }
        cf_result_t *r = &cf->results[cf->n_results++];
        memset(r, 0, sizeof *r);
        r->c = &cases[i];
        r->verdict = CF_PASS;
        r->t_start_ns = cf->link.ops->now_ns(cf->link.ctx);
        cf->cur = r;
        if (cf->link_failed) {
            (void)cf_fail(cf, "not run: the link failed before (%s)", cf->link_error);
        } else if (!cf->found) {
            (void)cf_fail(cf, "not run: the slave never answered a Slave_Diag in %u s",
                          CF_FIND_SLAVE_MS / 1000u);
        } else {
            cases[i].run(cf);
        }
        r->t_end_ns = cf->link.ops->now_ns(cf->link.ctx);
        cf->cur = NULL;
        if (cf->hooks.case_done != NULL) {
            cf->hooks.case_done(cf->hooks.ctx, r, cf->n_results - 1u, total);
        }
    }
}

void cf_count(const cf_t *cf, size_t *pass, size_t *fail, size_t *na)
{
    *pass = *fail = *na = 0;
    for (size_t i = 0; i < cf->n_results; i++) {
        switch (cf->results[i].verdict) {
        case CF_PASS: (*pass)++; break;
        case CF_FAIL: (*fail)++; break;
        case CF_NA: (*na)++; break;
        }
    }
}

const char *cf_verdict_name(cf_verdict_t v)
{
    switch (v) {
    case CF_PASS: return "PASS";
    case CF_FAIL: return "FAIL";
    case CF_NA: return "NOT APPLICABLE";
    }
    return "?";
}

/* ---- verdicts ----------------------------------------------------------------------------- */

static bool decide(cf_t *cf, cf_verdict_t v, const char *fmt, va_list ap)
{
    cf_result_t *r = cf->cur;
    if (r == NULL || r->verdict != CF_PASS) {
        return false;
    }
    r->verdict = v;
    (void)vsnprintf(r->reason, sizeof r->reason, fmt, ap);
    return false;
}

bool cf_fail(cf_t *cf, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    decide(cf, CF_FAIL, fmt, ap);
    va_end(ap);
    return false;
}

bool cf_na(cf_t *cf, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    decide(cf, CF_NA, fmt, ap);
    va_end(ap);
    return false;
}

bool cf_check(cf_t *cf, bool ok, const char *fmt, ...)
{
    if (!ok) {
        va_list ap;
        va_start(ap, fmt);
        decide(cf, CF_FAIL, fmt, ap);
        va_end(ap);
    }
    return ok;
}

void cf_info(cf_t *cf, const char *fmt, ...)
{
    cf_result_t *r = cf->cur;
    if (r == NULL) {
        return;
    }
    size_t used = strlen(r->info);
    if (used > 0u && used + 2u < sizeof r->info) {
        memcpy(&r->info[used], "; ", 3u);
        used += 2u;
    }
    if (used + 1u >= sizeof r->info) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(&r->info[used], sizeof r->info - used, fmt, ap);
    va_end(ap);
}

bool cf_decided(const cf_t *cf)
{
    return cf->cur != NULL && cf->cur->verdict != CF_PASS;
}

/* ---- evidence and the wire ---------------------------------------------------------------- */

static void keep(cf_t *cf, const cf_frame_t *f)
{
    cf_result_t *r = cf->cur;
    if (r == NULL) {
        return;
    }
    r->telegrams++;
    if (r->n_ev == CF_MAX_EVIDENCE) {
        memmove(&r->ev[0], &r->ev[1], sizeof r->ev[0] * (CF_MAX_EVIDENCE - 1u));
        r->n_ev--;
    }
    r->ev[r->n_ev++] = *f;
}

static uint32_t link_baud(const cf_t *cf)
{
    return cf->link.baud;
}

/* The medium failed during the case: the case fails and the run stops. Returns false. */
static bool medium_failed(cf_t *cf)
{
    cf->link_failed = true;
    snprintf(cf->link_error, sizeof cf->link_error, "the medium failed");
    (void)cf_fail(cf, "link: the medium failed during the case");
    return false;
}

bool cf_exchange_wait(cf_t *cf, const uint8_t *octets, size_t len, uint32_t wait_us,
                      cf_reply_t *out)
{
    cf_reply_t scratch;
    cf_reply_t *rp = out;
    if (rp == NULL) {
        rp = &scratch;
    }
    memset(rp, 0, sizeof *rp);
    rp->tsdr_bits = CF_TSDR_UNKNOWN;
    if (cf->link_failed) {
        return false;
    }
    cf_frame_t f = {.from_tester = true, .tsdr_bits = CF_TSDR_UNKNOWN, .baud = link_baud(cf)};
    f.len = (uint16_t)(len > CF_FRAME_MAX ? CF_FRAME_MAX : len);
    memcpy(f.octets, octets, f.len);
    int rc = cf->link.ops->exchange(cf->link.ctx, octets, len, wait_us, rp);
    f.t_ns = rp->tx_t_ns;
    keep(cf, &f);
    if (rc != 0) {
        return medium_failed(cf);
    }
    cf_frame_t a = {.from_tester = false, .len = rp->len, .t_ns = rp->t_ns,
                    .tsdr_bits = rp->tsdr_bits, .baud = link_baud(cf)};
    memcpy(a.octets, rp->octets, rp->len);
    if (rp->len == 0u) {
        a.t_ns = cf->link.ops->now_ns(cf->link.ctx);
    }
    keep(cf, &a);
    return true;
}

bool cf_exchange(cf_t *cf, const uint8_t *octets, size_t len, cf_reply_t *out)
{
    return cf_exchange_wait(cf, octets, len, cf->link.slot_us, out);
}

bool cf_pause_ms(cf_t *cf, uint32_t ms)
{
    if (cf->link_failed) {
        return false;
    }
    if (cf->link.ops->pause(cf->link.ctx, ms * 1000u) != 0) {
        return medium_failed(cf);
    }
    return true;
}

bool cf_settle(cf_t *cf)
{
    if (cf->link_failed) {
        return false;
    }
    if (cf->link.ops->settle == NULL) {
        return true;
    }
    /* Late answers come as far apart as their requests went: a slot time and the idle. */
    if (cf->link.ops->settle(cf->link.ctx, CF_SETTLE_QUIET_SLOTS * cf->link.slot_us,
                             CF_SETTLE_MAX_SLOTS * cf->link.slot_us) != 0) {
        return medium_failed(cf);
    }
    return true;
}

static bool fc_has_fcb(uint8_t code)
{
    return code == FDL_REQ_SDA_LOW || code == FDL_REQ_SDA_HIGH || code == FDL_REQ_SRD_LOW ||
           code == FDL_REQ_SRD_HIGH;
}

static uint8_t next_fc(cf_t *cf, uint8_t sa, uint8_t code)
{
    uint8_t fc = (uint8_t)(FDL_FC_REQUEST | (code & FDL_FC_CODE_MASK));
    if (!fc_has_fcb(code)) {
        return fc;
    }
    sa &= FDL_ADDR_MASK;
    if (!cf->fcb_started[sa]) {
        /* The first request after start-up: FCV = 0, FCB = 1 (EN 50170 vol. 2, 4.7.2.2). */
        cf->fcb_started[sa] = true;
        cf->fcb[sa] = true;
        return (uint8_t)(fc | FDL_FC_FCB);
    }
    cf->fcb[sa] = !cf->fcb[sa];
    return (uint8_t)(fc | FDL_FC_FCV | (cf->fcb[sa] ? FDL_FC_FCB : 0u));
}

void cf_fcb_restart(cf_t *cf, uint8_t sa)
{
    cf->fcb_started[sa & FDL_ADDR_MASK] = false;
}

/* cf_request with the wait for each answer and the number of repetitions given. */
static bool request(cf_t *cf, uint8_t sa, uint8_t fc_code, int dsap, int ssap, const uint8_t *du,
                    size_t du_len, uint32_t wait_us, uint8_t retries, cf_reply_t *out)
{
    uint8_t frame[CF_FRAME_MAX + 8u];
    bool saps = dsap >= 0;
    uint8_t fc = next_fc(cf, sa, fc_code);
    size_t n = fdl_encode(frame, cf->opt.address, sa, fc, saps, (uint8_t)(saps ? dsap : 0),
                          (uint8_t)(saps ? ssap : 0), du, du_len);
    if (n == 0u) {
        (void)cf_fail(cf, "tester: a request of %zu octets does not fit in a telegram", du_len);
        return false;
    }
    cf_reply_t scratch;
    cf_reply_t *rp = &scratch;
    if (out != NULL) {
        rp = out;
    }
    bool sent = cf_exchange_wait(cf, frame, n, wait_us, rp);
    /* A wall-clock medium on a loaded host may deliver an answer after the slot time: the
     * request goes again, unchanged (FCB too), as a master's retry does, so a late answer is
     * taken as the answer to that retry and never as the answer to the next request. An SDN
     * has no answer to wait for. */
    bool expects_answer = fc_code != FDL_REQ_SDN_LOW && fc_code != FDL_REQ_SDN_HIGH;
    uint8_t repeated = 0;
    while (sent && expects_answer && rp->len == 0u && repeated < retries) {
        repeated++;
        sent = cf_exchange_wait(cf, frame, n, wait_us, rp);
    }
    /* The answer taken may be a late one to an earlier send, the answers to the other sends
     * still to come: they would pass for the answers to the next requests. */
    if (sent && repeated > 0u) {
        sent = cf_settle(cf);
    }
    if (sent && rp->len == 0u && fc_has_fcb(fc_code)) {
        /* No answer: the cycle is not complete, the FCB stays as it was, and the next request
         * is the repetition the responder expects (IEC 61158-4-3, FCB rules). */
        sa &= FDL_ADDR_MASK;
        if ((fc & FDL_FC_FCV) == 0u) {
            cf->fcb_started[sa] = false;
        } else {
            cf->fcb[sa] = !cf->fcb[sa];
        }
    }
    return sent;
}

bool cf_request(cf_t *cf, uint8_t sa, uint8_t fc_code, int dsap, int ssap, const uint8_t *du,
                size_t du_len, cf_reply_t *out)
{
    return request(cf, sa, fc_code, dsap, ssap, du, du_len, cf->link.slot_us, cf->link.retries,
                   out);
}

bool cf_dp_from(cf_t *cf, uint8_t sa, uint8_t ssap, uint8_t dsap, const uint8_t *du,
                size_t du_len, cf_reply_t *out)
{
    return cf_request(cf, sa, FDL_REQ_SRD_HIGH, dsap, ssap, du, du_len, out);
}

bool cf_dp(cf_t *cf, uint8_t dsap, const uint8_t *du, size_t du_len, cf_reply_t *out)
{
    return cf_dp_from(cf, cf->opt.master, DP_SAP_MASTER, dsap, du, du_len, out);
}

bool cf_data_exchange(cf_t *cf, const uint8_t *out_data, size_t len, cf_reply_t *out)
{
    return cf_request(cf, cf->opt.master, FDL_REQ_SRD_HIGH, -1, -1, out_data, len, out);
}

/* ---- reading answers ---------------------------------------------------------------------- */

bool cf_answer(const cf_reply_t *r, cf_answer_t *a)
{
    memset(a, 0, sizeof *a);
    if (r->len == 0u || r->garbled) {
        return false;
    }
    fdl_msg_t m;
    if (fdl_check(r->octets, r->len, NULL, &m) != FDL_CHECK_OK || m.sd == FDL_SC ||
        m.sd == FDL_SD4) {
        return false;
    }
    a->sd = m.sd;
    a->da = m.da;
    a->sa = m.sa;
    a->fc = m.fc;
    a->saps = m.has_dsap;
    a->dsap = m.dsap;
    a->ssap = m.ssap;
    a->du = m.data;
    a->du_len = m.data_len;
    return true;
}

bool cf_is_sc(const cf_reply_t *r)
{
    return r->len == 1u && !r->garbled && r->octets[0] == FDL_SC;
}

bool cf_is_ack(const cf_reply_t *r)
{
    cf_answer_t a;
    if (cf_is_sc(r)) {
        return true;
    }
    if (!cf_answer(r, &a) || a.sd != FDL_SD1 || (a.fc & FDL_FC_REQUEST) != 0u) {
        return false;
    }
    unsigned code = a.fc & FDL_FC_CODE_MASK;
    return code == FDL_RSP_OK || code == FDL_RSP_DL || code == FDL_RSP_DH ||
           code == FDL_RSP_NR;
}

int cf_rsp_code(const cf_reply_t *r)
{
    cf_answer_t a;
    if (!cf_answer(r, &a) || (a.fc & FDL_FC_REQUEST) != 0u) {
        return -1;
    }
    return (int)(a.fc & FDL_FC_CODE_MASK);
}

const char *cf_rsp_name(int code)
{
    switch (code) {
    case FDL_RSP_OK: return "OK";
    case FDL_RSP_UE: return "UE";
    case FDL_RSP_RR: return "RR";
    case FDL_RSP_RS: return "RS";
    case FDL_RSP_DL: return "DL";
    case FDL_RSP_NR: return "NR";
    case FDL_RSP_DH: return "DH";
    case FDL_RSP_RDL: return "RDL";
    case FDL_RSP_RDH: return "RDH";
    default: return "reserved response";
    }
}

const char *cf_reply_text(const cf_reply_t *r, char *buf, size_t n)
{
    cf_answer_t a;
    if (r->len == 0u) {
        snprintf(buf, n, "silence");
    } else if (cf_is_sc(r)) {
        snprintf(buf, n, "SC");
    } else if (!cf_answer(r, &a)) {
        snprintf(buf, n, "%s%u octets that are no telegram", r->garbled ? "garbled: " : "",
                 (unsigned)r->len);
    } else if ((a.fc & FDL_FC_REQUEST) != 0u) {
        snprintf(buf, n, "a request (FC 0x%02X) instead of an answer", a.fc);
    } else {
        snprintf(buf, n, "%s (FC 0x%02X), %u data octets",
                 cf_rsp_name((int)(a.fc & FDL_FC_CODE_MASK)), a.fc, (unsigned)a.du_len);
    }
    return buf;
}

/* ---- start-up helpers --------------------------------------------------------------------- */

bool cf_diag(cf_t *cf, uint8_t *diag, size_t *len)
{
    cf_reply_t r;
    if (!cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r)) {
        return false;
    }
    cf_answer_t a;
    char t[96];
    if (!cf_answer(&r, &a) || (a.fc & FDL_FC_REQUEST) != 0u) {
        (void)cf_fail(cf, "Slave_Diag: expected a diagnosis, got %s",
                      cf_reply_text(&r, t, sizeof t));
        return false;
    }
    int code = (int)(a.fc & FDL_FC_CODE_MASK);
    if ((code != FDL_RSP_DL && code != FDL_RSP_DH) || !a.saps || a.dsap != DP_SAP_MASTER ||
        a.ssap != DP_SAP_SLAVE_DIAG || a.du_len < DP_DIAG_STD_LEN) {
        (void)cf_fail(cf, "Slave_Diag: expected DL/DH from SAP 60 to SAP 62 with at least 6 "
                          "octets, got %s, SAPs %u/%u", cf_reply_text(&r, t, sizeof t),
                      (unsigned)a.dsap, (unsigned)a.ssap);
        return false;
    }
    memcpy(diag, a.du, a.du_len);
    *len = a.du_len;
    return true;
}

size_t cf_default_prm(const cf_t *cf, uint32_t watchdog_ms, uint8_t *out, size_t cap)
{
    uint8_t user[DP_MASTER_MAX_PRM];
    size_t modules[CF_MAX_MODULES];
    size_t n_modules = 0;
    for (size_t k = 0; k < cf->opt.n_modules && k < CF_MAX_MODULES; k++) {
        modules[n_modules++] = (size_t)cf->opt.modules[k];
    }
    if (n_modules == 0u && cf->gsd->n_modules > 0u) {
        modules[n_modules++] = (size_t)(cf->opt.module < 0 ? 0 : cf->opt.module);
    }
    int n = gsd_default_prm(cf->gsd, modules, n_modules, user, sizeof user);
    if (n < 0 || (size_t)n + DP_PRM_LEN_STANDARD > cap || cap < DP_MASTER_MAX_PRM) {
        return 0;
    }
    if (cf->dpv1) {
        return dp_master_build_prm_dpv1(out, cf->ident, watchdog_ms, user, (size_t)n);
    }
    return dp_master_build_prm(out, cf->ident, watchdog_ms, user, (size_t)n);
}

bool cf_reset(cf_t *cf)
{
    /* Unlock_Req without Lock_Req: "the DP slave is unlocked for other masters" (EN 50170
     * vol. 2, 8.3.1.2); only the owner's counts, so it comes from every master a case uses. */
    uint8_t prm[DP_MASTER_MAX_PRM];
    memcpy(prm, cf->prm, cf->prm_len);
    prm[DP_PRM_STATION_STATUS] = DP_PRM_UNLOCK_REQ;
    const uint8_t masters[] = {cf->opt.master, cf->opt.master_2};
    for (size_t i = 0; i < sizeof masters; i++) {
        cf_reply_t r;
        if (!cf_dp_from(cf, masters[i], DP_SAP_MASTER, DP_SAP_SET_PRM, prm, cf->prm_len, &r)) {
            return false;
        }
    }
    return true;
}

static bool wait_ready(cf_t *cf)
{
    uint8_t d[244];
    size_t n = 0;
    for (unsigned i = 0; i < CF_START_UP_DIAG_POLLS; i++) {
        if (!cf_diag(cf, d, &n)) {
            return false;
        }
        bool faults = (d[DP_DIAG_STATUS_1] & (DP_DIAG1_CFG_FAULT | DP_DIAG1_PRM_FAULT |
                                              DP_DIAG1_NOT_SUPPORTED)) != 0u;
        if (faults) {
            return cf_fail(cf, "start-up: the diagnosis after Set_Prm and Chk_Cfg shows a fault "
                               "(status 1 = 0x%02X)", d[DP_DIAG_STATUS_1]);
        }
        bool ready = (d[DP_DIAG_STATUS_1] & DP_DIAG1_STATION_NOT_READY) == 0u &&
                     (d[DP_DIAG_STATUS_2] & (DP_DIAG2_PRM_REQ | DP_DIAG2_STAT_DIAG)) == 0u;
        if (ready) {
            return true;
        }
        if (!cf_pause_ms(cf, CF_START_UP_POLL_MS)) {
            return false;
        }
    }
    return cf_fail(cf, "start-up: the slave did not become ready (status 1/2 = 0x%02X/0x%02X)",
                   d[DP_DIAG_STATUS_1], d[DP_DIAG_STATUS_2]);
}

bool cf_start_up(cf_t *cf)
{
    cf_reply_t r;
    char t[96];
    if (!cf_reset(cf)) {
        return false;
    }
    uint8_t d[244];
    size_t n = 0;
    if (!cf_diag(cf, d, &n) ||
        !cf_dp(cf, DP_SAP_SET_PRM, cf->prm, cf->prm_len, &r)) {
        return false;
    }
    if (!cf_is_ack(&r)) {
        return cf_fail(cf, "start-up: Set_Prm answered %s, expected SC or SD1 without data",
                       cf_reply_text(&r, t, sizeof t));
    }
    if (!cf_dp(cf, DP_SAP_CHK_CFG, cf->cfg, cf->cfg_len, &r)) {
        return false;
    }
    if (!cf_is_ack(&r)) {
        return cf_fail(cf, "start-up: Chk_Cfg answered %s, expected SC or SD1 without data",
                       cf_reply_text(&r, t, sizeof t));
    }
    if (!wait_ready(cf)) {
        return false;
    }
    uint8_t outputs[DP_IO_LEN_LIMIT] = {0};
    if (!cf_data_exchange(cf, outputs, cf->out_len, &r)) {
        return false;
    }
    cf_answer_t a;
    int code = cf_rsp_code(&r);
    bool ok = (cf->in_len == 0u && cf_is_ack(&r)) ||
              (cf_answer(&r, &a) && (code == FDL_RSP_DL || code == FDL_RSP_DH));
    if (!ok) {
        return cf_fail(cf, "start-up: the first Data_Exchange answered %s",
                       cf_reply_text(&r, t, sizeof t));
    }
    return true;
}
