/* What the three reports share: escaping, counts, the DUT's texts, a telegram as text. */
#ifndef CONFORMANCE_CF_REPORT_PRIV_H
#define CONFORMANCE_CF_REPORT_PRIV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "conformance/cf.h"
#include "conformance/cf_report.h"

#define CF_RP_MAX_GROUPS 16u
#define CF_RP_RATE_TEXT 24u

/* Text for XML character data and attribute values: & < > " ' as entities, control characters
 * XML 1.0 cannot carry and octets that begin no UTF-8 sequence as '?'. NULL writes nothing. */
void cf_rp_xml(FILE *out, const char *s);
/* name="value" with the value escaped, a space before it. */
void cf_rp_attr(FILE *out, const char *name, const char *value);

/* Verdict counts: [CF_PASS], [CF_FAIL], [CF_NA]. group NULL: every result of the run. */
typedef struct cf_rp_counts {
    size_t v[3];
    size_t total;
} cf_rp_counts_t;
cf_rp_counts_t cf_rp_count(const cf_t *cf, const char *group);
/* Every result of every run. */
cf_rp_counts_t cf_rp_count_runs(const cf_report_run_t *runs, size_t n);

/* The groups of the runs' results in the order they first appear (the suite runs its cases
 * in report order, so this is the report order). Returns how many. */
size_t cf_rp_groups(const cf_report_run_t *runs, size_t n, const char **groups, size_t max);

/* "NA" for the terminal's column, the verdict's full name for the files. */
const char *cf_rp_verdict_short(cf_verdict_t v);
const char *cf_rp_verdict_long(cf_verdict_t v);

/* The DUT as the GSD names it: "SEW-EURODRIVE", "DFP21B" ("-" without a GSD or the key). */
const char *cf_rp_vendor(const cf_t *cf);
const char *cf_rp_model(const cf_t *cf);
/* "9.6 kbit/s, 1.5 Mbit/s": the runs' rates. */
void cf_rp_rates(const cf_report_run_t *runs, size_t n, char *out, size_t max);
/* "-" for NULL. */
const char *cf_rp_or_dash(const char *s);

/* One evidence telegram as the reports show it. */
typedef struct cf_rp_frame {
    const char *from;    /* "tester" or "DUT" */
    char time[32];       /* "+1.250 ms" from the case's start */
    char tsdr[32];       /* an answer's "37 bits" or "not measurable"; "" for a request */
    char hex[3u * CF_FRAME_MAX + 4u];
    char text[320];      /* replay_describe's line, "no answer" for a silent slot */
} cf_rp_frame_t;
void cf_rp_frame(const cf_result_t *r, const cf_frame_t *f, uint32_t run_baud,
                 cf_rp_frame_t *out);

#endif
