/* The suite's reports: terminal, JUnit, HTML, of one run or of several (one per rate). */
#ifndef CONFORMANCE_CF_REPORT_H
#define CONFORMANCE_CF_REPORT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "conformance/cf.h"

typedef struct cf_run {
    const cf_t *cf;
    uint32_t baud;
    const char *gsd_path;
} cf_run_t;

void cf_report_text(FILE *f, const cf_run_t *runs, size_t n);
int cf_report_junit_file(const char *path, const cf_run_t *runs, size_t n, char *err,
                         size_t errlen);
int cf_report_html_file(const char *path, const cf_run_t *runs, size_t n, char *err,
                        size_t errlen);

#endif
