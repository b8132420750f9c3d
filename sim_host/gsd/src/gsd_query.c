/* What a reader asks of a parsed file: keys, rates, modules, parameter definitions, and the
 * default user parameter octets a master sends. */
#include <string.h>

#include "dp_slave/dp_cfg.h"
#include "gsd/gsd.h"
#include "gsd_internal.h"

static const struct {
    const char *name;
    uint32_t baud;
} rates[GSD_RATE_COUNT] = {
    {"9.6", 9600u},       {"19.2", 19200u},     {"45.45", 45450u},    {"93.75", 93750u},
    {"187.5", 187500u},   {"500", 500000u},     {"1.5M", 1500000u},   {"3M", 3000000u},
    {"6M", 6000000u},     {"12M", 12000000u},
};

int gsd_rate_index(uint32_t baud)
{
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        if (rates[i].baud == baud) return (int)i;
    }
    return -1;
}

const char *gsd_rate_name(size_t index)
{
    return index < GSD_RATE_COUNT ? rates[index].name : "?";
}

uint32_t gsd_rate_baud(size_t index)
{
    return index < GSD_RATE_COUNT ? rates[index].baud : 0u;
}

bool gsd_supports_baud(const gsd_t *g, uint32_t baud)
{
    int i = gsd_rate_index(baud);
    return i >= 0 && g->rate[i].supp;
}

uint32_t gsd_max_tsdr_bits(const gsd_t *g, uint32_t baud)
{
    int i = gsd_rate_index(baud);
    if (i < 0 || !g->rate[i].supp || g->rate[i].tsdr_line == 0u) return 0u;
    return g->rate[i].max_tsdr;
}

bool gsd_key(const gsd_t *g, gsd_key_t k, uint32_t *value)
{
    bool present = k < GSD_K_COUNT && g->key_line[k] != 0u;
    if (value != NULL) *value = present ? g->key[k] : 0u;
    return present;
}

const char *gsd_chars(const gsd_t *g, uint32_t offset)
{
    return offset < g->n_chars ? g->chars + offset : "";
}

const char *gsd_text(const gsd_t *g, gsd_str_key_t s)
{
    return s < GSD_S_COUNT ? gsd_chars(g, g->str[s]) : "";
}

const uint8_t *gsd_module_cfg(const gsd_t *g, size_t module)
{
    return g->cfg + g->modules[module].cfg_first;
}

bool gsd_module_io(const gsd_t *g, size_t module, uint16_t *in_len, uint16_t *out_len)
{
    const gsd_module_t *m = &g->modules[module];
    return dp_cfg_io_lengths(g->cfg + m->cfg_first, m->cfg_len, out_len, in_len);
}

int gsd_find_module(const gsd_t *g, const char *name)
{
    for (size_t i = 0; i < g->n_modules; i++) {
        if (strcmp(gsd_chars(g, g->modules[i].name), name) == 0) return (int)i;
    }
    for (size_t i = 0; i < g->n_modules; i++) {
        if (gsd_same(gsd_chars(g, g->modules[i].name), name)) return (int)i;
    }
    return -1;
}

const gsd_prm_def_t *gsd_find_def(const gsd_t *g, uint16_t number)
{
    for (size_t i = 0; i < g->n_defs; i++) {
        if (g->defs[i].number == number) return &g->defs[i];
    }
    return NULL;
}

const char *gsd_prm_text(const gsd_t *g, int32_t table, int64_t v)
{
    for (size_t i = 0; i < g->n_tables; i++) {
        const gsd_text_table_t *t = &g->tables[i];
        if ((int32_t)t->number != table) continue;
        for (size_t j = t->first; j < (size_t)t->first + t->count; j++) {
            if (g->texts[j].value == v) return gsd_chars(g, g->texts[j].text);
        }
    }
    return NULL;
}

size_t gsd_def_octets(const gsd_prm_def_t *d)
{
    switch (d->type) {
    case GSD_T_UNSIGNED16:
    case GSD_T_SIGNED16:
        return 2u;
    case GSD_T_UNSIGNED32:
    case GSD_T_SIGNED32:
        return 4u;
    default:
        return 1u;
    }
}

bool gsd_prm_put(const gsd_prm_def_t *d, int64_t v, uint8_t *image, size_t len, size_t offset)
{
    size_t n = gsd_def_octets(d);
    if (offset + n > len || d->type == GSD_T_NONE) return false;
    if (d->type == GSD_T_BIT || d->type == GSD_T_BIT_AREA) {
        unsigned width = (unsigned)(d->bit_last - d->bit_first + 1u);
        uint8_t mask = (uint8_t)(((1u << width) - 1u) << d->bit_first);
        uint8_t bits = (uint8_t)(((uint64_t)v << d->bit_first) & mask);
        image[offset] = (uint8_t)((image[offset] & (uint8_t)~mask) | bits);
        return true;
    }
    uint32_t u = (uint32_t)v; /* two's complement for the signed types */
    for (size_t i = 0; i < n; i++) {
        image[offset + i] = (uint8_t)(u >> (8u * (n - 1u - i)));
    }
    return true;
}

/* Where the octets of part module end: its Const and Ref lines. */
static size_t part_extent(const gsd_t *g, int module)
{
    size_t end = 0;
    for (size_t i = 0; i < g->n_refs; i++) {
        const gsd_ref_t *r = &g->refs[i];
        if (r->module != module) continue;
        const gsd_prm_def_t *d = gsd_find_def(g, r->number);
        size_t e = (size_t)r->offset + (d != NULL ? gsd_def_octets(d) : 1u);
        if (e > end) end = e;
    }
    if (module == GSD_GLOBAL) {
        if (g->user_prm_written > end) end = g->user_prm_written;
    } else if (g->modules[module].prm_len > end) {
        end = g->modules[module].prm_len;
    }
    return end;
}

size_t gsd_part_len(const gsd_t *g, int module)
{
    if (module == GSD_GLOBAL) {
        uint32_t len;
        return gsd_key(g, GSD_K_USER_PRM_DATA_LEN, &len) ? len : part_extent(g, module);
    }
    const gsd_module_t *m = &g->modules[module];
    return m->has_ext_prm_len ? m->ext_prm_len : part_extent(g, module);
}

/* One part (global or a module's): its Const image, then the Refs' defaults. */
static void build_part(const gsd_t *g, int module, uint8_t *out, size_t len)
{
    const uint8_t *image = module == GSD_GLOBAL ? g->user_prm
                                                : g->module_prm + g->modules[module].prm_first;
    size_t have = module == GSD_GLOBAL ? GSD_MAX_USER_PRM : g->modules[module].prm_len;
    memset(out, 0, len);
    memcpy(out, image, len < have ? len : have);
    for (size_t i = 0; i < g->n_refs; i++) {
        const gsd_ref_t *r = &g->refs[i];
        const gsd_prm_def_t *d = gsd_find_def(g, r->number);
        if (r->module == module && d != NULL) (void)gsd_prm_put(d, d->def, out, len, r->offset);
    }
}

int gsd_default_prm(const gsd_t *g, const size_t *modules, size_t n, uint8_t *out, size_t cap)
{
    size_t total = 0;
    for (size_t i = 0; i <= n; i++) {
        int part = GSD_GLOBAL;
        if (i > 0u) {
            if (modules[i - 1u] >= g->n_modules) return -1;
            part = (int)modules[i - 1u];
        }
        size_t len = gsd_part_len(g, part);
        if (total + len > cap || total + len > GSD_MAX_USER_PRM) return -1;
        build_part(g, part, out + total, len);
        total += len;
    }
    return (int)total;
}
