/* The report a test lab hands over (dfp-sim conformance --report html FILE): one file that
 * opens anywhere and prints well — the style inline, no script, no link out of the file. The
 * DUT and the run first, a summary by group with a column per rate, then a section per rate
 * with every case: its clause, verdict, reason, information and the telegrams that decided it
 * decoded. Written as well-formed XML (no named entities but XML's own, every element closed)
 * so that XML tools read it as well as browsers. */
#include <stdio.h>
#include <string.h>

#include "cf_report_priv.h"

static const char style[] =
    "body{font-family:sans-serif;margin:2em;color:#222;max-width:80em}"
    "h1{font-size:1.5em}h2{font-size:1.25em;border-bottom:1px solid #999;margin-top:2em}"
    "h3{font-size:1em;margin:0 0 .4em 0}"
    "table{border-collapse:collapse;margin:.5em 0}"
    "th,td{border:1px solid #bbb;padding:.2em .5em;text-align:left;vertical-align:top}"
    "th{background:#eee}"
    ".v{font-weight:bold;padding:0 .4em;border-radius:3px;white-space:nowrap}"
    ".pass{background:#d7f5dd;color:#0a5c1e}.fail{background:#fbd5d5;color:#8a1010}"
    ".na{background:#e6e6e6;color:#444}"
    ".case{border:1px solid #ccc;padding:.6em;margin:1em 0;page-break-inside:avoid}"
    ".hex,.dec{font-family:monospace;font-size:.9em}.hex{word-break:break-all}"
    "td.n{text-align:right}";

static const char *verdict_class(cf_verdict_t v)
{
    return v == CF_PASS ? "pass" : v == CF_FAIL ? "fail" : "na";
}

static void verdict_span(FILE *out, cf_verdict_t v)
{
    fprintf(out, "<span class=\"v %s\">%s</span>", verdict_class(v), cf_rp_verdict_long(v));
}

/* <tag>text</tag> with the text escaped. */
static void elem(FILE *out, const char *tag, const char *text)
{
    fprintf(out, "<%s>", tag);
    cf_rp_xml(out, text);
    fprintf(out, "</%s>", tag);
}

static void kv(FILE *out, const char *key, const char *value)
{
    fputs("<tr>", out);
    elem(out, "th", key);
    elem(out, "td", value);
    fputs("</tr>\n", out);
}

/* The id of a case's section: the run, then the case's id (letters, digits, '.', '_'; anything
 * else as '-'), so the overview can link to it. */
static void anchor(FILE *out, size_t run, const char *id)
{
    fprintf(out, "r%zu-", run);
    for (const char *p = id; *p != '\0'; p++) {
        char c = *p;
        bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_';
        fputc(keep ? c : '-', out);
    }
}

static void head(FILE *out, const cf_t *cf)
{
    char title[CF_TEXT_MAX];
    (void)snprintf(title, sizeof title, "PROFIBUS-DP slave conformance: %s %s (ident 0x%04X)",
                   cf_rp_vendor(cf), cf_rp_model(cf), cf->ident);
    fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\"/>\n", out);
    elem(out, "title", title);
    fprintf(out, "\n<style>%s</style>\n</head>\n<body>\n", style);
    elem(out, "h1", title);
    fputs("\n", out);
}

static void dut_table(FILE *out, const cf_report_run_t *runs, size_t n,
                      const cf_report_info_t *info)
{
    const cf_t *cf = runs[0].cf;
    char text[CF_TEXT_MAX];
    fputs("<table class=\"dut\">\n", out);
    kv(out, "Vendor", cf_rp_vendor(cf));
    kv(out, "Model", cf_rp_model(cf));
    (void)snprintf(text, sizeof text, "0x%04X", cf->ident);
    kv(out, "Ident number", text);
    if (cf->gsd != NULL) {
        kv(out, "Revision", cf_rp_or_dash(gsd_text(cf->gsd, GSD_S_REVISION)));
        kv(out, "Software release", cf_rp_or_dash(gsd_text(cf->gsd, GSD_S_SOFTWARE_RELEASE)));
    }
    kv(out, "GSD file", cf_rp_or_dash(info->gsd_path));
    (void)snprintf(text, sizeof text, "%u", cf->opt.address);
    kv(out, "Address", text);
    kv(out, "Medium", cf_rp_or_dash(cf->link.name));
    kv(out, "Timing", cf->link.timing ? "measured to the bit" : "not measurable on this medium");
    cf_rp_rates(runs, n, text, sizeof text);
    kv(out, n > 1u ? "Rates" : "Rate", text);
    (void)snprintf(text, sizeof text, "class 1: %u and %u, class 2: %u", cf->opt.master,
                   cf->opt.master_2, cf->opt.class2);
    kv(out, "Tester's masters", text);
    kv(out, "Date", cf_rp_or_dash(info->date));
    kv(out, "Tool", cf_rp_or_dash(info->tool));
    fputs("</table>\n", out);
}

/* "12 PASS, 1 FAIL, 2 NOT APPLICABLE" with the non-zero counts coloured. */
static void counts_cell(FILE *out, cf_rp_counts_t c)
{
    fputs("<td>", out);
    for (unsigned v = 0; v < 3u; v++) {
        if (v > 0u) {
            fputs(", ", out);
        }
        if (c.v[v] > 0u) {
            fprintf(out, "<span class=\"v %s\">%zu %s</span>", verdict_class((cf_verdict_t)v),
                    c.v[v], cf_rp_verdict_long((cf_verdict_t)v));
        } else {
            fprintf(out, "0 %s", cf_rp_verdict_long((cf_verdict_t)v));
        }
    }
    fputs("</td>", out);
}

static void summary(FILE *out, const cf_report_run_t *runs, size_t n)
{
    const char *groups[CF_RP_MAX_GROUPS];
    size_t n_groups = cf_rp_groups(runs, n, groups, CF_RP_MAX_GROUPS);
    char rate[CF_RP_RATE_TEXT];
    fputs("<h2>Summary</h2>\n<table class=\"summary\">\n<tr><th>Group</th>", out);
    for (size_t i = 0; i < n; i++) {
        elem(out, "th", cf_report_rate_text(runs[i].baud, rate, sizeof rate));
    }
    fputs("</tr>\n", out);
    for (size_t g = 0; g <= n_groups; g++) {
        fputs("<tr>", out);
        elem(out, g < n_groups ? "td" : "th", g < n_groups ? groups[g] : "All groups");
        for (size_t i = 0; i < n; i++) {
            counts_cell(out, cf_rp_count(runs[i].cf, g < n_groups ? groups[g] : NULL));
        }
        fputs("</tr>\n", out);
    }
    fputs("</table>\n<p>PASS: the DUT did what the clause requires. FAIL: it did not (the reason "
          "says what it did). NOT APPLICABLE: the GSD does not claim the feature, or the medium "
          "cannot show it (the reason says which).</p>\n", out);
}

/* The cases of a run in a table linking to their sections. */
static void overview(FILE *out, const cf_t *cf, size_t run)
{
    fputs("<table class=\"overview\">\n<tr><th>Case</th><th>Group</th><th>Title</th>"
          "<th>Verdict</th></tr>\n", out);
    for (size_t i = 0; i < cf->n_results; i++) {
        const cf_result_t *r = &cf->results[i];
        fputs("<tr><td><a href=\"#", out);
        anchor(out, run, r->c->id);
        fputs("\">", out);
        cf_rp_xml(out, r->c->id);
        fputs("</a></td>", out);
        elem(out, "td", r->c->group);
        elem(out, "td", r->c->title);
        fputs("<td>", out);
        verdict_span(out, r->verdict);
        fputs("</td></tr>\n", out);
    }
    fputs("</table>\n", out);
}

static void telegrams(FILE *out, const cf_result_t *r, uint32_t baud)
{
    if (r->n_ev == 0u) {
        return;
    }
    fputs("<table class=\"telegrams\">\n<tr><th>From</th><th>Time</th><th>TSDR</th>"
          "<th>Octets</th><th>Decoded</th></tr>\n", out);
    for (unsigned i = 0; i < r->n_ev; i++) {
        cf_rp_frame_t f;
        cf_rp_frame(r, &r->ev[i], baud, &f);
        fputs("<tr>", out);
        elem(out, "td", f.from);
        fputs("<td class=\"n\">", out);
        cf_rp_xml(out, f.time);
        fputs("</td><td>", out);
        cf_rp_xml(out, f.tsdr);
        fputs("</td><td class=\"hex\">", out);
        cf_rp_xml(out, f.hex);
        fputs("</td><td class=\"dec\">", out);
        cf_rp_xml(out, f.text);
        fputs("</td></tr>\n", out);
    }
    fputs("</table>\n", out);
}

static void one_case(FILE *out, const cf_result_t *r, size_t run, uint32_t baud)
{
    char text[64];
    fputs("<div class=\"case\" id=\"", out);
    anchor(out, run, r->c->id);
    fputs("\">\n<h3>", out);
    verdict_span(out, r->verdict);
    fputs(" ", out);
    cf_rp_xml(out, r->c->id);
    fputs(": ", out);
    cf_rp_xml(out, r->c->title);
    fputs("</h3>\n<table class=\"case-facts\">\n", out);
    kv(out, "Group", r->c->group);
    kv(out, "Clause", r->c->clause);
    if (r->verdict != CF_PASS) {
        kv(out, "Reason", r->reason);
    }
    if (r->info[0] != '\0') {
        kv(out, "Information", r->info);
    }
    (void)snprintf(text, sizeof text, r->telegrams > r->n_ev ? "%lu, the last %u below" : "%lu",
                   (unsigned long)r->telegrams, r->n_ev);
    kv(out, "Telegrams", text);
    fputs("</table>\n", out);
    telegrams(out, r, baud);
    fputs("</div>\n", out);
}

static void run_section(FILE *out, const cf_report_run_t *run, size_t index, bool several)
{
    const cf_t *cf = run->cf;
    char rate[CF_RP_RATE_TEXT];
    char title[64];
    (void)snprintf(title, sizeof title, several ? "Cases at %s" : "Cases (%s)",
                   cf_report_rate_text(run->baud, rate, sizeof rate));
    elem(out, "h2", title);
    fputs("\n", out);
    if (cf->link_failed) {
        fputs("<p><span class=\"v fail\">The run stopped</span> ", out);
        cf_rp_xml(out, cf->link_error);
        fputs("</p>\n", out);
    }
    overview(out, cf, index);
    for (size_t i = 0; i < cf->n_results; i++) {
        one_case(out, &cf->results[i], index, run->baud);
    }
}

int cf_report_html(FILE *out, const cf_report_run_t *runs, size_t n,
                   const cf_report_info_t *info)
{
    static const cf_report_info_t none = {NULL, NULL, NULL};
    if (n == 0u) {
        return -1;
    }
    head(out, runs[0].cf);
    dut_table(out, runs, n, info != NULL ? info : &none);
    summary(out, runs, n);
    for (size_t i = 0; i < n; i++) {
        run_section(out, &runs[i], i, n > 1u);
    }
    fputs("</body>\n</html>\n", out);
    return ferror(out) ? -1 : 0;
}
