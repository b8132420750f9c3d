/* dfp-sim gsd FILE: what a GSD file says (ident, rates with MaxTsdr, modules with their config
 * octets, user parameters with their defaults, the DP-V1 keys) and its consistency problems,
 * for a person or (--json) for a script: tests/gsd compares it with pyprofibus's reading. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "gsd/gsd.h"

/* Problems listed; more are counted. */
#define GSD_CMD_MAX_PROBLEMS 100u
/* --module given at most this often (Set_Prm could not carry more modules' parameters). */
#define GSD_CMD_MAX_MODULES 32u

typedef struct gsd_cmd_opts {
    const char *file;
    bool json;
    const char *module_names[GSD_CMD_MAX_MODULES];
    size_t n_module_names;
    size_t modules[GSD_CMD_MAX_MODULES]; /* their indices */
} gsd_cmd_opts_t;

static bool gsd_operand(void *opts, const char *word)
{
    gsd_cmd_opts_t *o = opts;
    if (o->file != NULL) {
        cli_error("gsd takes one FILE; '%s' is a second", word);
        return false;
    }
    o->file = word;
    return true;
}

static const cli_opt_t gsd_options[] = {
    {CLI_OPT("--json", NULL, CLI_FLAG, offsetof(gsd_cmd_opts_t, json))},
    {CLI_OPT("--module", "NAME", CLI_LIST, offsetof(gsd_cmd_opts_t, module_names)),
     .aux = offsetof(gsd_cmd_opts_t, n_module_names), .max = GSD_CMD_MAX_MODULES},
};

static const cli_group_t gsd_groups[] = {
    {gsd_options, CLI_COUNT(gsd_options), 0},
};

const cli_command_t cli_gsd = {.name = "gsd", .groups = gsd_groups,
                               .n_groups = CLI_COUNT(gsd_groups), .operands = CLI_OPERANDS,
                               .operand = gsd_operand};

static const char *const type_names[] = {
    [GSD_T_BIT] = "Bit",           [GSD_T_BIT_AREA] = "BitArea",
    [GSD_T_UNSIGNED8] = "Unsigned8", [GSD_T_UNSIGNED16] = "Unsigned16",
    [GSD_T_UNSIGNED32] = "Unsigned32", [GSD_T_SIGNED8] = "Signed8",
    [GSD_T_SIGNED16] = "Signed16", [GSD_T_SIGNED32] = "Signed32",
    [GSD_T_NONE] = "none",
};

static void hex(const uint8_t *p, size_t n, const char *sep)
{
    for (size_t i = 0; i < n; i++) printf("%s%02X", i == 0u ? "" : sep, p[i]);
}

/* GSD text is ISO 8859-1: octets above 0x7F are U+0080..U+00FF. */
static void json_string(const char *s)
{
    putchar('"');
    for (const unsigned char *p = (const unsigned char *)s; *p != '\0'; p++) {
        if (*p == '"' || *p == '\\') {
            printf("\\%c", *p);
        } else if (*p < 0x20u || *p >= 0x7Fu) {
            printf("\\u%04x", *p);
        } else {
            putchar(*p);
        }
    }
    putchar('"');
}

static void json_key_string(const char *key, const char *s, const char *after)
{
    printf("\"%s\": ", key);
    json_string(s);
    fputs(after, stdout);
}

static void json_optional(const gsd_t *g, const char *name, gsd_key_t k, const char *after)
{
    uint32_t v;
    if (gsd_key(g, k, &v)) {
        printf("\"%s\": %u%s", name, (unsigned)v, after);
    } else {
        printf("\"%s\": null%s", name, after);
    }
}

static void json_rates(const gsd_t *g)
{
    fputs("  \"rates\": [", stdout);
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        const gsd_rate_t *r = &g->rate[i];
        printf("%s\n    {\"baud\": %u, \"name\": \"%s\", \"supported\": %s, \"max_tsdr\": ",
               i == 0u ? "" : ",", (unsigned)r->baud, gsd_rate_name(i),
               r->supp_line == 0u ? "null" : (r->supp ? "true" : "false"));
        if (r->tsdr_line != 0u) {
            printf("%u}", (unsigned)r->max_tsdr);
        } else {
            fputs("null}", stdout);
        }
    }
    fputs("\n  ],\n", stdout);
}

static void json_modules(const gsd_t *g)
{
    fputs("  \"modules\": [", stdout);
    for (size_t i = 0; i < g->n_modules; i++) {
        const gsd_module_t *m = &g->modules[i];
        uint16_t in = 0;
        uint16_t out = 0;
        bool ok = gsd_module_io(g, i, &in, &out);
        printf("%s\n    {", i == 0u ? "" : ",");
        json_key_string("name", gsd_chars(g, m->name), ", \"cfg\": \"");
        hex(gsd_module_cfg(g, i), m->cfg_len, "");
        if (ok) {
            printf("\", \"in\": %u, \"out\": %u, ", in, out);
        } else {
            fputs("\", \"in\": null, \"out\": null, ", stdout);
        }
        printf("\"prm_len\": %zu, \"line\": %u}", gsd_part_len(g, (int)i), (unsigned)m->line);
    }
    fputs("\n  ],\n", stdout);
}

static void json_defs(const gsd_t *g)
{
    fputs("  \"prm_defs\": [", stdout);
    for (size_t i = 0; i < g->n_defs; i++) {
        const gsd_prm_def_t *d = &g->defs[i];
        printf("%s\n    {\"number\": %u, ", i == 0u ? "" : ",", d->number);
        json_key_string("name", gsd_chars(g, d->name), ", ");
        printf("\"type\": \"%s\", \"bit_first\": %u, \"bit_last\": %u, \"default\": %lld, "
               "\"min\": %lld, \"max\": %lld, \"values\": [", type_names[d->type], d->bit_first,
               d->bit_last, (long long)d->def, (long long)d->min, (long long)d->max);
        for (size_t j = 0; j < d->value_count; j++) {
            printf("%s%lld", j == 0u ? "" : ", ", (long long)g->values[d->value_first + j]);
        }
        printf("], \"text_ref\": %d}", (int)d->text_ref);
    }
    fputs("\n  ],\n  \"refs\": [", stdout);
    for (size_t i = 0; i < g->n_refs; i++) {
        const gsd_ref_t *r = &g->refs[i];
        printf("%s{\"module\": %d, \"offset\": %u, \"number\": %u}", i == 0u ? "" : ", ",
               r->module, r->offset, r->number);
    }
    fputs("],\n  \"prm_texts\": [", stdout);
    for (size_t i = 0; i < g->n_tables; i++) {
        const gsd_text_table_t *t = &g->tables[i];
        printf("%s{\"number\": %u, \"texts\": [", i == 0u ? "" : ", ", t->number);
        for (size_t j = 0; j < t->count; j++) {
            printf("%s[%lld, ", j == 0u ? "" : ", ", (long long)g->texts[t->first + j].value);
            json_string(gsd_chars(g, g->texts[t->first + j].text));
            putchar(']');
        }
        fputs("]}", stdout);
    }
    fputs("],\n", stdout);
}

static void json_keys(const gsd_t *g)
{
    fputs("  \"keys\": {", stdout);
    bool first = true;
    for (int k = 0; k < GSD_K_COUNT; k++) {
        uint32_t v;
        if (!gsd_key(g, (gsd_key_t)k, &v)) continue;
        printf("%s\"%s\": %u", first ? "" : ", ", gsd_key_name((gsd_key_t)k), (unsigned)v);
        first = false;
    }
    fputs("},\n", stdout);
}

static void json_problems(const gsd_problem_t *p, size_t n, size_t shown)
{
    printf("  \"problem_count\": %zu,\n  \"problems\": [", n);
    for (size_t i = 0; i < shown; i++) {
        printf("%s\n    {\"line\": %u, ", i == 0u ? "" : ",", (unsigned)p[i].line);
        json_key_string("text", p[i].text, "}");
    }
    fputs("\n  ]\n}\n", stdout);
}

static void print_json(const gsd_cmd_opts_t *o, const gsd_t *g, const gsd_problem_t *p,
                       size_t n, size_t shown)
{
    uint8_t prm[GSD_MAX_USER_PRM];
    int len = gsd_default_prm(g, o->modules, o->n_module_names, prm, sizeof prm);
    fputs("{\n  ", stdout);
    json_key_string("file", o->file, ",\n  ");
    json_key_string("vendor", gsd_text(g, GSD_S_VENDOR_NAME), ",\n  ");
    json_key_string("model", gsd_text(g, GSD_S_MODEL_NAME), ",\n  ");
    json_key_string("revision", gsd_text(g, GSD_S_REVISION), ",\n  ");
    json_optional(g, "ident", GSD_K_IDENT_NUMBER, ",\n  ");
    json_optional(g, "gsd_revision", GSD_K_GSD_REVISION, ",\n  ");
    printf("\"dpv1\": %s,\n  \"modular\": %s,\n", gsd_key(g, GSD_K_DPV1_SLAVE, NULL) &&
           g->key[GSD_K_DPV1_SLAVE] != 0u ? "true" : "false",
           gsd_key(g, GSD_K_MODULAR_STATION, NULL) && g->key[GSD_K_MODULAR_STATION] != 0u
               ? "true" : "false");
    json_keys(g);
    json_rates(g);
    json_modules(g);
    json_defs(g);
    fputs("  \"user_prm\": ", stdout);
    if (len >= 0) {
        putchar('"');
        hex(prm, (size_t)len, "");
        fputs("\",\n", stdout);
    } else {
        fputs("null,\n", stdout);
    }
    fputs("  \"ignored\": [", stdout);
    for (size_t i = 0, k = 0; i < g->n_notes; i++) {
        if (g->notes[i].kind != GSD_NOTE_IGNORED) continue;
        printf("%s{\"line\": %u, ", k++ == 0u ? "" : ", ", (unsigned)g->notes[i].line);
        json_key_string("keyword", g->notes[i].keyword, "}");
    }
    fputs("],\n", stdout);
    json_problems(p, n, shown);
}

/* --- for a person ------------------------------------------------------------------------ */

static void text_header(const char *file, const gsd_t *g)
{
    uint32_t v;
    printf("%s: %s %s, revision %s", file, gsd_text(g, GSD_S_VENDOR_NAME),
           gsd_text(g, GSD_S_MODEL_NAME), gsd_text(g, GSD_S_REVISION));
    if (gsd_key(g, GSD_K_GSD_REVISION, &v)) printf(", GSD revision %u", (unsigned)v);
    printf("\nident 0x%04X", (unsigned)g->key[GSD_K_IDENT_NUMBER]);
    if (!gsd_key(g, GSD_K_IDENT_NUMBER, NULL)) fputs(" (missing)", stdout);
    bool modular = gsd_key(g, GSD_K_MODULAR_STATION, &v) && v != 0u;
    printf(", %s station", modular ? "modular" : "compact");
    if (gsd_key(g, GSD_K_MAX_MODULE, &v)) {
        printf(" (at most %u module%s)", (unsigned)v, v == 1u ? "" : "s");
    }
    static const struct {
        gsd_key_t k;
        const char *what;
    } lens[] = {{GSD_K_MAX_INPUT_LEN, "inputs"}, {GSD_K_MAX_OUTPUT_LEN, "outputs"},
                {GSD_K_MAX_DATA_LEN, "data"}, {GSD_K_MAX_DIAG_DATA_LEN, "diagnosis"},
                {GSD_K_USER_PRM_DATA_LEN, "user parameters"}};
    for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
        if (gsd_key(g, lens[i].k, &v)) printf(", %s <= %u", lens[i].what, (unsigned)v);
    }
    fputs(" octets\n", stdout);
}

static void text_rates(const gsd_t *g)
{
    uint32_t v;
    printf("rates%s (MaxTsdr in bit times):", gsd_key(g, GSD_K_AUTO_BAUD_SUPP, &v) && v != 0u
                                                  ? ", auto baud" : "");
    bool any = false;
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        const gsd_rate_t *r = &g->rate[i];
        if (!r->supp && r->tsdr_line == 0u) continue;
        printf("%s %s", any ? "," : "", gsd_rate_name(i));
        if (r->tsdr_line != 0u) printf(" %u", (unsigned)r->max_tsdr);
        if (!r->supp) fputs(" (not supported)", stdout);
        any = true;
    }
    puts(any ? "" : " none");
}

static void text_modules(const gsd_t *g)
{
    printf("modules (%zu):\n", g->n_modules);
    for (size_t i = 0; i < g->n_modules; i++) {
        const gsd_module_t *m = &g->modules[i];
        uint16_t in = 0;
        uint16_t out = 0;
        printf("  \"%s\" ", gsd_chars(g, m->name));
        hex(gsd_module_cfg(g, i), m->cfg_len, " ");
        if (gsd_module_io(g, i, &in, &out)) {
            printf(": %u in, %u out", in, out);
        } else {
            fputs(": malformed identifiers", stdout);
        }
        size_t plen = gsd_part_len(g, (int)i);
        if (plen != 0u) printf(", %zu parameter octet%s", plen, plen == 1u ? "" : "s");
        putchar('\n');
    }
}

static void text_def(const gsd_t *g, const gsd_ref_t *r, const gsd_prm_def_t *d)
{
    printf("  octet %u", r->offset);
    if (r->module != GSD_GLOBAL) printf(" of \"%s\"", gsd_chars(g, g->modules[r->module].name));
    printf(": %u \"%s\" %s", d->number, gsd_chars(g, d->name), type_names[d->type]);
    if (d->type == GSD_T_BIT) printf("(%u)", d->bit_first);
    if (d->type == GSD_T_BIT_AREA) printf("(%u-%u)", d->bit_first, d->bit_last);
    printf(" default %lld", (long long)d->def);
    const char *t = gsd_prm_text(g, d->text_ref, d->def);
    if (t != NULL) printf(" (%s)", t);
    if (d->value_count == 0u) {
        printf(", %lld-%lld\n", (long long)d->min, (long long)d->max);
        return;
    }
    fputs(", one of", stdout);
    for (size_t j = 0; j < d->value_count; j++) {
        printf("%s %lld", j == 0u ? "" : ",", (long long)g->values[d->value_first + j]);
    }
    putchar('\n');
}

static void text_prm(const gsd_cmd_opts_t *o, const gsd_t *g)
{
    uint8_t prm[GSD_MAX_USER_PRM];
    int len = gsd_default_prm(g, o->modules, o->n_module_names, prm, sizeof prm);
    if (len < 0) {
        fputs("user parameters: longer than Set_Prm carries\n", stdout);
    } else {
        printf("user parameters by default%s (%d octets):%s",
               o->n_module_names != 0u ? " with the modules given" : "", len,
               len == 0 ? " none" : " ");
        hex(prm, (size_t)len, " ");
        putchar('\n');
    }
    for (size_t i = 0; i < g->n_refs; i++) {
        const gsd_prm_def_t *d = gsd_find_def(g, g->refs[i].number);
        if (d != NULL) text_def(g, &g->refs[i], d);
    }
}

static void text_dpv1(const gsd_t *g)
{
    bool any = false;
    for (int k = GSD_K_DPV1_SLAVE; k <= GSD_K_DPV1_LAST; k++) {
        uint32_t v;
        if (!gsd_key(g, (gsd_key_t)k, &v)) continue;
        printf("%s %s %u", any ? "," : "DP-V1:", gsd_key_name((gsd_key_t)k), (unsigned)v);
        any = true;
    }
    puts(any ? "" : "DP-V1: no keys (DP-V0)");
}

static void print_text(const gsd_cmd_opts_t *o, const gsd_t *g, const gsd_problem_t *p,
                       size_t n, size_t shown)
{
    const char *file = o->file;
    text_header(file, g);
    text_rates(g);
    text_modules(g);
    text_prm(o, g);
    text_dpv1(g);
    for (size_t i = 0; i < g->n_notes; i++) {
        if (g->notes[i].kind == GSD_NOTE_IGNORED) {
            printf("ignored: line %u: %s (not a keyword this reader knows)\n",
                   (unsigned)g->notes[i].line, g->notes[i].keyword);
        }
    }
    if (n == 0u) {
        puts("consistent: no problems");
        return;
    }
    printf("%zu problem%s:\n", n, n == 1u ? "" : "s");
    for (size_t i = 0; i < shown; i++) {
        if (p[i].line != 0u) {
            printf("  %s:%u: %s\n", file, (unsigned)p[i].line, p[i].text);
        } else {
            printf("  %s: %s\n", file, p[i].text);
        }
    }
    if (shown < n) printf("  ... and %zu more\n", n - shown);
}

/* The --module names into indices: false after reporting. */
static bool find_modules(gsd_cmd_opts_t *o, const gsd_t *g)
{
    for (size_t i = 0; i < o->n_module_names; i++) {
        int m = gsd_find_module(g, o->module_names[i]);
        if (m < 0) {
            cli_error("gsd: no module \"%s\" in %s", o->module_names[i], o->file);
            return false;
        }
        o->modules[i] = (size_t)m;
    }
    return true;
}

int cmd_gsd(int argc, char **argv)
{
    gsd_cmd_opts_t o = {0};
    if (cli_parse(&cli_gsd, argc, argv, &o) != 0) return EXIT_USAGE;
    if (o.file == NULL) {
        cli_error("gsd needs a file: dfp-sim gsd FILE [--json] [--module NAME]...");
        return EXIT_USAGE;
    }
    gsd_t *g = malloc(sizeof *g);
    gsd_problem_t *p = malloc(GSD_CMD_MAX_PROBLEMS * sizeof *p);
    if (g == NULL || p == NULL) {
        free(g);
        free(p);
        cli_error("gsd: out of memory");
        return EXIT_USAGE;
    }
    char err[GSD_ERR_LEN + 512u];
    int rc = EXIT_USAGE;
    if (gsd_parse_file(o.file, g, err, sizeof err) != 0) {
        (void)fprintf(stderr, "dfp-sim: %s\n", err);
    } else if (find_modules(&o, g)) {
        size_t n = gsd_check(g, p, GSD_CMD_MAX_PROBLEMS);
        size_t shown = n < GSD_CMD_MAX_PROBLEMS ? n : GSD_CMD_MAX_PROBLEMS;
        if (o.json) {
            print_json(&o, g, p, n, shown);
        } else {
            print_text(&o, g, p, n, shown);
        }
        rc = n == 0u ? 0 : 1;
    }
    free(g);
    free(p);
    return rc;
}
