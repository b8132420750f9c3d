/* The consistency check: the file against itself (lengths, references, defaults, the DP-V1
 * keys) and against what the protocol can carry. Each problem names its line. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gsd/gsd.h"

typedef struct sink {
    gsd_problem_t *out;
    size_t max;
    size_t n;
} sink_t;

__attribute__((format(printf, 4, 5))) static void add(sink_t *s, gsd_problem_code_t code,
                                                      uint32_t line, const char *fmt, ...)
{
    if (s->n < s->max) {
        gsd_problem_t *p = &s->out[s->n];
        p->code = code;
        p->line = line;
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(p->text, sizeof p->text, fmt, ap);
        va_end(ap);
    }
    s->n++;
}

static bool key_is(const gsd_t *g, gsd_key_t k, uint32_t v)
{
    uint32_t have;
    return gsd_key(g, k, &have) && have == v;
}

static void check_mandatory(const gsd_t *g, sink_t *s)
{
    static const gsd_key_t keys[] = {GSD_K_GSD_REVISION, GSD_K_IDENT_NUMBER,
                                     GSD_K_PROTOCOL_IDENT, GSD_K_STATION_TYPE,
                                     GSD_K_MIN_SLAVE_INTERVALL, GSD_K_MAX_DIAG_DATA_LEN};
    static const gsd_key_t modular[] = {GSD_K_MAX_MODULE, GSD_K_MAX_INPUT_LEN,
                                        GSD_K_MAX_OUTPUT_LEN, GSD_K_MAX_DATA_LEN};
    static const struct {
        gsd_str_key_t key;
        const char *name;
    } strs[] = {{GSD_S_VENDOR_NAME, "Vendor_Name"}, {GSD_S_MODEL_NAME, "Model_Name"},
                {GSD_S_REVISION, "Revision"}, {GSD_S_HARDWARE_RELEASE, "Hardware_Release"},
                {GSD_S_SOFTWARE_RELEASE, "Software_Release"}};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        if (!gsd_key(g, keys[i], NULL)) {
            add(s, GSD_P_MISSING, 0, "%s is missing", gsd_key_name(keys[i]));
        }
    }
    for (size_t i = 0; i < sizeof strs / sizeof strs[0]; i++) {
        if (g->str_line[strs[i].key] == 0u) add(s, GSD_P_MISSING, 0, "%s is missing",
                                                strs[i].name);
    }
    if (!key_is(g, GSD_K_MODULAR_STATION, 1u)) return;
    for (size_t i = 0; i < sizeof modular / sizeof modular[0]; i++) {
        if (!gsd_key(g, modular[i], NULL)) {
            add(s, GSD_P_MISSING, g->key_line[GSD_K_MODULAR_STATION],
                "Modular_Station = 1 without %s", gsd_key_name(modular[i]));
        }
    }
}

static void check_rates(const gsd_t *g, sink_t *s)
{
    bool any = false;
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        const gsd_rate_t *r = &g->rate[i];
        any = any || r->supp;
        if (r->supp && r->tsdr_line == 0u) {
            add(s, GSD_P_RATE, r->supp_line, "%s_supp = 1 without MaxTsdr_%s", gsd_rate_name(i),
                gsd_rate_name(i));
        }
        if (r->tsdr_line != 0u && r->max_tsdr < 11u) {
            add(s, GSD_P_RATE, r->tsdr_line, "MaxTsdr_%s = %u is below the least TSDR (11)",
                gsd_rate_name(i), (unsigned)r->max_tsdr);
        }
    }
    if (!any) add(s, GSD_P_RATE, 0, "no rate is supported (every <rate>_supp absent or 0)");
}

static void check_limit(const gsd_t *g, sink_t *s, gsd_key_t k, uint32_t lo, uint32_t hi)
{
    uint32_t v;
    if (gsd_key(g, k, &v) && (v < lo || v > hi)) {
        add(s, GSD_P_LIMIT, g->key_line[k], "%s = %u is outside %u..%u", gsd_key_name(k),
            (unsigned)v, (unsigned)lo, (unsigned)hi);
    }
}

static void check_limits(const gsd_t *g, sink_t *s)
{
    check_limit(g, s, GSD_K_MAX_DIAG_DATA_LEN, 6u, 244u);
    check_limit(g, s, GSD_K_MAX_INPUT_LEN, 0u, 244u);
    check_limit(g, s, GSD_K_MAX_OUTPUT_LEN, 0u, 244u);
    check_limit(g, s, GSD_K_MAX_DATA_LEN, 0u, 488u);
    check_limit(g, s, GSD_K_USER_PRM_DATA_LEN, 0u, GSD_MAX_USER_PRM);
    check_limit(g, s, GSD_K_MAX_USER_PRM_DATA_LEN, 0u, GSD_MAX_USER_PRM);
    check_limit(g, s, GSD_K_C1_MAX_DATA_LEN, 0u, 240u);
    check_limit(g, s, GSD_K_C2_MAX_DATA_LEN, 0u, 240u);
    if (key_is(g, GSD_K_MODULAR_STATION, 1u)) check_limit(g, s, GSD_K_MAX_MODULE, 1u, 255u);
}

static void check_module(const gsd_t *g, sink_t *s, size_t i)
{
    const gsd_module_t *m = &g->modules[i];
    const char *name = gsd_chars(g, m->name);
    uint16_t in = 0;
    uint16_t out = 0;
    uint32_t max;
    if (!gsd_module_io(g, i, &in, &out)) {
        add(s, GSD_P_MODULE, m->line, "module \"%s\": its identifiers are malformed (a length "
            "or manufacturer octet missing, or over 244 octets of data)", name);
        return;
    }
    if (gsd_key(g, GSD_K_MAX_INPUT_LEN, &max) && in > max) {
        add(s, GSD_P_MODULE, m->line, "module \"%s\": %u input octets, Max_Input_Len is %u",
            name, in, (unsigned)max);
    }
    if (gsd_key(g, GSD_K_MAX_OUTPUT_LEN, &max) && out > max) {
        add(s, GSD_P_MODULE, m->line, "module \"%s\": %u output octets, Max_Output_Len is %u",
            name, out, (unsigned)max);
    }
    if (gsd_key(g, GSD_K_MAX_DATA_LEN, &max) && (uint32_t)in + out > max) {
        add(s, GSD_P_MODULE, m->line, "module \"%s\": %u data octets, Max_Data_Len is %u",
            name, (unsigned)(in + out), (unsigned)max);
    }
    if (m->cfg_len > 244u) {
        add(s, GSD_P_MODULE, m->line, "module \"%s\": %u config octets, Chk_Cfg carries 244",
            name, m->cfg_len);
    }
}

static void check_modules(const gsd_t *g, sink_t *s)
{
    for (size_t i = 0; i < g->n_modules; i++) check_module(g, s, i);
    bool modular = key_is(g, GSD_K_MODULAR_STATION, 1u);
    if (modular && g->n_modules == 0u) {
        add(s, GSD_P_MODULES, g->key_line[GSD_K_MODULAR_STATION],
            "Modular_Station = 1 but no Module");
    } else if (!modular && g->n_modules != 1u) {
        add(s, GSD_P_MODULES, g->key_line[GSD_K_MODULAR_STATION],
            "a compact station (Modular_Station absent or 0) needs exactly one Module, "
            "there are %zu", g->n_modules);
    }
}

static const char *part_name(const gsd_t *g, int module, char *buf, size_t n)
{
    if (module == GSD_GLOBAL) return "User_Prm_Data_Len";
    (void)snprintf(buf, n, "module \"%s\" Ext_Module_Prm_Data_Len",
                   gsd_chars(g, g->modules[module].name));
    return buf;
}

static void check_consts(const gsd_t *g, sink_t *s)
{
    char buf[96];
    for (size_t i = 0; i < g->n_consts; i++) {
        const gsd_const_t *c = &g->consts[i];
        size_t len = gsd_part_len(g, c->module);
        if ((size_t)c->offset + c->len > len) {
            add(s, GSD_P_PRM_LEN, c->line, "Ext_User_Prm_Data_Const(%u) with %u octets "
                "reaches past %s = %zu", c->offset, c->len, part_name(g, c->module, buf,
                sizeof buf), len);
        }
    }
}

static uint8_t def_mask(const gsd_prm_def_t *d)
{
    if (d->type != GSD_T_BIT && d->type != GSD_T_BIT_AREA) return 0xFFu;
    return (uint8_t)(((1u << (d->bit_last - d->bit_first + 1u)) - 1u) << d->bit_first);
}

/* The Ref lines of one part against its length and against each other. */
static void check_refs(const gsd_t *g, sink_t *s, int module)
{
    char buf[96];
    uint8_t used[GSD_MAX_USER_PRM + 4u];
    memset(used, 0, sizeof used);
    size_t len = gsd_part_len(g, module);
    for (size_t i = 0; i < g->n_refs; i++) {
        const gsd_ref_t *r = &g->refs[i];
        if (r->module != module) continue;
        const gsd_prm_def_t *d = gsd_find_def(g, r->number);
        if (d == NULL) {
            add(s, GSD_P_PRM_REF, r->line, "Ext_User_Prm_Data_Ref(%u) = %u: no ExtUserPrmData "
                "%u", r->offset, r->number, r->number);
            continue;
        }
        size_t n = gsd_def_octets(d);
        if (r->offset + n > len) {
            add(s, GSD_P_PRM_LEN, r->line, "Ext_User_Prm_Data_Ref(%u) (%zu octets) reaches past "
                "%s = %zu", r->offset, n, part_name(g, module, buf, sizeof buf), len);
            continue;
        }
        for (size_t j = 0; j < n; j++) {
            if ((used[r->offset + j] & def_mask(d)) != 0u) {
                add(s, GSD_P_PRM_REF, r->line, "Ext_User_Prm_Data_Ref(%u) = %u overlaps the bits "
                    "of another Ref", r->offset, r->number);
                break;
            }
            used[r->offset + j] |= def_mask(d);
        }
    }
}

static void check_lengths(const gsd_t *g, sink_t *s)
{
    uint32_t len = 0;
    uint32_t max = 0;
    /* Without User_Prm_Data_Len the octets defined give the length (vendors' files rely on
     * it): only a length given can be too short or too long. */
    bool has_len = gsd_key(g, GSD_K_USER_PRM_DATA_LEN, &len);
    if (has_len && gsd_key(g, GSD_K_MAX_USER_PRM_DATA_LEN, &max) && len > max) {
        add(s, GSD_P_PRM_LEN, g->key_line[GSD_K_USER_PRM_DATA_LEN],
            "User_Prm_Data_Len = %u is more than Max_User_Prm_Data_Len = %u", (unsigned)len,
            (unsigned)max);
    }
    if (key_is(g, GSD_K_DPV1_SLAVE, 1u) && gsd_part_len(g, GSD_GLOBAL) < 3u) {
        add(s, GSD_P_PRM_LEN, g->key_line[GSD_K_DPV1_SLAVE], "DPV1_Slave = 1 needs at least "
            "3 octets of user parameters (DPV1_Status_1..3), there are %zu",
            gsd_part_len(g, GSD_GLOBAL));
    }
    for (size_t i = 0; i < g->n_modules; i++) {
        const gsd_module_t *m = &g->modules[i];
        if (m->prm_len != 0u && !m->has_ext_prm_len) {
            add(s, GSD_P_PRM_LEN, m->line, "module \"%s\" defines parameter octets without "
                "Ext_Module_Prm_Data_Len", gsd_chars(g, m->name));
        }
    }
}

static bool value_allowed(const gsd_t *g, const gsd_prm_def_t *d, int64_t v)
{
    if (d->value_count == 0u) return v >= d->min && v <= d->max;
    for (size_t i = 0; i < d->value_count; i++) {
        if (g->values[d->value_first + i] == v) return true;
    }
    return false;
}

static bool has_table(const gsd_t *g, int32_t number)
{
    for (size_t i = 0; i < g->n_tables; i++) {
        if ((int32_t)g->tables[i].number == number) return true;
    }
    return false;
}

static void check_defs(const gsd_t *g, sink_t *s)
{
    for (size_t i = 0; i < g->n_defs; i++) {
        const gsd_prm_def_t *d = &g->defs[i];
        if (d->value_count == 0u && d->min > d->max) {
            add(s, GSD_P_PRM_DEFAULT, d->type_line, "ExtUserPrmData %u: range %lld-%lld is "
                "empty", d->number, (long long)d->min, (long long)d->max);
        } else if (!value_allowed(g, d, d->def)) {
            add(s, GSD_P_PRM_DEFAULT, d->type_line, "ExtUserPrmData %u: default %lld is not "
                "one of its allowed values", d->number, (long long)d->def);
        }
        if (d->text_ref >= 0 && !has_table(g, d->text_ref)) {
            add(s, GSD_P_PRM_REF, d->line, "ExtUserPrmData %u: Prm_Text_Ref = %d, no PrmText "
                "%d", d->number, (int)d->text_ref, (int)d->text_ref);
        }
        for (size_t j = 0; j < i; j++) {
            if (g->defs[j].number == d->number) {
                add(s, GSD_P_PRM_REF, d->line, "ExtUserPrmData %u is defined twice (first on "
                    "line %u)", d->number, (unsigned)g->defs[j].line);
                break;
            }
        }
    }
    for (size_t i = 0; i < g->n_tables; i++) {
        for (size_t j = 0; j < i; j++) {
            if (g->tables[j].number == g->tables[i].number) {
                add(s, GSD_P_PRM_REF, g->tables[i].line, "PrmText %u is defined twice (first "
                    "on line %u)", g->tables[i].number, (unsigned)g->tables[j].line);
                break;
            }
        }
    }
}

static void check_dpv1(const gsd_t *g, sink_t *s)
{
    bool dpv1 = key_is(g, GSD_K_DPV1_SLAVE, 1u);
    uint32_t rev;
    if (!dpv1) {
        for (int k = GSD_K_DPV1_FIRST; k <= GSD_K_DPV1_LAST; k++) {
            if (g->key_line[k] != 0u) {
                add(s, GSD_P_DPV1, g->key_line[k], "%s without DPV1_Slave = 1",
                    gsd_key_name((gsd_key_t)k));
            }
        }
        return;
    }
    if (gsd_key(g, GSD_K_GSD_REVISION, &rev) && rev < 3u) {
        add(s, GSD_P_DPV1, g->key_line[GSD_K_DPV1_SLAVE], "DPV1_Slave = 1 needs GSD_Revision "
            "3 or later (it is %u)", (unsigned)rev);
    }
    static const struct {
        gsd_key_t supp;
        gsd_key_t needs;
    } needs[] = {
        {GSD_K_C1_READ_WRITE_SUPP, GSD_K_C1_MAX_DATA_LEN},
        {GSD_K_C2_READ_WRITE_SUPP, GSD_K_C2_MAX_DATA_LEN},
        {GSD_K_C2_READ_WRITE_SUPP, GSD_K_C2_RESPONSE_TIMEOUT},
        {GSD_K_C2_READ_WRITE_SUPP, GSD_K_C2_MAX_COUNT_CHANNELS},
        {GSD_K_C2_READ_WRITE_SUPP, GSD_K_MAX_INITIATE_PDU_LENGTH},
    };
    for (size_t i = 0; i < sizeof needs / sizeof needs[0]; i++) {
        if (key_is(g, needs[i].supp, 1u) && !gsd_key(g, needs[i].needs, NULL)) {
            add(s, GSD_P_DPV1, g->key_line[needs[i].supp], "%s = 1 without %s",
                gsd_key_name(needs[i].supp), gsd_key_name(needs[i].needs));
        }
    }
    if (key_is(g, GSD_K_C2_READ_WRITE_SUPP, 1u) && key_is(g, GSD_K_C2_MAX_COUNT_CHANNELS, 0u)) {
        add(s, GSD_P_DPV1, g->key_line[GSD_K_C2_MAX_COUNT_CHANNELS],
            "C2_Read_Write_supp = 1 with C2_Max_Count_Channels = 0");
    }
}

size_t gsd_check(const gsd_t *g, gsd_problem_t *out, size_t max)
{
    sink_t s = {.out = out, .max = out != NULL ? max : 0u, .n = 0};
    check_mandatory(g, &s);
    check_rates(g, &s);
    check_limits(g, &s);
    check_modules(g, &s);
    check_lengths(g, &s);
    check_consts(g, &s);
    check_refs(g, &s, GSD_GLOBAL);
    for (size_t i = 0; i < g->n_modules; i++) check_refs(g, &s, (int)i);
    check_defs(g, &s);
    check_dpv1(g, &s);
    for (size_t i = 0; i < g->n_notes; i++) {
        const gsd_note_t *n = &g->notes[i];
        if (n->kind == GSD_NOTE_REPEATED) {
            add(&s, GSD_P_REPEATED, n->line, "%s repeated (first on line %u)", n->keyword,
                (unsigned)n->first_line);
        }
    }
    return s.n;
}
