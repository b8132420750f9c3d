/* The FDL group: layer 2 as a slave (a passive station) must keep it. Frame forms, every kind
 * of damaged telegram, addresses, SDN and broadcast, the FCB/FCV rules, SAPs and function
 * codes. Requests are built octet by octet here where the case needs a form, an FCB or damage
 * the request helpers of cf.h would not send. */
#include <stdio.h>
#include <string.h>

#include "conformance/cf_cases_fdl.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

#define FDL_GROUP "FDL"
#define CLAUSE_CHECK "IEC 61158-4-3 frame check: SD, LE = LEr, SD repeated, FCS, ED (PROFIBUS " \
                     "Spec. Part 4 4.7.2); a damaged frame is discarded"
#define DX_OUT_SD3 8u /* a Data_Exchange with 8 outputs and no SAPs is the SD3 request */

typedef struct frame {
    char what[80];
    uint8_t o[CF_FRAME_MAX];
    size_t n;
} frame_t;

/* ---- building requests -------------------------------------------------------------------- */

static uint8_t dut(const cf_t *cf) { return cf->opt.address; }
static uint8_t tester(const cf_t *cf) { return cf->opt.master; }

/* Slave_Diag from sa (SD2: 68 05 05 68 DA|80 SA|80 FC 3C 3E FCS 16). */
static size_t diag_req(const cf_t *cf, uint8_t da, uint8_t sa, uint8_t fc, uint8_t *o)
{
    (void)cf;
    return fdl_encode(o, da, sa, fc, true, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, NULL, 0);
}

/* A request of the tester with DSAP/SSAP to da. */
static size_t sap_req(const cf_t *cf, uint8_t da, uint8_t fc, uint8_t dsap, const uint8_t *du,
                      size_t len, uint8_t *o)
{
    return fdl_encode(o, da, tester(cf), fc, true, dsap, DP_SAP_MASTER, du, len);
}

/* 10 DA SA 49 FCS 16. */
static size_t status_req(uint8_t da, uint8_t sa, uint8_t *o)
{
    return fdl_encode(o, da, sa, cf_gf_fc(FDL_REQ_FDL_STATUS, false, false), false, 0, 0, NULL,
                      0);
}

/* Data_Exchange with 8 zero outputs: fdl_encode makes it SD3. */
static size_t dx8_req(const cf_t *cf, uint8_t da, uint8_t fc, uint8_t *o)
{
    static const uint8_t zero[DX_OUT_SD3] = {0};
    return fdl_encode(o, da, tester(cf), fc, false, 0, 0, zero, sizeof zero);
}

/* SD2 whatever the DU's length (an 8-octet DU, which fdl_encode would put into SD3). */
static size_t sd2_req(uint8_t da, uint8_t sa, uint8_t fc, const uint8_t *du, size_t len,
                      uint8_t *o)
{
    o[0] = FDL_SD2;
    o[1] = o[2] = (uint8_t)(len + FDL_ADDR_FC_LEN);
    o[3] = FDL_SD2;
    o[4] = da;
    o[5] = sa;
    o[6] = fc;
    if (len > 0u) memcpy(o + 7, du, len);
    o[7 + len] = fdl_fcs(o + FDL_SD2_HEADER_LEN, len + FDL_ADDR_FC_LEN);
    o[8 + len] = FDL_ED;
    return len + 9u;
}

/* The run's Set_Prm with Unlock_Req instead of Lock_Req: carried out, it ends Data_Exch. */
static size_t unlock_prm(const cf_t *cf, uint8_t *du)
{
    memcpy(du, cf->prm, cf->prm_len);
    du[DP_PRM_STATION_STATUS] = DP_PRM_UNLOCK_REQ;
    return cf->prm_len;
}

/* Another station address than the DUT's and the tester's (on a line the tester holds). */
static uint8_t other_address(const cf_t *cf)
{
    uint8_t a = dut(cf);
    for (;;) {
        a = (uint8_t)(a >= 125u ? 0u : a + 1u);
        if (a != cf->opt.master && a != cf->opt.master_2 && a != cf->opt.class2) return a;
    }
}

/* ---- judging answers ---------------------------------------------------------------------- */

static bool silent(cf_t *cf, const uint8_t *o, size_t n, const char *what)
{
    cf_reply_t r;
    char t[96];
    if (!cf_exchange(cf, o, n, &r)) return false;
    if (r.len == 0u && !r.garbled) return true;
    return cf_fail(cf, "%s: expected no answer, got %s", what, cf_reply_text(&r, t, sizeof t));
}

/* The next good request, with a fresh FCB, is answered. */
static bool still_answers(cf_t *cf, const char *after)
{
    uint8_t d[CF_GF_DU_MAX];
    size_t len = 0;
    char why[CF_TEXT_MAX];
    cf_fcb_restart(cf, tester(cf));
    if (cf_gf_diag(cf, d, &len, why, sizeof why)) return true;
    return cf_fail(cf, "after %s, the next good request: %s", after, why);
}

/* The DUT is still in Data_Exch with the tester as its master. */
static bool still_exchanging(cf_t *cf, const char *after)
{
    uint8_t d[CF_GF_DU_MAX];
    size_t len = 0;
    char why[CF_TEXT_MAX], h[64];
    cf_fcb_restart(cf, tester(cf));
    if (!cf_gf_diag(cf, d, &len, why, sizeof why)) {
        return cf_fail(cf, "after %s: %s", after, why);
    }
    return cf_check(cf, cf_gf_in_data_exch(d, len) && d[DP_DIAG_MASTER_ADD] == tester(cf),
                    "after %s: expected Data_Exch with Master_Add %u (not carried out), "
                    "diagnosis %s", after, tester(cf), cf_gf_hex(d, len, h, sizeof h));
}

/* Data_Exch without the watchdog: a case that waits out silent slots (long ones on a PTY) and
 * then asks whether the slave is still exchanging must not meet the watchdog's expiry. */
static bool start_up_no_wd(cf_t *cf, uint8_t station_bits)
{
    cf_gf_setup_t s;
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, &s);
    s.prm[DP_PRM_STATION_STATUS] =
        (uint8_t)((s.prm[DP_PRM_STATION_STATUS] & ~DP_PRM_WD_ON) | station_bits);
    if (cf_gf_bring_up(cf, &s, true, NULL, why, sizeof why)) return true;
    return cf_fail(cf, "start-up without watchdog: %s", why);
}

static void run_bad(cf_t *cf, const frame_t *f, size_t n, const char *kind)
{
    for (size_t i = 0; i < n; i++) {
        if (!silent(cf, f[i].o, f[i].n, f[i].what) || !still_answers(cf, f[i].what)) return;
    }
    cf_info(cf, "%zu %s, none answered; the next good request answered", n, kind);
}

/* The three good requests damaged below: FDL status (SD1), Slave_Diag (SD2), Data_Exchange
 * with 8 outputs (SD3). */
static void good_three(const cf_t *cf, frame_t *sd1, frame_t *sd2, frame_t *sd3)
{
    uint8_t first = cf_gf_fc(FDL_REQ_SRD_HIGH, false, true);
    sd1->n = status_req(dut(cf), tester(cf), sd1->o);
    sd2->n = diag_req(cf, dut(cf), tester(cf), first, sd2->o);
    sd3->n = dx8_req(cf, dut(cf), first, sd3->o);
}

static void name(frame_t *f, const char *what)
{
    char h[64];
    (void)snprintf(f->what, sizeof f->what, "%s (%s)", what, cf_gf_hex(f->o, f->n, h, 40));
}

/* ---- the damaged telegrams ---------------------------------------------------------------- */

static void bad_fcs_run(cf_t *cf)
{
    frame_t f[3];
    good_three(cf, &f[0], &f[1], &f[2]);
    for (size_t i = 0; i < 3u; i++) f[i].o[f[i].n - 2u]++;
    name(&f[0], "SD1 with FCS + 1");
    name(&f[1], "SD2 with FCS + 1");
    name(&f[2], "SD3 with FCS + 1");
    run_bad(cf, f, 3, "damaged telegrams");
}

static void bad_ed_run(cf_t *cf)
{
    frame_t f[3];
    good_three(cf, &f[0], &f[1], &f[2]);
    f[0].o[f[0].n - 1u] = 0x17u;
    f[1].o[f[1].n - 1u] = 0x17u;
    f[2].o[f[2].n - 1u] = 0x00u;
    name(&f[0], "SD1 with ED 17");
    name(&f[1], "SD2 with ED 17");
    name(&f[2], "SD3 with ED 00");
    run_bad(cf, f, 3, "damaged telegrams");
}

static void le_mismatch_run(cf_t *cf)
{
    frame_t f[3], unused1, unused3;
    good_three(cf, &unused1, &f[0], &unused3);
    f[1] = f[0];
    f[2] = f[0];
    f[0].o[2]++;
    f[1].o[2]--;
    f[2].o[1]++;
    name(&f[0], "SD2 with LEr = LE + 1");
    name(&f[1], "SD2 with LEr = LE - 1");
    name(&f[2], "SD2 with LE = LEr + 1");
    run_bad(cf, f, 3, "damaged telegrams");
}

static void sd2_repeat_run(cf_t *cf)
{
    frame_t f[2], unused1, unused3;
    good_three(cf, &unused1, &f[0], &unused3);
    f[1] = f[0];
    f[0].o[3] = 0x69u;
    f[1].o[3] = FDL_SD3;
    name(&f[0], "SD2 repeated as 69");
    name(&f[1], "SD2 repeated as A2");
    run_bad(cf, f, 2, "damaged telegrams");
}

static void short_run(cf_t *cf)
{
    frame_t f[5], sd1, sd3;
    good_three(cf, &sd1, &f[0], &sd3);
    f[1] = f[0];
    f[0].n--;
    f[1].n = 6;
    f[2] = sd1;
    f[2].n--;
    f[3] = sd3;
    f[3].n--;
    /* LE 3: DA SA FC and no DU, below the least LE of 4 */
    f[4].n = sd2_req(dut(cf), tester(cf), cf_gf_fc(FDL_REQ_SRD_HIGH, false, true), NULL, 0,
                     f[4].o);
    name(&f[0], "SD2 without ED");
    name(&f[1], "SD2 cut after SA");
    name(&f[2], "SD1 without ED");
    name(&f[3], "SD3 without ED");
    name(&f[4], "SD2 with LE 3");
    run_bad(cf, f, 5, "damaged telegrams");
}

static void unknown_sd_run(cf_t *cf)
{
    frame_t f[4], sd2, sd3;
    good_three(cf, &f[0], &sd2, &sd3);
    f[0].o[0] = 0x11u;
    f[1] = sd2;
    f[1].o[0] = f[1].o[3] = 0x69u;
    f[2].o[0] = FDL_SD4;
    f[2].o[1] = dut(cf);
    f[2].o[2] = tester(cf);
    f[2].n = FDL_SD4_LEN;
    f[3].o[0] = FDL_SC;
    f[3].n = FDL_SC_LEN;
    name(&f[0], "SD1 with start delimiter 11");
    name(&f[1], "SD2 with delimiters 69");
    name(&f[2], "SD4 token to the slave");
    name(&f[3], "SC alone");
    run_bad(cf, f, 4, "telegrams no slave answers");
}

/* ---- frame forms -------------------------------------------------------------------------- */

static bool status_in(cf_t *cf, const char *state)
{
    uint8_t o[CF_FRAME_MAX], e[FDL_SD1_LEN];
    char h1[32], h2[96];
    size_t n = status_req(dut(cf), tester(cf), o);
    /* SD1, DA and SA swapped, FC 00: a response, station type 00 (passive), OK */
    size_t en = fdl_encode(e, tester(cf), dut(cf), FDL_RSP_OK, false, 0, 0, NULL, 0);
    cf_reply_t r;
    if (!cf_exchange(cf, o, n, &r)) return false;
    return cf_check(cf, !r.garbled && r.len == en && memcmp(r.octets, e, en) == 0,
                    "Request FDL Status %s: expected %s, got %s", state,
                    cf_gf_hex(e, en, h1, sizeof h1), cf_reply_text(&r, h2, sizeof h2));
}

static void status_run(cf_t *cf)
{
    if (!cf_reset(cf) || !status_in(cf, "in Wait_Prm")) return;
    if (!cf_start_up(cf)) return;
    (void)status_in(cf, "in Data_Exch");
}

static const char *const check_names[] = {
    "OK", "empty", "unknown SD", "short", "LE != LEr", "LE out of 4..249", "SD2 not repeated",
    "bad ED", "bad FCS", "octets after ED",
};

/* The answer is a telegram a slave may send: a valid frame (the delimiter fits the DU: SD1 none,
 * SD3 exactly 8 octets, SD2 LE 4..249) with a response FC of station type 00, to the tester. */
static bool form_legal(cf_t *cf, const cf_reply_t *r, const char *what, char *form, size_t n)
{
    char t[96];
    if (r->len == 0u || r->garbled) {
        return cf_fail(cf, "%s: expected an answer, got %s", what, cf_reply_text(r, t, n));
    }
    if (cf_is_sc(r)) {
        (void)snprintf(form, n, "SC");
        return true;
    }
    fdl_check_info_t ci;
    fdl_msg_t m;
    fdl_check_result_t c = fdl_check(r->octets, r->len, &ci, &m);
    if (c != FDL_CHECK_OK || ci.parse != FDL_PARSE_OK) {
        return cf_fail(cf, "%s: answered with no valid telegram (%s): %s", what,
                       c < sizeof check_names / sizeof check_names[0] ? check_names[c] : "?",
                       cf_gf_hex(r->octets, r->len, t, sizeof t));
    }
    if ((m.fc & (0x80u | FDL_FC_REQUEST | FDL_FC_STATION_MASK)) != 0u || m.da != tester(cf) ||
        m.sa != dut(cf)) {
        return cf_fail(cf, "%s: expected a slave's response (FC 0x0n) from %u to %u, got FC "
                       "0x%02X from %u to %u", what, dut(cf), tester(cf), m.fc, m.sa, m.da);
    }
    size_t du = m.data_len + (m.has_dsap ? 1u : 0u) + (m.has_ssap ? 1u : 0u);
    (void)snprintf(form, n, "%s (DU %zu octets)",
                   m.sd == FDL_SD1 ? "SD1" : m.sd == FDL_SD3 ? "SD3" : "SD2", du);
    return true;
}

static void frame_form_run(cf_t *cf)
{
    if (!cf_start_up(cf)) return;
    cf_reply_t r[3];
    uint8_t out[CF_GF_DU_MAX] = {0};
    if (!cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r[0]) ||
        !cf_dp(cf, DP_SAP_GET_CFG, NULL, 0, &r[1]) ||
        !cf_data_exchange(cf, out, cf->out_len, &r[2])) {
        return;
    }
    static const char *const what[3] = {"Slave_Diag", "Get_Cfg", "Data_Exchange"};
    char form[3][48];
    for (size_t i = 0; i < 3u; i++) {
        if (!form_legal(cf, &r[i], what[i], form[i], sizeof form[i])) return;
    }
    cf_info(cf, "Slave_Diag answered with %s; Get_Cfg with %s; Data_Exchange with %s",
            form[0], form[1], form[2]);
}

static bool fits_sd3(const cf_gf_setup_t *s, bool *by_dx)
{
    *by_dx = s->out_len == DX_OUT_SD3;
    return *by_dx || s->cfg_len == DX_OUT_SD3 - FDL_SAPS_LEN;
}

/* A module whose request has 8 DU octets: 8 outputs (Data_Exchange) or a 6-octet Chk_Cfg; the
 * configured one first. */
static bool pick_sd3(const cf_t *cf, cf_gf_setup_t *s, bool *by_dx)
{
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, s);
    if (fits_sd3(s, by_dx)) return true;
    for (size_t m = 0; m < cf->gsd->n_modules; m++) {
        if (cf_gf_setup_module(cf, m, s, why, sizeof why) && fits_sd3(s, by_dx)) return true;
    }
    return false;
}

/* The same 8-octet request as SD2 (r[0]) and as SD3 (r[1]) from Data_Exch. */
static bool sd3_by_dx(cf_t *cf, const cf_gf_setup_t *s, cf_reply_t *r)
{
    static const uint8_t zero[DX_OUT_SD3] = {0};
    uint8_t o[CF_FRAME_MAX];
    cf_gf_fcb_t seq = {false, false};
    char why[CF_TEXT_MAX];
    if (!cf_gf_bring_up(cf, s, true, NULL, why, sizeof why)) {
        return cf_fail(cf, "start-up with %s: %s", s->name, why);
    }
    size_t n = sd2_req(dut(cf), tester(cf), cf_gf_next_fc(&seq, FDL_REQ_SRD_HIGH), zero,
                       sizeof zero, o);
    if (!cf_exchange(cf, o, n, &r[0])) return false;
    n = dx8_req(cf, dut(cf), cf_gf_next_fc(&seq, FDL_REQ_SRD_HIGH), o);
    if (!cf_exchange(cf, o, n, &r[1])) return false;
    cf_fcb_restart(cf, tester(cf));
    for (size_t i = 0; i < 2u; i++) {
        if (!cf_gf_dx_ok(cf, &r[i], s->in_len, why, sizeof why)) {
            return cf_fail(cf, "%s as %s: %s", s->name, i ? "SD3" : "SD2", why);
        }
    }
    return still_exchanging(cf, "Data_Exchange as SD3");
}

/* Set_Prm, then the 6-octet Chk_Cfg as SD2 (r[0]) or SD3 (r[1]): Data_Exch either way. */
static bool sd3_by_cfg(cf_t *cf, const cf_gf_setup_t *s, cf_reply_t *r)
{
    uint8_t du[CF_GF_DU_MAX], o[CF_FRAME_MAX];
    char t[96];
    if (!cf_reset(cf)) return false;
    du[0] = DP_SAP_CHK_CFG;
    du[1] = DP_SAP_MASTER;
    memcpy(du + 2, s->cfg, s->cfg_len);
    for (size_t i = 0; i < 2u; i++) {
        cf_reply_t a;
        if (!cf_dp(cf, DP_SAP_SET_PRM, s->prm, s->prm_len, &a)) return false;
        if (!cf_gf_ack(&a)) {
            return cf_fail(cf, "Set_Prm: expected SC, got %s", cf_reply_text(&a, t, sizeof t));
        }
        uint8_t fc = cf_gf_fc(FDL_REQ_SRD_HIGH, false, true);
        size_t n = i == 0u ? sd2_req(dut(cf) | FDL_ADDR_EXT, tester(cf) | FDL_ADDR_EXT, fc, du,
                                     DX_OUT_SD3, o)
                           : sap_req(cf, dut(cf), fc, DP_SAP_CHK_CFG, s->cfg, s->cfg_len, o);
        if (!cf_exchange(cf, o, n, &r[i])) return false;
        if (!cf_gf_ack(&r[i])) {
            return cf_fail(cf, "Chk_Cfg as %s: expected SC, got %s", i ? "SD3" : "SD2",
                           cf_reply_text(&r[i], t, sizeof t));
        }
        if (!still_exchanging(cf, i ? "Chk_Cfg as SD3" : "Chk_Cfg as SD2")) return false;
    }
    return true;
}

static void sd3_request_run(cf_t *cf)
{
    cf_gf_setup_t s;
    bool by_dx = false;
    if (!pick_sd3(cf, &s, &by_dx)) {
        return (void)cf_na(cf, "no module of the GSD has 8 output octets or 6 identifier "
                               "octets: no DP request of 8 DU octets has a known answer");
    }
    cf_reply_t r[2];
    if (!(by_dx ? sd3_by_dx(cf, &s, r) : sd3_by_cfg(cf, &s, r))) return;
    cf_info(cf, "%s with %s: the same answer to SD2 and SD3", by_dx ? "Data_Exchange" : "Chk_Cfg",
            s.name);
}

/* ---- addresses ---------------------------------------------------------------------------- */

static void other_address_run(cf_t *cf)
{
    if (!start_up_no_wd(cf, 0u)) return;
    uint8_t other = other_address(cf), du[CF_GF_DU_MAX];
    uint8_t first = cf_gf_fc(FDL_REQ_SRD_HIGH, false, true);
    frame_t f[4];
    f[0].n = status_req(other, tester(cf), f[0].o);
    f[1].n = diag_req(cf, other, tester(cf), first, f[1].o);
    f[2].n = dx8_req(cf, other, first, f[2].o);
    f[3].n = sap_req(cf, other, first, DP_SAP_SET_PRM, du, unlock_prm(cf, du), f[3].o);
    name(&f[0], "FDL Status to another DA");
    name(&f[1], "Slave_Diag to another DA");
    name(&f[2], "Data_Exchange (SD3) to another DA");
    name(&f[3], "Set_Prm (unlock) to another DA");
    for (size_t i = 0; i < 4u; i++) {
        if (!silent(cf, f[i].o, f[i].n, f[i].what)) return;
    }
    if (still_exchanging(cf, "the requests to another DA")) {
        cf_info(cf, "DA %u: 4 requests, none answered or carried out", other);
    }
}

static void sa_127_run(cf_t *cf)
{
    uint8_t before[CF_GF_DU_MAX], after[CF_GF_DU_MAX];
    size_t lb = 0, la = 0;
    char why[CF_TEXT_MAX], hb[64], ha[64];
    if (!cf_reset(cf)) return;
    if (!cf_gf_diag(cf, before, &lb, why, sizeof why)) return (void)cf_fail(cf, "%s", why);
    uint8_t first = cf_gf_fc(FDL_REQ_SRD_HIGH, false, true);
    frame_t f[3];
    f[0].n = status_req(dut(cf), FDL_ADDR_BROADCAST, f[0].o);
    f[1].n = diag_req(cf, dut(cf), FDL_ADDR_BROADCAST, first, f[1].o);
    f[2].n = fdl_encode(f[2].o, dut(cf), FDL_ADDR_BROADCAST, first, true, DP_SAP_SET_PRM,
                        DP_SAP_MASTER, cf->prm, cf->prm_len);
    name(&f[0], "FDL Status from SA 127");
    name(&f[1], "Slave_Diag from SA 127");
    name(&f[2], "Set_Prm (lock) from SA 127");
    for (size_t i = 0; i < 3u; i++) {
        if (!silent(cf, f[i].o, f[i].n, f[i].what)) return;
    }
    cf_fcb_restart(cf, tester(cf));
    if (!cf_gf_diag(cf, after, &la, why, sizeof why)) return (void)cf_fail(cf, "%s", why);
    (void)cf_check(cf, after[DP_DIAG_MASTER_ADD] == before[DP_DIAG_MASTER_ADD] &&
                           (after[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ) ==
                               (before[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ),
                   "Set_Prm from SA 127 carried out: diagnosis %s before, %s after",
                   cf_gf_hex(before, lb, hb, sizeof hb), cf_gf_hex(after, la, ha, sizeof ha));
}

static void broadcast_srd_run(cf_t *cf)
{
    frame_t f[2];
    f[0].n = diag_req(cf, FDL_ADDR_BROADCAST, tester(cf), cf_gf_fc(FDL_REQ_SRD_HIGH, false, true),
                      f[0].o);
    f[1].n = status_req(FDL_ADDR_BROADCAST, tester(cf), f[1].o);
    name(&f[0], "Slave_Diag (SRD) to DA 127");
    name(&f[1], "FDL Status to DA 127");
    run_bad(cf, f, 2, "requests with reply to DA 127");
}

/* ---- SDN ---------------------------------------------------------------------------------- */

static size_t gc_req(const cf_t *cf, uint8_t da, uint8_t command, uint8_t *o)
{
    const uint8_t du[DP_GC_LEN] = {command, 0}; /* Group_Select 0: every group */
    return sap_req(cf, da, cf_gf_fc(FDL_REQ_SDN_HIGH, false, false), DP_SAP_GLOBAL_CONTROL, du,
                   sizeof du, o);
}

/* A Global_Control as SDN: no answer; then the diagnosis bit shows whether it took effect. */
static bool gc_sdn(cf_t *cf, uint8_t da, uint8_t command, uint8_t bit, bool want,
                   const char *what)
{
    uint8_t o[CF_FRAME_MAX], d[CF_GF_DU_MAX];
    size_t len = 0;
    char why[CF_TEXT_MAX], h[64];
    size_t n = gc_req(cf, da, command, o);
    if (!silent(cf, o, n, what)) return false;
    if (!cf_gf_diag(cf, d, &len, why, sizeof why)) return cf_fail(cf, "after %s: %s", what, why);
    if (bit == 0u) {
        return cf_check(cf, cf_gf_in_data_exch(d, len), "after %s: expected Data_Exch, "
                        "diagnosis %s", what, cf_gf_hex(d, len, h, sizeof h));
    }
    return cf_check(cf, ((d[DP_DIAG_STATUS_2] & bit) != 0u) == want,
                    "after %s: expected Station_status_2 bit 0x%02X %s, diagnosis %s", what, bit,
                    want ? "set" : "clear", cf_gf_hex(d, len, h, sizeof h));
}

static void sdn_run(cf_t *cf)
{
    const gsd_t *g = cf->gsd;
    uint32_t freeze = 0, sync = 0;
    (void)gsd_key(g, GSD_K_FREEZE_MODE_SUPP, &freeze);
    (void)gsd_key(g, GSD_K_SYNC_MODE_SUPP, &sync);
    uint8_t req = freeze ? DP_PRM_FREEZE_REQ : sync ? DP_PRM_SYNC_REQ : 0u;
    uint8_t on = freeze ? DP_GC_FREEZE : sync ? DP_GC_SYNC : DP_GC_CLEAR_DATA;
    uint8_t off = freeze ? DP_GC_UNFREEZE : sync ? DP_GC_UNSYNC : DP_GC_CLEAR_DATA;
    uint8_t bit = freeze ? DP_DIAG2_FREEZE_MODE : sync ? DP_DIAG2_SYNC_MODE : 0u;
    const char *cmd = freeze ? "Freeze" : sync ? "Sync" : "Clear_Data";
    char w1[64], w2[64];
    if (!start_up_no_wd(cf, req)) return;
    (void)snprintf(w1, sizeof w1, "Global_Control %s as SDN to DA %u", cmd, dut(cf));
    (void)snprintf(w2, sizeof w2, "Global_Control %s as SDN to DA 127",
                   freeze ? "Unfreeze" : sync ? "Unsync" : cmd);
    if (!gc_sdn(cf, dut(cf), on, bit, true, w1) ||
        !gc_sdn(cf, FDL_ADDR_BROADCAST, off, bit, false, w2)) {
        return;
    }
    if (bit == 0u) {
        cf_info(cf, "the effect is not visible: the GSD claims neither Freeze_Mode_supp nor "
                    "Sync_Mode_supp (Clear_Data sent, no answer checked)");
    }
}

/* ---- FCB and FCV -------------------------------------------------------------------------- */

/* Sends o and checks the answer comes from SAP want (the request was carried out). */
static bool served_by(cf_t *cf, const uint8_t *o, size_t n, uint8_t want, const char *what,
                      cf_reply_t *r)
{
    char t[96];
    cf_answer_t a;
    if (!cf_exchange(cf, o, n, r)) return false;
    return cf_check(cf, cf_answer(r, &a) && a.saps && a.ssap == want && a.dsap == DP_SAP_MASTER,
                    "%s: expected the answer of SAP %u, got %s", what, want,
                    cf_reply_text(r, t, sizeof t));
}

static bool same_reply(cf_t *cf, const cf_reply_t *held, const cf_reply_t *r, const char *what)
{
    char h1[64], h2[96];
    return cf_check(cf, !r->garbled && r->len == held->len &&
                            memcmp(r->octets, held->octets, held->len) == 0,
                    "%s: expected the held answer %s again, got %s", what,
                    cf_gf_hex(held->octets, held->len, h1, sizeof h1),
                    cf_reply_text(r, h2, sizeof h2));
}

/* Slave_Diag, Get_Cfg, the same Get_Cfg again, then a Set_Prm (unlock) with that FCB once
 * more: both repetitions get the Get_Cfg answer, and the unlock is not carried out. */
static void fcb_repeat_run(cf_t *cf)
{
    if (!cf_start_up(cf)) return;
    uint8_t o[CF_FRAME_MAX], du[CF_GF_DU_MAX];
    cf_gf_fcb_t seq = {false, false};
    cf_reply_t r, held;
    size_t n = diag_req(cf, dut(cf), tester(cf), cf_gf_next_fc(&seq, FDL_REQ_SRD_HIGH), o);
    if (!served_by(cf, o, n, DP_SAP_SLAVE_DIAG, "Slave_Diag (FCV 0, FCB 1)", &r)) return;
    uint8_t fc = cf_gf_next_fc(&seq, FDL_REQ_SRD_HIGH);
    n = sap_req(cf, dut(cf), fc, DP_SAP_GET_CFG, NULL, 0, o);
    if (!served_by(cf, o, n, DP_SAP_GET_CFG, "Get_Cfg (FCV 1, FCB 0)", &held)) return;
    if (!cf_exchange(cf, o, n, &r) ||
        !same_reply(cf, &held, &r, "the same Get_Cfg again (FCV 1, FCB 0)")) {
        return;
    }
    n = sap_req(cf, dut(cf), fc, DP_SAP_SET_PRM, du, unlock_prm(cf, du), o);
    if (!cf_exchange(cf, o, n, &r) ||
        !same_reply(cf, &held, &r, "Set_Prm (unlock) with the FCB of the Get_Cfg")) {
        return;
    }
    n = diag_req(cf, dut(cf), tester(cf), cf_gf_next_fc(&seq, FDL_REQ_SRD_HIGH), o);
    if (!served_by(cf, o, n, DP_SAP_SLAVE_DIAG, "Slave_Diag (FCV 1, FCB 1)", &r)) return;
    (void)still_exchanging(cf, "the Set_Prm (unlock) taken for a repetition");
}

/* FCV 0: every request is carried out, the same FCB or not. */
static void fcv_off_run(cf_t *cf)
{
    static const struct {
        uint8_t sap;
        bool fcb;
        const char *what;
    } step[] = {
        {DP_SAP_SLAVE_DIAG, true, "Slave_Diag (FCV 0, FCB 1)"},
        {DP_SAP_GET_CFG, true, "Get_Cfg (FCV 0, FCB 1)"},
        {DP_SAP_SLAVE_DIAG, true, "Slave_Diag (FCV 0, FCB 1)"},
        {DP_SAP_GET_CFG, false, "Get_Cfg (FCV 0, FCB 0)"},
        {DP_SAP_SLAVE_DIAG, false, "Slave_Diag (FCV 0, FCB 0)"},
        {DP_SAP_GET_CFG, false, "Get_Cfg (FCV 0, FCB 0)"},
    };
    if (!cf_start_up(cf)) return;
    uint8_t o[CF_FRAME_MAX];
    cf_reply_t r;
    for (size_t i = 0; i < sizeof step / sizeof step[0]; i++) {
        uint8_t fc = cf_gf_fc(FDL_REQ_SRD_HIGH, false, step[i].fcb);
        size_t n = sap_req(cf, dut(cf), fc, step[i].sap, NULL, 0, o);
        if (!served_by(cf, o, n, step[i].sap, step[i].what, &r)) return;
    }
}

/* ---- SAPs and function codes -------------------------------------------------------------- */

/* SAP 54 serves master-to-master traffic and no slave; SAP 10 is no DP service (in a DP-V1
 * slave an MSAC2 SAP, open only while a connection holds it). */
static void sap_unknown_run(cf_t *cf)
{
    static const uint8_t sap[] = {54u, 10u};
    if (!start_up_no_wd(cf, 0u)) return;
    for (size_t i = 0; i < sizeof sap; i++) {
        uint8_t o[CF_FRAME_MAX], e[FDL_SD1_LEN], du[1] = {0};
        char h1[32], h2[96];
        cf_fcb_restart(cf, tester(cf));
        size_t n = sap_req(cf, dut(cf), cf_gf_fc(FDL_REQ_SRD_HIGH, false, true), sap[i], du,
                           sizeof du, o);
        size_t en = fdl_encode(e, tester(cf), dut(cf), FDL_RSP_RS, false, 0, 0, NULL, 0);
        cf_reply_t r;
        if (!cf_exchange(cf, o, n, &r)) return;
        if (!cf_check(cf, !r.garbled && r.len == en && memcmp(r.octets, e, en) == 0,
                      "SRD to DSAP %u: expected RS %s, got %s", sap[i],
                      cf_gf_hex(e, en, h1, sizeof h1), cf_reply_text(&r, h2, sizeof h2))) {
            return;
        }
    }
    (void)still_exchanging(cf, "the requests to unused SAPs");
}

/* Codes 1, 2 and 8 are reserved: the frame is not carried out; the slave stays silent or
 * answers it negatively (RS or UE, SD1). */
static void reserved_fc_run(cf_t *cf)
{
    static const uint8_t code[] = {0x1u, 0x2u, 0x8u};
    if (!start_up_no_wd(cf, 0u)) return;
    char seen[CF_TEXT_MAX] = "";
    size_t at = 0;
    for (size_t i = 0; i < sizeof code; i++) {
        uint8_t o[CF_FRAME_MAX], du[CF_GF_DU_MAX], fc = cf_gf_fc(code[i], false, false);
        char t[96];
        size_t n = sap_req(cf, dut(cf), fc, DP_SAP_SET_PRM, du, unlock_prm(cf, du), o);
        cf_reply_t r;
        if (!cf_exchange(cf, o, n, &r)) return;
        int rsp = cf_rsp_code(&r);
        bool quiet = r.len == 0u && !r.garbled;
        bool negative = r.len == FDL_SD1_LEN && r.octets[0] == FDL_SD1 &&
                        (rsp == (int)FDL_RSP_RS || rsp == (int)FDL_RSP_UE) &&
                        r.octets[1] == tester(cf) && r.octets[2] == dut(cf);
        if (!cf_check(cf, quiet || negative, "FC 0x%02X (reserved code %u): expected no "
                      "answer or SD1 RS/UE, got %s", fc, code[i],
                      cf_reply_text(&r, t, sizeof t))) {
            return;
        }
        if (at < sizeof seen) {
            at += (size_t)snprintf(seen + at, sizeof seen - at, "%scode %u: %s", i ? ", " : "",
                                   code[i], quiet ? "silence" : rsp == FDL_RSP_RS ? "RS" : "UE");
        }
    }
    if (still_exchanging(cf, "Set_Prm (unlock) with reserved function codes")) {
        cf_info(cf, "%s", seen);
    }
}

/* ---- the table ---------------------------------------------------------------------------- */

/* Every case ends with the tester's FCB sequence restarted: a request built here may have left
 * the slave holding an FCB the request helpers of cf.h do not know of, and the next request
 * must not be taken for a repetition. */
#define RESTARTING(x)                                                                       \
    static void x##_case(cf_t *cf)                                                          \
    {                                                                                       \
        x##_run(cf);                                                                        \
        cf_fcb_restart(cf, tester(cf));                                                     \
    }
RESTARTING(bad_fcs)
RESTARTING(bad_ed)
RESTARTING(le_mismatch)
RESTARTING(sd2_repeat)
RESTARTING(short)
RESTARTING(unknown_sd)
RESTARTING(status)
RESTARTING(frame_form)
RESTARTING(sd3_request)
RESTARTING(other_address)
RESTARTING(sa_127)
RESTARTING(broadcast_srd)
RESTARTING(sdn)
RESTARTING(fcb_repeat)
RESTARTING(fcv_off)
RESTARTING(sap_unknown)
RESTARTING(reserved_fc)

#define CLAUSE_FCB "IEC 61158-4-3 FCB/FCV (PROFIBUS Spec. Part 4): FCB evaluated when FCV = 1"
#define CLAUSE_ADDR "IEC 61158-4-3 addressing: DA the station's own or 127 (SDN only); 127 " \
                    "never a source"

const cf_case_t cf_cases_fdl[] = {
    {"fdl.status", FDL_GROUP, "IEC 61158-4-3 Request FDL Status: SD1, FC passive station, OK",
     "Request FDL Status is answered 10 M A 00 FCS 16 in every state", status_case},
    {"fdl.sd3_request", FDL_GROUP, "IEC 61158-4-3 frame formats: SD3 fixed 8-octet DU",
     "a request of 8 DU octets sent as SD3 is served as the same request as SD2",
     sd3_request_case},
    {"fdl.frame_form", FDL_GROUP, "IEC 61158-4-3 frame formats: SD1, SD2 (LE 4..249), SD3, SC",
     "the slave's answers are telegrams of a legal form", frame_form_case},
    {"fdl.bad_fcs", FDL_GROUP, CLAUSE_CHECK, "a telegram with a wrong FCS is not answered",
     bad_fcs_case},
    {"fdl.bad_ed", FDL_GROUP, CLAUSE_CHECK, "a telegram with a wrong ED is not answered",
     bad_ed_case},
    {"fdl.le_mismatch", FDL_GROUP, CLAUSE_CHECK, "an SD2 with LE != LEr is not answered",
     le_mismatch_case},
    {"fdl.sd2_repeat", FDL_GROUP, CLAUSE_CHECK,
     "an SD2 whose fourth octet is not 68 is not answered", sd2_repeat_case},
    {"fdl.short", FDL_GROUP, CLAUSE_CHECK, "a telegram cut short or with LE 3 is not answered",
     short_case},
    {"fdl.unknown_sd", FDL_GROUP, CLAUSE_CHECK,
     "an unknown start delimiter, a token or a lone SC is not answered", unknown_sd_case},
    {"fdl.other_address", FDL_GROUP, CLAUSE_ADDR,
     "requests to another DA are neither answered nor carried out", other_address_case},
    {"fdl.sa_127", FDL_GROUP, CLAUSE_ADDR,
     "a request from SA 127 is neither answered nor carried out", sa_127_case},
    {"fdl.broadcast_srd", FDL_GROUP, CLAUSE_ADDR,
     "a request with reply to DA 127 is not answered", broadcast_srd_case},
    {"fdl.sdn", FDL_GROUP, "IEC 61158-4-3 SDN (no reply, DA 127); IEC 61158-6-3 Global_Control",
     "Global_Control as SDN to the slave and to DA 127: no answer, and it takes effect",
     sdn_case},
    {"fdl.fcb_repeat", FDL_GROUP, CLAUSE_FCB "; a repetition gets the held answer, the "
     "indication is not repeated",
     "a request with FCV 1 and the previous FCB gets the previous answer, and is not carried out",
     fcb_repeat_case},
    {"fdl.fcv_off", FDL_GROUP, CLAUSE_FCB,
     "with FCV 0 every request is carried out, whatever its FCB", fcv_off_case},
    {"fdl.sap_unknown", FDL_GROUP, "IEC 61158-4-3 response code RS: SAP not activated",
     "a request to an unused DSAP is answered RS (SD1)", sap_unknown_case},
    {"fdl.reserved_fc", FDL_GROUP, "IEC 61158-4-3 FC coding: request codes 1, 2, 8 reserved",
     "a reserved function code is not carried out (no answer, or RS/UE)", reserved_fc_case},
};

const size_t cf_cases_fdl_count = sizeof cf_cases_fdl / sizeof cf_cases_fdl[0];
