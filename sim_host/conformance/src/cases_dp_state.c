/* The DP slave's services in each state (Wait_Prm, Wait_Cfg, Data_Exch) and the diagnosis it
 * gives in them, judged by the DP slave state machine of IEC 61158-6-3 / EN 50170 vol. 2 as
 * docs/protocol.md §A3.4 and §A3.6 digest it. Where the standard leaves the answer open (Rd_Inp
 * and Rd_Outp before Data_Exch, Chk_Cfg in Wait_Prm) the answer is information and only the
 * effect is judged. */
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"

static const uint8_t NO_DU[1] = {0};

static bool ident_ok(cf_t *cf, const uint8_t *d, const char *what)
{
    unsigned got = ((unsigned)d[DP_DIAG_IDENT_HIGH] << 8) | d[DP_DIAG_IDENT_LOW];
    return cf_check(cf, got == cf->ident, "%s: Ident_Number expected 0x%04X, got 0x%04X", what,
                    (unsigned)cf->ident, got);
}

void dpc_diag_wait_prm(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    char h[DPX_HEX_MAX];
    if (!cf_reset(cf) || !cf_diag(cf, d, &n)) return;
    const char *what = "Slave_Diag after unlock (Wait_Prm)";
    if (!dpx_wait_prm_bits(cf, d, n, what) || !ident_ok(cf, d, what)) return;
    if (!dpx_bits(cf, d, n, DP_DIAG_STATUS_3, 0x7Fu, 0, "Station_status_3 reserved bits", what)) {
        return;
    }
    cf_info(cf, "diagnosis %s", dpx_hex(d, n, h, sizeof h));
}

/* Chk_Cfg before any Set_Prm: its answer is the implementation's, but it must not bring the
 * slave to Data_Exch. */
static bool wait_prm_chk_cfg(cf_t *cf)
{
    cf_reply_t r;
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    if (!cf_dp(cf, DP_SAP_CHK_CFG, cf->cfg, cf->cfg_len, &r)) return false;
    dpx_note(cf, &r, "Chk_Cfg");
    return dpx_dx_refused(cf, "Data_Exchange after Chk_Cfg in Wait_Prm") && cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, DP_DIAG2_PRM_REQ,
                    "Station_status_2.Prm_Req", "Slave_Diag after Chk_Cfg in Wait_Prm");
}

/* Rd_Inp and Rd_Outp before Data_Exch: no I/O image exists yet; the answer is noted. */
static bool note_reads(cf_t *cf)
{
    cf_reply_t r;
    if (!cf_dp(cf, DP_SAP_RD_INP, NO_DU, 0, &r)) return false;
    dpx_note(cf, &r, "Rd_Inp");
    if (!cf_dp(cf, DP_SAP_RD_OUTP, NO_DU, 0, &r)) return false;
    dpx_note(cf, &r, "Rd_Outp");
    return true;
}

static bool get_cfg_answered(cf_t *cf, const char *what)
{
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    if (!cf_dp(cf, DP_SAP_GET_CFG, NO_DU, 0, &r)) return false;
    return cf_check(cf, dpx_is_data(&r, &a) && a.du_len > 0u,
                    "%s: Get_Cfg: expected DL with the configuration, got %s", what,
                    cf_reply_text(&r, t, sizeof t));
}

/* Set_Slave_Add: a slave whose GSD says Set_Slave_Add_supp = 0 has SAP 55 closed (RS); one that
 * claims it is not readdressed by the suite. */
static bool set_slave_add(cf_t *cf)
{
    uint32_t supp = 0;
    (void)gsd_key(cf->gsd, GSD_K_SET_SLAVE_ADD_SUPP, &supp);
    if (supp != 0u) {
        cf_info(cf, "Set_Slave_Add not sent (Set_Slave_Add_supp = 1)");
        return true;
    }
    const uint8_t du[4] = {cf->opt.address, (uint8_t)(cf->ident >> 8), (uint8_t)cf->ident, 0};
    cf_reply_t r;
    if (!cf_dp(cf, DP_SAP_SET_SLAVE_ADD, du, sizeof du, &r)) return false;
    return dpx_expect_rs(cf, &r, "Set_Slave_Add with Set_Slave_Add_supp = 0");
}

void dpc_wait_prm_services(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    if (!cf_reset(cf) || !cf_diag(cf, d, &n)) return;
    if (!dpx_wait_prm_bits(cf, d, n, "Slave_Diag in Wait_Prm")) return;
    if (!get_cfg_answered(cf, "Wait_Prm")) return;
    if (!dpx_dx_refused(cf, "Data_Exchange in Wait_Prm")) return;
    if (!note_reads(cf) || !set_slave_add(cf)) return;
    if (!dpx_gc(cf, cf->opt.master, DP_GC_SYNC | DP_GC_FREEZE, 0)) return;
    if (!cf_diag(cf, d, &n) ||
        !dpx_wait_prm_bits(cf, d, n, "Slave_Diag after Global_Control in Wait_Prm")) {
        return;
    }
    (void)wait_prm_chk_cfg(cf);
}

/* Into Wait_Cfg: unlocked, then the tester's Set_Prm. */
static bool to_wait_cfg(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return cf_reset(cf) && cf_diag(cf, d, &n) &&
           dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm in Wait_Prm");
}

static bool to_data_exch(cf_t *cf, const char *what)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, what) && dpx_wait_ready(cf, d, &n, what) &&
           dpx_dx(cf, NULL, NULL, what);
}

void dpc_wait_cfg_data_exchange(cf_t *cf)
{
    if (!to_wait_cfg(cf) || !dpx_dx_refused(cf, "Data_Exchange in Wait_Cfg")) return;
    (void)to_data_exch(cf, "Chk_Cfg after the refused Data_Exchange");
}

void dpc_wait_cfg_services(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    const char *what = "Slave_Diag in Wait_Cfg";
    if (!to_wait_cfg(cf) || !cf_diag(cf, d, &n)) return;
    if (!dpx_bits(cf, d, n, DP_DIAG_STATUS_1, DP_DIAG1_STATION_NOT_READY | DP_DIAG1_PRM_FAULT,
                  DP_DIAG1_STATION_NOT_READY, "Station_Not_Ready 1, Prm_Fault 0", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_ALWAYS_ONE, DP_DIAG2_ALWAYS_ONE,
                  "Station_status_2 bit 2 (always 1)", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master,
                  "Master_Add (the master that locked it)", what)) {
        return;
    }
    if (!get_cfg_answered(cf, "Wait_Cfg") || !note_reads(cf)) return;
    /* Data_Exchange and a second Set_Prm in Wait_Cfg have cases of their own
     * (dp.wait_cfg.data_exchange, dp.set_prm.repeated). */
    if (!dpx_gc(cf, cf->opt.master, DP_GC_CLEAR_DATA, 0)) return;
    (void)to_data_exch(cf, "Chk_Cfg in Wait_Cfg");
}

/* The I/O reads of Data_Exch give the configured lengths. */
static bool io_read(cf_t *cf, uint8_t sap, uint16_t want, const char *name)
{
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    if (!cf_dp(cf, sap, NO_DU, 0, &r)) return false;
    return cf_check(cf, dpx_is_data(&r, &a) && a.du_len == want,
                    "%s in Data_Exch: expected DL with %u octets, got %s", name, (unsigned)want,
                    cf_reply_text(&r, t, sizeof t));
}

void dpc_data_exch_services(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    if (!cf_start_up(cf) || !cf_diag(cf, d, &n)) return;
    if (!get_cfg_answered(cf, "Data_Exch")) return;
    if (!io_read(cf, DP_SAP_RD_INP, cf->in_len, "Rd_Inp") ||
        !io_read(cf, DP_SAP_RD_OUTP, cf->out_len, "Rd_Outp")) {
        return;
    }
    if (!dpx_gc(cf, cf->opt.master, 0, 0) || !dpx_dx(cf, NULL, NULL, "after Global_Control")) {
        return;
    }
    if (!dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, "Chk_Cfg in Data_Exch") ||
        !dpx_wait_ready(cf, d, &n, "after Chk_Cfg in Data_Exch") ||
        !dpx_dx(cf, NULL, NULL, "after Chk_Cfg in Data_Exch")) {
        return;
    }
    if (!dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm in Data_Exch")) return;
    (void)to_data_exch(cf, "Chk_Cfg after Set_Prm in Data_Exch");
}

void dpc_diag_data_exch(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    char h[DPX_HEX_MAX];
    const char *what = "Slave_Diag in Data_Exch";
    if (!cf_start_up(cf) || !cf_diag(cf, d, &n)) return;
    uint8_t wd = dpx_watchdog_ms(cf, cf->prm, cf->prm_len) ? DP_DIAG2_WD_ON : 0u;
    if (!dpx_bits(cf, d, n, DP_DIAG_STATUS_1, (uint8_t)~DP_DIAG1_EXT_DIAG, 0,
                  "Station_status_1 (all but Ext_Diag)", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_2, (uint8_t)~DP_DIAG2_STAT_DIAG,
                  (uint8_t)(DP_DIAG2_ALWAYS_ONE | wd),
                  "Station_status_2 (always-one bit and WD_On as Set_Prm asked, all else 0)",
                  what) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_3, 0x7Fu, 0, "Station_status_3 reserved bits", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, "Master_Add", what) ||
        !ident_ok(cf, d, what)) {
        return;
    }
    uint32_t max = 0;
    if (gsd_key(cf->gsd, GSD_K_MAX_DIAG_DATA_LEN, &max)) {
        if (!cf_check(cf, n <= max, "%s: %zu octets, Max_Diag_Data_Len is %u", what, n,
                      (unsigned)max)) {
            return;
        }
    }
    cf_info(cf, "diagnosis %s", dpx_hex(d, n, h, sizeof h));
}
