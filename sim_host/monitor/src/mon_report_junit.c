/* The monitor's verdicts as JUnit XML: one testsuite, the cases of mon_station_cases. */
#include <stdio.h>

#include "mon_report_priv.h"

#define SUITE "dfp-sim monitor"

static void attr(const mon_sink_t *out, const char *name, const char *value)
{
    mon_printf(out, " %s=\"", name);
    mon_xml_text(out, value);
    out->put(out->ctx, "\"", 1);
}

static void write_case(const mon_case_t *c, const mon_sink_t *out)
{
    mon_printf(out, "  <testcase");
    attr(out, "classname", SUITE);
    attr(out, "name", c->name);
    switch (c->verdict) {
    case MON_PASS:
        mon_printf(out, "/>\n");
        break;
    case MON_SKIP:
        mon_printf(out, ">\n    <skipped");
        attr(out, "message", c->message);
        mon_printf(out, "/>\n  </testcase>\n");
        break;
    case MON_FAIL:
        mon_printf(out, ">\n    <failure");
        attr(out, "message", c->message);
        mon_printf(out, ">");
        mon_xml_text(out, c->message);
        mon_printf(out, "</failure>\n  </testcase>\n");
        break;
    }
}

static void properties(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    char v[32];
    mon_printf(out, "  <properties>\n    <property name=\"source\"");
    attr(out, "value", info->source != NULL ? info->source : "");
    (void)snprintf(v, sizeof v, "%lu", (unsigned long)m->cfg.baud);
    mon_printf(out, "/>\n    <property name=\"baud\"");
    attr(out, "value", v);
    mon_printf(out, "/>\n    <property name=\"timing\"");
    attr(out, "value", m->cfg.timing ? "true" : "false");
    (void)snprintf(v, sizeof v, "%llu", (unsigned long long)m->line.telegrams);
    mon_printf(out, "/>\n    <property name=\"telegrams\"");
    attr(out, "value", v);
    mon_printf(out, "/>\n  </properties>\n");
}

void mon_report_junit(const mon_t *m, const mon_report_info_t *info,
                      const mon_report_opts_t *opts, const mon_sink_t *out)
{
    unsigned tests = 0;
    unsigned failures = 0;
    unsigned skipped = 0;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        mon_case_t cases[MON_CASES_PER_STATION];
        unsigned n = mon_station_cases(m, opts, a, cases);
        for (unsigned i = 0; i < n; i++) {
            tests++;
            failures += cases[i].verdict == MON_FAIL ? 1u : 0u;
            skipped += cases[i].verdict == MON_SKIP ? 1u : 0u;
        }
    }
    mon_printf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite");
    attr(out, "name", SUITE);
    mon_printf(out, " tests=\"%u\" failures=\"%u\" errors=\"0\" skipped=\"%u\" time=\"%.3f\">\n",
               tests, failures, skipped, mon_rel_s(info, info->t_now_ns));
    properties(m, info, out);
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        mon_case_t cases[MON_CASES_PER_STATION];
        unsigned n = mon_station_cases(m, opts, a, cases);
        for (unsigned i = 0; i < n; i++) {
            write_case(&cases[i], out);
        }
    }
    mon_printf(out, "</testsuite>\n");
}
