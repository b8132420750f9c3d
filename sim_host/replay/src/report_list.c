/* The list of mismatches below the report's table, and what the report writers share
 * (report_out.h). */
#include <string.h>

#include "replay/replay.h"
#include "report_out.h"

const char *replay_baud_text(uint32_t baud, char *buf, size_t max)
{
    if (baud >= 1000000u) {
        snprintf(buf, max, "%g Mbit/s", (double)baud / 1e6);
    } else {
        snprintf(buf, max, "%g kbit/s", (double)baud / 1e3);
    }
    return buf;
}

/* Appends to out at *k, never past max. */
#define PUT(...)                                                                              \
    do {                                                                                      \
        int n_ = snprintf(out + *k, max - *k, __VA_ARGS__);                                   \
        *k += n_ >= 0 && (size_t)n_ < max - *k ? (size_t)n_ : max - *k - 1u;                  \
    } while (0)

/* "16 (data 9)", "21 (FCS)": an offset with what it is in the answer. */
static void put_offset(const replay_listed_t *m, uint16_t off, char *out, size_t max, size_t *k)
{
    size_t fcs = m->expected_len >= 2u ? m->expected_len - 2u : SIZE_MAX;
    if (off == fcs) {
        PUT("%u (FCS)", off);
    } else if (m->data_offset > 0u && off >= m->data_offset) {
        PUT("%u (data %u)", off, (unsigned)(off - m->data_offset));
    } else {
        PUT("%u", off);
    }
}

void replay_listed_what(const replay_listed_t *m, char *out, size_t max)
{
    size_t used = 0;
    size_t *k = &used;
    out[0] = '\0';
    if (m->expected_present && !m->actual_present) {
        PUT("the card did not answer");
        return;
    }
    if (!m->expected_present) {
        PUT("the card answered, the capture shows no answer");
        return;
    }
    uint16_t d[8];
    size_t n = replay_listed_diffs(m, d, sizeof d / sizeof d[0]);
    if (m->expected_len != m->actual_len) {
        PUT("the card's answer has %u octets, the recorded one %u%s", m->actual_len,
            m->expected_len, n > 0u ? "; " : "");
    }
    if (n == 0u) {
        return;
    }
    PUT("octet%s ", n > 1u ? "s" : "");
    for (size_t i = 0; i < n && i < sizeof d / sizeof d[0]; i++) {
        PUT("%s", i > 0u ? ", " : "");
        put_offset(m, d[i], out, max, k);
    }
    PUT("%s %s", n > sizeof d / sizeof d[0] ? ", ..." : "", n > 1u ? "differ" : "differs");
}

void replay_print_listed(FILE *out, const replay_report_info_t *info, const replay_listed_t *m)
{
    char at[96];
    char what[256];
    char hex[3u * CAP_MAX_RECORD + 8u];
    replay_where(info, m->record, m->position, at, sizeof at);
    replay_listed_what(m, what, sizeof what);
    fprintf(out, "  #%-3llu %s, t = %.6f s, %s: %s\n", (unsigned long long)m->number, at,
            (double)m->t_ns / 1e9, replay_service_name(m->service), what);
    replay_hex(m->request, m->request_len, hex, sizeof hex);
    fprintf(out, "       request   %s\n", hex);
    if (m->expected_present) {
        replay_hex(m->expected, m->expected_len, hex, sizeof hex);
        fprintf(out, "       expected  %s\n", hex);
    } else {
        fprintf(out, "       expected  no answer\n");
    }
    if (m->actual_present) {
        replay_hex(m->actual, m->actual_len, hex, sizeof hex);
        fprintf(out, "       actual    %s\n", hex);
    } else {
        fprintf(out, "       actual    no answer\n");
    }
    if (m->masked > 0u) {
        fprintf(out, "       masked    %u octets not compared\n", m->masked);
    }
}

void replay_print_list(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    replay_list_t *l = info->list;
    if (l != NULL && r->mismatches > 0u) {
        replay_listed_t m;
        if (replay_list_rewind(l)) {
            while (replay_list_next(l, &m)) {
                replay_print_listed(out, info, &m);
            }
        }
        if (l->failed) {
            fprintf(out, "  (not listed: %s)\n", l->error);
        } else if (r->mismatches > l->kept) {
            fprintf(out, "  ... and %llu more (--max-mismatches 0 lists all)\n",
                    (unsigned long long)(r->mismatches - l->kept));
        }
    }
    if (r->opt.mask != NULL && r->opt.mask->any) {
        fprintf(out, "masked: %llu octets not compared (--ignore %s)\n",
                (unsigned long long)r->masked_octets, r->opt.mask->text);
    }
}

uint64_t replay_list_count(replay_list_t *l, replay_service_t s)
{
    uint64_t n = 0;
    replay_listed_t m;
    if (l == NULL || !replay_list_rewind(l)) {
        return 0u;
    }
    while (replay_list_next(l, &m)) {
        n += s == REPLAY_SVC_COUNT || m.service == s ? 1u : 0u;
    }
    return n;
}

void replay_json_string(FILE *out, const char *s)
{
    if (s == NULL) {
        fputs("null", out);
        return;
    }
    fputc('"', out);
    for (const unsigned char *p = (const unsigned char *)s; *p != '\0'; p++) {
        if (*p == '"' || *p == '\\') {
            fprintf(out, "\\%c", *p);
        } else if (*p == '\n') {
            fputs("\\n", out);
        } else if (*p < 0x20u || *p == 0x7Fu) {
            fprintf(out, "\\u%04x", *p);
        } else {
            fputc(*p, out);
        }
    }
    fputc('"', out);
}

void replay_json_hex(FILE *out, bool present, const uint8_t *p, size_t len)
{
    if (!present) {
        fputs("null", out);
        return;
    }
    fputc('"', out);
    for (size_t i = 0; i < len; i++) {
        fprintf(out, "%s%02X", i > 0u ? " " : "", p[i]);
    }
    fputc('"', out);
}

void replay_xml_text(FILE *out, const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p != '\0'; p++) {
        switch (*p) {
        case '&': fputs("&amp;", out); break;
        case '<': fputs("&lt;", out); break;
        case '>': fputs("&gt;", out); break;
        case '"': fputs("&quot;", out); break;
        case '\'': fputs("&apos;", out); break;
        default:
            /* XML 1.0 has no way to carry other control characters, not even as references. */
            fputc(*p < 0x20u && *p != '\t' && *p != '\n' && *p != '\r' ? '?' : *p, out);
            break;
        }
    }
}
