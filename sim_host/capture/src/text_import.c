/* Text captures, one telegram per line (capture/text_import.h lists the shapes, docs/captures.md
 * shows them with examples and says what is rebuilt and what is lost).
 *
 * The line is not NUL-terminated and may hold any bytes: every scan below is bounded by the
 * line's length, and numbers are range-checked before they are multiplied. */
#include "capture/text_import.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define NS_PER_S 1000000000ull
/* Beyond 10^10 s (317 years) a time is garbage, and seconds * 10^9 still fits 64 bits. */
#define MAX_SECONDS 10000000000ull
#define MAX_FRACTION_DIGITS 9
#define SECONDS_PER_DAY 86400ull
#define QUOTE_MAX 20u

#include "fdl_octets.h"
#define ADDR_MASK 0x7Fu
#define FC_FCB_FCV_OR_TYPE 0x30u /* FCB/FCV of a request, station type of a reply */
#define SD3_DU_LEN 8u
#define SAP_MAX 63u

typedef struct span {
    const char *p;
    size_t n;
} span_t;

/* ---- small helpers ------------------------------------------------------------------------ */

static bool is_ws(char c)
{
    return c == ' ' || c == '\t';
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static char to_upper(char c)
{
    if (c >= 'a' && c <= 'z') {
        return (char)(unsigned char)((unsigned char)c - ('a' - 'A'));
    }
    return c;
}

static bool span_is(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    return t.n == n && memcmp(t.p, lit, n) == 0;
}

static bool span_is_nocase(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    if (t.n != n) {
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        if (to_upper(t.p[i]) != to_upper(lit[i])) {
            return false;
        }
    }
    return true;
}

static bool span_starts(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    return t.n >= n && memcmp(t.p, lit, n) == 0;
}

static span_t span_from(span_t t, size_t k)
{
    return k >= t.n ? (span_t){t.p + t.n, 0} : (span_t){t.p + k, t.n - k};
}

static span_t trim(span_t t)
{
    while (t.n > 0u && is_ws(t.p[0])) {
        t.p++;
        t.n--;
    }
    while (t.n > 0u && is_ws(t.p[t.n - 1u])) {
        t.n--;
    }
    return t;
}

/* The next whitespace-separated token at or after *pos; an empty span at the end. */
static span_t next_token(span_t line, size_t *pos)
{
    size_t i = *pos;
    while (i < line.n && is_ws(line.p[i])) {
        i++;
    }
    size_t start = i;
    while (i < line.n && !is_ws(line.p[i])) {
        i++;
    }
    *pos = i;
    return (span_t){line.p + start, i - start};
}

static span_t rest_of(span_t line, size_t pos)
{
    return trim(span_from(line, pos));
}

/* A token for a message: at most QUOTE_MAX characters, anything unprintable as '?'. */
typedef struct quoted {
    char s[QUOTE_MAX + 4u];
} quoted_t;

static quoted_t quote(span_t t)
{
    quoted_t q;
    size_t n = t.n < QUOTE_MAX ? t.n : QUOTE_MAX;
    /* cppcheck 2.10 takes n for 0 from one caller's empty span and calls the loop dead. */
    for (size_t i = 0; i < n; i++) { // cppcheck-suppress knownConditionTrueFalse
        char c = t.p[i];
        if (c >= 0x20 && c < 0x7F) {
            q.s[i] = c;
        } else {
            q.s[i] = '?';
        }
    }
    if (t.n > QUOTE_MAX) {
        memcpy(&q.s[n], "...", 3);
        n += 3u;
    }
    q.s[n] = '\0';
    return q;
}

static text_line_result_t bad(cap_record_t *rec, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(rec->problem, sizeof rec->problem, fmt, ap);
    va_end(ap);
    rec->len = 0;
    rec->orig_len = 0;
    return TEXT_LINE_BAD;
}

/* ---- octets ------------------------------------------------------------------------------- */

/* Where octets go: into the record (cut at CAP_MAX_RECORD, orig_len counts all) or, with rec
 * NULL, only counted. The FCS sums are kept here because a cut record no longer holds every
 * octet they cover. */
typedef struct sink {
    cap_record_t *rec;
    size_t n;
    uint8_t sum_from1; /* octets 1.. (SD1, SD3: FCS from DA) */
    uint8_t sum_from4; /* octets 4.. (SD2: FCS from DA) */
} sink_t;

static void put(sink_t *s, uint8_t b)
{
    if (s->rec != NULL) {
        if (s->rec->len < CAP_MAX_RECORD) {
            s->rec->data[s->rec->len++] = b;
        }
        s->rec->orig_len++;
    }
    if (s->n >= 1u) {
        s->sum_from1 = (uint8_t)(s->sum_from1 + b);
    }
    if (s->n >= 4u) {
        s->sum_from4 = (uint8_t)(s->sum_from4 + b);
    }
    s->n++;
}

static bool all_hex(span_t t)
{
    for (size_t i = 0; i < t.n; i++) {
        if (hex_value(t.p[i]) < 0) {
            return false;
        }
    }
    return true;
}

/* One hex word: "0x5"/"0x05" is one octet, "05"/"0502" is one octet per digit pair. */
static bool hex_word(span_t w, sink_t *out, char *problem, size_t max)
{
    if (w.n >= 2u && w.p[0] == '0' && (w.p[1] == 'x' || w.p[1] == 'X')) {
        span_t digits = span_from(w, 2u);
        if (digits.n == 0u || !all_hex(digits)) {
            (void)snprintf(problem, max, "not hex: '%s'", quote(w).s);
            return false;
        }
        if (digits.n > 2u) {
            (void)snprintf(problem, max, "not one octet: '%s'", quote(w).s);
            return false;
        }
        int v = hex_value(digits.p[0]);
        if (digits.n == 2u) {
            v = v * 16 + hex_value(digits.p[1]);
        }
        put(out, (uint8_t)v);
        return true;
    }
    if (!all_hex(w)) {
        (void)snprintf(problem, max, "not hex: '%s'", quote(w).s);
        return false;
    }
    if (w.n % 2u != 0u) {
        (void)snprintf(problem, max, "odd number of hex digits: '%s'", quote(w).s);
        return false;
    }
    for (size_t i = 0; i < w.n; i += 2u) {
        put(out, (uint8_t)(hex_value(w.p[i]) * 16 + hex_value(w.p[i + 1u])));
    }
    return true;
}

static bool is_hex_separator(char c)
{
    return is_ws(c) || c == ',' || c == ':';
}

/* Hex octets separated by blanks, ',' or ':'; with comments, '#' or "//" at the start of a word
 * ends the octets. */
static bool hex_octets(span_t s, sink_t *out, bool comments, char *problem, size_t max)
{
    size_t i = 0;
    while (i < s.n) {
        if (is_hex_separator(s.p[i])) {
            i++;
            continue;
        }
        if (comments && (s.p[i] == '#' || (s.p[i] == '/' && i + 1u < s.n && s.p[i + 1u] == '/'))) {
            break;
        }
        size_t start = i;
        while (i < s.n && !is_hex_separator(s.p[i])) {
            i++;
        }
        if (!hex_word((span_t){s.p + start, i - start}, out, problem, max)) {
            return false;
        }
    }
    return true;
}

/* ---- times -------------------------------------------------------------------------------- */

typedef enum time_parse {
    TIME_OK = 0,
    TIME_NOT_A_TIME, /* not shaped like a time at all */
    TIME_TOO_BIG,
    TIME_TOO_PRECISE,
} time_parse_t;

typedef struct parsed_time {
    uint64_t ns;
    unsigned fields;         /* ':'-separated fields before the fraction (1..3) */
    int fraction_digits;     /* -1 without a '.' */
    bool unit_s;             /* a trailing 's' */
} parsed_time_t;

/* [[h:]m:]s[.fraction][s]. ProSoft writes ',' between the ms/µs/ns groups of the fraction;
 * minutes and seconds after a ':' have two digits and are below 60. */
static time_parse_t parse_time(span_t t, bool prosoft, parsed_time_t *out)
{
    *out = (parsed_time_t){.fraction_digits = -1};
    size_t i = 0;
    uint64_t fields[3] = {0, 0, 0};
    unsigned nfields = 0;
    for (;;) {
        size_t start = i;
        uint64_t v = 0;
        while (i < t.n && is_digit(t.p[i])) {
            v = v * 10u + (uint64_t)(t.p[i] - '0');
            if (v > MAX_SECONDS) {
                return TIME_TOO_BIG;
            }
            i++;
        }
        if (i == start || nfields == 3u) {
            return TIME_NOT_A_TIME;
        }
        if (nfields > 0u && (i - start != 2u || v >= 60u)) {
            return TIME_NOT_A_TIME;
        }
        fields[nfields++] = v;
        if (i < t.n && t.p[i] == ':') {
            i++;
            continue;
        }
        break;
    }
    uint64_t fraction = 0;
    int digits = -1;
    if (i < t.n && t.p[i] == '.') {
        i++;
        digits = 0;
        while (i < t.n) {
            char c = t.p[i];
            if (is_digit(c)) {
                if (digits == MAX_FRACTION_DIGITS) {
                    return TIME_TOO_PRECISE;
                }
                fraction = fraction * 10u + (uint64_t)(c - '0');
                digits++;
            } else if (!(prosoft && c == ',' && digits > 0 && i + 1u < t.n &&
                         is_digit(t.p[i + 1u]))) {
                break;
            }
            i++;
        }
        if (digits == 0) {
            return TIME_NOT_A_TIME;
        }
    }
    bool unit_s = false;
    if (!prosoft && i < t.n && t.p[i] == 's') {
        unit_s = true;
        i++;
    }
    if (i != t.n) {
        return TIME_NOT_A_TIME;
    }
    uint64_t seconds = 0;
    for (unsigned f = 0; f < nfields; f++) {
        if (seconds > MAX_SECONDS / 60u) {
            return TIME_TOO_BIG;
        }
        seconds = seconds * (f == 0u ? 1u : 60u) + fields[f];
        if (seconds > MAX_SECONDS) {
            return TIME_TOO_BIG;
        }
    }
    for (int d = digits < 0 ? MAX_FRACTION_DIGITS : digits; d < MAX_FRACTION_DIGITS; d++) {
        fraction *= 10u;
    }
    out->ns = seconds * NS_PER_S + fraction;
    out->fields = nfields;
    out->fraction_digits = digits;
    out->unit_s = unit_s;
    return TIME_OK;
}

static text_line_result_t bad_time(cap_record_t *rec, time_parse_t r, span_t tok)
{
    if (r == TIME_TOO_BIG) {
        return bad(rec, "time beyond 10^10 s: '%s'", quote(tok).s);
    }
    if (r == TIME_TOO_PRECISE) {
        return bad(rec, "more than 9 fraction digits: '%s'", quote(tok).s);
    }
    return bad(rec, "not a time: '%s'", quote(tok).s);
}

/* ---- the record --------------------------------------------------------------------------- */

static void record_start(cap_record_t *rec, uint64_t line)
{
    rec->position = line;
    rec->has_time = false;
    rec->t_ns = 0;
    rec->baud = 0;
    rec->error_flags = 0;
    rec->dir = CAP_DIR_UNKNOWN;
    rec->len = 0;
    rec->orig_len = 0;
    rec->problem[0] = '\0';
}

static text_line_result_t record_done(text_import_state_t *st, cap_record_t *rec, uint32_t shape)
{
    if (rec->orig_len == 0u) {
        return bad(rec, "no octets");
    }
    if (rec->orig_len > rec->len) {
        (void)snprintf(rec->problem, sizeof rec->problem,
                       "%zu octets, longer than any telegram (first %zu kept)", rec->orig_len,
                       rec->len);
    } else {
        (void)cap_check_telegram(rec->data, rec->len, rec->problem, sizeof rec->problem);
    }
    if (rec->has_time) {
        st->last_t_ns = rec->t_ns;
        st->seen_time = true;
    }
    st->shape_seen |= shape;
    return TEXT_LINE_RECORD;
}

/* ---- pyprofibus profisniff: FdlTelegram(...) ---------------------------------------------- */

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
    if (digits.n == 0u || digits.n > 8u || !all_hex(digits)) {
        (void)snprintf(problem, max, "%s is not 0x.. or None: '%s'", name, quote(v).s);
        return false;
    }
    uint32_t x = 0;
    for (size_t i = 0; i < digits.n; i++) {
        x = x * 16u + (uint32_t)hex_value(digits.p[i]);
    }
    if (x > 0xFFu) {
        (void)snprintf(problem, max, "%s=%s is not an octet", name, quote(v).s);
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
    (void)snprintf(problem, max, "%s is not True or False: '%s'", name, quote(v).s);
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
    static const struct {
        const char *name;
        int sd;
    } names[] = {{"SD1", SD1}, {"SD2", SD2}, {"SD3", SD3}, {"SD4", SD4}, {"SC", SC}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (span_is(v, names[i].name)) {
            *out = names[i].sd;
            return true;
        }
    }
    return sniff_int(v, out, problem, max, "sd");
}

static bool sniff_field(sniff_t *s, span_t part, char *problem, size_t max)
{
    size_t eq = 0;
    while (eq < part.n && part.p[eq] != '=') {
        eq++;
    }
    span_t key = trim((span_t){part.p, eq});
    if (eq == part.n) {
        (void)snprintf(problem, max, "no '=' in '%s'", quote(part).s);
        return false;
    }
    span_t v = trim(span_from(part, eq + 1u));
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
    (void)snprintf(problem, max, "unknown field '%s'", quote(key).s);
    return false;
}

static void emit_octets(const sniff_octets_t *o, sink_t *out)
{
    if (o->count > 0u) {
        char ignored[8];
        (void)hex_octets(o->hex, out, false, ignored, sizeof ignored);
    }
}

/* body: what follows "FdlTelegram(". Rebuilt exactly as FdlTelegram.getRawData() does. */
static text_line_result_t import_profisniff(text_import_state_t *st, span_t body,
                                            cap_record_t *rec)
{
    body = trim(body);
    if (body.n == 0u || body.p[body.n - 1u] != ')') {
        return bad(rec, "FdlTelegram(...) without its ')'");
    }
    body.n--;
    sniff_t s = {.sd = -1, .da = -1, .sa = -1, .fc = -1, .ed = -1};
    size_t i = 0;
    while (i <= body.n) {
        size_t start = i;
        while (i < body.n && body.p[i] != ',') {
            i++;
        }
        if (!sniff_field(&s, trim((span_t){body.p + start, i - start}), rec->problem,
                         sizeof rec->problem)) {
            rec->len = 0;
            rec->orig_len = 0;
            return TEXT_LINE_BAD;
        }
        i++;
    }
    for (int f = 0; f < SF_COUNT; f++) {
        if (!s.seen[f]) {
            return bad(rec, "FdlTelegram without %s", sniff_names[f]);
        }
    }
    if (s.sd < 0) {
        return bad(rec, "FdlTelegram with sd=None");
    }
    if (s.dae.none || s.sae.none) {
        return bad(rec, "dae/sae None cannot be encoded (pyprofibus asserts bytes)");
    }
    if (s.have_le && s.du.none) {
        return bad(rec, "haveLE=True with du=None");
    }
    sink_t out = {.rec = rec};
    if (s.have_le) {
        size_t le = 3u + s.du.count + s.dae.count + s.sae.count;
        if (le > 0xFFu) {
            return bad(rec, "LE would be %zu, more than an octet", le);
        }
        put(&out, (uint8_t)s.sd);
        put(&out, (uint8_t)le);
        put(&out, (uint8_t)le);
    }
    put(&out, (uint8_t)s.sd);
    /* pyprofibus keeps 7-bit addresses and sets the extension bit when DAE/SAE octets follow. */
    if (s.da >= 0) {
        put(&out, (uint8_t)(((unsigned)s.da & ADDR_MASK) | (s.dae.count > 0u ? ADDR_EXT : 0u)));
    }
    if (s.sa >= 0) {
        put(&out, (uint8_t)(((unsigned)s.sa & ADDR_MASK) | (s.sae.count > 0u ? ADDR_EXT : 0u)));
    }
    if (s.fc >= 0) {
        put(&out, (uint8_t)s.fc);
    }
    emit_octets(&s.dae, &out);
    emit_octets(&s.sae, &out);
    emit_octets(&s.du, &out);
    if (s.have_fcs) {
        put(&out, s.have_le ? out.sum_from4 : out.sum_from1);
    }
    if (s.ed >= 0) {
        put(&out, (uint8_t)s.ed);
    }
    return record_done(st, rec, TEXT_SHAPE_PROFISNIFF);
}

/* ---- pyprofibus PHY debug lines ----------------------------------------------------------- */

/* "PHY-serial: TX   10 02 01 49 4C 16": the prefix is the PHY's PFX ("PHY: ", "PHY-serial: ",
 * "PHY-fpga: "); returns false when the line does not start with one. */
static bool phy_prefix(span_t line, size_t *after)
{
    if (!span_starts(line, "PHY")) {
        return false;
    }
    size_t i = 3;
    if (i < line.n && line.p[i] == '-') {
        i++;
        size_t start = i;
        while (i < line.n && i - start < 32u &&
               (is_digit(line.p[i]) || (to_upper(line.p[i]) >= 'A' && to_upper(line.p[i]) <= 'Z') ||
                line.p[i] == '_' || line.p[i] == '-')) {
            i++;
        }
        if (i == start) {
            return false;
        }
    }
    if (i >= line.n || line.p[i] != ':') {
        return false;
    }
    *after = i + 1u;
    return true;
}

static text_line_result_t import_phy(text_import_state_t *st, span_t msg, cap_record_t *rec)
{
    msg = trim(msg);
    if (span_starts(msg, "RX (fragment)")) {
        return TEXT_LINE_SKIP;
    }
    size_t pos = 0;
    span_t tok = next_token(msg, &pos);
    if (span_is(tok, "TX")) {
        rec->dir = CAP_DIR_TX;
    } else if (span_is(tok, "RX")) {
        rec->dir = CAP_DIR_RX;
    } else {
        return bad(rec, "pyprofibus message, not a telegram: '%s'", quote(msg).s);
    }
    sink_t out = {.rec = rec};
    if (!hex_octets(rest_of(msg, pos), &out, false, rec->problem, sizeof rec->problem)) {
        rec->len = 0;
        rec->orig_len = 0;
        return TEXT_LINE_BAD;
    }
    return record_done(st, rec, TEXT_SHAPE_PHY);
}

/* ---- ProSoft AN-X-PBCAPT ------------------------------------------------------------------ */

/* Frame control mnemonics of the AN-X-PBCAPT manual (page 27 of the AN-X-PB manual) with FCB and
 * FCV 0 (the analyser prints neither by default). SDAL..SDNH follow the manual's naming and its
 * equation example "SDNL"; the page listing them was not available (docs/captures.md). */
static const struct {
    const char *name;
    uint8_t fc;
} prosoft_fc[] = {
    {"SDAL", 0x43}, {"SDNL", 0x44}, {"SDAH", 0x45}, {"SDNH", 0x46}, {"RFDL", 0x49},
    {"MDLY", 0x4A}, {"MKEP", 0x4B}, {"SRDL", 0x4C}, {"SRDH", 0x4D}, {"RIR", 0x4E},
    {"RLSR", 0x4F}, {"MTM2", 0xC0}, {"OK", 0x00},   {"UE", 0x01},   {"RR", 0x02},
    {"RS", 0x03},   {"DL", 0x08},   {"NR", 0x09},   {"DH", 0x0A},   {"RDL", 0x0C},
    {"RDH", 0x0D},
};

/* Detailed status columns (DetailSts): '.' or the column's letter. */
static const char prosoft_status_letters[8] = {'s', 'p', 'd', 'r', 'u', 'o', 'c', 'e'};
static const char *const prosoft_status_names[8] = {
    "stop bit", "parity", "start delimiter", "SD repeat", "underrun", "overrun", "checksum",
    "end delimiter"};

static bool prosoft_status(span_t t)
{
    if (t.n < 8u) {
        return false;
    }
    for (size_t i = 0; i < 8u; i++) {
        if (t.p[i] != '.' && t.p[i] != prosoft_status_letters[i]) {
            return false;
        }
    }
    return true;
}

static bool all_digits(span_t t)
{
    if (t.n == 0u) {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        if (!is_digit(t.p[i])) {
            return false;
        }
    }
    return true;
}

/* A gap or delta value ("0,027", "0.002,975", "5,666"). */
static bool prosoft_number(span_t t)
{
    if (t.n == 0u || !is_digit(t.p[0])) {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        char c = t.p[i];
        if (!is_digit(c) && c != '.' && c != ',' && c != ':') {
            return false;
        }
    }
    return true;
}

/* A gap/delta graph: 'g' or 'd', then '.' or '*' only, maybe ending in the '|' that closes it. */
static bool prosoft_graph(span_t t)
{
    if (t.n < 2u || (t.p[0] != 'g' && t.p[0] != 'd')) {
        return false;
    }
    for (size_t i = 1; i < t.n; i++) {
        if (t.p[i] != '.' && t.p[i] != '*' && !(t.p[i] == '|' && i + 1u == t.n)) {
            return false;
        }
    }
    return true;
}

/* "120<0", "*255<", "<0": returns false when t is not shaped like that. */
static bool prosoft_addresses(span_t t, span_t *da, span_t *sa)
{
    size_t lt = 0;
    while (lt < t.n && t.p[lt] != '<') {
        lt++;
    }
    if (lt == t.n) {
        return false;
    }
    *da = (span_t){t.p, lt};
    *sa = span_from(t, lt + 1u);
    if ((da->n == 0u && sa->n == 0u) || (da->n > 0u && !all_digits(*da)) ||
        (sa->n > 0u && !all_digits(*sa))) {
        return false;
    }
    return true;
}

static bool small_decimal(span_t t, unsigned limit, unsigned *out)
{
    if (!all_digits(t) || t.n > 5u) {
        return false;
    }
    unsigned v = 0;
    for (size_t i = 0; i < t.n; i++) {
        v = v * 10u + (unsigned)(t.p[i] - '0');
    }
    *out = v;
    return v <= limit;
}

static int prosoft_sd(span_t t)
{
    if (span_is(t, "SD1")) {
        return SD1;
    }
    if (span_is(t, "SD2")) {
        return SD2;
    }
    if (span_is(t, "SD3")) {
        return SD3;
    }
    if (span_is(t, "SD4")) {
        return SD4;
    }
    if (span_is(t, "SC")) {
        return SC;
    }
    return -1;
}

/* Is this line ProSoft's? Its reference "46:", its timestamp "a 3.040,029" / "a11.000,517"
 * (a '.', ':' or ',' keeps "a2 04 ..." hex out), "120<0" or a delimiter name first. */
static bool prosoft_line(span_t line)
{
    size_t pos = 0;
    span_t first = next_token(line, &pos);
    span_t second = next_token(line, &pos);
    if (first.n >= 2u && first.p[first.n - 1u] == ':' &&
        all_digits((span_t){first.p, first.n - 1u})) {
        return true;
    }
    if (span_is(first, "a")) {
        return second.n > 0u && is_digit(second.p[0]);
    }
    if (first.n >= 2u && first.p[0] == 'a' && is_digit(first.p[1])) {
        for (size_t i = 1; i < first.n; i++) {
            if (first.p[i] == '.' || first.p[i] == ':' || first.p[i] == ',') {
                return true;
            }
        }
        return false;
    }
    span_t da;
    span_t sa;
    span_t f = (first.n > 0u && first.p[0] == '*') ? span_from(first, 1u) : first;
    if (prosoft_addresses(f, &da, &sa)) {
        return true;
    }
    return prosoft_sd(first) >= 0;
}

typedef struct prosoft_frame {
    int sd; /* -1: not written */
    bool have_da, have_sa, have_dsap, have_ssap, have_fc, have_fcs;
    unsigned da, sa, dsap, ssap;
    uint8_t fc, fcs;
    bool end_delimiter;
    bool marked_bad;      /* '*' instead of the detailed status */
    uint8_t status;       /* detailed status columns with a letter, bit i = column i+1 */
    span_t data;          /* the data tokens as one span, from the first to the last */
    size_t data_octets;
    bool e5;              /* "e5" alone: a short acknowledgement without delimiter names */
} prosoft_frame_t;

static void prosoft_problem_from_status(const prosoft_frame_t *f, cap_record_t *rec)
{
    if (rec->problem[0] != '\0') {
        return;
    }
    if (f->marked_bad) {
        (void)snprintf(rec->problem, sizeof rec->problem, "analyser marked the frame bad ('*')");
        return;
    }
    if (f->status == 0u) {
        return;
    }
    size_t n = (size_t)snprintf(rec->problem, sizeof rec->problem, "analyser status:");
    const char *separator = " ";
    for (unsigned i = 0; i < 8u && n < sizeof rec->problem; i++) {
        if ((f->status & (1u << i)) != 0u) {
            n += (size_t)snprintf(&rec->problem[n], sizeof rec->problem - n, "%s%s", separator,
                                  prosoft_status_names[i]);
            separator = ", ";
        }
    }
}

/* The telegram's own problem first; a rebuilt frame is usually clean, then the analyser's. */
static text_line_result_t prosoft_done(text_import_state_t *st, const prosoft_frame_t *f,
                                       cap_record_t *rec)
{
    text_line_result_t r = record_done(st, rec, TEXT_SHAPE_PROSOFT);
    if (r == TEXT_LINE_RECORD) {
        prosoft_problem_from_status(f, rec);
    }
    return r;
}

static text_line_result_t prosoft_build(text_import_state_t *st, prosoft_frame_t *f,
                                        cap_record_t *rec)
{
    sink_t out = {.rec = rec};
    bool addressed = f->have_da || f->have_sa;
    if (!addressed) {
        if (f->sd == SC || (f->sd < 0 && f->e5 && !f->have_fc)) {
            put(&out, SC);
            return prosoft_done(st, f, rec);
        }
        return bad(rec, "no addresses (written with NoDst/NoSrc?)");
    }
    if (!f->have_da) {
        return bad(rec, "no destination address (written with NoDst?)");
    }
    if (!f->have_sa) {
        return bad(rec, "no source address (written with NoSrc?)");
    }
    if (f->sd == SC) {
        return bad(rec, "SC with addresses");
    }
    bool token = !f->have_fc && !f->have_dsap && !f->have_ssap && f->data_octets == 0u;
    if (f->sd == SD4 || (f->sd < 0 && token)) {
        if (!token) {
            return bad(rec, "SD4 token with frame control or data");
        }
        if (f->have_fcs) {
            return bad(rec, "SD4 token with an FCS");
        }
        put(&out, SD4);
        put(&out, (uint8_t)f->da);
        put(&out, (uint8_t)f->sa);
        return prosoft_done(st, f, rec);
    }
    if (!f->have_fc) {
        return bad(rec, "no frame control");
    }
    size_t du = (f->have_dsap ? 1u : 0u) + (f->have_ssap ? 1u : 0u) + f->data_octets;
    int sd = f->sd >= 0 ? f->sd : (du == 0u ? (int)SD1 : (int)SD2);
    if (sd == SD1 && du != 0u) {
        return bad(rec, "SD1 with %zu data octets", du);
    }
    if (sd == SD3 && du != SD3_DU_LEN) {
        return bad(rec, "SD3 with %zu data octets, not 8", du);
    }
    if (sd == SD2 && du + 3u > 0xFFu) {
        return bad(rec, "%zu data octets, more than an SD2 holds", du);
    }
    if (sd == SD2) {
        put(&out, SD2);
        put(&out, (uint8_t)(du + 3u));
        put(&out, (uint8_t)(du + 3u));
    }
    put(&out, (uint8_t)sd);
    size_t fc_at = out.n + 2u;
    put(&out, (uint8_t)(f->da | (f->have_dsap ? ADDR_EXT : 0u)));
    put(&out, (uint8_t)(f->sa | (f->have_ssap ? ADDR_EXT : 0u)));
    put(&out, f->fc);
    if (f->have_dsap) {
        put(&out, (uint8_t)f->dsap);
    }
    if (f->have_ssap) {
        put(&out, (uint8_t)f->ssap);
    }
    char ignored[8];
    (void)hex_octets(f->data, &out, false, ignored, sizeof ignored);
    uint8_t fcs = sd == SD2 ? out.sum_from4 : out.sum_from1;
    if (f->have_fcs && f->fcs != fcs) {
        /* The written FCS covers the FC bits 5-4 the line does not show (FCB/FCV of a request,
         * station type of a reply): a difference of exactly those bits restores them. */
        uint8_t diff = (uint8_t)(f->fcs - fcs);
        if ((diff & ~FC_FCB_FCV_OR_TYPE) == 0u && (f->fc & FC_FCB_FCV_OR_TYPE) == 0u &&
            fc_at < rec->len) {
            rec->data[fc_at] = (uint8_t)(f->fc | diff);
        }
        fcs = f->fcs;
    }
    put(&out, fcs);
    put(&out, ED);
    return prosoft_done(st, f, rec);
}

static bool prosoft_fc_lookup(span_t t, uint8_t *fc)
{
    for (size_t i = 0; i < sizeof prosoft_fc / sizeof prosoft_fc[0]; i++) {
        if (span_is(t, prosoft_fc[i].name)) {
            *fc = prosoft_fc[i].fc;
            return true;
        }
    }
    return false;
}

static bool upper_word(span_t t)
{
    if (t.n == 0u || t.p[0] < 'A' || t.p[0] > 'Z') {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        char c = t.p[i];
        if (!((c >= 'A' && c <= 'Z') || is_digit(c))) {
            return false;
        }
    }
    return true;
}

static text_line_result_t import_prosoft(text_import_state_t *st, span_t line,
                                         cap_record_t *rec)
{
    /* A '?' is how the analyser marks what it could not decode ("FrmLen?(1)1e", "LE?(46)",
     * "SD?54"): nothing to rebuild from. */
    {
        size_t pos = 0;
        for (span_t t = next_token(line, &pos); t.n > 0u; t = next_token(line, &pos)) {
            if (memchr(t.p, '?', t.n) != NULL) {
                return bad(rec, "analyser reports a malformed frame: '%s'", quote(t).s);
            }
        }
    }
    size_t pos = 0;
    span_t t = next_token(line, &pos);
    if (t.n >= 2u && t.p[t.n - 1u] == ':' && all_digits((span_t){t.p, t.n - 1u})) {
        t = next_token(line, &pos);
    }
    /* Times, graphs and the graph's closing '|'. */
    for (;;) {
        if (t.n == 0u) {
            break;
        }
        if (t.p[0] == 'a' && !rec->has_time && (t.n == 1u || is_digit(t.p[1]))) {
            span_t value = t.n == 1u ? next_token(line, &pos) : span_from(t, 1u);
            parsed_time_t pt;
            time_parse_t r = parse_time(value, true, &pt);
            if (r != TIME_OK) {
                return bad_time(rec, r, value);
            }
            rec->has_time = true;
            rec->t_ns = pt.ns;
        } else if ((span_is(t, "d") || span_is(t, "g"))) {
            size_t peek = pos;
            span_t value = next_token(line, &peek);
            if (prosoft_number(value)) {
                pos = peek;
            }
        } else if ((t.p[0] == 'd' || t.p[0] == 'g') && prosoft_number(span_from(t, 1u))) {
            /* a gap or delta glued to its letter */
        } else if (!prosoft_graph(t) && !span_is(t, "|")) {
            break;
        }
        t = next_token(line, &pos);
    }

    prosoft_frame_t f = {.sd = -1};
    enum { BEFORE_ADDRESSES, SAPS, DATA } phase = BEFORE_ADDRESSES;
    const char *data_start = NULL;
    const char *data_end = NULL;
    for (; t.n > 0u; t = next_token(line, &pos)) {
        if (phase == BEFORE_ADDRESSES) {
            while (t.n > 0u && t.p[0] == '|') {
                t = span_from(t, 1u);
            }
            if (prosoft_status(t)) {
                for (unsigned i = 0; i < 8u; i++) {
                    if (t.p[i] != '.') {
                        f.status = (uint8_t)(f.status | (1u << i));
                    }
                }
                t = span_from(t, 8u);
            }
            if (t.n > 0u && t.p[0] == '*') {
                f.marked_bad = true;
                t = span_from(t, 1u);
            }
            if (t.n == 0u) {
                continue;
            }
            int sd = prosoft_sd(t);
            if (sd >= 0) {
                if (f.sd >= 0) {
                    return bad(rec, "two start delimiters: '%s'", quote(t).s);
                }
                f.sd = sd;
                continue;
            }
            span_t da;
    span_t sa;
            if (prosoft_addresses(t, &da, &sa)) {
                if (da.n > 0u) {
                    if (!small_decimal(da, ADDR_MASK, &f.da)) {
                        return bad(rec, "destination '%s' is not a station address (0..127)",
                                   quote(da).s);
                    }
                    f.have_da = true;
                }
                if (sa.n > 0u) {
                    if (!small_decimal(sa, ADDR_MASK, &f.sa)) {
                        return bad(rec, "source '%s' is not a station address (0..127)",
                                   quote(sa).s);
                    }
                    f.have_sa = true;
                }
                phase = SAPS;
                continue;
            }
            if ((span_is(t, "e5") || span_is(t, "E5")) && !f.e5) {
                f.e5 = true;
                continue;
            }
            if (upper_word(t) && prosoft_fc_lookup(t, &f.fc)) {
                return bad(rec, "frame control %s without addresses (written with NoDst/NoSrc?)",
                           quote(t).s);
            }
            return bad(rec, "unexpected '%s' before the addresses", quote(t).s);
        }
        if (phase == SAPS) {
            span_t num = t.n > 0u ? (span_t){t.p, t.n - 1u} : t;
            char mark = t.p[t.n - 1u];
            if ((mark == '^' || mark == '-') && all_digits(num)) {
                unsigned sap;
                if (!small_decimal(num, SAP_MAX, &sap)) {
                    return bad(rec, "SAP '%s' outside 0..63", quote(t).s);
                }
                if (mark == '^') {
                    if (f.have_dsap || f.have_ssap) {
                        return bad(rec, "destination SAP out of place: '%s'", quote(t).s);
                    }
                    f.have_dsap = true;
                    f.dsap = sap;
                } else {
                    if (f.have_ssap) {
                        return bad(rec, "two source SAPs: '%s'", quote(t).s);
                    }
                    f.have_ssap = true;
                    f.ssap = sap;
                }
                continue;
            }
            if (prosoft_fc_lookup(t, &f.fc)) {
                f.have_fc = true;
                phase = DATA;
                continue;
            }
            if (upper_word(t) && !all_hex(t)) {
                return bad(rec, "unknown frame control '%s'", quote(t).s);
            }
            return bad(rec, "no frame control before '%s'", quote(t).s);
        }
        /* DATA: hex octets, then maybe "ED" (only written with the delimiter names) and the FCS
         * "[3e]" (ShowFcs) in either order. */
        if (t.n >= 3u && t.p[0] == '[' && t.p[t.n - 1u] == ']') {
            span_t hex = {t.p + 1, t.n - 2u};
            if (f.have_fcs || hex.n > 2u || !all_hex(hex)) {
                return bad(rec, "not an FCS: '%s'", quote(t).s);
            }
            f.have_fcs = true;
            f.fcs = (uint8_t)(hex.n == 2u ? hex_value(hex.p[0]) * 16 + hex_value(hex.p[1])
                                          : hex_value(hex.p[0]));
            continue;
        }
        if (f.sd >= 0 && span_is(t, "ED")) {
            f.end_delimiter = true;
            continue;
        }
        if (f.have_fcs || f.end_delimiter) {
            return bad(rec, "data after the FCS or end delimiter: '%s'", quote(t).s);
        }
        sink_t count = {0};
        if (!hex_word(t, &count, rec->problem, sizeof rec->problem)) {
            rec->len = 0;
            rec->orig_len = 0;
            return TEXT_LINE_BAD;
        }
        f.data_octets += count.n;
        if (data_start == NULL) {
            data_start = t.p;
        }
        data_end = t.p + t.n;
    }
    f.data = data_start != NULL ? (span_t){data_start, (size_t)(data_end - data_start)}
                                : (span_t){line.p, 0};
    return prosoft_build(st, &f, rec);
}

/* ---- the generic shape: [time] [direction] hex -------------------------------------------- */

static bool direction_marker(span_t t, cap_dir_t *dir, bool *export_marker)
{
    *export_marker = false;
    if (span_is_nocase(t, "TX") || span_is_nocase(t, "TX:") || span_is(t, ">") ||
        span_is(t, "->") || span_is_nocase(t, "M>")) {
        *dir = CAP_DIR_TX;
        *export_marker = span_is(t, "TX");
        return true;
    }
    if (span_is_nocase(t, "RX") || span_is_nocase(t, "RX:") || span_is(t, "<") ||
        span_is(t, "<-") || span_is_nocase(t, "S<")) {
        *dir = CAP_DIR_RX;
        *export_marker = span_is(t, "RX");
        return true;
    }
    if (span_is(t, "--")) {
        *dir = CAP_DIR_UNKNOWN;
        *export_marker = true;
        return true;
    }
    return false;
}

/* Digits with a '.', a ':' or a trailing 's': a time or nothing ("68:05:05" is hex again once
 * it fails as a time of day); digits alone are hex, however many. */
static bool time_shaped(span_t t)
{
    bool mark = false;
    for (size_t i = 0; i < t.n; i++) {
        char c = t.p[i];
        if (c == '.' || c == ':' || (c == 's' && i + 1u == t.n && i > 0u)) {
            mark = true;
        } else if (!is_digit(c)) {
            return false;
        }
    }
    return mark && is_digit(t.p[0]);
}

static bool is_comment(span_t line)
{
    return line.p[0] == '#' || line.p[0] == ';' || span_starts(line, "//");
}

text_line_result_t text_import_line(text_import_state_t *st, const char *line, size_t len,
                                    cap_record_t *rec)
{
    st->line++;
    record_start(rec, st->line);
    if (len > TEXT_IMPORT_MAX_LINE) {
        return bad(rec, "line longer than %u characters", TEXT_IMPORT_MAX_LINE);
    }
    span_t l = {line, line != NULL ? len : 0u};
    /* Editors on Windows start a UTF-8 file with a byte order mark. */
    if (st->line == 1u && span_starts(l, "\xEF\xBB\xBF")) {
        l = span_from(l, 3u);
    }
    while (l.n > 0u && (l.p[l.n - 1u] == '\r' || l.p[l.n - 1u] == '\n')) {
        l.n--;
    }
    l = trim(l);
    if (l.n == 0u || is_comment(l)) {
        return TEXT_LINE_SKIP;
    }
    if (prosoft_line(l)) {
        return import_prosoft(st, l, rec);
    }

    size_t pos = 0;
    bool export_time = false;
    /* "[12.345678]", "[   12.345678]" (dmesg) */
    if (l.p[0] == '[') {
        size_t close = 1;
        while (close < l.n && l.p[close] != ']') {
            close++;
        }
        if (close == l.n) {
            return bad(rec, "no ']' after '%s'", quote(l).s);
        }
        span_t inner = trim((span_t){l.p + 1, close - 1u});
        parsed_time_t pt;
        time_parse_t r = parse_time(inner, false, &pt);
        if (r != TIME_OK || pt.fields != 1u) {
            return bad_time(rec, r == TIME_OK ? TIME_NOT_A_TIME : r, inner);
        }
        rec->has_time = true;
        rec->t_ns = pt.ns;
        pos = close + 1u;
    } else {
        size_t after = 0;
        span_t first = next_token(l, &after);
        size_t peek = after;
        bool more = next_token(l, &peek).n > 0u;
        parsed_time_t pt;
        time_parse_t r = time_shaped(first) ? parse_time(first, false, &pt) : TIME_NOT_A_TIME;
        /* A lone number is hex ("10 02 ..."); a time has a fraction, a unit or is h:mm:ss with
         * something after it ("10:02:01" alone is three octets). */
        bool timed = r == TIME_OK &&
                     ((pt.fields == 1u && (pt.fraction_digits >= 0 || pt.unit_s)) ||
                      (pt.fields == 3u && pt.ns < SECONDS_PER_DAY * NS_PER_S &&
                       (more || pt.fraction_digits >= 0)));
        if (timed) {
            rec->has_time = true;
            rec->t_ns = pt.ns;
            export_time = pt.fields == 1u && pt.fraction_digits == 9 && !pt.unit_s;
            pos = after;
        } else if (r == TIME_TOO_BIG || r == TIME_TOO_PRECISE) {
            return bad_time(rec, r, first);
        }
    }
    size_t peek = pos;
    span_t marker = next_token(l, &peek);
    bool export_marker = false;
    bool have_dir = false;
    if (marker.n > 0u && direction_marker(marker, &rec->dir, &export_marker)) {
        have_dir = true;
        pos = peek;
    }
    span_t rest = rest_of(l, pos);
    size_t phy_at = 0;
    if (span_starts(rest, "FdlTelegram(")) {
        return import_profisniff(st, span_from(rest, strlen("FdlTelegram(")), rec);
    }
    if (phy_prefix(rest, &phy_at)) {
        return import_phy(st, span_from(rest, phy_at), rec);
    }
    sink_t out = {.rec = rec};
    if (!hex_octets(rest, &out, true, rec->problem, sizeof rec->problem)) {
        rec->len = 0;
        rec->orig_len = 0;
        return TEXT_LINE_BAD;
    }
    if (out.n == 0u) {
        return bad(rec, have_dir ? "no octets after the direction" : "no octets after the time");
    }
    bool export_shape = export_time && have_dir && export_marker;
    return record_done(st, rec, export_shape ? TEXT_SHAPE_EXPORT : TEXT_SHAPE_HEX);
}

void text_import_init(text_import_state_t *st)
{
    *st = (text_import_state_t){0};
}

const char *text_shape_name(uint32_t shape)
{
    switch (shape) {
    case TEXT_SHAPE_HEX:
        return "hex";
    case TEXT_SHAPE_EXPORT:
        return "dfp-sim export";
    case TEXT_SHAPE_PHY:
        return "pyprofibus PHY";
    case TEXT_SHAPE_PROFISNIFF:
        return "pyprofibus profisniff";
    case TEXT_SHAPE_PROSOFT:
        return "ProSoft AN-X-PBCAPT";
    default:
        return "?";
    }
}

/* ---- export ------------------------------------------------------------------------------- */

size_t text_export_line(char *out, size_t max, uint64_t t_ns, cap_dir_t dir,
                        const uint8_t *data, size_t len)
{
    if (out == NULL || max == 0u) {
        return 0;
    }
    out[0] = '\0';
    if (data == NULL && len > 0u) {
        return 0;
    }
    const char *marker = dir == CAP_DIR_TX ? "TX" : dir == CAP_DIR_RX ? "RX" : "--";
    char head[48];
    int h = snprintf(head, sizeof head, "%" PRIu64 ".%09" PRIu64 " %s",
                     (uint64_t)(t_ns / NS_PER_S), (uint64_t)(t_ns % NS_PER_S), marker);
    if (h < 0 || (size_t)h >= sizeof head) {
        return 0;
    }
    size_t head_len = (size_t)h;
    if (max - 1u < head_len || len > (max - 1u - head_len) / 3u) {
        return 0;
    }
    static const char digits[] = "0123456789ABCDEF";
    memcpy(out, head, head_len);
    size_t n = head_len;
    for (size_t i = 0; i < len; i++) {
        out[n++] = ' ';
        out[n++] = digits[data[i] >> 4];
        out[n++] = digits[data[i] & 0x0Fu];
    }
    out[n] = '\0';
    return n;
}
