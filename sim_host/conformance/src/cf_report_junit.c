/* The suite as JUnit XML (dfp-sim conformance --report junit FILE): a testsuite per group and
 * run, so a CI server shows the groups as the lab's test specification does; with several runs
 * the rate is in each testsuite's name and classname ("DP state machine at 1500000 bit/s": no
 * dot, which CI servers would take for a package separator). */
#include <stdio.h>
#include <string.h>

#include "cf_report_priv.h"

#define NS_PER_S 1e9

static void property(FILE *out, const char *name, const char *value)
{
    fputs("      <property", out);
    cf_rp_attr(out, "name", name);
    cf_rp_attr(out, "value", value);
    fputs("/>\n", out);
}

static void properties(FILE *out, const cf_report_run_t *run, const cf_report_info_t *info)
{
    const cf_t *cf = run->cf;
    char text[CF_TEXT_MAX];
    fputs("    <properties>\n", out);
    (void)snprintf(text, sizeof text, "%u", cf->opt.address);
    property(out, "address", text);
    property(out, "vendor", cf_rp_vendor(cf));
    property(out, "model", cf_rp_model(cf));
    (void)snprintf(text, sizeof text, "0x%04X", cf->ident);
    property(out, "ident", text);
    property(out, "gsd", cf_rp_or_dash(info->gsd_path));
    property(out, "medium", cf_rp_or_dash(cf->link.name));
    property(out, "rate", cf_report_rate_text(run->baud, text, sizeof text));
    property(out, "date", cf_rp_or_dash(info->date));
    property(out, "tool", cf_rp_or_dash(info->tool));
    if (cf->link_failed) {
        property(out, "link_error", cf->link_error);
    }
    fputs("    </properties>\n", out);
}

/* The case's clause, information and evidence, one telegram a line. */
static void system_out(FILE *out, const cf_result_t *r, uint32_t baud)
{
    char line[1400];
    fputs("      <system-out>", out);
    (void)snprintf(line, sizeof line, "clause: %s\n%s\n", r->c->clause, r->c->title);
    cf_rp_xml(out, line);
    if (r->info[0] != '\0') {
        fputs("info: ", out);
        cf_rp_xml(out, r->info);
        fputs("\n", out);
    }
    fprintf(out, "telegrams: %lu", (unsigned long)r->telegrams);
    if (r->telegrams > r->n_ev) {
        fprintf(out, ", the last %u", r->n_ev);
    }
    fputs(r->n_ev > 0u ? ":\n" : "\n", out);
    for (unsigned i = 0; i < r->n_ev; i++) {
        cf_rp_frame_t f;
        cf_rp_frame(r, &r->ev[i], baud, &f);
        (void)snprintf(line, sizeof line, "  %-6s %12s %-14s %s | %s\n", f.from, f.time,
                       f.tsdr[0] != '\0' ? f.tsdr : "-", f.hex[0] != '\0' ? f.hex : "-", f.text);
        cf_rp_xml(out, line);
    }
    fputs("</system-out>\n", out);
}

static void testcase(FILE *out, const cf_result_t *r, const char *classname, uint32_t baud)
{
    char t[32];
    uint64_t dt = r->t_end_ns > r->t_start_ns ? r->t_end_ns - r->t_start_ns : 0u;
    (void)snprintf(t, sizeof t, "%.3f", (double)dt / NS_PER_S);
    fputs("    <testcase", out);
    cf_rp_attr(out, "classname", classname);
    cf_rp_attr(out, "name", r->c->id);
    cf_rp_attr(out, "time", t);
    fputs(">\n", out);
    if (r->verdict == CF_FAIL) {
        fputs("      <failure", out);
        cf_rp_attr(out, "message", r->reason);
        fputs(">", out);
        cf_rp_xml(out, r->reason);
        fputs("</failure>\n", out);
    } else if (r->verdict == CF_NA) {
        fputs("      <skipped", out);
        cf_rp_attr(out, "message", r->reason);
        fputs("/>\n", out);
    }
    system_out(out, r, baud);
    fputs("    </testcase>\n", out);
}

static void suite(FILE *out, const cf_report_run_t *run, const char *group, bool several,
                  const cf_report_info_t *info)
{
    const cf_t *cf = run->cf;
    char name[96];
    if (several) {
        (void)snprintf(name, sizeof name, "%s at %lu bit/s", group, (unsigned long)run->baud);
    } else {
        (void)snprintf(name, sizeof name, "%s", group);
    }
    cf_rp_counts_t c = cf_rp_count(cf, group);
    uint64_t ns = 0;
    for (size_t i = 0; i < cf->n_results; i++) {
        const cf_result_t *r = &cf->results[i];
        if (strcmp(r->c->group, group) == 0 && r->t_end_ns > r->t_start_ns) {
            ns += r->t_end_ns - r->t_start_ns;
        }
    }
    fputs("  <testsuite", out);
    cf_rp_attr(out, "name", name);
    fprintf(out, " tests=\"%zu\" failures=\"%zu\" errors=\"0\" skipped=\"%zu\" time=\"%.3f\">\n",
            c.total, c.v[CF_FAIL], c.v[CF_NA], (double)ns / NS_PER_S);
    properties(out, run, info);
    for (size_t i = 0; i < cf->n_results; i++) {
        if (strcmp(cf->results[i].c->group, group) == 0) {
            testcase(out, &cf->results[i], name, run->baud);
        }
    }
    fputs("  </testsuite>\n", out);
}

int cf_report_junit(FILE *out, const cf_report_run_t *runs, size_t n,
                    const cf_report_info_t *info)
{
    static const cf_report_info_t none = {NULL, NULL, NULL};
    const char *groups[CF_RP_MAX_GROUPS];
    if (n == 0u) {
        return -1;
    }
    size_t n_groups = cf_rp_groups(runs, n, groups, CF_RP_MAX_GROUPS);
    cf_rp_counts_t all = cf_rp_count_runs(runs, n);
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites", out);
    cf_rp_attr(out, "name", "PROFIBUS-DP slave conformance");
    fprintf(out, " tests=\"%zu\" failures=\"%zu\" errors=\"0\" skipped=\"%zu\">\n", all.total,
            all.v[CF_FAIL], all.v[CF_NA]);
    for (size_t i = 0; i < n; i++) {
        for (size_t g = 0; g < n_groups; g++) {
            if (cf_rp_count(runs[i].cf, groups[g]).total > 0u) {
                suite(out, &runs[i], groups[g], n > 1u, info != NULL ? info : &none);
            }
        }
    }
    fputs("</testsuites>\n", out);
    return ferror(out) ? -1 : 0;
}
