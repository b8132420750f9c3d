/* Names for people (movidrive_names.h) over the generated tables in movidrive_names_table.c. */
#include "movidrive/movidrive_names.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "movidrive_names_table.h"
#include "movidrive_params.h"

#define MAX_LISTED 5u /* an ambiguous name lists this many candidates */

/* ---- small helpers --------------------------------------------------------------------- */

/* Appends like snprintf to a buffer that may be too small (or absent), counting what a large
 * enough one would hold, so callers can return snprintf's result. */
typedef struct appender {
    char *out;
    size_t n;
    size_t len;
} appender_t;

static appender_t app_init(char *out, size_t n)
{
    appender_t a = {.out = out, .n = n, .len = 0u};
    if (out != NULL && n > 0u) {
        out[0] = '\0';
    }
    return a;
}

static void app(appender_t *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void app(appender_t *a, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *dst = a->out != NULL && a->len < a->n ? a->out + a->len : NULL;
    size_t room = dst != NULL ? a->n - a->len : 0u;
    int k = vsnprintf(dst, room, fmt, ap);
    va_end(ap);
    if (k > 0) {
        a->len += (size_t)k;
    }
}

static int app_result(const appender_t *a)
{
    return a->len > (size_t)INT32_MAX ? INT32_MAX : (int)a->len;
}

static void set_err(char *err, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void set_err(char *err, size_t n, const char *fmt, ...)
{
    if (err == NULL || n == 0u) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, n, fmt, ap);
    va_end(ap);
}

static int lower(char c)
{
    return tolower((unsigned char)c);
}

/* Case-insensitive: a[0..alen) equals the whole of b. */
static bool ci_equal(const char *a, size_t alen, const char *b)
{
    size_t i = 0;
    for (; i < alen && b[i] != '\0'; i++) {
        if (lower(a[i]) != lower(b[i])) {
            return false;
        }
    }
    return i == alen && b[i] == '\0';
}

/* Case-insensitive: needle[0..nlen) occurs in hay. */
static bool ci_contains(const char *hay, const char *needle, size_t nlen)
{
    size_t hlen = strlen(hay);
    for (size_t i = 0; i + nlen <= hlen; i++) {
        size_t k = 0;
        while (k < nlen && lower(hay[i + k]) == lower(needle[k])) {
            k++;
        }
        if (k == nlen) {
            return true;
        }
    }
    return false;
}

/* The text without leading and trailing blanks: start and length. */
static const char *trim(const char *s, size_t *len)
{
    while (*s != '\0' && isspace((unsigned char)*s)) {
        s++;
    }
    size_t n = strlen(s);
    while (n > 0u && isspace((unsigned char)s[n - 1u])) {
        n--;
    }
    *len = n;
    return s;
}

static const movidrive_param_def_t *param_def(uint16_t index)
{
    size_t lo = 0;
    size_t hi = movidrive_params_count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2u;
        if (movidrive_params[mid].index == index) {
            return &movidrive_params[mid];
        }
        if (movidrive_params[mid].index < index) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

static bool is_unsigned(const movidrive_param_info_t *p)
{
    const movidrive_param_def_t *d = param_def(p->index);
    return d != NULL && (d->flags & MOVIDRIVE_PF_UNSIGNED) != 0u;
}

static int64_t pow10_i64(int32_t e)
{
    int64_t v = 1;
    for (int32_t i = 0; i < e && i < 18; i++) {
        v *= 10;
    }
    return v;
}

/* ---- parameters ------------------------------------------------------------------------ */

const movidrive_param_info_t *movidrive_param_info(uint16_t index)
{
    size_t lo = 0;
    size_t hi = movidrive_param_infos_count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2u;
        const movidrive_param_info_t *p =
            &movidrive_param_infos[movidrive_param_infos_by_index[mid]];
        if (p->index == index) {
            return p;
        }
        if (p->index < index) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

size_t movidrive_param_count(void)
{
    return movidrive_param_infos_count;
}

const movidrive_param_info_t *movidrive_param_at(size_t i)
{
    return i < movidrive_param_infos_count ? &movidrive_param_infos[i] : NULL;
}

/* "'speed' matches 12 parameters: P000 speed, P001 ..., ..." */
static void ambiguous(const char *s, size_t len, bool exact, char *err, size_t errlen)
{
    size_t count = 0;
    for (size_t i = 0; i < movidrive_param_infos_count; i++) {
        const char *name = movidrive_param_infos[i].name;
        if (exact ? ci_equal(s, len, name) : ci_contains(name, s, len)) {
            count++;
        }
    }
    appender_t a = app_init(err, errlen);
    app(&a, "'%.*s' matches %zu parameters:", (int)len, s, count);
    size_t listed = 0;
    for (size_t i = 0; i < movidrive_param_infos_count && listed < MAX_LISTED; i++) {
        const movidrive_param_info_t *p = &movidrive_param_infos[i];
        if (exact ? ci_equal(s, len, p->name) : ci_contains(p->name, s, len)) {
            app(&a, "%s %s %s", listed == 0u ? "" : ",", p->p_number, p->name);
            listed++;
        }
    }
    if (count > listed) {
        app(&a, ", ...");
    }
    (void)app_result(&a);
}

static bool all_digits(const char *s, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        if (!isdigit((unsigned char)s[i])) {
            return false;
        }
    }
    return len > 0u;
}

/* "P100", or an error memory sub-entry "P080.Speed"; aliases (P031 = P600) included. */
static const movidrive_param_info_t *find_by_p_number(const char *s, size_t len, char *err,
                                               size_t errlen)
{
    for (size_t i = 0; i < movidrive_param_infos_count; i++) {
        if (ci_equal(s, len, movidrive_param_infos[i].p_number)) {
            return &movidrive_param_infos[i];
        }
    }
    for (size_t i = 0; i < movidrive_param_aliases_count; i++) {
        if (ci_equal(s, len, movidrive_param_aliases[i].p_number)) {
            return movidrive_param_info(movidrive_param_aliases[i].index);
        }
    }
    set_err(err, errlen, "no parameter '%.*s'", (int)len, s);
    return NULL;
}

/* "H12": never a table parameter, but the reason says what it is. */
static void explain_ipos_variable(const char *s, size_t len, char *err, size_t errlen)
{
    long n = strtol(s + 1, NULL, 10);
    if (n >= 0 && n <= 511) {
        set_err(err, errlen, "'%.*s' is IPOS variable H%ld (index %ld), not a table parameter",
                (int)len, s, n, 11000 + n);
    } else {
        set_err(err, errlen, "no parameter '%.*s' (IPOS variables are H0..H511)", (int)len, s);
    }
}

/* The len characters at s as a C string for strtoul/strtoll; false if they do not fit. */
static bool copy_token(char *out, size_t cap, const char *s, size_t len)
{
    if (len >= cap) {
        return false;
    }
    memcpy(out, s, len);
    out[len] = '\0';
    return true;
}

/* An index, decimal or 0xHEX. False when the text is no number after all ("4-quadrant
 * operation 1" is a name); true with *found (NULL and a reason when no parameter has it). */
static bool find_by_index(const char *s, size_t len, const movidrive_param_info_t **found,
                          char *err, size_t errlen)
{
    char num[24];
    if (!copy_token(num, sizeof num, s, len)) {
        return false;
    }
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(num, &end, 0);
    if (*end != '\0' || errno != 0) {
        return false;
    }
    *found = NULL;
    if (v > 65535u) {
        set_err(err, errlen, "index %s is out of 0..65535", num);
        return true;
    }
    *found = movidrive_param_info((uint16_t)v);
    if (*found == NULL) {
        set_err(err, errlen, "no parameter with index %lu", v);
    }
    return true;
}

/* The one parameter whose name equals the text, or else the one whose name contains it. */
static const movidrive_param_info_t *find_by_name(const char *s, size_t len, char *err,
                                                  size_t errlen)
{
    for (int exact = 1; exact >= 0; exact--) {
        const movidrive_param_info_t *hit = NULL;
        size_t hits = 0;
        for (size_t i = 0; i < movidrive_param_infos_count; i++) {
            const char *name = movidrive_param_infos[i].name;
            if (exact ? ci_equal(s, len, name) : ci_contains(name, s, len)) {
                hit = &movidrive_param_infos[i];
                hits++;
            }
        }
        if (hits == 1u) {
            return hit;
        }
        if (hits > 1u) {
            ambiguous(s, len, exact != 0, err, errlen);
            return NULL;
        }
    }
    set_err(err, errlen, "no parameter '%.*s'", (int)len, s);
    return NULL;
}

const movidrive_param_info_t *movidrive_param_find(const char *text, char *err, size_t errlen)
{
    size_t len = 0;
    const char *s = text != NULL ? trim(text, &len) : "";
    if (len == 0u) {
        set_err(err, errlen, "no parameter given (P-number, index or name)");
        return NULL;
    }
    if (len > 80u) {
        set_err(err, errlen, "no parameter '%.40s...'", s);
        return NULL;
    }
    if ((s[0] == 'P' || s[0] == 'p') && len >= 2u && isdigit((unsigned char)s[1])) {
        return find_by_p_number(s, len, err, errlen);
    }
    if ((s[0] == 'H' || s[0] == 'h') && all_digits(s + 1, len - 1u)) {
        explain_ipos_variable(s, len, err, errlen);
        return NULL;
    }
    const movidrive_param_info_t *found = NULL;
    if (isdigit((unsigned char)s[0]) && find_by_index(s, len, &found, err, errlen)) {
        return found;
    }
    return find_by_name(s, len, err, errlen);
}

/* ---- values ---------------------------------------------------------------------------- */

const char *movidrive_enum_text(const movidrive_param_info_t *p, int32_t raw)
{
    if (p == NULL) {
        return NULL;
    }
    for (uint16_t i = 0; i < p->num_enums; i++) {
        if (p->enums[i].value == raw) {
            return p->enums[i].text;
        }
    }
    return NULL;
}

int movidrive_value_text(const movidrive_param_info_t *p, int32_t raw, char *out, size_t n)
{
    appender_t a = app_init(out, n);
    if (p == NULL) {
        app(&a, "%ld", (long)raw);
        return app_result(&a);
    }
    if (p->num_enums > 0u) {
        const char *t = movidrive_enum_text(p, raw);
        app(&a, "%ld (%s)", (long)raw, t != NULL ? t : "unknown value");
        return app_result(&a);
    }
    int64_t v = is_unsigned(p) ? (int64_t)(uint32_t)raw : (int64_t)raw;
    const char *sep = p->unit[0] != '\0' ? " " : "";
    if (p->scale_exp >= 0) {
        app(&a, "%lld%s%s", (long long)v * (long long)pow10_i64(p->scale_exp), sep, p->unit);
    } else {
        int32_t decimals = -p->scale_exp;
        int64_t d = pow10_i64(decimals);
        uint64_t mag = v < 0 ? (uint64_t)(-v) : (uint64_t)v;
        app(&a, "%s%llu.%0*llu%s%s", v < 0 ? "-" : "", (unsigned long long)(mag / (uint64_t)d),
            (int)decimals, (unsigned long long)(mag % (uint64_t)d), sep, p->unit);
    }
    return app_result(&a);
}

/* A decimal number as read from the text: sign, whole part, fraction digits (no more than the
 * parameter's decimals), whether a point or the unit was there. */
typedef struct decimal {
    bool neg;
    uint64_t whole;
    size_t wdigits;
    uint64_t frac;
    size_t fdigits;
    bool point;
    bool unit;
} decimal_t;

/* Sign and whole part from s[*i]; false with a reason when it is beyond any 32-bit value. */
static bool read_whole(const char *s, size_t len, size_t *i, decimal_t *d, char *err,
                       size_t errlen)
{
    if (*i < len && (s[*i] == '-' || s[*i] == '+')) {
        d->neg = s[*i] == '-';
        (*i)++;
    }
    while (*i < len && isdigit((unsigned char)s[*i])) {
        if (d->whole > 1000000000000ull) {
            set_err(err, errlen, "'%.*s' is out of the 32-bit range", (int)len, s);
            return false;
        }
        d->whole = d->whole * 10u + (uint64_t)(s[*i] - '0');
        d->wdigits++;
        (*i)++;
    }
    return true;
}

/* ".25" from s[*i]; false with a reason when it has more non-zero decimals than allowed. */
static bool read_fraction(const movidrive_param_info_t *p, const char *s, size_t len, size_t *i,
                          int32_t decimals, decimal_t *d, char *err, size_t errlen)
{
    if (*i >= len || s[*i] != '.') {
        return true;
    }
    d->point = true;
    (*i)++;
    while (*i < len && isdigit((unsigned char)s[*i])) {
        if ((int32_t)d->fdigits < decimals) {
            d->frac = d->frac * 10u + (uint64_t)(s[*i] - '0');
            d->fdigits++;
        } else if (s[*i] != '0') {
            set_err(err, errlen, "'%.*s' has more than %ld decimal%s for %s", (int)len, s,
                    (long)decimals, decimals == 1 ? "" : "s",
                    p != NULL && p->unit[0] != '\0' ? p->unit : "this parameter");
            return false;
        }
        (*i)++;
    }
    return true;
}

/* A value in the unit to the raw magnitude: × 10^decimals, or ÷ 10^scale_exp for a positive
 * scale (false with a reason when it is no multiple of that). */
static bool unit_to_raw(const movidrive_param_info_t *p, const char *s, size_t len, decimal_t *d,
                        int32_t decimals, uint64_t *mag, char *err, size_t errlen)
{
    while ((int32_t)d->fdigits < decimals) {
        d->frac *= 10u;
        d->fdigits++;
    }
    if (p != NULL && p->scale_exp > 0) {
        uint64_t div = (uint64_t)pow10_i64(p->scale_exp);
        if (d->whole % div != 0u) {
            set_err(err, errlen, "'%.*s' is not a multiple of %llu %s", (int)len, s,
                    (unsigned long long)div, p->unit);
            return false;
        }
        *mag = d->whole / div;
        return true;
    }
    *mag = d->whole * (uint64_t)pow10_i64(decimals) + d->frac;
    return true;
}

/* "300.5", "-1.25 rpm", "2000 ms": sign, digits, optional fraction, optional unit. Raw value
 * in *raw; false with a reason. *scaled tells whether it was a value in the unit (a fraction or
 * a unit given) rather than a raw integer. */
static bool parse_number(const movidrive_param_info_t *p, const char *s, size_t len, int64_t *raw,
                         bool *scaled, char *err, size_t errlen)
{
    decimal_t d = {0};
    size_t i = 0;
    int32_t decimals = p != NULL && p->scale_exp < 0 ? -p->scale_exp : 0;
    if (!read_whole(s, len, &i, &d, err, errlen) ||
        !read_fraction(p, s, len, &i, decimals, &d, err, errlen)) {
        return false;
    }
    if (d.wdigits == 0u && !(d.point && d.fdigits > 0u)) {
        return false;
    }
    while (i < len && s[i] == ' ') {
        i++;
    }
    if (i < len) {
        if (p == NULL || p->unit[0] == '\0' || !ci_equal(s + i, len - i, p->unit)) {
            return false;
        }
        d.unit = true;
    }
    *scaled = d.point || d.unit;
    uint64_t mag = d.whole;
    if (*scaled && !unit_to_raw(p, s, len, &d, decimals, &mag, err, errlen)) {
        return false;
    }
    *raw = d.neg ? -(int64_t)mag : (int64_t)mag;
    return true;
}

/* A raw integer as strtoll reads it, so the hexadecimal and octal forms work too ("0x10").
 * False when the text is no such integer; true with *ok false and a reason when it is beyond
 * 32 bits. */
static bool parse_raw_integer(const char *s, size_t len, int32_t *raw, bool *ok, char *err,
                              size_t errlen)
{
    char num[32];
    if (!copy_token(num, sizeof num, s, len)) {
        return false;
    }
    char *end = NULL;
    errno = 0;
    long long v = strtoll(num, &end, 0);
    if (*end != '\0' || end == num) {
        return false;
    }
    *ok = errno == 0 && v >= INT32_MIN && v <= (long long)UINT32_MAX;
    if (!*ok) {
        set_err(err, errlen, "'%s' is out of the 32-bit range", num);
        return true;
    }
    *raw = (int32_t)(uint32_t)(uint64_t)v;
    return true;
}

/* The reason a text is no value of p: the enumeration texts, or the number forms it takes. */
static void explain_not_a_value(const movidrive_param_info_t *p, const char *s, size_t len,
                                char *err, size_t errlen)
{
    if (p == NULL) {
        set_err(err, errlen, "'%.*s' is not a number (decimal, -N or 0xHEX)", (int)len, s);
        return;
    }
    appender_t a = app_init(err, errlen);
    if (p->num_enums > 0u) {
        app(&a, "'%.*s' is not a value of %s %s:", (int)len, s, p->p_number, p->name);
        uint16_t k = 0;
        for (; k < p->num_enums && k < MAX_LISTED; k++) {
            app(&a, "%s %s", k == 0u ? "" : ",", p->enums[k].text);
        }
        app(&a, "%s or a number", k < p->num_enums ? ", ..." : ",");
    } else if (p->unit[0] != '\0' || p->scale_exp != 0) {
        app(&a, "'%.*s' is not a number for %s %s (raw integer, or %s with up to %ld decimals)",
            (int)len, s, p->p_number, p->name, p->unit[0] != '\0' ? p->unit : "a value",
            (long)(p->scale_exp < 0 ? -p->scale_exp : 0));
    } else {
        app(&a, "'%.*s' is not a number for %s %s (decimal, -N or 0xHEX)", (int)len, s,
            p->p_number, p->name);
    }
    (void)app_result(&a);
}

bool movidrive_value_parse(const movidrive_param_info_t *p, const char *text, int32_t *raw,
                           char *err, size_t errlen)
{
    size_t len = 0;
    const char *s = text != NULL ? trim(text, &len) : "";
    if (len == 0u) {
        set_err(err, errlen, "no value given");
        return false;
    }
    for (uint16_t i = 0; p != NULL && i < p->num_enums; i++) {
        if (ci_equal(s, len, p->enums[i].text)) {
            *raw = p->enums[i].value;
            return true;
        }
    }
    bool ok = false;
    if (parse_raw_integer(s, len, raw, &ok, err, errlen)) {
        return ok;
    }
    int64_t v = 0;
    bool scaled = false;
    char why[160] = "";
    if (parse_number(p, s, len, &v, &scaled, why, sizeof why)) {
        bool uns = p != NULL && is_unsigned(p);
        if (v < (uns ? 0 : INT32_MIN) || v > (uns ? (int64_t)UINT32_MAX : INT32_MAX)) {
            set_err(err, errlen, "'%.*s' is out of %s range", (int)len, s,
                    uns ? "the unsigned 32-bit" : "the 32-bit");
            return false;
        }
        *raw = (int32_t)(uint32_t)(uint64_t)v;
        return true;
    }
    if (why[0] != '\0') {
        set_err(err, errlen, "%s", why);
        return false;
    }
    explain_not_a_value(p, s, len, err, errlen);
    return false;
}

/* ---- faults, unit status, control and status words ------------------------------------- */

static const char *code_name(const movidrive_code_name_t *t, size_t n, uint8_t code)
{
    for (size_t i = 0; i < n; i++) {
        if (t[i].code == code) {
            return t[i].name;
        }
    }
    return NULL;
}

const char *movidrive_fault_name(uint8_t fault)
{
    return code_name(movidrive_fault_names, movidrive_fault_names_count, fault);
}

const char *movidrive_unit_status_name(uint8_t code)
{
    return code_name(movidrive_unit_status_names, movidrive_unit_status_names_count, code);
}

/* Bits 0..2 say what they mean set or clear; the others only when set. */
static void word_bits(appender_t *a, const movidrive_bit_text_t *bits, uint16_t w, uint16_t skip)
{
    bool first = true;
    for (unsigned b = 0; b < 8u; b++) {
        if ((skip & (1u << b)) != 0u) {
            continue;
        }
        bool set = (w & (1u << b)) != 0u;
        const char *t = set ? bits[b].set : (b < 3u ? bits[b].clear : "");
        if (t[0] == '\0') {
            continue;
        }
        app(a, "%s%s", first ? "" : ", ", t);
        first = false;
    }
}

int movidrive_control_word_text(uint16_t cw, char *out, size_t n)
{
    appender_t a = app_init(out, n);
    app(&a, "%04X = ", cw);
    word_bits(&a, movidrive_control_bits, cw, 0u);
    if ((cw >> 8) != 0u) {
        app(&a, ", high byte 0x%02X", (unsigned)(cw >> 8));
    }
    return app_result(&a);
}

int movidrive_status_word_text(uint16_t sw, char *out, size_t n)
{
    appender_t a = app_init(out, n);
    app(&a, "%04X = ", sw);
    word_bits(&a, movidrive_status_bits, sw, 1u << 5); /* bit 5 shows as the fault below */
    uint8_t high = (uint8_t)(sw >> 8);
    if ((sw & 0x0020u) != 0u) {
        const char *f = movidrive_fault_name(high);
        app(&a, ", fault %u (%s)", (unsigned)high, f != NULL ? f : "unknown");
    } else {
        const char *u = movidrive_unit_status_name(high);
        app(&a, ", unit status %u (%s)", (unsigned)high, u != NULL ? u : "unknown");
    }
    return app_result(&a);
}
