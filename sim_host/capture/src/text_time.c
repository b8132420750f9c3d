/* Times as capture tools write them (text_scan.h: text_parse_time). */
#include "text_scan.h"

/* Beyond 10^10 s (317 years) a time is garbage, and seconds * 10^9 still fits 64 bits. */
#define MAX_SECONDS 10000000000ull
#define MAX_FRACTION_DIGITS 9
#define MAX_FIELDS 3u /* h:m:s */

/* The ':'-separated whole fields from *i on; a field after a ':' has two digits below 60. */
static time_parse_t parse_fields(span_t t, size_t *i, uint64_t fields[MAX_FIELDS],
                                 unsigned *nfields)
{
    *nfields = 0;
    for (;;) {
        size_t start = *i;
        uint64_t v = 0;
        while (*i < t.n && char_is_digit(t.p[*i])) {
            v = v * 10u + (uint64_t)(t.p[*i] - '0');
            if (v > MAX_SECONDS) {
                return TIME_TOO_BIG;
            }
            (*i)++;
        }
        if (*i == start || *nfields == MAX_FIELDS) {
            return TIME_NOT_A_TIME;
        }
        if (*nfields > 0u && (*i - start != 2u || v >= 60u)) {
            return TIME_NOT_A_TIME;
        }
        fields[(*nfields)++] = v;
        if (*i < t.n && t.p[*i] == ':') {
            (*i)++;
            continue;
        }
        return TIME_OK;
    }
}

/* ".fraction" at *i, if there is one: *digits stays -1 without it. ProSoft groups the digits
 * with ',' ("3.040,029"). */
static time_parse_t parse_fraction(span_t t, bool prosoft, size_t *i, uint64_t *fraction,
                                   int *digits)
{
    *fraction = 0;
    *digits = -1;
    if (*i >= t.n || t.p[*i] != '.') {
        return TIME_OK;
    }
    (*i)++;
    *digits = 0;
    while (*i < t.n) {
        char c = t.p[*i];
        if (char_is_digit(c)) {
            if (*digits == MAX_FRACTION_DIGITS) {
                return TIME_TOO_PRECISE;
            }
            *fraction = *fraction * 10u + (uint64_t)(c - '0');
            (*digits)++;
        } else if (!(prosoft && c == ',' && *digits > 0 && *i + 1u < t.n &&
                     char_is_digit(t.p[*i + 1u]))) {
            break;
        }
        (*i)++;
    }
    return *digits == 0 ? TIME_NOT_A_TIME : TIME_OK;
}

static time_parse_t fields_to_seconds(const uint64_t fields[MAX_FIELDS], unsigned nfields,
                                      uint64_t *seconds)
{
    *seconds = 0;
    for (unsigned f = 0; f < nfields; f++) {
        if (*seconds > MAX_SECONDS / 60u) {
            return TIME_TOO_BIG;
        }
        *seconds = *seconds * (f == 0u ? 1u : 60u) + fields[f];
        if (*seconds > MAX_SECONDS) {
            return TIME_TOO_BIG;
        }
    }
    return TIME_OK;
}

time_parse_t text_parse_time(span_t t, bool prosoft, parsed_time_t *out)
{
    *out = (parsed_time_t){.fraction_digits = -1};
    size_t i = 0;
    uint64_t fields[MAX_FIELDS] = {0, 0, 0};
    unsigned nfields = 0;
    time_parse_t r = parse_fields(t, &i, fields, &nfields);
    if (r != TIME_OK) {
        return r;
    }
    uint64_t fraction = 0;
    int digits = -1;
    r = parse_fraction(t, prosoft, &i, &fraction, &digits);
    if (r != TIME_OK) {
        return r;
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
    r = fields_to_seconds(fields, nfields, &seconds);
    if (r != TIME_OK) {
        return r;
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
