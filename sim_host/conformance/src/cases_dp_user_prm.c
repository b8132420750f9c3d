/* dp.set_prm.user_prm: every user parameter the GSD defines (Ext_User_Prm_Data_Ref to an
 * ExtUserPrmData) with the values it allows, accepted through to Data_Exch, and values outside
 * its range or list, refused with Prm_Fault (EN 50170 vol. 2 DP "Send Parameter Data": invalid
 * User_Prm_Data give Prm_Fault; GSD specification: ExtUserPrmData ranges and lists).
 *
 * Only what is unambiguous is asked: a parameter with Changeable = 0 is sent with its default
 * alone (a master never sends another), and octets the GSD gives as constants are left as they
 * are. */
#include <stdio.h>
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_wire.h"

#define MAX_VALUES 4u
#define MAX_PARAMS 16u
#define LIST_SCAN 4096

typedef struct target {
    const gsd_prm_def_t *def;
    size_t at; /* its octet in the Set_Prm DU */
} target_t;

static void type_range(const gsd_prm_def_t *d, int64_t *lo, int64_t *hi)
{
    *lo = 0;
    switch (d->type) {
    case GSD_T_BIT: *hi = 1; break;
    case GSD_T_BIT_AREA: *hi = ((int64_t)1 << (d->bit_last - d->bit_first + 1)) - 1; break;
    case GSD_T_UNSIGNED8: *hi = 0xFF; break;
    case GSD_T_UNSIGNED16: *hi = 0xFFFF; break;
    case GSD_T_UNSIGNED32: *hi = 0xFFFFFFFF; break;
    case GSD_T_SIGNED8: *lo = -0x80; *hi = 0x7F; break;
    case GSD_T_SIGNED16: *lo = -0x8000; *hi = 0x7FFF; break;
    case GSD_T_SIGNED32: *lo = -0x80000000LL; *hi = 0x7FFFFFFF; break;
    default: *hi = -1; break;
    }
}

static bool is_allowed(const gsd_t *g, const gsd_prm_def_t *d, int64_t v)
{
    if (d->value_count == 0u) return v >= d->min && v <= d->max;
    for (size_t i = 0; i < d->value_count; i++) {
        if (g->values[d->value_first + i] == v) return true;
    }
    return false;
}

static size_t add_value(int64_t *out, size_t n, int64_t v)
{
    for (size_t i = 0; i < n; i++) {
        if (out[i] == v) return n;
    }
    if (n < MAX_VALUES) out[n++] = v;
    return n;
}

static size_t allowed_values(const gsd_t *g, const gsd_prm_def_t *d, int64_t *out)
{
    size_t n = add_value(out, 0, d->def);
    if (!d->changeable) return n;
    if (d->value_count > 0u) {
        for (size_t i = 0; i < d->value_count; i++) {
            n = add_value(out, n, g->values[d->value_first + i]);
        }
        return n;
    }
    n = add_value(out, n, d->min);
    n = add_value(out, n, d->max);
    return add_value(out, n, d->min + (d->max - d->min) / 2);
}

/* Values the type can carry but the definition does not allow: below and above the range, or
 * the first the list leaves out. */
static size_t refused_values(const gsd_t *g, const gsd_prm_def_t *d, int64_t *out)
{
    int64_t lo, hi;
    size_t n = 0;
    type_range(d, &lo, &hi);
    if (!d->changeable || hi < lo) return 0;
    if (d->min - 1 >= lo) n = add_value(out, n, d->min - 1);
    if (d->max + 1 <= hi) n = add_value(out, n, d->max + 1);
    if (d->value_count > 0u) {
        for (int64_t v = d->min; v <= d->max && v - d->min < LIST_SCAN; v++) {
            if (!is_allowed(g, d, v)) return add_value(out, n, v);
        }
    }
    return n;
}

static size_t targets(const cf_t *cf, target_t *out)
{
    const gsd_t *g = cf->gsd;
    int module = g->n_modules > 0u ? (cf->opt.module < 0 ? 0 : cf->opt.module) : GSD_GLOBAL - 1;
    size_t n = 0;
    for (size_t i = 0; i < g->n_refs && n < MAX_PARAMS; i++) {
        const gsd_ref_t *r = &g->refs[i];
        const gsd_prm_def_t *d = gsd_find_def(g, r->number);
        if (d == NULL || d->type == GSD_T_NONE) continue;
        size_t at = DP_PRM_LEN_STANDARD + r->offset;
        if (r->module != GSD_GLOBAL) {
            if (r->module != module) continue;
            at += gsd_part_len(g, GSD_GLOBAL);
        }
        if (at + gsd_def_octets(d) > cf->prm_len) continue;
        out[n++] = (target_t){d, at};
    }
    return n;
}

static bool try_value(cf_t *cf, const target_t *t, int64_t v, bool accept)
{
    uint8_t prm[sizeof cf->prm];
    uint8_t d[DPX_DIAG_MAX];
    size_t n;
    char what[CF_TEXT_MAX];
    memcpy(prm, cf->prm, cf->prm_len);
    if (!gsd_prm_put(t->def, v, prm, cf->prm_len, t->at)) return true;
    snprintf(what, sizeof what, "user parameter \"%s\" (Set_Prm octet %zu) = %lld, %s by the GSD",
             gsd_chars(cf->gsd, t->def->name), t->at, (long long)v,
             accept ? "allowed" : "not allowed");
    if (!dpx_set_prm(cf, prm, cf->prm_len, what)) return false;
    if (accept) {
        return dpx_chk_cfg(cf, cf->cfg, cf->cfg_len, what) && dpx_wait_ready(cf, d, &n, what) &&
               dpx_dx(cf, NULL, NULL, what);
    }
    return cf_diag(cf, d, &n) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_1, DP_DIAG1_PRM_FAULT, DP_DIAG1_PRM_FAULT,
                    "Prm_Fault", what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ, DP_DIAG2_PRM_REQ, "Prm_Req",
                   what);
}

void dpc_set_prm_user_prm(cf_t *cf)
{
    target_t t[MAX_PARAMS];
    int64_t v[MAX_VALUES];
    uint8_t d[DPX_DIAG_MAX];
    size_t diag_len, accepted = 0, refused = 0;
    size_t nt = targets(cf, t);
    if (nt == 0u) {
        cf_na(cf, "the GSD defines no user parameter (Ext_User_Prm_Data_Ref) for the configured "
                  "module: its constant User_Prm_Data is gsd.user_prm's");
        return;
    }
    if (!cf_reset(cf) || !cf_diag(cf, d, &diag_len)) return;
    for (size_t i = 0; i < nt; i++) {
        size_t n = allowed_values(cf->gsd, t[i].def, v);
        for (size_t k = 0; k < n; k++, accepted++) {
            if (!try_value(cf, &t[i], v[k], true)) return;
        }
        n = refused_values(cf->gsd, t[i].def, v);
        for (size_t k = 0; k < n; k++, refused++) {
            if (!try_value(cf, &t[i], v[k], false)) return;
        }
    }
    cf_info(cf, "%zu parameters: %zu allowed values accepted, %zu others refused", nt, accepted,
            refused);
}
