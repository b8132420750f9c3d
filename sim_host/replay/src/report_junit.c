/* The check as JUnit XML (dfp-sim replay --report junit FILE): one testsuite, one testcase per
 * service kind with requests, failed when any of its replies differ (the failure lists its kept
 * mismatches as the text report does), and a testcase "capture" failed when nothing was
 * checked or the file was not read to its end. Jenkins and GitLab show each service as a
 * test. */
#include <stdlib.h>
#include <string.h>

#include "replay/infer.h"
#include "replay/replay.h"
#include "report_out.h"

static void xml_attr(FILE *out, const char *name, const char *value)
{
    fprintf(out, " %s=\"", name);
    replay_xml_text(out, value != NULL ? value : "");
    fputc('"', out);
}

static void property(FILE *out, const char *name, const char *value)
{
    fputs("    <property", out);
    xml_attr(out, "name", name);
    xml_attr(out, "value", value);
    fputs("/>\n", out);
}

/* What was replayed how: the verdict, the address, rate and timing with their reasons. */
static void properties(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char text[1024];
    char b[32];
    const struct replay_inferred *inf = info->inferred;
    fputs("  <properties>\n", out);
    property(out, "verdict", replay_verdict(r, info, NULL));
    snprintf(text, sizeof text, "%u (%s)", r->opt.address,
             info->address_source != NULL ? info->address_source : "given");
    property(out, "address", text);
    snprintf(text, sizeof text, "%s (%s)", replay_baud_text(r->opt.baud, b, sizeof b),
             info->baud_source != NULL ? info->baud_source : "given");
    property(out, "rate", text);
    if (inf != NULL) {
        snprintf(text, sizeof text, "%s (%s)",
                 inf->timing == REPLAY_TIMING_RELAXED ? "relaxed" : "line", inf->timing_source);
        property(out, "timing", text);
    }
    snprintf(text, sizeof text, "%llu", (unsigned long long)r->masked_octets);
    property(out, "masked_octets", text);
    snprintf(text, sizeof text, "%llu", (unsigned long long)r->damaged_count);
    property(out, "damaged_records", text);
    fputs("  </properties>\n", out);
}

/* The service's kept mismatches, as the text report lists them. */
static char *failure_text(const replay_t *r, const replay_report_info_t *info, replay_service_t s)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&buf, &len);
    if (mem == NULL) {
        return NULL;
    }
    uint64_t listed = 0;
    replay_listed_t m;
    if (info->list != NULL && replay_list_rewind(info->list)) {
        while (replay_list_next(info->list, &m)) {
            if (m.service == s) {
                replay_print_listed(mem, info, &m);
                listed++;
            }
        }
    }
    if (r->svc[s].differ > listed) {
        fprintf(mem, "  ... and %llu more\n", (unsigned long long)(r->svc[s].differ - listed));
    }
    if (fclose(mem) != 0) {
        free(buf);
        return NULL;
    }
    return buf;
}

static void testcase_open(FILE *out, const char *classname, const char *name)
{
    fputs("  <testcase", out);
    xml_attr(out, "classname", classname);
    xml_attr(out, "name", name);
}

static void service_case(FILE *out, const replay_t *r, const replay_report_info_t *info,
                         const char *classname, replay_service_t s)
{
    const replay_counts_t *c = &r->svc[s];
    testcase_open(out, classname, replay_service_name(s));
    if (c->differ == 0u) {
        fputs("/>\n", out);
        return;
    }
    char msg[96];
    snprintf(msg, sizeof msg, "%llu of %llu replies differ", (unsigned long long)c->differ,
             (unsigned long long)c->requests);
    fputs(">\n    <failure type=\"mismatch\"", out);
    xml_attr(out, "message", msg);
    fputs(">", out);
    char *text = failure_text(r, info, s);
    replay_xml_text(out, text != NULL ? text : msg);
    free(text);
    fputs("</failure>\n  </testcase>\n", out);
}

/* The capture as a whole: something checked, the file read to its end. */
static void capture_case(FILE *out, const replay_t *r, const replay_report_info_t *info,
                         const char *classname)
{
    char msg[1200];
    msg[0] = '\0';
    if (replay_total_requests(r) == 0u) {
        snprintf(msg, sizeof msg, "nothing checked: no request to station %u in the capture",
                 r->opt.address);
    } else if (info->file_error != NULL) {
        snprintf(msg, sizeof msg, "file error: %s", info->file_error);
    } else if (info->interrupted) {
        snprintf(msg, sizeof msg, "interrupted after %llu records",
                 (unsigned long long)r->records);
    }
    testcase_open(out, classname, "capture");
    if (msg[0] == '\0') {
        fputs("/>\n", out);
        return;
    }
    fputs(">\n    <failure type=\"incomplete\"", out);
    xml_attr(out, "message", msg);
    fputs("/>\n  </testcase>\n", out);
}

int replay_report_junit(const replay_t *r, const replay_report_info_t *info, FILE *out)
{
    const char *file = info->file != NULL ? info->file : "(records)";
    const char *base = strrchr(file, '/') != NULL ? strrchr(file, '/') + 1 : file;
    char classname[300];
    char name[600];
    snprintf(classname, sizeof classname, "replay.%s", base);
    snprintf(name, sizeof name, "dfp-sim replay %s", file);
    unsigned tests = 1;
    unsigned failures = 0;
    for (unsigned i = 0; i < REPLAY_SVC_COUNT; i++) {
        tests += r->svc[i].requests > 0u ? 1u : 0u;
        failures += r->svc[i].differ > 0u ? 1u : 0u;
    }
    bool capture_ok = replay_total_requests(r) > 0u && info->file_error == NULL &&
                      !info->interrupted;
    failures += capture_ok ? 0u : 1u;
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuite", out);
    xml_attr(out, "name", name);
    fprintf(out, " tests=\"%u\" failures=\"%u\" errors=\"0\" skipped=\"0\">\n", tests, failures);
    properties(out, r, info);
    capture_case(out, r, info, classname);
    for (unsigned i = 0; i < REPLAY_SVC_COUNT; i++) {
        if (r->svc[i].requests > 0u) {
            service_case(out, r, info, classname, (replay_service_t)i);
        }
    }
    fputs("</testsuite>\n", out);
    return ferror(out) ? -1 : 0;
}
