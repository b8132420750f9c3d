/* The conformance suite's reports: the terminal's, JUnit XML for a CI server, and an HTML file a
 * test lab hands over (self-contained: inline style, no scripts, no external links).
 *
 * A report covers one or several finished runs of the same DUT: dfp-sim conformance --baud all
 * runs the suite once per rate, and each run is one cf_t. The terminal report lists each run's
 * cases and counts, JUnit gives each group of each run a testsuite (the rate in its name and
 * the classname), the HTML report a summary by group with a column per rate and then a section
 * per rate with every case and its decisive telegrams decoded.
 *
 * Everything from the wire, the GSD file and the reasons is escaped for where it goes: control
 * characters shown as "\xNN" on the terminal, & < > " ' as entities in XML and HTML, an octet
 * that begins no UTF-8 sequence as '?' (the files are UTF-8). */
#ifndef CONFORMANCE_CF_REPORT_H
#define CONFORMANCE_CF_REPORT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "conformance/cf.h"

/* One finished run and the rate it ran at (0: a medium without a rate, a PTY). */
typedef struct cf_report_run {
    const cf_t *cf;
    uint32_t baud;
} cf_report_run_t;

/* What the report says beside the runs. Every field may be NULL (then left out or "-"). */
typedef struct cf_report_info {
    const char *gsd_path; /* the GSD file as given on the command line */
    const char *date;     /* when the runs were made, as the caller writes it */
    const char *tool;     /* "dfp-sim 0.9.0": what tested */
} cf_report_info_t;

/* The terminal report: a header (DUT, GSD file, ident, medium, rates, date), then per run one
 * line per case "VERDICT  id  title" with a FAIL's or NA's reason and any information
 * indented below it, the run's counts, and the counts of all runs when there are several.
 * Returns 0, or -1 when writing failed. */
int cf_report_text(FILE *out, const cf_report_run_t *runs, size_t n,
                   const cf_report_info_t *info);

/* JUnit XML: <testsuites> with one <testsuite> per group and run; a FAIL is a <failure>, a
 * NOT APPLICABLE a <skipped>, each with its reason as message; the evidence (the case's last
 * telegrams decoded) and its information in <system-out>. 0 or -1 as above. */
int cf_report_junit(FILE *out, const cf_report_run_t *runs, size_t n,
                    const cf_report_info_t *info);

/* The HTML report (well-formed XML as well, so any XML tool reads it). 0 or -1 as above. */
int cf_report_html(FILE *out, const cf_report_run_t *runs, size_t n,
                   const cf_report_info_t *info);

/* "9.6 kbit/s", "1.5 Mbit/s", "no rate" (0): the rate as the reports name it. */
const char *cf_report_rate_text(uint32_t baud, char *buf, size_t n);

#endif
