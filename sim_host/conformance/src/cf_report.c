/* Reports (cf_report.h). */
#include "conformance/cf_report.h"

void cf_report_text(FILE *f, const cf_run_t *runs, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        size_t pass, fail, na;
        cf_count(runs[k].cf, &pass, &fail, &na);
        fprintf(f, "%u bit/s: %zu PASS, %zu FAIL, %zu NOT APPLICABLE\n", (unsigned)runs[k].baud,
                pass, fail, na);
    }
}

static int not_yet(const char *path, char *err, size_t errlen)
{
    snprintf(err, errlen, "%s: this report is not written yet", path);
    return -1;
}

int cf_report_junit_file(const char *path, const cf_run_t *runs, size_t n, char *err,
                         size_t errlen)
{
    (void)runs;
    (void)n;
    return not_yet(path, err, errlen);
}

int cf_report_html_file(const char *path, const cf_run_t *runs, size_t n, char *err,
                        size_t errlen)
{
    (void)runs;
    (void)n;
    return not_yet(path, err, errlen);
}
