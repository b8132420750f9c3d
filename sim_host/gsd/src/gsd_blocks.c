/* The blocks: Module ... EndModule, PrmText ... EndPrmText, ExtUserPrmData ...
 * EndExtUserPrmData, and the user parameter keywords found both outside and in modules. */
#include <string.h>

#include "gsd_internal.h"

int gsd_read_octets(gsd_parser_t *p, const gsd_stmt_t *st, const char **s, uint8_t *dst,
                    size_t cap, size_t *n)
{
    *n = 0;
    for (;;) {
        int64_t v = 0;
        if (!gsd_read_number(p, st, s, 0, 255, &v)) return 0;
        if (*n == cap) return -1;
        dst[(*n)++] = (uint8_t)v;
        if (**s != ',') return 1;
        (*s)++;
        gsd_skip_blanks(s);
    }
}

/* The number in the parentheses, alone, in lo..hi. */
static bool arg_number(gsd_parser_t *p, const gsd_stmt_t *st, int64_t lo, int64_t hi,
                       int64_t *v)
{
    if (st->arg == NULL) return gsd_fail(p, st->line, "%s needs '(number)'", st->kw);
    const char *s = st->arg;
    gsd_skip_blanks(&s);
    if (!gsd_read_number(p, st, &s, lo, hi, v)) return false;
    if (s != st->arg + st->arg_len) {
        return gsd_fail(p, st->line, "%s: '(%.*s)' is not one number", st->kw,
                        (int)st->arg_len, st->arg);
    }
    return true;
}

static gsd_module_t *open_module(gsd_parser_t *p)
{
    return &p->g->modules[p->g->n_modules - 1u];
}

/* Ext_User_Prm_Data_Const(offset) = octets into the global image or the open module's. */
static bool prm_const(gsd_parser_t *p, const gsd_stmt_t *st, int module)
{
    gsd_t *g = p->g;
    int64_t off = 0;
    if (!arg_number(p, st, 0, GSD_MAX_USER_PRM - 1, &off)) return false;
    if (!st->eq) return gsd_fail(p, st->line, "%s needs '= value'", st->kw);
    if (g->n_consts == GSD_MAX_CONSTS) {
        return gsd_fail(p, st->line, "more than %u Ext_User_Prm_Data_Const (GSD_MAX_CONSTS)",
                        GSD_MAX_CONSTS);
    }
    uint8_t octets[GSD_MAX_USER_PRM];
    size_t n;
    const char *s = st->val;
    int r = gsd_read_octets(p, st, &s, octets, GSD_MAX_USER_PRM - (size_t)off, &n);
    if (r < 0) {
        return gsd_fail(p, st->line, "%s(%lld) reaches past the %u octets of the user "
                        "parameters", st->kw, (long long)off, GSD_MAX_USER_PRM);
    }
    if (r == 0 || !gsd_expect_end(p, st, s)) return false;
    size_t end = (size_t)off + n;
    if (module == GSD_GLOBAL) {
        memcpy(g->user_prm + off, octets, n);
        if (end > g->user_prm_written) g->user_prm_written = (uint16_t)end;
    } else {
        gsd_module_t *m = open_module(p);
        if (m->prm_first + end > GSD_MAX_MODULE_PRM) {
            return gsd_fail(p, st->line, "the modules' parameter octets exceed %u "
                            "(GSD_MAX_MODULE_PRM)", GSD_MAX_MODULE_PRM);
        }
        memcpy(g->module_prm + m->prm_first + off, octets, n);
        if (end > m->prm_len) m->prm_len = (uint16_t)end;
    }
    g->consts[g->n_consts++] = (gsd_const_t){.module = (int16_t)module,
                                             .offset = (uint16_t)off, .len = (uint16_t)n,
                                             .line = st->line};
    return true;
}

static bool prm_ref(gsd_parser_t *p, const gsd_stmt_t *st, int module)
{
    gsd_t *g = p->g;
    int64_t off = 0;
    int64_t number = 0;
    if (!arg_number(p, st, 0, GSD_MAX_USER_PRM - 1, &off)) return false;
    if (!gsd_plain_number(p, st, 0, 65535, &number)) return false;
    if (g->n_refs == GSD_MAX_REFS) {
        return gsd_fail(p, st->line, "more than %u Ext_User_Prm_Data_Ref (GSD_MAX_REFS)",
                        GSD_MAX_REFS);
    }
    g->refs[g->n_refs++] = (gsd_ref_t){.module = (int16_t)module, .offset = (uint16_t)off,
                                       .number = (uint16_t)number, .line = st->line};
    return true;
}

gsd_outcome_t gsd_prm_keyword(gsd_parser_t *p, const gsd_stmt_t *st, int module)
{
    bool ok;
    if (gsd_same(st->kw, "Ext_User_Prm_Data_Const")) {
        ok = prm_const(p, st, module);
    } else if (gsd_same(st->kw, "Ext_User_Prm_Data_Ref")) {
        ok = prm_ref(p, st, module);
    } else {
        return GSD_NOT_MINE;
    }
    return ok ? GSD_DONE : GSD_FAILED;
}

/* --- openers and closers ------------------------------------------------------------------ */

static const struct {
    gsd_state_t st;
    const char *open;
    const char *close;
} blocks[] = {
    {GSD_ST_MODULE, "Module", "EndModule"},
    {GSD_ST_PRMTEXT, "PrmText", "EndPrmText"},
    {GSD_ST_EXTPRM, "ExtUserPrmData", "EndExtUserPrmData"},
};

/* Inside a block, the keywords that open or close one that is not open. */
static bool misplaced(gsd_parser_t *p, const gsd_stmt_t *st)
{
    for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++) {
        bool mine = blocks[i].st == p->st;
        if (gsd_same(st->kw, blocks[i].open) || (!mine && gsd_same(st->kw, blocks[i].close))) {
            for (size_t j = 0; j < sizeof blocks / sizeof blocks[0]; j++) {
                if (blocks[j].st != p->st) continue;
                return gsd_fail(p, st->line, "%s inside the %s of line %u (no %s before it)",
                                st->kw, blocks[j].open, (unsigned)p->block_line,
                                blocks[j].close);
            }
        }
    }
    return true;
}

static bool module_opener(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    if (!st->eq) return gsd_fail(p, st->line, "Module needs '= \"name\" octets'");
    if (g->n_modules == GSD_MAX_MODULES) {
        return gsd_fail(p, st->line, "more than %u modules (GSD_MAX_MODULES)", GSD_MAX_MODULES);
    }
    gsd_module_t *m = &g->modules[g->n_modules];
    memset(m, 0, sizeof *m);
    const char *s = st->val;
    if (!gsd_read_string(p, st, &s, &m->name)) return false;
    size_t n;
    int r = gsd_read_octets(p, st, &s, g->cfg + g->n_cfg, GSD_MAX_CFG_OCTETS - g->n_cfg, &n);
    if (r < 0) {
        return gsd_fail(p, st->line, "the modules' config octets exceed %u "
                        "(GSD_MAX_CFG_OCTETS)", GSD_MAX_CFG_OCTETS);
    }
    if (r == 0 || !gsd_expect_end(p, st, s)) return false;
    m->cfg_first = (uint16_t)g->n_cfg;
    m->cfg_len = (uint16_t)n;
    m->prm_first = (uint16_t)g->n_module_prm;
    m->line = st->line;
    g->n_cfg += n;
    g->n_modules++;
    p->st = GSD_ST_MODULE;
    p->block_line = st->line;
    return true;
}

static bool prmtext_opener(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    int64_t number = 0;
    if (!gsd_plain_number(p, st, 0, 65535, &number)) return false;
    if (g->n_tables == GSD_MAX_TEXT_TABLES) {
        return gsd_fail(p, st->line, "more than %u PrmText (GSD_MAX_TEXT_TABLES)",
                        GSD_MAX_TEXT_TABLES);
    }
    g->tables[g->n_tables++] = (gsd_text_table_t){.number = (uint16_t)number,
                                                  .first = (uint16_t)g->n_texts,
                                                  .line = st->line};
    p->st = GSD_ST_PRMTEXT;
    p->block_line = st->line;
    return true;
}

static bool extprm_opener(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    if (!st->eq) return gsd_fail(p, st->line, "ExtUserPrmData needs '= number \"name\"'");
    if (g->n_defs == GSD_MAX_PRM_DEFS) {
        return gsd_fail(p, st->line, "more than %u ExtUserPrmData (GSD_MAX_PRM_DEFS)",
                        GSD_MAX_PRM_DEFS);
    }
    gsd_prm_def_t *d = &g->defs[g->n_defs];
    memset(d, 0, sizeof *d);
    const char *s = st->val;
    int64_t number = 0;
    if (!gsd_read_number(p, st, &s, 0, 65535, &number)) return false;
    if (!gsd_read_string(p, st, &s, &d->name) || !gsd_expect_end(p, st, s)) return false;
    d->number = (uint16_t)number;
    d->type = GSD_T_NONE;
    d->text_ref = -1;
    d->changeable = true;
    d->visible = true;
    d->line = st->line;
    g->n_defs++;
    p->st = GSD_ST_EXTPRM;
    p->block_line = st->line;
    return true;
}

gsd_outcome_t gsd_block_opener(gsd_parser_t *p, const gsd_stmt_t *st)
{
    bool ok;
    if (gsd_same(st->kw, "Module")) {
        ok = module_opener(p, st);
    } else if (gsd_same(st->kw, "PrmText")) {
        ok = prmtext_opener(p, st);
    } else if (gsd_same(st->kw, "ExtUserPrmData")) {
        ok = extprm_opener(p, st);
    } else {
        for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++) {
            if (gsd_same(st->kw, blocks[i].close)) {
                (void)gsd_fail(p, st->line, "%s without %s", blocks[i].close, blocks[i].open);
                return GSD_FAILED;
            }
        }
        return GSD_NOT_MINE;
    }
    return ok ? GSD_DONE : GSD_FAILED;
}

bool gsd_finish(gsd_parser_t *p)
{
    if (p->st == GSD_ST_BEFORE) return gsd_fail(p, 0, "no #Profibus_DP line");
    for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++) {
        if (blocks[i].st == p->st) {
            return gsd_fail(p, p->block_line, "%s without %s", blocks[i].open,
                            blocks[i].close);
        }
    }
    return true;
}

/* A keyword the block does not know: the block's closers and openers are errors, the rest is
 * ignored and noted. */
static bool other_in_block(gsd_parser_t *p, const gsd_stmt_t *st)
{
    if (!misplaced(p, st)) return false;
    gsd_note(p, GSD_NOTE_IGNORED, st->kw, st->line, 0u);
    return true;
}

static bool bare(const gsd_stmt_t *st)
{
    return !st->eq && st->arg == NULL && st->val[0] == '\0';
}

/* --- Module ... EndModule ------------------------------------------------------------------ */

static bool end_module(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    gsd_module_t *m = open_module(p);
    if (m->has_ext_prm_len && m->ext_prm_len > m->prm_len) {
        if (m->prm_first + m->ext_prm_len > GSD_MAX_MODULE_PRM) {
            return gsd_fail(p, st->line, "the modules' parameter octets exceed %u "
                            "(GSD_MAX_MODULE_PRM)", GSD_MAX_MODULE_PRM);
        }
        m->prm_len = m->ext_prm_len;
    }
    g->n_module_prm = (size_t)m->prm_first + m->prm_len;
    m->end_line = st->line;
    p->st = GSD_ST_GLOBAL;
    return true;
}

static bool module_reference(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_module_t *m = open_module(p);
    const char *s = st->kw;
    int64_t v = 0;
    if (!gsd_read_int(&s, &v) || *s != '\0' || v < 0 || v > 0xFFFFFFFFLL) {
        return gsd_fail(p, st->line, "module reference '%s' is no number 0..4294967295",
                        st->kw);
    }
    if (m->has_reference) {
        return gsd_fail(p, st->line, "a second module reference in the Module of line %u",
                        (unsigned)m->line);
    }
    m->has_reference = true;
    m->reference = (uint32_t)v;
    return true;
}

bool gsd_module_statement(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_module_t *m = open_module(p);
    int64_t v = 0;
    if (gsd_same(st->kw, "EndModule") && bare(st)) return end_module(p, st);
    if (st->kw[0] >= '0' && st->kw[0] <= '9' && bare(st)) return module_reference(p, st);
    if (gsd_same(st->kw, "Ext_Module_Prm_Data_Len")) {
        if (!gsd_plain_number(p, st, 0, GSD_MAX_USER_PRM, &v)) return false;
        m->ext_prm_len = (uint16_t)v;
        m->has_ext_prm_len = true;
        return true;
    }
    if (gsd_same(st->kw, "Preset")) {
        if (!gsd_plain_number(p, st, 0, 1, &v)) return false;
        m->preset = v != 0;
        return true;
    }
    gsd_outcome_t o = gsd_prm_keyword(p, st, (int)(p->g->n_modules - 1u));
    if (o != GSD_NOT_MINE) return o == GSD_DONE;
    return other_in_block(p, st);
}

/* --- PrmText ... EndPrmText ---------------------------------------------------------------- */

bool gsd_prmtext_statement(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_t *g = p->g;
    if (gsd_same(st->kw, "EndPrmText") && bare(st)) {
        p->st = GSD_ST_GLOBAL;
        return true;
    }
    if (!gsd_same(st->kw, "Text")) return other_in_block(p, st);
    int64_t v = 0;
    if (!arg_number(p, st, INT32_MIN, UINT32_MAX, &v)) return false;
    if (!st->eq) return gsd_fail(p, st->line, "Text needs '= \"text\"'");
    if (g->n_texts == GSD_MAX_TEXTS) {
        return gsd_fail(p, st->line, "more than %u Text lines (GSD_MAX_TEXTS)", GSD_MAX_TEXTS);
    }
    gsd_text_t *t = &g->texts[g->n_texts];
    const char *s = st->val;
    if (!gsd_read_string(p, st, &s, &t->text) || !gsd_expect_end(p, st, s)) return false;
    t->value = v;
    g->n_texts++;
    g->tables[g->n_tables - 1u].count++;
    return true;
}

/* --- ExtUserPrmData ... EndExtUserPrmData -------------------------------------------------- */

static const struct {
    const char *name;
    gsd_type_t type;
    int64_t lo;
    int64_t hi;
} types[] = {
    {"Bit", GSD_T_BIT, 0, 1},
    {"BitArea", GSD_T_BIT_AREA, 0, 255},
    {"Unsigned8", GSD_T_UNSIGNED8, 0, 255},
    {"Unsigned16", GSD_T_UNSIGNED16, 0, 65535},
    {"Unsigned32", GSD_T_UNSIGNED32, 0, 4294967295LL},
    {"Signed8", GSD_T_SIGNED8, -128, 127},
    {"Signed16", GSD_T_SIGNED16, -32768, 32767},
    {"Signed32", GSD_T_SIGNED32, -2147483648LL, 2147483647LL},
};

/* Bit(n): n 0..7; BitArea(a-b): 0 <= a <= b <= 7. */
static bool bit_position(gsd_parser_t *p, const gsd_stmt_t *st, gsd_prm_def_t *d)
{
    int64_t a = 0;
    int64_t b = 0;
    if (d->type == GSD_T_BIT) {
        if (!arg_number(p, st, 0, 7, &a)) return false;
        d->bit_first = d->bit_last = (uint8_t)a;
        return true;
    }
    if (st->arg == NULL) return gsd_fail(p, st->line, "BitArea needs '(first-last)'");
    const char *s = st->arg;
    gsd_skip_blanks(&s);
    if (!gsd_read_number(p, st, &s, 0, 7, &a)) return false;
    if (*s++ != '-') return gsd_fail(p, st->line, "BitArea needs '(first-last)'");
    gsd_skip_blanks(&s);
    if (!gsd_read_number(p, st, &s, 0, 7, &b)) return false;
    if (s != st->arg + st->arg_len || b < a) {
        return gsd_fail(p, st->line, "BitArea(%.*s): not first-last with first <= last <= 7",
                        (int)st->arg_len, st->arg);
    }
    d->bit_first = (uint8_t)a;
    d->bit_last = (uint8_t)b;
    return true;
}

/* default then min-max, or a list v1,v2,..., or one value. */
static bool type_values(gsd_parser_t *p, const gsd_stmt_t *st, gsd_prm_def_t *d, int64_t lo,
                        int64_t hi)
{
    gsd_t *g = p->g;
    const char *s = st->val;
    int64_t v = 0;
    if (!gsd_read_number(p, st, &s, lo, hi, &d->def)) return false;
    if (*s == '\0') {
        return gsd_fail(p, st->line, "%s: a default needs its allowed values after it", st->kw);
    }
    if (!gsd_read_number(p, st, &s, lo, hi, &v)) return false;
    d->min = d->max = v;
    if (*s == '-') {
        s++;
        gsd_skip_blanks(&s);
        if (!gsd_read_number(p, st, &s, lo, hi, &d->max)) return false;
        return gsd_expect_end(p, st, s);
    }
    d->value_first = (uint16_t)g->n_values;
    for (;;) {
        if (g->n_values == GSD_MAX_VALUES) {
            return gsd_fail(p, st->line, "more than %u listed values (GSD_MAX_VALUES)",
                            GSD_MAX_VALUES);
        }
        g->values[g->n_values++] = v;
        d->value_count++;
        if (v < d->min) d->min = v;
        if (v > d->max) d->max = v;
        if (*s != ',') return gsd_expect_end(p, st, s);
        s++;
        gsd_skip_blanks(&s);
        if (!gsd_read_number(p, st, &s, lo, hi, &v)) return false;
    }
}

static gsd_outcome_t type_line(gsd_parser_t *p, const gsd_stmt_t *st, gsd_prm_def_t *d)
{
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++) {
        if (!gsd_same(st->kw, types[i].name)) continue;
        if (st->eq) {
            (void)gsd_fail(p, st->line, "%s takes no '='", st->kw);
            return GSD_FAILED;
        }
        if (d->type != GSD_T_NONE) {
            (void)gsd_fail(p, st->line, "a second data type in the ExtUserPrmData of line %u",
                           (unsigned)d->line);
            return GSD_FAILED;
        }
        d->type = types[i].type;
        d->type_line = st->line;
        int64_t hi = types[i].hi;
        if (d->type == GSD_T_BIT || d->type == GSD_T_BIT_AREA) {
            if (!bit_position(p, st, d)) return GSD_FAILED;
            hi = ((int64_t)1 << (d->bit_last - d->bit_first + 1)) - 1;
        } else if (st->arg != NULL) {
            (void)gsd_fail(p, st->line, "%s takes no '(...)'", st->kw);
            return GSD_FAILED;
        }
        return type_values(p, st, d, types[i].lo, hi) ? GSD_DONE : GSD_FAILED;
    }
    return GSD_NOT_MINE;
}

bool gsd_extprm_statement(gsd_parser_t *p, const gsd_stmt_t *st)
{
    gsd_prm_def_t *d = &p->g->defs[p->g->n_defs - 1u];
    int64_t v = 0;
    if (gsd_same(st->kw, "EndExtUserPrmData") && bare(st)) {
        if (d->type == GSD_T_NONE) {
            return gsd_fail(p, p->block_line, "ExtUserPrmData %u has no data type line "
                            "(Bit, BitArea, Unsigned8 ...)", (unsigned)d->number);
        }
        p->st = GSD_ST_GLOBAL;
        return true;
    }
    gsd_outcome_t o = type_line(p, st, d);
    if (o != GSD_NOT_MINE) return o == GSD_DONE;
    if (gsd_same(st->kw, "Prm_Text_Ref")) {
        if (!gsd_plain_number(p, st, 0, 65535, &v)) return false;
        d->text_ref = (int32_t)v;
        return true;
    }
    if (gsd_same(st->kw, "Changeable") || gsd_same(st->kw, "Visible")) {
        if (!gsd_plain_number(p, st, 0, 1, &v)) return false;
        *(gsd_same(st->kw, "Visible") ? &d->visible : &d->changeable) = v != 0;
        return true;
    }
    return other_in_block(p, st);
}
