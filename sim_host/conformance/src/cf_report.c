/* What the reports share (cf_report_priv.h) and the terminal report. */
#include <stdio.h>
#include <string.h>

#include "cf_report_priv.h"
#include "replay/decode.h"
#include "sim_hal/error_text.h"

#define NS_PER_MS 1e6
/* sim_text_visible writes a control character as 4 octets */
#define VISIBLE(n) (4u * (n) + 1u)

/* ---- shared ------------------------------------------------------------------------------- */

/* Octets of the well-formed UTF-8 sequence at s (no overlong forms, no surrogates, nothing
 * above U+10FFFF), 0 when there is none. A NUL ends every check before the string's end. */
static size_t utf8_seq(const unsigned char *s)
{
    unsigned c = s[0];
    size_t n = 0;
    unsigned lo = 0x80u;
    unsigned hi = 0xBFu;
    if (c >= 0xC2u && c <= 0xDFu) {
        n = 2;
    } else if (c >= 0xE0u && c <= 0xEFu) {
        n = 3;
        lo = c == 0xE0u ? 0xA0u : lo;
        hi = c == 0xEDu ? 0x9Fu : hi;
    } else if (c >= 0xF0u && c <= 0xF4u) {
        n = 4;
        lo = c == 0xF0u ? 0x90u : lo;
        hi = c == 0xF4u ? 0x8Fu : hi;
    }
    if (n == 0u || s[1] < lo || s[1] > hi) {
        return 0;
    }
    for (size_t i = 2; i < n; i++) {
        if ((s[i] & 0xC0u) != 0x80u) {
            return 0;
        }
    }
    return n;
}

static const char *xml_entity(unsigned c)
{
    switch (c) {
    case '&': return "&amp;";
    case '<': return "&lt;";
    case '>': return "&gt;";
    case '"': return "&quot;";
    case '\'': return "&#39;";
    default: return NULL;
    }
}

void cf_rp_xml(FILE *out, const char *s)
{
    if (s == NULL) {
        return;
    }
    const unsigned char *p = (const unsigned char *)s;
    while (*p != '\0') {
        const char *e = xml_entity(*p);
        size_t n = *p >= 0x80u ? utf8_seq(p) : 1u;
        if (e != NULL) {
            fputs(e, out);
        } else if (n == 0u || (*p < 0x20u && *p != '\n' && *p != '\t') || *p == 0x7Fu) {
            fputc('?', out);
            n = 1;
        } else {
            fwrite(p, 1, n, out);
        }
        p += n;
    }
}

void cf_rp_attr(FILE *out, const char *name, const char *value)
{
    fprintf(out, " %s=\"", name);
    cf_rp_xml(out, value);
    fputc('"', out);
}

cf_rp_counts_t cf_rp_count(const cf_t *cf, const char *group)
{
    cf_rp_counts_t c = {{0, 0, 0}, 0};
    for (size_t i = 0; i < cf->n_results; i++) {
        const cf_result_t *r = &cf->results[i];
        if (group != NULL && strcmp(r->c->group, group) != 0) {
            continue;
        }
        if ((unsigned)r->verdict < 3u) {
            c.v[r->verdict]++;
        }
        c.total++;
    }
    return c;
}

cf_rp_counts_t cf_rp_count_runs(const cf_report_run_t *runs, size_t n)
{
    cf_rp_counts_t all = {{0, 0, 0}, 0};
    for (size_t i = 0; i < n; i++) {
        cf_rp_counts_t c = cf_rp_count(runs[i].cf, NULL);
        for (size_t v = 0; v < 3u; v++) {
            all.v[v] += c.v[v];
        }
        all.total += c.total;
    }
    return all;
}

size_t cf_rp_groups(const cf_report_run_t *runs, size_t n, const char **groups, size_t max)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        for (size_t j = 0; j < runs[i].cf->n_results; j++) {
            const char *g = runs[i].cf->results[j].c->group;
            size_t m = 0;
            while (m < k && strcmp(groups[m], g) != 0) {
                m++;
            }
            if (m == k && k < max) {
                groups[k++] = g;
            }
        }
    }
    return k;
}

const char *cf_rp_verdict_short(cf_verdict_t v)
{
    return v == CF_PASS ? "PASS" : v == CF_FAIL ? "FAIL" : "NA";
}

const char *cf_rp_verdict_long(cf_verdict_t v)
{
    return v == CF_PASS ? "PASS" : v == CF_FAIL ? "FAIL" : "NOT APPLICABLE";
}

static const char *gsd_string(const cf_t *cf, gsd_str_key_t k)
{
    const char *s = cf->gsd != NULL ? gsd_text(cf->gsd, k) : NULL;
    return s != NULL && s[0] != '\0' ? s : "-";
}

const char *cf_rp_vendor(const cf_t *cf)
{
    return gsd_string(cf, GSD_S_VENDOR_NAME);
}

const char *cf_rp_model(const cf_t *cf)
{
    return gsd_string(cf, GSD_S_MODEL_NAME);
}

const char *cf_rp_or_dash(const char *s)
{
    return s != NULL && s[0] != '\0' ? s : "-";
}

const char *cf_report_rate_text(uint32_t baud, char *buf, size_t n)
{
    if (baud == 0u) {
        (void)snprintf(buf, n, "no rate");
    } else if (baud < 1000000u) {
        (void)snprintf(buf, n, "%g kbit/s", (double)baud / 1e3);
    } else {
        (void)snprintf(buf, n, "%g Mbit/s", (double)baud / 1e6);
    }
    return buf;
}

void cf_rp_rates(const cf_report_run_t *runs, size_t n, char *out, size_t max)
{
    size_t used = 0;
    out[0] = '\0';
    for (size_t i = 0; i < n && used < max; i++) {
        char r[CF_RP_RATE_TEXT];
        int w = snprintf(out + used, max - used, "%s%s", i > 0u ? ", " : "",
                         cf_report_rate_text(runs[i].baud, r, sizeof r));
        used += w > 0 ? (size_t)w : 0u;
    }
}

void cf_rp_frame(const cf_result_t *r, const cf_frame_t *f, uint32_t run_baud,
                 cf_rp_frame_t *out)
{
    out->from = f->from_tester ? "tester" : "DUT";
    uint64_t dt = f->t_ns > r->t_start_ns ? f->t_ns - r->t_start_ns : 0u;
    (void)snprintf(out->time, sizeof out->time, "+%.3f ms", (double)dt / NS_PER_MS);
    out->tsdr[0] = '\0';
    if (!f->from_tester && f->len > 0u) {
        if (f->tsdr_bits == CF_TSDR_UNKNOWN || f->tsdr_bits < 0) {
            (void)snprintf(out->tsdr, sizeof out->tsdr, "not measurable");
        } else {
            (void)snprintf(out->tsdr, sizeof out->tsdr, "%ld bits", (long)f->tsdr_bits);
        }
    }
    (void)replay_hex(f->octets, f->len, out->hex, sizeof out->hex);
    if (f->len == 0u) {
        (void)snprintf(out->text, sizeof out->text, "%s",
                       f->from_tester ? "nothing sent" : "no answer (silence)");
    } else {
        (void)replay_describe(f->octets, f->len, NULL, out->text, sizeof out->text);
    }
    if (f->baud != 0u && run_baud != 0u && f->baud != run_baud) {
        char rate[CF_RP_RATE_TEXT];
        size_t used = strlen(out->text);
        (void)snprintf(out->text + used, sizeof out->text - used, " (at %s)",
                       cf_report_rate_text(f->baud, rate, sizeof rate));
    }
}

/* ---- the terminal report ------------------------------------------------------------------ */

/* fputs of text from the wire, a file or a reason, control characters made visible. */
static void put_visible(FILE *out, const char *s)
{
    char shown[VISIBLE(CF_TEXT_MAX)];
    sim_text_visible(s != NULL ? s : "", shown, sizeof shown);
    fputs(shown, out);
}

static void header(FILE *out, const cf_report_run_t *runs, size_t n, const cf_report_info_t *in)
{
    const cf_t *cf = runs[0].cf;
    char rates[CF_RP_RATE_TEXT * 10u + 24u];
    cf_rp_rates(runs, n, rates, sizeof rates);
    fprintf(out, "DUT:     station %u, ", cf->opt.address);
    put_visible(out, cf_rp_vendor(cf));
    fputc(' ', out);
    put_visible(out, cf_rp_model(cf));
    fprintf(out, ", ident 0x%04X\nGSD:     ", cf->ident);
    put_visible(out, cf_rp_or_dash(in->gsd_path));
    fputs("\nmedium:  ", out);
    put_visible(out, cf_rp_or_dash(cf->link.name));
    fprintf(out, "\n%s%s\ndate:    ", n > 1u ? "rates:   " : "rate:    ", rates);
    put_visible(out, cf_rp_or_dash(in->date));
    fputs("\ntool:    ", out);
    put_visible(out, cf_rp_or_dash(in->tool));
    fputs("\n", out);
}

static void counts_line(FILE *out, const char *what, cf_rp_counts_t c)
{
    fprintf(out, "%s: %zu case%s, %zu PASS, %zu FAIL, %zu NOT APPLICABLE\n", what, c.total,
            c.total == 1u ? "" : "s", c.v[CF_PASS], c.v[CF_FAIL], c.v[CF_NA]);
}

static void text_run(FILE *out, const cf_report_run_t *run, bool several)
{
    const cf_t *cf = run->cf;
    char rate[CF_RP_RATE_TEXT];
    int width = 0;
    for (size_t i = 0; i < cf->n_results; i++) {
        int w = (int)strlen(cf->results[i].c->id);
        width = w > width ? w : width;
    }
    fputs("\n", out);
    if (several) {
        fprintf(out, "at %s:\n", cf_report_rate_text(run->baud, rate, sizeof rate));
    }
    for (size_t i = 0; i < cf->n_results; i++) {
        const cf_result_t *r = &cf->results[i];
        fprintf(out, "%-4s  ", cf_rp_verdict_short(r->verdict));
        put_visible(out, r->c->id);
        fprintf(out, "%*s  ", width - (int)strlen(r->c->id), "");
        put_visible(out, r->c->title);
        fputs("\n", out);
        if (r->verdict != CF_PASS) {
            fputs("      ", out);
            put_visible(out, r->reason);
            fputs("\n", out);
        }
        if (r->info[0] != '\0') {
            fputs("      info: ", out);
            put_visible(out, r->info);
            fputs("\n", out);
        }
    }
    if (cf->link_failed) {
        fputs("the run stopped: ", out);
        put_visible(out, cf->link_error);
        fputs("\n", out);
    }
    counts_line(out, several ? rate : "summary", cf_rp_count(cf, NULL));
}

int cf_report_text(FILE *out, const cf_report_run_t *runs, size_t n,
                   const cf_report_info_t *info)
{
    static const cf_report_info_t none = {NULL, NULL, NULL};
    if (n == 0u) {
        return -1;
    }
    header(out, runs, n, info != NULL ? info : &none);
    for (size_t i = 0; i < n; i++) {
        text_run(out, &runs[i], n > 1u);
    }
    if (n > 1u) {
        counts_line(out, "\nsummary", cf_rp_count_runs(runs, n));
    }
    return ferror(out) ? -1 : 0;
}
