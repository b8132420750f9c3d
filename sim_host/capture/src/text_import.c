/* Text captures, one telegram per line (capture/text_import.h lists the shapes, docs/captures.md
 * shows them with examples and says what is rebuilt and what is lost). This module finds the
 * line's shape, reads the generic one ([time] [direction] hex, dfp-sim's own export among them)
 * and finishes records for all; ProSoft, pyprofibus PHY and profisniff lines have their own
 * modules (text_formats.h). */
#include "capture/text_import.h"

#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "text_formats.h"

#define SECONDS_PER_DAY 86400ull

/* ---- finishing a record ------------------------------------------------------------------- */

static void refuse_line(cap_record_t *rec, const char *fmt, va_list ap)
{
    (void)vsnprintf(rec->problem, sizeof rec->problem, fmt, ap);
    rec->len = 0;
    rec->orig_len = 0;
}

text_line_result_t text_bad(cap_record_t *rec, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    refuse_line(rec, fmt, ap);
    va_end(ap);
    return TEXT_LINE_BAD;
}

bool text_refuse(cap_record_t *rec, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    refuse_line(rec, fmt, ap);
    va_end(ap);
    return false;
}

text_line_result_t text_bad_time(cap_record_t *rec, time_parse_t r, span_t tok)
{
    if (r == TIME_TOO_BIG) {
        return text_bad(rec, "time beyond 10^10 s: '%s'", quote_span(tok).s);
    }
    if (r == TIME_TOO_PRECISE) {
        return text_bad(rec, "more than 9 fraction digits: '%s'", quote_span(tok).s);
    }
    return text_bad(rec, "not a time: '%s'", quote_span(tok).s);
}

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

text_line_result_t text_record_done(text_import_state_t *st, cap_record_t *rec, uint32_t shape)
{
    if (rec->orig_len == 0u) {
        return text_bad(rec, "no octets");
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
        } else if (!char_is_digit(c)) {
            return false;
        }
    }
    return mark && char_is_digit(t.p[0]);
}

static bool is_comment(span_t line)
{
    return line.p[0] == '#' || line.p[0] == ';' || span_starts(line, "//");
}

/* "[12.345678]", "[   12.345678]" (dmesg): seconds only. */
static bool bracketed_time(span_t l, size_t *pos, cap_record_t *rec)
{
    size_t close = 1;
    while (close < l.n && l.p[close] != ']') {
        close++;
    }
    if (close == l.n) {
        return text_refuse(rec, "no ']' after '%s'", quote_span(l).s);
    }
    span_t inner = span_trim((span_t){l.p + 1, close - 1u});
    parsed_time_t pt;
    time_parse_t r = text_parse_time(inner, false, &pt);
    if (r != TIME_OK || pt.fields != 1u) {
        (void)text_bad_time(rec, r == TIME_OK ? TIME_NOT_A_TIME : r, inner);
        return false;
    }
    rec->has_time = true;
    rec->t_ns = pt.ns;
    *pos = close + 1u;
    return true;
}

/* A first token that is a time. A lone number is hex ("10 02 ..."); a time has a fraction, a
 * unit or is h:mm:ss with something after it ("10:02:01" alone is three octets).
 * *export_time: written as dfp-sim's export writes it (seconds and 9 fraction digits). */
static bool leading_time(span_t l, size_t *pos, cap_record_t *rec, bool *export_time)
{
    size_t after = 0;
    span_t first = span_next_token(l, &after);
    size_t peek = after;
    bool more = span_next_token(l, &peek).n > 0u;
    parsed_time_t pt;
    time_parse_t r = time_shaped(first) ? text_parse_time(first, false, &pt) : TIME_NOT_A_TIME;
    bool timed = r == TIME_OK &&
                 ((pt.fields == 1u && (pt.fraction_digits >= 0 || pt.unit_s)) ||
                  (pt.fields == 3u && pt.ns < SECONDS_PER_DAY * NS_PER_S &&
                   (more || pt.fraction_digits >= 0)));
    if (timed) {
        rec->has_time = true;
        rec->t_ns = pt.ns;
        *export_time = pt.fields == 1u && pt.fraction_digits == 9 && !pt.unit_s;
        *pos = after;
    } else if (r == TIME_TOO_BIG || r == TIME_TOO_PRECISE) {
        (void)text_bad_time(rec, r, first);
        return false;
    }
    return true;
}

/* [time] [direction], then a pyprofibus line or hex octets. */
static text_line_result_t import_generic(text_import_state_t *st, span_t l, cap_record_t *rec)
{
    size_t pos = 0;
    bool export_time = false;
    bool timed_ok = l.p[0] == '[' ? bracketed_time(l, &pos, rec)
                                  : leading_time(l, &pos, rec, &export_time);
    if (!timed_ok) {
        return TEXT_LINE_BAD;
    }
    size_t peek = pos;
    span_t marker = span_next_token(l, &peek);
    bool export_marker = false;
    bool have_dir = false;
    if (marker.n > 0u && direction_marker(marker, &rec->dir, &export_marker)) {
        have_dir = true;
        pos = peek;
    }
    span_t rest = span_rest(l, pos);
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
        return text_bad(rec, have_dir ? "no octets after the direction"
                                      : "no octets after the time");
    }
    bool export_shape = export_time && have_dir && export_marker;
    return text_record_done(st, rec, export_shape ? TEXT_SHAPE_EXPORT : TEXT_SHAPE_HEX);
}

text_line_result_t text_import_line(text_import_state_t *st, const char *line, size_t len,
                                    cap_record_t *rec)
{
    st->line++;
    record_start(rec, st->line);
    if (len > TEXT_IMPORT_MAX_LINE) {
        return text_bad(rec, "line longer than %u characters", TEXT_IMPORT_MAX_LINE);
    }
    span_t l = {line, line != NULL ? len : 0u};
    /* Editors on Windows start a UTF-8 file with a byte order mark. */
    if (st->line == 1u && span_starts(l, "\xEF\xBB\xBF")) {
        l = span_from(l, 3u);
    }
    while (l.n > 0u && (l.p[l.n - 1u] == '\r' || l.p[l.n - 1u] == '\n')) {
        l.n--;
    }
    l = span_trim(l);
    if (l.n == 0u || is_comment(l)) {
        return TEXT_LINE_SKIP;
    }
    if (prosoft_line(l)) {
        return import_prosoft(st, l, rec);
    }
    return import_generic(st, l, rec);
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
