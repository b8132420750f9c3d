/* Chk_Cfg right and wrong, Get_Cfg in each state, and the user parameters the GSD defines,
 * judged by EN 50170 vol. 2 DP "Check Configuration Data", "Read Configuration Data", "Send
 * Parameter Data" and the GSD specification's ExtUserPrmData (docs/protocol.md §A3.2,
 * §A3.3). */
#include <stdio.h>
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_cfg.h"
#include "dp_slave/dp_wire.h"

static const uint8_t NO_DU[1] = {0};

static bool to_wait_cfg(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return cf_reset(cf) && cf_diag(cf, d, &n) &&
           dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm in Wait_Prm");
}

void dpc_chk_cfg_right(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    char h[DPX_HEX_MAX];
    if (!to_wait_cfg(cf)) return;
    if (!dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, "Chk_Cfg with the configured module") ||
        !dpx_wait_ready(cf, d, &n, "after Chk_Cfg") || !dpx_dx(cf, NULL, NULL, "after Chk_Cfg")) {
        return;
    }
    cf_info(cf, "Chk_Cfg %s accepted", dpx_hex(cf->cfg, cf->cfg_len, h, sizeof h));
}

/* A configuration no slave of this GSD can take: inputs of 16 words each beyond Max_Input_Len
 * (or the 244 octets DP carries). */
static size_t wrong_cfg(const cf_t *cf, uint8_t *out)
{
    uint32_t max = DP_IO_LEN_LIMIT;
    (void)gsd_key(cf->gsd, GSD_K_MAX_INPUT_LEN, &max);
    if (max > DP_IO_LEN_LIMIT) max = DP_IO_LEN_LIMIT;
    size_t n = max / 32u + 1u;
    memset(out, DP_CFG_GENERAL(DP_CFG_WORDS | DP_CFG_DIR_IN, 16u), n);
    return n;
}

void dpc_chk_cfg_wrong(cf_t *cf)
{
    uint8_t cfg[16];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    cf_reply_t r;
    const char *what = "Slave_Diag after a wrong Chk_Cfg";
    size_t len = wrong_cfg(cf, cfg);
    if (!to_wait_cfg(cf)) return;
    if (!cf_dp(cf, DP_SAP_CHK_CFG, cfg, len, &r)) return;
    dpx_note(cf, &r, "wrong Chk_Cfg");
    if (!cf_diag(cf, d, &n) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_1, DP_DIAG1_CFG_FAULT | DP_DIAG1_STATION_NOT_READY,
                  DP_DIAG1_CFG_FAULT | DP_DIAG1_STATION_NOT_READY,
                  "Cfg_Fault and Station_Not_Ready", what) ||
        !dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, DP_DIAG2_PRM_REQ,
                  "Prm_Req (back in Wait_Prm)", what)) {
        return;
    }
    if (!dpx_dx_refused(cf, "Data_Exchange after a wrong Chk_Cfg")) return;
    /* Not stuck: parameterised and configured again, it reaches Data_Exch. */
    if (!dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm after the Cfg_Fault")) return;
    (void)(dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, "the right Chk_Cfg after the Cfg_Fault") &&
           dpx_wait_ready(cf, d, &n, "after the right Chk_Cfg") &&
           dpx_dx(cf, NULL, NULL, "after the right Chk_Cfg"));
}

/* Get_Cfg answered with well-formed identifiers; in Data_Exch they describe the lengths the
 * slave exchanges. */
static bool get_cfg_in(cf_t *cf, const char *state, bool lengths)
{
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX], h[DPX_HEX_MAX];
    uint16_t in = 0, out = 0;
    if (!cf_dp(cf, DP_SAP_GET_CFG, NO_DU, 0, &r)) return false;
    if (!cf_check(cf, dpx_is_data(&r, &a) && a.du_len > 0u,
                  "Get_Cfg in %s: expected DL with the configuration, got %s", state,
                  cf_reply_text(&r, t, sizeof t)) ||
        !cf_check(cf, dp_cfg_io_lengths(a.du, a.du_len, &out, &in),
                  "Get_Cfg in %s: expected well-formed identifiers, got %s", state,
                  dpx_hex(a.du, a.du_len, h, sizeof h))) {
        return false;
    }
    if (!lengths) return true;
    if (!cf_check(cf, in == cf->in_len && out == cf->out_len,
                  "Get_Cfg in Data_Exch: expected %u input and %u output octets (Chk_Cfg), "
                  "got %u and %u (%s)", (unsigned)cf->in_len, (unsigned)cf->out_len,
                  (unsigned)in, (unsigned)out, dpx_hex(a.du, a.du_len, h, sizeof h))) {
        return false;
    }
    bool same = a.du_len == cf->cfg_len && memcmp(a.du, cf->cfg, a.du_len) == 0;
    cf_info(cf, "Get_Cfg in Data_Exch %s%s", dpx_hex(a.du, a.du_len, h, sizeof h),
            same ? " (= Chk_Cfg)" : " (differs from Chk_Cfg)");
    return true;
}

void dpc_get_cfg(cf_t *cf)
{
    if (!cf_reset(cf) || !get_cfg_in(cf, "Wait_Prm", false)) return;
    if (!dpx_set_prm(cf, cf->prm, cf->prm_len, "Set_Prm") || !get_cfg_in(cf, "Wait_Cfg", false)) {
        return;
    }
    if (!cf_start_up(cf)) return;
    (void)get_cfg_in(cf, "Data_Exch", true);
}
