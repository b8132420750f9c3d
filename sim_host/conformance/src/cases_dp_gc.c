/* Global_Control Clear_Data, Sync/Unsync, Freeze/Unfreeze and groups, a second class-1 master
 * and a class-2 master, judged by EN 50170 vol. 2 DP "Global Control", "Read Inputs/Outputs"
 * and the lock rules of "Send Parameter Data" (docs/protocol.md §A3.1, §A3.5, §A3.6).
 *
 * The modes show in the diagnosis (Sync_Mode, Freeze_Mode). What they do to the data shows
 * only where the DUT's inputs follow its outputs (the card in process without an inverter):
 * dpx_echo_probe finds out, and the data checks run there. Clear_Data shows through Rd_Outp. */
#include <stdio.h>
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"

#define TRIES 3
#define NO_ECHO "the inputs do not follow the outputs here: only the diagnosis bits were judged"

static const uint8_t NO_DU[1] = {0};

static bool supported(const cf_t *cf, gsd_key_t k)
{
    uint32_t v = 0;
    return gsd_key(cf->gsd, k, &v) && v == 1u;
}

static bool mode_is(cf_t *cf, uint8_t bit, bool on, const char *name, const char *what)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, bit, on ? bit : 0u, name, what);
}

/* Rd_Outp of the class-2 master: the outputs into out; false (NA) when it gives none. */
static bool rd_outp(cf_t *cf, uint8_t *out, bool *served)
{
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    *served = false;
    if (!cf_dp_from(cf, cf->opt.class2, DP_SAP_MASTER, DP_SAP_RD_OUTP, NO_DU, 0, &r)) {
        return false;
    }
    if (!dpx_is_data(&r, &a) || a.du_len != cf->out_len) {
        cf_na(cf, "Clear_Data shows only through Rd_Outp, which answered %s",
              cf_reply_text(&r, t, sizeof t));
        return false;
    }
    memcpy(out, a.du, a.du_len);
    *served = true;
    return true;
}

static bool outputs_are(cf_t *cf, const uint8_t *want, const char *what)
{
    uint8_t got[DP_IO_LEN_LIMIT];
    char h1[DPX_HEX_MAX], h2[DPX_HEX_MAX];
    bool served;
    if (!rd_outp(cf, got, &served)) return false;
    return cf_check(cf, memcmp(got, want, cf->out_len) == 0, "%s: Rd_Outp expected %s, got %s",
                    what, dpx_hex(want, cf->out_len, h1, sizeof h1),
                    dpx_hex(got, cf->out_len, h2, sizeof h2));
}

/* Outputs p taken (two Data_Exchange) and read back. */
static bool outputs_set(cf_t *cf, const uint8_t *p)
{
    return dpx_dx(cf, p, NULL, "outputs for Clear_Data") &&
           dpx_dx(cf, p, NULL, "outputs for Clear_Data") &&
           outputs_are(cf, p, "before Clear_Data");
}

void dpc_global_control_clear(cf_t *cf)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    uint8_t p[DP_IO_LEN_LIMIT];
    if (cf->out_len == 0u) {
        cf_na(cf, "the configured module has no outputs to clear");
        return;
    }
    dpx_pattern(p, cf->out_len, 0x4Bu);
    if (!cf_start_up(cf) || !outputs_set(cf, p)) return;
    if (!dpx_gc(cf, cf->opt.master, DP_GC_CLEAR_DATA, 0) ||
        !outputs_are(cf, zeros, "after Global_Control Clear_Data")) {
        return;
    }
    /* Operate again: the slave is still in Data_Exch and takes outputs. */
    (void)(dpx_gc(cf, cf->opt.master, 0, 0) && dpx_dx(cf, p, NULL, "after Clear_Data") &&
           dpx_dx(cf, p, NULL, "after Clear_Data") && outputs_are(cf, p, "after Operate"));
}

/* Data_Exchange with pattern seed never/at last shows it in the inputs. */
static bool held(cf_t *cf, uint8_t seed, const char *what)
{
    uint8_t p[DP_IO_LEN_LIMIT];
    dpx_pattern(p, cf->out_len, seed);
    int got = dpx_dx_until(cf, p, p, TRIES, what);
    return got >= 0 && cf_check(cf, got == 0, "%s: expected the inputs to stay, they followed "
                                              "the new outputs at exchange %d", what, got);
}

static bool follows(cf_t *cf, uint8_t seed, const char *what)
{
    uint8_t p[DP_IO_LEN_LIMIT];
    dpx_pattern(p, cf->out_len, seed);
    int got = dpx_dx_until(cf, p, p, TRIES, what);
    return got >= 0 && cf_check(cf, got > 0, "%s: expected the inputs to follow the outputs "
                                             "within %d exchanges, they did not", what, TRIES);
}

void dpc_global_control_sync(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    if (!supported(cf, GSD_K_SYNC_MODE_SUPP)) {
        cf_na(cf, "the GSD does not claim Sync_Mode_supp");
        return;
    }
    size_t len = dpx_prm_with(cf, DP_PRM_SYNC_REQ, 0, prm);
    if (!dpx_start_up_with(cf, prm, len) ||
        !mode_is(cf, DP_DIAG2_SYNC_MODE, false, "Sync_Mode", "before Sync")) {
        return;
    }
    int echo = dpx_echo_probe(cf);
    if (echo < 0 || !dpx_gc(cf, cf->opt.master, DP_GC_SYNC, 0) ||
        !mode_is(cf, DP_DIAG2_SYNC_MODE, true, "Sync_Mode", "after Sync")) {
        return;
    }
    if (echo == 1) {
        if (!held(cf, 0x13u, "outputs after Sync (held until the next Sync)") ||
            !dpx_gc(cf, cf->opt.master, DP_GC_SYNC, 0) ||
            !follows(cf, 0x13u, "outputs after the second Sync")) {
            return;
        }
    }
    if (!dpx_gc(cf, cf->opt.master, DP_GC_UNSYNC, 0) ||
        !mode_is(cf, DP_DIAG2_SYNC_MODE, false, "Sync_Mode", "after Unsync")) {
        return;
    }
    if (echo == 1) {
        (void)follows(cf, 0x27u, "outputs after Unsync");
    } else {
        cf_info(cf, NO_ECHO);
    }
}

void dpc_global_control_freeze(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm], c[DP_IO_LEN_LIMIT];
    if (!supported(cf, GSD_K_FREEZE_MODE_SUPP)) {
        cf_na(cf, "the GSD does not claim Freeze_Mode_supp");
        return;
    }
    size_t len = dpx_prm_with(cf, DP_PRM_FREEZE_REQ, 0, prm);
    if (!dpx_start_up_with(cf, prm, len) ||
        !mode_is(cf, DP_DIAG2_FREEZE_MODE, false, "Freeze_Mode", "before Freeze")) {
        return;
    }
    int echo = dpx_echo_probe(cf);
    if (echo < 0 || !dpx_gc(cf, cf->opt.master, DP_GC_FREEZE, 0) ||
        !mode_is(cf, DP_DIAG2_FREEZE_MODE, true, "Freeze_Mode", "after Freeze")) {
        return;
    }
    if (echo == 1) {
        dpx_pattern(c, cf->out_len, 0x13u);
        if (!held(cf, 0x13u, "inputs after Freeze (frozen until the next Freeze)") ||
            !dpx_gc(cf, cf->opt.master, DP_GC_FREEZE, 0)) {
            return;
        }
        int got = dpx_dx_until(cf, NULL, c, 1, "inputs after the second Freeze");
        if (got < 0 || !cf_check(cf, got == 1, "inputs after the second Freeze: expected the "
                                               "outputs of before it, they were not")) {
            return;
        }
    }
    if (!dpx_gc(cf, cf->opt.master, DP_GC_UNFREEZE, 0) ||
        !mode_is(cf, DP_DIAG2_FREEZE_MODE, false, "Freeze_Mode", "after Unfreeze")) {
        return;
    }
    if (echo == 1) {
        (void)follows(cf, 0x27u, "inputs after Unfreeze");
    } else {
        cf_info(cf, NO_ECHO);
    }
}

/* Groups by a mode: a command for another group leaves it, one for its own group sets it. */
static void groups_by_mode(cf_t *cf, uint8_t cmd, uint8_t uncmd, uint8_t bit, const char *name)
{
    char what[CF_TEXT_MAX];
    snprintf(what, sizeof what, "%s to group 2 (Group_Ident 0x01)", name);
    if (!dpx_gc(cf, cf->opt.master, cmd, 0x02) || !mode_is(cf, bit, false, name, what)) return;
    snprintf(what, sizeof what, "%s to groups 1 and 8 (Group_Ident 0x01)", name);
    if (!dpx_gc(cf, cf->opt.master, cmd, 0x81) || !mode_is(cf, bit, true, name, what)) return;
    snprintf(what, sizeof what, "the opposite of %s to groups 2..8", name);
    if (!dpx_gc(cf, cf->opt.master, uncmd, 0xFE) || !mode_is(cf, bit, true, name, what)) return;
    cf_info(cf, "judged by %s", name);
}

static void groups_by_clear(cf_t *cf)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    uint8_t p[DP_IO_LEN_LIMIT];
    if (cf->out_len == 0u) {
        cf_na(cf, "no Sync or Freeze claimed and no outputs for Clear_Data");
        return;
    }
    dpx_pattern(p, cf->out_len, 0x4Bu);
    if (!outputs_set(cf, p) || !dpx_gc(cf, cf->opt.master, DP_GC_CLEAR_DATA, 0x02) ||
        !outputs_are(cf, p, "Clear_Data to group 2 (Group_Ident 0x01)")) {
        return;
    }
    if (!dpx_gc(cf, cf->opt.master, DP_GC_CLEAR_DATA, 0x01)) return;
    (void)outputs_are(cf, zeros, "Clear_Data to group 1 (Group_Ident 0x01)");
}

void dpc_global_control_groups(cf_t *cf)
{
    uint8_t prm[sizeof cf->prm];
    bool sync = supported(cf, GSD_K_SYNC_MODE_SUPP);
    bool freeze = supported(cf, GSD_K_FREEZE_MODE_SUPP);
    uint8_t req = sync ? DP_PRM_SYNC_REQ : freeze ? DP_PRM_FREEZE_REQ : 0u;
    size_t len = dpx_prm_with(cf, req, 0, prm);
    prm[DP_PRM_GROUP_IDENT] = 0x01;
    if (!dpx_start_up_with(cf, prm, len)) return;
    if (sync) {
        groups_by_mode(cf, DP_GC_SYNC, DP_GC_UNSYNC, DP_DIAG2_SYNC_MODE, "Sync");
    } else if (freeze) {
        groups_by_mode(cf, DP_GC_FREEZE, DP_GC_UNFREEZE, DP_DIAG2_FREEZE_MODE, "Freeze");
    } else {
        groups_by_clear(cf);
    }
}

static bool read_as(cf_t *cf, uint8_t sa, uint8_t sap, uint16_t want, const char *name)
{
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    /* The owner polls between the reads: its watchdog runs on its own telegrams only. */
    if (!dpx_dx(cf, NULL, NULL, "the owner between the class-2 reads") ||
        !cf_dp_from(cf, sa, DP_SAP_MASTER, sap, NO_DU, 0, &r)) {
        return false;
    }
    bool data = dpx_is_data(&r, &a);
    bool len_ok = data && (want == 0xFFFFu ? a.du_len > 0u : a.du_len == want);
    return cf_check(cf, len_ok,
                    "%s of the class-2 master: expected DL with %s octets, got %s", name,
                    want == 0xFFFFu ? "the configuration's" : "the module's",
                    cf_reply_text(&r, t, sizeof t));
}

static bool owner_keeps(cf_t *cf, const char *what)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    return dpx_dx(cf, NULL, NULL, what) && cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, "Master_Add (the owner)",
                    what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, 0, "Prm_Req", what);
}

void dpc_class2_read(cf_t *cf)
{
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    const uint8_t c2 = cf->opt.class2;
    if (!cf_start_up(cf) || !dpx_diag_from(cf, c2, d, &n, "Slave_Diag of the class-2 master") ||
        !dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, "Master_Add (the owner)",
                  "Slave_Diag of the class-2 master")) {
        return;
    }
    if (!read_as(cf, c2, DP_SAP_GET_CFG, 0xFFFFu, "Get_Cfg") ||
        !read_as(cf, c2, DP_SAP_RD_INP, cf->in_len, "Rd_Inp") ||
        !read_as(cf, c2, DP_SAP_RD_OUTP, cf->out_len, "Rd_Outp")) {
        return;
    }
    (void)owner_keeps(cf, "the owner after the class-2 master's reads");
}

void dpc_second_master(cf_t *cf)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    cf_reply_t r;
    const uint8_t m2 = cf->opt.master_2;
    if (!cf_start_up(cf) || !dpx_diag_from(cf, m2, d, &n, "Slave_Diag of the second master") ||
        !dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, cf->opt.master, "Master_Add (the owner)",
                  "Slave_Diag of the second master")) {
        return;
    }
    if (!dpx_dx(cf, NULL, NULL, "the owner between the second master's requests") ||
        !cf_dp_from(cf, m2, DP_SAP_MASTER, DP_SAP_CHK_CFG, cf->cfg, cf->cfg_len, &r) ||
        !dpx_expect_rs(cf, &r, "Chk_Cfg of the second master while locked")) {
        return;
    }
    if (!dpx_dx(cf, NULL, NULL, "the owner between the second master's requests") ||
        !cf_request(cf, m2, FDL_REQ_SRD_HIGH, -1, -1, zeros, cf->out_len, &r) ||
        !dpx_expect_rs(cf, &r, "Data_Exchange of the second master while locked")) {
        return;
    }
    (void)owner_keeps(cf, "the owner after the second master's requests");
}
