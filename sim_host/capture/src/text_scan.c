/* Spans, tokens and hex octets of one text line (text_scan.h). */
#include "text_scan.h"

#include <stdio.h>
#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

bool char_is_ws(char c)
{
    return c == ' ' || c == '\t';
}

bool char_is_digit(char c)
{
    return c >= '0' && c <= '9';
}

int char_hex_value(char c)
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

char char_upper(char c)
{
    if (c >= 'a' && c <= 'z') {
        return (char)(unsigned char)((unsigned char)c - ('a' - 'A'));
    }
    return c;
}

bool span_is(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    return t.n == n && memcmp(t.p, lit, n) == 0;
}

bool span_is_nocase(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    if (t.n != n) {
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        if (char_upper(t.p[i]) != char_upper(lit[i])) {
            return false;
        }
    }
    return true;
}

bool span_starts(span_t t, const char *lit)
{
    size_t n = strlen(lit);
    return t.n >= n && memcmp(t.p, lit, n) == 0;
}

span_t span_from(span_t t, size_t k)
{
    return k >= t.n ? (span_t){t.p + t.n, 0} : (span_t){t.p + k, t.n - k};
}

span_t span_trim(span_t t)
{
    while (t.n > 0u && char_is_ws(t.p[0])) {
        t.p++;
        t.n--;
    }
    while (t.n > 0u && char_is_ws(t.p[t.n - 1u])) {
        t.n--;
    }
    return t;
}

span_t span_next_token(span_t line, size_t *pos)
{
    size_t i = *pos;
    while (i < line.n && char_is_ws(line.p[i])) {
        i++;
    }
    size_t start = i;
    while (i < line.n && !char_is_ws(line.p[i])) {
        i++;
    }
    *pos = i;
    return (span_t){line.p + start, i - start};
}

span_t span_rest(span_t line, size_t pos)
{
    return span_trim(span_from(line, pos));
}

quoted_t quote_span(span_t t)
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

/* ---- octets ------------------------------------------------------------------------------- */

void sink_put(sink_t *s, uint8_t b)
{
    if (s->rec != NULL) {
        if (s->rec->len < CAP_MAX_RECORD) {
            s->rec->data[s->rec->len++] = b;
        }
        s->rec->orig_len++;
    }
    s->n++;
}

uint8_t sink_fcs(const sink_t *s, size_t from)
{
    if (s->rec == NULL || s->n >= CAP_MAX_RECORD || from > s->n) {
        return 0;
    }
    return fdl_fcs(&s->rec->data[from], s->n - from);
}

bool span_all_hex(span_t t)
{
    for (size_t i = 0; i < t.n; i++) {
        if (char_hex_value(t.p[i]) < 0) {
            return false;
        }
    }
    return true;
}

bool hex_word(span_t w, sink_t *out, char *problem, size_t max)
{
    if (w.n >= 2u && w.p[0] == '0' && (w.p[1] == 'x' || w.p[1] == 'X')) {
        span_t digits = span_from(w, 2u);
        if (digits.n == 0u || !span_all_hex(digits)) {
            (void)snprintf(problem, max, "not hex: '%s'", quote_span(w).s);
            return false;
        }
        if (digits.n > 2u) {
            (void)snprintf(problem, max, "not one octet: '%s'", quote_span(w).s);
            return false;
        }
        int v = char_hex_value(digits.p[0]);
        if (digits.n == 2u) {
            v = v * 16 + char_hex_value(digits.p[1]);
        }
        sink_put(out, (uint8_t)v);
        return true;
    }
    if (!span_all_hex(w)) {
        (void)snprintf(problem, max, "not hex: '%s'", quote_span(w).s);
        return false;
    }
    if (w.n % 2u != 0u) {
        (void)snprintf(problem, max, "odd number of hex digits: '%s'", quote_span(w).s);
        return false;
    }
    for (size_t i = 0; i < w.n; i += 2u) {
        sink_put(out, (uint8_t)(char_hex_value(w.p[i]) * 16 + char_hex_value(w.p[i + 1u])));
    }
    return true;
}

static bool is_hex_separator(char c)
{
    return char_is_ws(c) || c == ',' || c == ':';
}

bool hex_octets(span_t s, sink_t *out, bool comments, char *problem, size_t max)
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

bool span_all_digits(span_t t)
{
    if (t.n == 0u) {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        if (!char_is_digit(t.p[i])) {
            return false;
        }
    }
    return true;
}

bool span_small_decimal(span_t t, unsigned limit, unsigned *out)
{
    if (!span_all_digits(t) || t.n > 5u) {
        return false;
    }
    unsigned v = 0;
    for (size_t i = 0; i < t.n; i++) {
        v = v * 10u + (unsigned)(t.p[i] - '0');
    }
    *out = v;
    return v <= limit;
}

int start_delimiter_named(span_t t)
{
    static const struct {
        const char *name;
        int sd;
    } names[] = {{"SD1", FDL_SD1}, {"SD2", FDL_SD2}, {"SD3", FDL_SD3}, {"SD4", FDL_SD4},
                 {"SC", FDL_SC}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (span_is(t, names[i].name)) {
            return names[i].sd;
        }
    }
    return -1;
}
