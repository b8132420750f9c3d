/* The conformance reports (cf_report.h) of results built by hand: the terminal report's exact
 * lines for one run and for two rates; JUnit and HTML parsed by Python (argv[1], the script
 * argv[2]) with their counts, names, messages and escaping; the HTML self-contained. GSD
 * strings, the medium's name and the reasons carry < & " ' and an octet that is no UTF-8. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "conformance/cf_report.h"

static gsd_t g;
static cf_t run_a, run_b;

static const char gsd_text_src[] =
    "#Profibus_DP\n"
    "GSD_Revision = 3\n"
    "Vendor_Name = \"Ve<nd> & 'Co' \xE9\"\n"
    "Model_Name = \"M\xC3\xBCller-1\"\n"
    "Revision = \"R1\"\n"
    "Ident_Number = 0x6003\n";

static const cf_case_t cases[] = {
    {"gsd.check", "GSD", "GSD specification 2.122", "the GSD file is consistent", NULL},
    {"fdl.status", "FDL", "IEC 61158-4-3 8.6", "Request FDL Status is answered", NULL},
    {"dp.set_prm.lock", "DP state machine", "IEC 61158-6-3 8.3.2",
     "a locked slave refuses another master's Set_Prm", NULL},
    {"timing.tsdr.min", "Timing", "IEC 61158-4-3 8.7", "answers wait min TSDR", NULL},
};

static void frame(cf_result_t *r, bool from_tester, uint64_t t_ns, int32_t tsdr,
                  const uint8_t *o, uint16_t len)
{
    cf_frame_t *f = &r->ev[r->n_ev++];
    if (len > 0u) { /* a silent slot has no octets (o may be NULL) */
        memcpy(f->octets, o, len);
    }
    f->len = len;
    f->from_tester = from_tester;
    f->t_ns = t_ns;
    f->tsdr_bits = tsdr;
    f->baud = 1500000u;
    r->telegrams++;
}

static void result(cf_t *cf, size_t i, cf_verdict_t v, const char *reason, const char *info)
{
    cf_result_t *r = &cf->results[cf->n_results++];
    r->c = &cases[i];
    r->verdict = v;
    (void)snprintf(r->reason, sizeof r->reason, "%s", reason);
    (void)snprintf(r->info, sizeof r->info, "%s", info);
    r->t_start_ns = 1000000000ull * (i + 1u);
    r->t_end_ns = r->t_start_ns + 250000000ull;
}

/* One run: a PASS with information and an FDL status exchange (answered, then a silent slot),
 * a FAIL whose reason needs escaping, an NA. */
static void fill(cf_t *cf, cf_verdict_t lock_verdict)
{
    static const uint8_t status_req[] = {0x10, 0x05, 0x01, 0x49, 0x4F, 0x16};
    static const uint8_t status_rsp[] = {0x10, 0x01, 0x05, 0x00, 0x06, 0x16};
    static const uint8_t sc[] = {0xE5};
    memset(cf, 0, sizeof *cf);
    cf->gsd = &g;
    cf->ident = 0x6003;
    cf->opt.address = 5;
    cf->opt.master = 1;
    cf->opt.master_2 = 3;
    cf->opt.class2 = 2;
    cf->link.name = "pty <a&b>";
    result(cf, 0, CF_PASS, "", "");
    result(cf, 1, CF_PASS, "", "answered with SD1");
    cf_result_t *r = &cf->results[1];
    frame(r, true, r->t_start_ns + 1000000u, CF_TSDR_UNKNOWN, status_req, sizeof status_req);
    frame(r, false, r->t_start_ns + 1500000u, 37, status_rsp, sizeof status_rsp);
    frame(r, true, r->t_start_ns + 4000000u, CF_TSDR_UNKNOWN, status_req, sizeof status_req);
    frame(r, false, r->t_start_ns + 6000000u, CF_TSDR_UNKNOWN, NULL, 0);
    result(cf, 2, lock_verdict,
           lock_verdict == CF_PASS ? "" : "Set_Prm from master 3 <accepted> & \"owner\" \xFF",
           "");
    r = &cf->results[2];
    frame(r, false, r->t_start_ns + 2000000u, CF_TSDR_UNKNOWN, sc, sizeof sc);
    result(cf, 3, CF_NA, "the medium has no timing (a PTY)", "");
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    static char buf[1 << 17];
    size_t n = f != NULL ? fread(buf, 1, sizeof buf - 1u, f) : 0u;
    buf[n] = '\0';
    if (f != NULL) {
        (void)fclose(f);
    }
    return buf;
}

/* The report writer's output as a string (static: one at a time). */
typedef int (*writer_t)(FILE *, const cf_report_run_t *, size_t, const cf_report_info_t *);
static const char *written(writer_t w, const cf_report_run_t *runs, size_t n, const char *path)
{
    static const cf_report_info_t info = {"dfp<21b>.gsd", "2025-03-01 10:00 UTC", "dfp-sim 1.0"};
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (f == NULL) {
        return "";
    }
    CHECK_EQ(w(f, runs, n, &info), 0);
    CHECK_EQ(fclose(f), 0);
    return slurp(path);
}

/* What the Python script says about a file (its whole output). */
static const char *parsed(const char *python, const char *script, const char *mode,
                          const char *path)
{
    static char buf[1 << 14];
    char cmd[1024];
    (void)snprintf(cmd, sizeof cmd, "'%s' '%s' %s '%s'", python, script, mode, path);
    FILE *p = popen(cmd, "r");
    size_t n = p != NULL ? fread(buf, 1, sizeof buf - 1u, p) : 0u;
    buf[n] = '\0';
    CHECK(p != NULL && pclose(p) == 0);
    return buf;
}

static const char text_one[] =
    "DUT:     station 5, Ve<nd> & 'Co' \\xe9 M\xC3\xBCller-1, ident 0x6003\n"
    "GSD:     dfp<21b>.gsd\n"
    "medium:  pty <a&b>\n"
    "rate:    1.5 Mbit/s\n"
    "date:    2025-03-01 10:00 UTC\n"
    "tool:    dfp-sim 1.0\n"
    "\n"
    "PASS  gsd.check        the GSD file is consistent\n"
    "PASS  fdl.status       Request FDL Status is answered\n"
    "      info: answered with SD1\n"
    "FAIL  dp.set_prm.lock  a locked slave refuses another master's Set_Prm\n"
    "      Set_Prm from master 3 <accepted> & \"owner\" \\xff\n"
    "NA    timing.tsdr.min  answers wait min TSDR\n"
    "      the medium has no timing (a PTY)\n"
    "summary: 4 cases, 2 PASS, 1 FAIL, 1 NOT APPLICABLE\n";

static void test_text(void)
{
    check_test_name_ = "text";
    cf_report_run_t one = {&run_a, 1500000u};
    CHECK_STR(written(cf_report_text, &one, 1, "cf_report.txt"), text_one);
    /* two rates: each run under its rate with its counts, then the counts of both */
    cf_report_run_t two[2] = {{&run_a, 1500000u}, {&run_b, 9600u}};
    const char *t = written(cf_report_text, two, 2, "cf_report2.txt");
    CHECK(strstr(t, "rates:   1.5 Mbit/s, 9.6 kbit/s\n") != NULL);
    CHECK(strstr(t, "\nat 1.5 Mbit/s:\nPASS  gsd.check        the GSD") != NULL);
    CHECK(strstr(t, "1.5 Mbit/s: 4 cases, 2 PASS, 1 FAIL, 1 NOT APPLICABLE\n\nat 9.6 kbit/s:\n")
          != NULL);
    CHECK(strstr(t, "PASS  dp.set_prm.lock  a locked") != NULL);
    const char *end = "9.6 kbit/s: 4 cases, 3 PASS, 0 FAIL, 1 NOT APPLICABLE\n\n"
                      "summary: 8 cases, 5 PASS, 1 FAIL, 2 NOT APPLICABLE\n";
    CHECK(strlen(t) > strlen(end) && strcmp(t + strlen(t) - strlen(end), end) == 0);
    /* a run the medium ended: why, before its counts, a control character made visible */
    run_b.link_failed = true;
    (void)snprintf(run_b.link_error, sizeof run_b.link_error, "link: read: \x1b[2J gone");
    t = written(cf_report_text, two, 2, "cf_report3.txt");
    CHECK(strstr(t, "the medium has no timing (a PTY)\n"
                    "the run stopped: link: read: \\x1b[2J gone\n9.6 kbit/s: 4 cases") != NULL);
    run_b.link_failed = false;
}

static const char junit_one[] =
    "testsuites tests=4 failures=1 skipped=1\n"
    "suite GSD tests=1 failures=0 skipped=0 rate=1.5 Mbit/s vendor=Ve<nd> & 'Co' ?\n"
    "  case GSD gsd.check pass\n"
    "suite FDL tests=1 failures=0 skipped=0 rate=1.5 Mbit/s vendor=Ve<nd> & 'Co' ?\n"
    "  case FDL fdl.status pass\n"
    "suite DP state machine tests=1 failures=1 skipped=0 rate=1.5 Mbit/s"
    " vendor=Ve<nd> & 'Co' ?\n"
    "  case DP state machine dp.set_prm.lock failure: Set_Prm from master 3 <accepted> &"
    " \"owner\" ?\n"
    "suite Timing tests=1 failures=0 skipped=1 rate=1.5 Mbit/s vendor=Ve<nd> & 'Co' ?\n"
    "  case Timing timing.tsdr.min skipped: the medium has no timing (a PTY)\n";

static void test_junit(const char *python, const char *script)
{
    check_test_name_ = "junit";
    cf_report_run_t one = {&run_a, 1500000u};
    (void)written(cf_report_junit, &one, 1, "cf_report.xml");
    CHECK_STR(parsed(python, script, "junit", "cf_report.xml"), junit_one);
    /* the evidence of fdl.status in its system-out: request, timed answer, silent slot */
    const char *x = slurp("cf_report.xml");
    CHECK(strstr(x, "  DUT       +1.500 ms 37 bits        10 01 05 00 06 16 | ") != NULL);
    CHECK(strstr(x, "  DUT       +6.000 ms -              - | no answer (silence)\n"
                    "</system-out>") != NULL);
    CHECK(strstr(x, "info: answered with SD1\ntelegrams: 4:\n  tester    +1.000 ms -    "
                    "          10 05 01 49 4F 16 | FDL_Status 1 -&gt; 5 (FDL status request)\n")
          != NULL);
    CHECK(strstr(x, "the GSD file is consistent\ntelegrams: 0\n</system-out>") != NULL);
    /* two rates: a testsuite per group and rate, the rate in the classname */
    cf_report_run_t two[2] = {{&run_a, 1500000u}, {&run_b, 9600u}};
    (void)written(cf_report_junit, two, 2, "cf_report2.xml");
    const char *p = parsed(python, script, "junit", "cf_report2.xml");
    CHECK(strncmp(p, "testsuites tests=8 failures=1 skipped=2\n", 40) == 0);
    CHECK(strstr(p, "  case DP state machine at 1500000 bit/s dp.set_prm.lock failure:") != NULL);
    CHECK(strstr(p, "  case DP state machine at 9600 bit/s dp.set_prm.lock pass\n") != NULL);
    CHECK(strstr(p, "suite Timing at 9600 bit/s tests=1 failures=0 skipped=1 rate=9.6 kbit/s")
          != NULL);
}

static const char html_two[] =
    "title PROFIBUS-DP slave conformance: Ve<nd> & 'Co' ? M\xC3\xBCller-1 (ident 0x6003)\n"
    "dut Vendor=Ve<nd> & 'Co' ? Model=M\xC3\xBCller-1 Ident number=0x6003 GSD file=dfp<21b>.gsd"
    " Address=5 Medium=pty <a&b> Rates=1.5 Mbit/s, 9.6 kbit/s Date=2025-03-01 10:00 UTC"
    " Tool=dfp-sim 1.0\n"
    "summary Group | 1.5 Mbit/s | 9.6 kbit/s\n"
    "summary GSD | 1 PASS, 0 FAIL, 0 NOT APPLICABLE | 1 PASS, 0 FAIL, 0 NOT APPLICABLE\n"
    "summary FDL | 1 PASS, 0 FAIL, 0 NOT APPLICABLE | 1 PASS, 0 FAIL, 0 NOT APPLICABLE\n"
    "summary DP state machine | 0 PASS, 1 FAIL, 0 NOT APPLICABLE"
    " | 1 PASS, 0 FAIL, 0 NOT APPLICABLE\n"
    "summary Timing | 0 PASS, 0 FAIL, 1 NOT APPLICABLE | 0 PASS, 0 FAIL, 1 NOT APPLICABLE\n"
    "summary All groups | 2 PASS, 1 FAIL, 1 NOT APPLICABLE | 3 PASS, 0 FAIL, 1 NOT APPLICABLE\n"
    "h2 Cases at 1.5 Mbit/s\n"
    "case r0-gsd.check pass GSD\n"
    "case r0-fdl.status pass FDL\n"
    "  tg tester|+1.000 ms||10 05 01 49 4F 16|FDL_Status 1 -> 5 (FDL status request)\n"
    "  tg DUT|+1.500 ms|37 bits|10 01 05 00 06 16|FDL status reply 5 -> 1: OK\n"
    "  tg tester|+4.000 ms||10 05 01 49 4F 16|FDL_Status 1 -> 5 (FDL status request)\n"
    "  tg DUT|+6.000 ms|||no answer (silence)\n"
    "case r0-dp.set_prm.lock fail DP state machine"
    " reason=Set_Prm from master 3 <accepted> & \"owner\" ?\n"
    "  tg DUT|+2.000 ms|not measurable|E5|SC (short acknowledgement)\n"
    "case r0-timing.tsdr.min na Timing reason=the medium has no timing (a PTY)\n"
    "h2 Cases at 9.6 kbit/s\n"
    "case r1-gsd.check pass GSD\n"
    "case r1-fdl.status pass FDL\n"
    "  tg tester|+1.000 ms||10 05 01 49 4F 16|FDL_Status 1 -> 5 (FDL status request)"
    " (at 1.5 Mbit/s)\n"
    "  tg DUT|+1.500 ms|37 bits|10 01 05 00 06 16|FDL status reply 5 -> 1: OK (at 1.5 Mbit/s)\n"
    "  tg tester|+4.000 ms||10 05 01 49 4F 16|FDL_Status 1 -> 5 (FDL status request)"
    " (at 1.5 Mbit/s)\n"
    "  tg DUT|+6.000 ms|||no answer (silence) (at 1.5 Mbit/s)\n"
    "case r1-dp.set_prm.lock pass DP state machine\n"
    "  tg DUT|+2.000 ms|not measurable|E5|SC (short acknowledgement) (at 1.5 Mbit/s)\n"
    "case r1-timing.tsdr.min na Timing reason=the medium has no timing (a PTY)\n"
    "self-contained\n";

static void test_html(const char *python, const char *script)
{
    check_test_name_ = "html";
    cf_report_run_t two[2] = {{&run_a, 1500000u}, {&run_b, 9600u}};
    (void)written(cf_report_html, two, 2, "cf_report.html");
    CHECK_STR(parsed(python, script, "html", "cf_report.html"), html_two);
}

int main(int argc, char **argv)
{
    char err[GSD_ERR_LEN];
    if (argc != 3) {
        fprintf(stderr, "usage: test_cf_report PYTHON SCRIPT\n");
        return 2;
    }
    CHECK_EQ(gsd_parse_text(gsd_text_src, strlen(gsd_text_src), &g, err, sizeof err), 0);
    fill(&run_a, CF_FAIL);
    fill(&run_b, CF_PASS);
    test_text();
    test_junit(argv[1], argv[2]);
    test_html(argv[1], argv[2]);
    return check_report();
}
