/* Reading one text line of a capture: spans over the unterminated line, whitespace tokens, hex
 * octets into a record and times. Shared by the line shapes (text_formats.h); private to the
 * capture library.
 *
 * A line is not NUL-terminated and may hold any bytes: every scan is bounded by the span's
 * length, and numbers are range-checked before they are multiplied. */
#ifndef CAPTURE_TEXT_SCAN_H
#define CAPTURE_TEXT_SCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/record.h"

#define NS_PER_S 1000000000ull
#define QUOTE_MAX 20u

typedef struct span {
    const char *p;
    size_t n;
} span_t;

bool char_is_ws(char c);
bool char_is_digit(char c);
int char_hex_value(char c); /* -1 when c is no hex digit */
char char_upper(char c);

bool span_is(span_t t, const char *lit);
bool span_is_nocase(span_t t, const char *lit);
bool span_starts(span_t t, const char *lit);
span_t span_from(span_t t, size_t k); /* t without its first k characters */
span_t span_trim(span_t t);
bool span_all_hex(span_t t);
bool span_all_digits(span_t t); /* false for an empty span */
/* Decimal digits (at most 5) of a value <= limit. */
bool span_small_decimal(span_t t, unsigned limit, unsigned *out);

/* The start delimiter a name stands for ("SD1".."SD4", "SC": pyprofibus and ProSoft both write
 * them), -1 for any other token. */
int start_delimiter_named(span_t t);

/* The next whitespace-separated token at or after *pos; an empty span at the end. */
span_t span_next_token(span_t line, size_t *pos);
/* The line from pos on, trimmed. */
span_t span_rest(span_t line, size_t pos);

/* A token for a message: at most QUOTE_MAX characters, anything unprintable as '?'. */
typedef struct quoted {
    char s[QUOTE_MAX + 4u];
} quoted_t;

quoted_t quote_span(span_t t);

/* Where octets go: into the record (cut at CAP_MAX_RECORD, orig_len counts all) or, with rec
 * NULL, only counted. */
typedef struct sink {
    cap_record_t *rec;
    size_t n; /* octets put so far, the cut ones included */
} sink_t;

void sink_put(sink_t *s, uint8_t b);
/* The FCS (fdl_fcs) of the octets put from index from on, for a sink started on an empty
 * record. An FCS put next that still lands in the record covers only octets the record holds;
 * one that does not is cut anyway, so its value does not matter (0). */
uint8_t sink_fcs(const sink_t *s, size_t from);

/* One hex word: "0x5"/"0x05" is one octet, "05"/"0502" is one octet per digit pair. On false,
 * problem says why. */
bool hex_word(span_t w, sink_t *out, char *problem, size_t max);
/* Hex octets separated by blanks, ',' or ':'; with comments, '#' or "//" at the start of a word
 * ends the octets. */
bool hex_octets(span_t s, sink_t *out, bool comments, char *problem, size_t max);

typedef enum time_parse {
    TIME_OK = 0,
    TIME_NOT_A_TIME, /* not shaped like a time at all */
    TIME_TOO_BIG,
    TIME_TOO_PRECISE,
} time_parse_t;

typedef struct parsed_time {
    uint64_t ns;
    unsigned fields;     /* ':'-separated fields before the fraction (1..3) */
    int fraction_digits; /* -1 without a '.' */
    bool unit_s;         /* a trailing 's' */
} parsed_time_t;

/* [[h:]m:]s[.fraction][s]. ProSoft writes ',' between the ms/µs/ns groups of the fraction and
 * no unit; minutes and seconds after a ':' have two digits and are below 60. */
time_parse_t text_parse_time(span_t t, bool prosoft, parsed_time_t *out);

#endif
