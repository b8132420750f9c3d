/* The GSD group: the file is consistent, and the slave on the wire is what its GSD says (ident,
 * diagnosis length, I/O lengths, default parameters, every module). Also the watched start-up
 * and the telegram helpers the FDL group shares (cf_cases_fdl.h). */
#include <stdio.h>
#include <string.h>

#include "conformance/cf_cases_fdl.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"

/* Polls of Slave_Diag a slave may need after Chk_Cfg before it reports Data_Exch without
 * Stat_Diag (which asks the master to poll the diagnosis again), and the pause between them. */
#define GF_READY_POLLS 10u
#define GF_READY_POLL_MS 10u

/* ---- helpers shared with cases_fdl.c ------------------------------------------------------ */

const char *cf_gf_hex(const uint8_t *p, size_t len, char *buf, size_t cap)
{
    size_t at = 0;
    if (cap == 0u) return buf;
    buf[0] = '\0';
    for (size_t i = 0; i < len; i++) {
        if (at + 8u > cap) { /* " XX", then room for " ..." */
            (void)snprintf(buf + at, cap - at, i == 0u ? "..." : " ...");
            break;
        }
        at += (size_t)snprintf(buf + at, cap - at, i == 0u ? "%02X" : " %02X", p[i]);
    }
    return buf;
}

uint8_t cf_gf_fc(uint8_t code, bool fcv, bool fcb)
{
    return (uint8_t)(FDL_FC_REQUEST | (fcb ? FDL_FC_FCB : 0u) | (fcv ? FDL_FC_FCV : 0u) |
                     (code & FDL_FC_CODE_MASK));
}

uint8_t cf_gf_next_fc(cf_gf_fcb_t *s, uint8_t code)
{
    if (!s->started) {
        s->started = true;
        s->fcb = true;
        return cf_gf_fc(code, false, true);
    }
    s->fcb = !s->fcb;
    return cf_gf_fc(code, true, s->fcb);
}

void cf_gf_setup_default(const cf_t *cf, cf_gf_setup_t *s)
{
    memset(s, 0, sizeof *s);
    memcpy(s->prm, cf->prm, cf->prm_len);
    s->prm_len = cf->prm_len;
    memcpy(s->cfg, cf->cfg, cf->cfg_len);
    s->cfg_len = cf->cfg_len;
    s->in_len = cf->in_len;
    s->out_len = cf->out_len;
    (void)snprintf(s->name, sizeof s->name, "the configured module");
}

bool cf_gf_setup_module(const cf_t *cf, size_t m, cf_gf_setup_t *s, char *why, size_t n)
{
    const gsd_t *g = cf->gsd;
    memset(s, 0, sizeof *s);
    (void)snprintf(s->name, sizeof s->name, "module \"%s\"",
                   gsd_chars(g, g->modules[m].name));
    const gsd_module_t *mod = &g->modules[m];
    if (mod->cfg_len == 0u || mod->cfg_len > CF_GF_DU_MAX ||
        !gsd_module_io(g, m, &s->in_len, &s->out_len)) {
        (void)snprintf(why, n, "%s: its identifiers are empty or malformed", s->name);
        return false;
    }
    memcpy(s->cfg, gsd_module_cfg(g, m), mod->cfg_len);
    s->cfg_len = (uint8_t)mod->cfg_len;
    /* cf->prm carries the standard octets and the global part as the run's master sends them
     * (DPV1_Enable set where the GSD claims DP-V1); only the module's part differs. */
    uint8_t user[GSD_MAX_USER_PRM];
    int len = gsd_default_prm(g, &m, 1, user, sizeof user);
    size_t global = gsd_part_len(g, GSD_GLOBAL);
    size_t head = DP_PRM_LEN_STANDARD + global;
    if (len < 0 || (size_t)len < global || head > cf->prm_len ||
        head + ((size_t)len - global) > CF_GF_DU_MAX) {
        (void)snprintf(why, n, "%s: its Set_Prm does not fit into 244 octets", s->name);
        return false;
    }
    memcpy(s->prm, cf->prm, head);
    memcpy(s->prm + head, user + global, (size_t)len - global);
    s->prm_len = (uint8_t)(head + ((size_t)len - global));
    return true;
}

bool cf_gf_ack(const cf_reply_t *r)
{
    return cf_is_sc(r) || (r->len == FDL_SD1_LEN && r->octets[0] == FDL_SD1 &&
                           cf_rsp_code(r) == (int)FDL_RSP_NR);
}

static bool addressed_back(const cf_t *cf, const cf_answer_t *a)
{
    return (a->da & FDL_ADDR_MASK) == cf->opt.master &&
           (a->sa & FDL_ADDR_MASK) == cf->opt.address &&
           (a->fc & (FDL_FC_REQUEST | FDL_FC_STATION_MASK | 0x80u)) == 0u;
}

bool cf_gf_diag(cf_t *cf, uint8_t *diag, size_t *len, char *why, size_t n)
{
    cf_reply_t r;
    char t[96];
    if (!cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r)) {
        (void)snprintf(why, n, "the link failed");
        return false;
    }
    cf_answer_t a;
    int code = cf_rsp_code(&r);
    if (!cf_answer(&r, &a) || !a.saps || a.dsap != DP_SAP_MASTER ||
        a.ssap != DP_SAP_SLAVE_DIAG || !addressed_back(cf, &a) ||
        (code != (int)FDL_RSP_DL && code != (int)FDL_RSP_DH) || a.du_len < DP_DIAG_STD_LEN) {
        (void)snprintf(why, n, "Slave_Diag: expected DL with SAPs 62/60 and 6 or more octets, "
                       "got %s", cf_reply_text(&r, t, sizeof t));
        return false;
    }
    memcpy(diag, a.du, a.du_len);
    *len = a.du_len;
    return true;
}

bool cf_gf_dx_ok(const cf_t *cf, const cf_reply_t *r, uint16_t in_len, char *why, size_t n)
{
    char t[96];
    cf_answer_t a;
    int code = cf_rsp_code(r);
    bool ok;
    if (in_len == 0u) {
        ok = cf_is_sc(r) || (r->len == FDL_SD1_LEN && (code == (int)FDL_RSP_DL ||
                                                      code == (int)FDL_RSP_DH ||
                                                      code == (int)FDL_RSP_NR));
    } else {
        ok = cf_answer(r, &a) && !a.saps && addressed_back(cf, &a) &&
             (code == (int)FDL_RSP_DL || code == (int)FDL_RSP_DH) && a.du_len == in_len;
    }
    if (!ok) {
        (void)snprintf(why, n, "Data_Exchange: expected DL with %u input octets, got %s",
                       (unsigned)in_len, cf_reply_text(r, t, sizeof t));
    }
    return ok;
}

bool cf_gf_in_data_exch(const uint8_t *diag, size_t len)
{
    return len >= DP_DIAG_STD_LEN &&
           (diag[DP_DIAG_STATUS_1] & (DP_DIAG1_STATION_NOT_READY | DP_DIAG1_CFG_FAULT |
                                      DP_DIAG1_PRM_FAULT)) == 0u &&
           (diag[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ) == 0u;
}

/* One Slave_Diag of the watched start-up, kept in t. */
static bool trace_diag(cf_t *cf, cf_gf_trace_t *t, const char *step, char *why, size_t n)
{
    uint8_t d[CF_GF_DU_MAX];
    size_t len = 0;
    if (!cf_gf_diag(cf, d, &len, why, n)) return false;
    if (t->n_diag < CF_GF_MAX_DIAGS) {
        t->diag_len[t->n_diag] = (uint8_t)len;
        t->ident[t->n_diag] = (uint16_t)((d[DP_DIAG_IDENT_HIGH] << 8) | d[DP_DIAG_IDENT_LOW]);
        t->step[t->n_diag] = step;
        t->n_diag++;
    }
    memcpy(t->last, d, len);
    t->last_len = (uint8_t)len;
    return true;
}

/* A service answered with SC (or SD1 NR). */
static bool acked(cf_t *cf, uint8_t sap, const uint8_t *du, size_t len, const char *what,
                  char *why, size_t n)
{
    cf_reply_t r;
    char t[96];
    if (!cf_dp(cf, sap, du, len, &r)) {
        (void)snprintf(why, n, "the link failed");
        return false;
    }
    if (!cf_gf_ack(&r)) {
        (void)snprintf(why, n, "%s: expected SC, got %s", what, cf_reply_text(&r, t, sizeof t));
        return false;
    }
    return true;
}

static bool wait_ready(cf_t *cf, cf_gf_trace_t *t, char *why, size_t n)
{
    cf_gf_trace_t *tr = t;
    for (unsigned i = 0; i < GF_READY_POLLS; i++) {
        if (!trace_diag(cf, tr, "after Chk_Cfg", why, n)) return false;
        if (cf_gf_in_data_exch(tr->last, tr->last_len) &&
            (tr->last[DP_DIAG_STATUS_2] & DP_DIAG2_STAT_DIAG) == 0u) {
            return true;
        }
        if ((tr->last[DP_DIAG_STATUS_1] & (DP_DIAG1_CFG_FAULT | DP_DIAG1_PRM_FAULT)) != 0u ||
            (tr->last[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ) != 0u) {
            break; /* refused: polling again changes nothing */
        }
        if (!cf_pause_ms(cf, GF_READY_POLL_MS)) {
            (void)snprintf(why, n, "the link failed");
            return false;
        }
    }
    char h[64];
    (void)snprintf(why, n, "Chk_Cfg not accepted: the diagnosis %s is not Data_Exch",
                   cf_gf_hex(tr->last, tr->last_len, h, sizeof h));
    return false;
}

bool cf_gf_bring_up(cf_t *cf, const cf_gf_setup_t *s, bool reset, cf_gf_trace_t *t, char *why,
                    size_t n)
{
    char h[64], h2[64];
    cf_gf_trace_t local;
    if (t == NULL) t = &local;
    memset(t, 0, sizeof *t);
    if (reset && !cf_reset(cf)) {
        (void)snprintf(why, n, "the reset to Wait_Prm failed");
        return false;
    }
    if (!trace_diag(cf, t, "in Wait_Prm", why, n) ||
        !acked(cf, DP_SAP_SET_PRM, s->prm, s->prm_len, "Set_Prm", why, n) ||
        !trace_diag(cf, t, "after Set_Prm", why, n)) {
        return false;
    }
    if ((t->last[DP_DIAG_STATUS_1] & DP_DIAG1_PRM_FAULT) != 0u) {
        (void)snprintf(why, n, "Set_Prm %s refused: Prm_Fault in the diagnosis %s",
                       cf_gf_hex(s->prm, s->prm_len, h, sizeof h),
                       cf_gf_hex(t->last, t->last_len, h2, sizeof h2));
        return false;
    }
    if (!acked(cf, DP_SAP_CHK_CFG, s->cfg, s->cfg_len, "Chk_Cfg", why, n) ||
        !wait_ready(cf, t, why, n)) {
        return false;
    }
    uint8_t out[CF_GF_DU_MAX] = {0};
    cf_reply_t r;
    if (!cf_data_exchange(cf, out, s->out_len, &r)) {
        (void)snprintf(why, n, "the link failed");
        return false;
    }
    t->dx = r;
    return cf_gf_dx_ok(cf, &r, s->in_len, why, n);
}

/* ---- the cases ---------------------------------------------------------------------------- */

static void gsd_check_case(cf_t *cf)
{
    gsd_problem_t p[3];
    size_t n = gsd_check(cf->gsd, p, 3);
    if (n == 0u) return;
    char list[CF_TEXT_MAX] = "";
    size_t at = 0;
    for (size_t i = 0; i < n && i < 3u && at < sizeof list; i++) {
        at += (size_t)snprintf(list + at, sizeof list - at, "%sline %u: %s", i ? "; " : "",
                               (unsigned)p[i].line, p[i].text);
    }
    (void)cf_fail(cf, "expected a consistent GSD, found %zu problem(s): %s", n, list);
}

static void gsd_ident_case(cf_t *cf)
{
    cf_gf_setup_t s;
    cf_gf_trace_t t;
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, &s);
    /* The idents first: a slave with another ident refuses the GSD's Set_Prm, and the ident
     * is the better reason. */
    bool up = cf_gf_bring_up(cf, &s, true, &t, why, sizeof why);
    for (uint8_t i = 0; i < t.n_diag; i++) {
        if (!cf_check(cf, t.ident[i] == cf->ident,
                      "diagnosis %s: expected Ident_Number 0x%04X (GSD), got 0x%04X",
                      t.step[i], cf->ident, t.ident[i])) {
            return;
        }
    }
    if (!up) (void)cf_fail(cf, "start-up: %s", why);
}

static void gsd_diag_len_case(cf_t *cf)
{
    uint32_t max = 0;
    if (!gsd_key(cf->gsd, GSD_K_MAX_DIAG_DATA_LEN, &max)) {
        return (void)cf_fail(cf, "the GSD gives no Max_Diag_Data_Len (mandatory)");
    }
    cf_gf_setup_t s;
    cf_gf_trace_t t;
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, &s);
    bool up = cf_gf_bring_up(cf, &s, true, &t, why, sizeof why);
    char why2[CF_TEXT_MAX];
    if (up && !trace_diag(cf, &t, "in Data_Exch", why2, sizeof why2)) {
        return (void)cf_fail(cf, "%s", why2);
    }
    for (uint8_t i = 0; i < t.n_diag; i++) {
        if (!cf_check(cf, t.diag_len[i] >= DP_DIAG_STD_LEN && t.diag_len[i] <= max,
                      "diagnosis %s: expected 6..%u octets (Max_Diag_Data_Len), got %u",
                      t.step[i], (unsigned)max, t.diag_len[i])) {
            return;
        }
    }
    if (!up) return (void)cf_fail(cf, "start-up: %s", why);
    unsigned lo = 255u, hi = 0u;
    for (uint8_t i = 0; i < t.n_diag; i++) {
        lo = t.diag_len[i] < lo ? t.diag_len[i] : lo;
        hi = t.diag_len[i] > hi ? t.diag_len[i] : hi;
    }
    cf_info(cf, "%u diagnoses of %u..%u octets, Max_Diag_Data_Len %u", t.n_diag, lo, hi,
            (unsigned)max);
}

static void gsd_io_len_case(cf_t *cf)
{
    cf_gf_setup_t s;
    cf_gf_trace_t t;
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, &s);
    if (!cf_gf_bring_up(cf, &s, true, &t, why, sizeof why)) {
        return (void)cf_fail(cf, "start-up: %s", why);
    }
    /* A second exchange with other output values: the slave keeps taking the length. */
    uint8_t out[CF_GF_DU_MAX];
    memset(out, 0, sizeof out);
    cf_reply_t r;
    if (!cf_data_exchange(cf, out, s.out_len, &r)) return;
    if (!cf_gf_dx_ok(cf, &r, s.in_len, why, sizeof why)) {
        return (void)cf_fail(cf, "second %s", why);
    }
    if (!trace_diag(cf, &t, "in Data_Exch", why, sizeof why)) {
        return (void)cf_fail(cf, "%s", why);
    }
    char h[64];
    (void)cf_check(cf, cf_gf_in_data_exch(t.last, t.last_len),
                   "after Data_Exchange with %u output octets: expected Data_Exch, diagnosis %s",
                   (unsigned)s.out_len, cf_gf_hex(t.last, t.last_len, h, sizeof h));
    cf_info(cf, "%u output octets, %u input octets", (unsigned)s.out_len, (unsigned)s.in_len);
}

static void gsd_user_prm_case(cf_t *cf)
{
    cf_gf_setup_t s;
    cf_gf_trace_t t;
    char why[CF_TEXT_MAX];
    cf_gf_setup_default(cf, &s);
    if (!cf_gf_bring_up(cf, &s, true, &t, why, sizeof why)) {
        (void)cf_fail(cf, "default Set_Prm from the GSD: %s", why);
    }
}

/* Every module alone, after one reset: Set_Prm with its parameters, Chk_Cfg with its
 * identifiers, Data_Exchange with its lengths. All are tried; the reason lists the refused. */
static void gsd_modules_case(cf_t *cf)
{
    const gsd_t *g = cf->gsd;
    uint32_t max_module = 1;
    if (gsd_key(g, GSD_K_MAX_MODULE, &max_module) && max_module == 0u) {
        return (void)cf_na(cf, "Max_Module = 0: no module may be configured alone");
    }
    if (g->n_modules == 0u) return (void)cf_na(cf, "the GSD has no Module");
    if (!cf_reset(cf)) return;
    char bad[CF_TEXT_MAX] = "";
    size_t at = 0, n_bad = 0;
    for (size_t m = 0; m < g->n_modules && !cf->link_failed; m++) {
        cf_gf_setup_t s;
        char why[CF_TEXT_MAX];
        if (cf_gf_setup_module(cf, m, &s, why, sizeof why) &&
            cf_gf_bring_up(cf, &s, false, NULL, why, sizeof why)) {
            continue;
        }
        if (n_bad++ == 0u && at < sizeof bad) {
            at += (size_t)snprintf(bad + at, sizeof bad - at, "%s", why);
        } else if (at < sizeof bad) {
            at += (size_t)snprintf(bad + at, sizeof bad - at, "; %s", s.name);
        }
    }
    if (cf->link_failed) return;
    if (n_bad > 0u) {
        return (void)cf_fail(cf, "%zu of %zu modules refused alone: %s", n_bad, g->n_modules,
                             bad);
    }
    cf_info(cf, "%zu modules, each accepted alone", g->n_modules);
}

#define GSD_GROUP "GSD"

const cf_case_t cf_cases_gsd[] = {
    {"gsd.check", GSD_GROUP, "GSD specification (PI 2.122): keywords, limits, consistency",
     "the GSD file is consistent in itself and with the protocol's limits", gsd_check_case},
    {"gsd.ident", GSD_GROUP, "IEC 61158-6-3 Slave_Diag (Ident_Number); GSD Ident_Number",
     "every diagnosis of a start-up carries the GSD's Ident_Number", gsd_ident_case},
    {"gsd.diag_len", GSD_GROUP,
     "IEC 61158-6-3 Slave_Diag (6..244 octets); GSD Max_Diag_Data_Len",
     "every diagnosis in start-up and Data_Exch has 6..Max_Diag_Data_Len octets",
     gsd_diag_len_case},
    {"gsd.io_len", GSD_GROUP, "IEC 61158-6-3 Data_Exchange; GSD Module (Chk_Cfg identifiers)",
     "Data_Exchange takes the module's output length and answers its input length",
     gsd_io_len_case},
    {"gsd.user_prm", GSD_GROUP,
     "IEC 61158-6-3 Set_Prm (Prm_Fault); GSD User_Prm_Data, Ext_User_Prm_Data defaults",
     "the Set_Prm a master builds from the GSD's defaults is accepted", gsd_user_prm_case},
    {"gsd.modules", GSD_GROUP, "IEC 61158-6-3 Chk_Cfg (Cfg_Fault); GSD Module, Max_Module",
     "each module of the GSD is accepted as the whole configuration", gsd_modules_case},
};

const size_t cf_cases_gsd_count = sizeof cf_cases_gsd / sizeof cf_cases_gsd[0];
