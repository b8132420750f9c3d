/* pyprofibus profisniff: the repr of an FdlTelegram, "FdlTelegram(sd=SD2, haveLE=True, ...)"
 * (capture/text_import.h), rebuilt to the octets pyprofibus read (fdl.py getRawData). */
#include "text_formats.h"

#include <stdio.h>

#include "dp_slave/fdl_wire.h"

/* The repr of pyprofibus' FdlTelegram (fdl.py __repr__): intToHex ("0x%02X", "None"),
 * bytesToHex ("02 05 00", "Empty", "None"), str(bool). */
typedef enum sniff_field {
    SF_SD = 0,
    SF_HAVE_LE,
    SF_DA,
    SF_SA,
    SF_FC,
    SF_DAE,
    SF_SAE,
    SF_DU,
    SF_HAVE_FCS,
    SF_ED,
    SF_COUNT,
} sniff_field_t;

static const char *const sniff_names[SF_COUNT] = {"sd",  "haveLE", "da", "sa",      "fc",
                                                  "dae", "sae",    "du", "haveFCS", "ed"};

typedef struct sniff_octets {
    bool none;
    span_t hex; /* empty for "Empty" */
    size_t count;
} sniff_octets_t;

typedef struct sniff {
    bool seen[SF_COUNT];
    int sd;             /* -1: None */
    int da, sa, fc, ed; /* -1: None */
    bool have_le, have_fcs;
    sniff_octets_t dae, sae, du;
} sniff_t;

static bool sniff_int(span_t v, int *out, char *problem, size_t max, const char *name)
{
    if (span_is(v, "None")) {
        *out = -1;
        return true;
    }
    span_t digits = span_starts(v, "0x") ? span_from(v, 2u) : (span_t){v.p, 0};
    if (digits.n == 0u || digits.n > 8u || !span_all_hex(digits)) {
        (void)snprintf(problem, max, "%s is not 0x.. or None: '%s'", name, quote_span(v).s);
        return false;
    }
    uint32_t x = 0;
    for (size_t i = 0; i < digits.n; i++) {
        x = x * 16u + (uint32_t)char_hex_value(digits.p[i]);
    }
    if (x > 0xFFu) {
        (void)snprintf(problem, max, "%s=%s is not an octet", name, quote_span(v).s);
        return false;
    }
    *out = (int)x;
    return true;
}

static bool sniff_bool(span_t v, bool *out, char *problem, size_t max, const char *name)
{
    if (span_is(v, "True") || span_is(v, "False")) {
        *out = span_is(v, "True");
        return true;
    }
    (void)snprintf(problem, max, "%s is not True or False: '%s'", name, quote_span(v).s);
    return false;
}

static bool sniff_bytes(span_t v, sniff_octets_t *out, char *problem, size_t max)
{
    *out = (sniff_octets_t){0};
    if (span_is(v, "None")) {
        out->none = true;
        return true;
    }
    if (span_is(v, "Empty")) {
        return true;
    }
    sink_t count = {0};
    if (!hex_octets(v, &count, false, problem, max)) {
        return false;
    }
    out->hex = v;
    out->count = count.n;
    return true;
}

static bool sniff_sd(span_t v, int *out, char *problem, size_t max)
{
    *out = start_delimiter_named(v);
    return *out >= 0 || sniff_int(v, out, problem, max, "sd");
}

static bool sniff_field(sniff_t *s, span_t part, char *problem, size_t max)
{
    size_t eq = 0;
    while (eq < part.n && part.p[eq] != '=') {
        eq++;
    }
    span_t key = span_trim((span_t){part.p, eq});
    if (eq == part.n) {
        (void)snprintf(problem, max, "no '=' in '%s'", quote_span(part).s);
        return false;
    }
    span_t v = span_trim(span_from(part, eq + 1u));
    for (int f = 0; f < SF_COUNT; f++) {
        if (!span_is(key, sniff_names[f])) {
            continue;
        }
        if (s->seen[f]) {
            (void)snprintf(problem, max, "%s given twice", sniff_names[f]);
            return false;
        }
        s->seen[f] = true;
        switch ((sniff_field_t)f) {
        case SF_SD:
            return sniff_sd(v, &s->sd, problem, max);
        case SF_HAVE_LE:
            return sniff_bool(v, &s->have_le, problem, max, "haveLE");
        case SF_DA:
            return sniff_int(v, &s->da, problem, max, "da");
        case SF_SA:
            return sniff_int(v, &s->sa, problem, max, "sa");
        case SF_FC:
            return sniff_int(v, &s->fc, problem, max, "fc");
        case SF_DAE:
            return sniff_bytes(v, &s->dae, problem, max);
        case SF_SAE:
            return sniff_bytes(v, &s->sae, problem, max);
        case SF_DU:
            return sniff_bytes(v, &s->du, problem, max);
        case SF_HAVE_FCS:
            return sniff_bool(v, &s->have_fcs, problem, max, "haveFCS");
        case SF_ED:
            return sniff_int(v, &s->ed, problem, max, "ed");
        case SF_COUNT:
            break;
        }
    }
    (void)snprintf(problem, max, "unknown field '%s'", quote_span(key).s);
    return false;
}

static void emit_octets(const sniff_octets_t *o, sink_t *out)
{
    if (o->count > 0u) {
        char ignored[8];
        (void)hex_octets(o->hex, out, false, ignored, sizeof ignored);
    }
}

/* The fields between the parentheses, each exactly once, and what getRawData() needs of them. */
static bool sniff_parse(span_t body, sniff_t *s, cap_record_t *rec)
{
    size_t i = 0;
    while (i <= body.n) {
        size_t start = i;
        while (i < body.n && body.p[i] != ',') {
            i++;
        }
        if (!sniff_field(s, span_trim((span_t){body.p + start, i - start}), rec->problem,
                         sizeof rec->problem)) {
            rec->len = 0;
            rec->orig_len = 0;
            return false;
        }
        i++;
    }
    for (int f = 0; f < SF_COUNT; f++) {
        if (!s->seen[f]) {
            (void)text_bad(rec, "FdlTelegram without %s", sniff_names[f]);
            return false;
        }
    }
    if (s->sd < 0) {
        (void)text_bad(rec, "FdlTelegram with sd=None");
        return false;
    }
    if (s->dae.none || s->sae.none) {
        (void)text_bad(rec, "dae/sae None cannot be encoded (pyprofibus asserts bytes)");
        return false;
    }
    if (s->have_le && s->du.none) {
        (void)text_bad(rec, "haveLE=True with du=None");
        return false;
    }
    return true;
}

/* pyprofibus keeps 7-bit addresses and sets the extension bit when DAE/SAE octets follow. */
static uint8_t sniff_address(int address, const sniff_octets_t *extension)
{
    return (uint8_t)(((unsigned)address & FDL_ADDR_MASK) |
                     (extension->count > 0u ? FDL_ADDR_EXT : 0u));
}

/* Octet by octet as FdlTelegram.getRawData() does: fields that are None are left out, the FCS
 * covers DA to the end of the data unit. */
static text_line_result_t sniff_encode(text_import_state_t *st, const sniff_t *s,
                                       cap_record_t *rec)
{
    sink_t out = {.rec = rec};
    if (s->have_le) {
        size_t le = 3u + s->du.count + s->dae.count + s->sae.count;
        if (le > FDL_LE_MAX) {
            return text_bad(rec, "LE would be %zu, more than %u", le, FDL_LE_MAX);
        }
        sink_put(&out, (uint8_t)s->sd);
        sink_put(&out, (uint8_t)le);
        sink_put(&out, (uint8_t)le);
    }
    sink_put(&out, (uint8_t)s->sd);
    size_t fcs_from = out.n;
    if (s->da >= 0) {
        sink_put(&out, sniff_address(s->da, &s->dae));
    }
    if (s->sa >= 0) {
        sink_put(&out, sniff_address(s->sa, &s->sae));
    }
    if (s->fc >= 0) {
        sink_put(&out, (uint8_t)s->fc);
    }
    emit_octets(&s->dae, &out);
    emit_octets(&s->sae, &out);
    emit_octets(&s->du, &out);
    if (s->have_fcs) {
        sink_put(&out, sink_fcs(&out, fcs_from));
    }
    if (s->ed >= 0) {
        sink_put(&out, (uint8_t)s->ed);
    }
    return text_record_done(st, rec, TEXT_SHAPE_PROFISNIFF);
}

text_line_result_t import_profisniff(text_import_state_t *st, span_t body, cap_record_t *rec)
{
    body = span_trim(body);
    if (body.n == 0u || body.p[body.n - 1u] != ')') {
        return text_bad(rec, "FdlTelegram(...) without its ')'");
    }
    body.n--;
    sniff_t s = {.sd = -1, .da = -1, .sa = -1, .fc = -1, .ed = -1};
    if (!sniff_parse(body, &s, rec)) {
        return TEXT_LINE_BAD;
    }
    return sniff_encode(st, &s, rec);
}
