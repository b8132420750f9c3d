/* Set_Prm with and without lock and unlock, repeated, with a wrong ident, and the watchdog on
 * and off, judged by EN 50170 vol. 2 DP "Send Parameter Data" (Set_Prm) and the DP slave state
 * machine of IEC 61158-6-3 (docs/protocol.md §A2.3, §A3.2, §A3.6). */
#include <stdio.h>
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"

#define DIAG_OWNER "Master_Add (the owner)"

static bool owner_in_data_exch(cf_t *cf, const char *what)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, DIAG_OWNER, what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, 0, "Prm_Req", what) &&
           dpx_dx(cf, NULL, NULL, what);
}

void dpc_set_prm_lock(cf_t *cf)
{
    cf_reply_t r;
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    const uint8_t m2 = cf->opt.master_2;
    if (!cf_start_up(cf)) return;
    if (!cf_dp_from(cf, m2, DP_SAP_MASTER, DP_SAP_SET_PRM, cf->prm, cf->prm_len, &r)) return;
    if (!dpx_expect_rs(cf, &r, "Set_Prm with Lock_Req from a second master while locked")) return;
    if (!owner_in_data_exch(cf, "after the second master's Set_Prm")) return;
    if (!dpx_diag_from(cf, m2, d, &n, "Slave_Diag of the second master")) return;
    (void)dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, DIAG_OWNER,
                   "Slave_Diag of the second master");
}

void dpc_set_prm_unlock(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    cf_reply_t r;
    const uint8_t m2 = cf->opt.master_2;
    if (!cf_start_up(cf)) return;
    uint8_t clear = DP_PRM_LOCK_REQ | DP_PRM_WD_ON | DP_PRM_SYNC_REQ | DP_PRM_FREEZE_REQ;
    size_t len = dpx_prm_with(cf, DP_PRM_UNLOCK_REQ, clear, prm);
    if (!dpx_set_prm(cf, prm, len, "Set_Prm with Unlock_Req")) return;
    if (!cf_diag(cf, d, &n) || !dpx_wait_prm_bits(cf, d, n, "Slave_Diag after unlock")) return;
    if (!dpx_dx_refused(cf, "Data_Exchange after unlock")) return;
    /* Released: another master may lock it now. */
    if (!cf_dp_from(cf, m2, DP_SAP_MASTER, DP_SAP_SET_PRM, cf->prm, cf->prm_len, &r)) return;
    if (!dpx_expect_ack(cf, &r, "Set_Prm with Lock_Req from a second master after unlock")) {
        return;
    }
    if (!dpx_diag_from(cf, m2, d, &n, "Slave_Diag of the second master")) return;
    (void)dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, m2, "Master_Add (the second master)",
                   "after the second master's Set_Prm");
}

/* The min TSDR a case sets: the GSD's MaxTsdr at the run's rate (an answer may not come later,
 * so the slave can keep both), else 20 bit times. */
static uint8_t raised_min_tsdr(const cf_t *cf)
{
    uint32_t max = cf->link.baud ? gsd_max_tsdr_bits(cf->gsd, cf->link.baud) : 0u;
    if (max <= FDL_MIN_TSDR_DEFAULT_BITS) return 20u;
    return max > 255u ? 255u : (uint8_t)max;
}

/* Lock_Req = Unlock_Req = 0 with other watchdog, group and (second round) a wrong ident: only
 * min TSDR may change; the ident is not checked then (EN 50170 vol. 2 DP, Set_Prm octet 4..6). */
static bool min_tsdr_round(cf_t *cf, bool wrong_ident, uint8_t tsdr)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    const char *what = wrong_ident ? "after Set_Prm lock 0 unlock 0 with another ident"
                                   : "after Set_Prm lock 0 unlock 0";
    size_t len = dpx_prm_with(cf, 0, DP_PRM_LOCK_REQ | DP_PRM_UNLOCK_REQ | DP_PRM_WD_ON, prm);
    prm[DP_PRM_WD_FACT_1] = 3;
    prm[DP_PRM_WD_FACT_2] = 7;
    prm[DP_PRM_MIN_TSDR] = tsdr;
    prm[DP_PRM_GROUP_IDENT] = 0xFF;
    if (wrong_ident) prm[DP_PRM_IDENT_LOW] ^= 0xFFu;
    if (!dpx_set_prm(cf, prm, len, what)) return false;
    /* The diagnosis bits of Data_Exch as such (WD_On) are dp.diag.data_exch's. */
    return cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_1,
                    DP_DIAG1_PRM_FAULT | DP_DIAG1_STATION_NOT_READY | DP_DIAG1_CFG_FAULT, 0,
                    "Prm_Fault, Station_Not_Ready, Cfg_Fault", what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, 0, "Prm_Req 0", what) &&
           dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, DIAG_OWNER, what);
}

void dpc_set_prm_min_tsdr_only(cf_t *cf)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    uint8_t tsdr = raised_min_tsdr(cf);
    cf_reply_t r;
    if (!cf_start_up(cf) || !min_tsdr_round(cf, false, tsdr) || !min_tsdr_round(cf, true, tsdr)) {
        return;
    }
    if (!cf_data_exchange(cf, zeros, cf->out_len, &r)) return;
    char t[CF_TEXT_MAX];
    cf_answer_t a;
    if (!cf_check(cf, dpx_is_data(&r, &a) || (cf->in_len == 0u && dpx_is_ack(&r)),
                  "Data_Exchange after Set_Prm lock 0 unlock 0: expected the inputs, got %s",
                  cf_reply_text(&r, t, sizeof t))) {
        return;
    }
    /* Whether answers keep the new min TSDR to the bit is timing.tsdr.min's to judge. */
    if (r.tsdr_bits == CF_TSDR_UNKNOWN) {
        cf_info(cf, "min TSDR %u bit set; the medium cannot time the answers", tsdr);
    } else {
        cf_info(cf, "min TSDR %u bit set; the next answer came after %d bit", tsdr,
                (int)r.tsdr_bits);
    }
}

void dpc_set_prm_repeated(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    if (!cf_reset(cf) || !cf_diag(cf, d, &n)) return;
    for (int i = 0; i < 3; i++) {
        if (!dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm repeated in Wait_Prm/Wait_Cfg")) {
            return;
        }
    }
    if (!dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, "Chk_Cfg after three Set_Prm") ||
        !dpx_wait_ready(cf, d, &n, "after three Set_Prm") ||
        !dpx_dx(cf, NULL, NULL, "after three Set_Prm")) {
        return;
    }
    for (int i = 0; i < 2; i++) {
        if (!dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm repeated in Data_Exch")) return;
    }
    (void)(dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, "Chk_Cfg after two Set_Prm in Data_Exch") &&
           dpx_wait_ready(cf, d, &n, "after two Set_Prm in Data_Exch") &&
           dpx_dx(cf, NULL, NULL, "after two Set_Prm in Data_Exch"));
}

void dpc_set_prm_wrong_ident(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    cf_reply_t r;
    const char *what = "Slave_Diag after Set_Prm with a wrong Ident_Number";
    if (!cf_reset(cf) || !cf_diag(cf, d, &n)) return;
    size_t len = dpx_prm_with(cf, 0, 0, prm);
    prm[DP_PRM_IDENT_HIGH] ^= 0xFFu;
    prm[DP_PRM_IDENT_LOW] ^= 0xFFu;
    if (!cf_dp(cf, DP_SAP_SET_PRM, prm, len, &r)) return;
    dpx_note(cf, &r, "Set_Prm with the wrong ident");
    if (!cf_diag(cf, d, &n) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_1, DP_DIAG1_PRM_FAULT | DP_DIAG1_STATION_NOT_READY,
                  DP_DIAG1_PRM_FAULT | DP_DIAG1_STATION_NOT_READY,
                  "Prm_Fault and Station_Not_Ready", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, DP_DIAG2_PRM_REQ, "Prm_Req",
                  what)) {
        return;
    }
    if (!cf_dp(cf, DP_SAP_CHK_CFG, cf->cfg, cf->cfg_len, &r)) return;
    dpx_note(cf, &r, "Chk_Cfg after it");
    (void)dpx_dx_refused(cf, "Data_Exchange after Set_Prm with a wrong ident and Chk_Cfg");
}

void dpc_set_prm_watchdog_off(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    size_t len = cf_default_prm(cf, 0, prm, sizeof prm);
    prm[DP_PRM_STATION_STATUS] &= (uint8_t)~DP_PRM_WD_ON;
    prm[DP_PRM_WD_FACT_1] = 1; /* 100 ms, were the watchdog on */
    prm[DP_PRM_WD_FACT_2] = 10;
    if (cf->dpv1 && len >= DP_PRM_LEN_DPV1) {
        prm[DP_PRM_DPV1_STATUS_1] &= (uint8_t)~DP_DPV1_1_WD_BASE_1MS;
    }
    if (!dpx_start_up_with(cf, prm, len) || !cf_diag(cf, d, &n)) return;
    if (!dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_WD_ON, 0, "WD_On",
                  "Slave_Diag after Set_Prm without WD_On")) {
        return;
    }
    if (!cf_pause_ms(cf, 300)) return;
    (void)owner_in_data_exch(cf, "after 300 ms of silence, watchdog off (factors: 100 ms)");
}

/* How long the line is busy around one pause beside the pause: the answer before it and the
 * request after it, with their idle times. */
static uint32_t line_ms(const cf_t *cf)
{
    if (cf->link.baud == 0u) return 2u;
    uint32_t octets = (cf->in_len > cf->out_len ? cf->in_len : cf->out_len) + 11u;
    /* each telegram: its characters, the idle before it and an answer's station delay */
    uint64_t bits = 2u * ((uint64_t)octets * FDL_CHAR_BITS + FDL_TSYN_BITS + 100u);
    return (uint32_t)(bits * 1000u / cf->link.baud) + 1u + 2u * cf->link.idle_us / 1000u;
}

/* The watchdog parameterised for the case: 100 ms, longer where telegrams take long. */
static uint32_t expiry_target_ms(const cf_t *cf)
{
    if (!cf->link.timing) return 200u;
    uint32_t want = 4u * line_ms(cf);
    return want < 100u ? 100u : (want + 9u) / 10u * 10u;
}

static bool silent_then(cf_t *cf, uint32_t ms, bool alive, const char *what)
{
    if (!cf_pause_ms(cf, ms)) return false;
    return alive ? dpx_dx(cf, NULL, NULL, what) : dpx_dx_refused(cf, what);
}

void dpc_watchdog_expiry(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    char what[CF_TEXT_MAX];
    size_t len = cf_default_prm(cf, expiry_target_ms(cf), prm, sizeof prm);
    uint32_t t = dpx_watchdog_ms(cf, prm, len);
    if (!cf_check(cf, t > 0u, "the tester's Set_Prm has no watchdog (WD_On 0)")) return;
    uint32_t margin = t / 10u > 10u ? t / 10u : 10u;
    uint32_t before = cf->link.timing ? t - margin - line_ms(cf) : t / 2u;
    uint32_t after = cf->link.timing ? t + margin : 2u * t + 50u;
    if (!dpx_start_up_with(cf, prm, len)) return;
    for (int i = 0; i < 3; i++) {
        snprintf(what, sizeof what, "silent %u ms with a %u ms watchdog (still Data_Exch)",
                 (unsigned)before, (unsigned)t);
        if (!silent_then(cf, before, true, what)) return;
    }
    snprintf(what, sizeof what, "silent %u ms with a %u ms watchdog (Data_Exch left)",
             (unsigned)after, (unsigned)t);
    if (!silent_then(cf, after, false, what)) return;
    if (!cf_diag(cf, d, &n) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, DP_DIAG2_PRM_REQ, "Prm_Req",
                  "Slave_Diag after the watchdog expired")) {
        return;
    }
    cf_info(cf, "watchdog %u ms: answered after %u ms of silence, left Data_Exch after %u ms%s",
            (unsigned)t, (unsigned)before, (unsigned)after,
            cf->link.timing ? "" : " (the medium has no timing: wide bounds)");
}
