/* A mutant card through the whole conformance suite (mutants.cmake): the card in process (with
 * whatever card sources this program was linked with), the suite run once, and the verdicts
 * compared with what the mutant must show: the cases named on the command line FAIL, every
 * other case PASSes or is NOT APPLICABLE.
 *
 * usage: cf_mutant_NAME GSD CASE[,CASE...]   (an empty list: the real card, nothing fails)
 * Prints every case that did not do as expected, then "mutant failing: ..." (the cases that
 * failed, for the table in the report). Exit 0 when all did as expected, 1 if not, 2 for a bad
 * command line. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "conformance/cf.h"
#include "conformance/cf_rig.h"

#define MUTANT_ADDRESS 5u
#define MUTANT_BAUD 1500000u

static gsd_t gsd;
static cf_t cf;
static cf_rig_t rig;
static cf_case_t cases[CF_MAX_CASES];

/* id is one of the comma-separated ids in list. */
static bool listed(const char *list, const char *id)
{
    size_t n = strlen(id);
    for (const char *p = list; *p != '\0';) {
        const char *end = strchr(p, ',');
        size_t len = end != NULL ? (size_t)(end - p) : strlen(p);
        if (len == n && strncmp(p, id, n) == 0) {
            return true;
        }
        p += len + (end != NULL ? 1u : 0u);
    }
    return false;
}

/* Every id of the list names a case that ran. */
static bool expected_ran(const char *list)
{
    bool ok = true;
    for (const char *p = list; *p != '\0';) {
        const char *end = strchr(p, ',');
        size_t len = end != NULL ? (size_t)(end - p) : strlen(p);
        bool found = false;
        for (size_t i = 0; i < cf.n_results && !found; i++) {
            found = strlen(cf.results[i].c->id) == len &&
                    strncmp(cf.results[i].c->id, p, len) == 0;
        }
        if (!found) {
            printf("expected to fail: %.*s, which the suite does not have or did not run\n",
                   (int)len, p);
            ok = false;
        }
        p += len + (end != NULL ? 1u : 0u);
    }
    return ok;
}

static bool judge(const char *expect)
{
    bool ok = expected_ran(expect);
    for (size_t i = 0; i < cf.n_results; i++) {
        const cf_result_t *r = &cf.results[i];
        bool must_fail = listed(expect, r->c->id);
        if (must_fail != (r->verdict == CF_FAIL)) {
            printf("%s: %s%s%s\n", r->c->id, cf_verdict_name(r->verdict),
                   r->reason[0] != '\0' ? ": " : "", r->reason);
            printf("    expected %s\n", must_fail ? "FAIL" : "PASS or NOT APPLICABLE");
            ok = false;
        }
    }
    printf("mutant failing:");
    const char *sep = " ";
    for (size_t i = 0; i < cf.n_results; i++) {
        if (cf.results[i].verdict == CF_FAIL) {
            printf("%s%s", sep, cf.results[i].c->id);
            sep = ", ";
        }
    }
    printf("%s\n", sep[0] == ' ' ? " none" : "");
    return ok;
}

int main(int argc, char **argv)
{
    char err[GSD_ERR_LEN];
    if (argc != 3) {
        fprintf(stderr, "usage: %s GSD CASE[,CASE...]\n", argv[0]);
        return 2;
    }
    if (gsd_parse_file(argv[1], &gsd, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    cf_rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .card_address = MUTANT_ADDRESS,
                       .baud = MUTANT_BAUD};
    if (cf_rig_open(&rig, &rc, err, sizeof err) != 0) {
        fprintf(stderr, "the card in process: %s\n", err);
        return 1;
    }
    cf_link_t link = cf_rig_link(&rig, "the mutant card in process");
    cf_options_t opt = {.address = MUTANT_ADDRESS, .master = 1, .master_2 = 3, .class2 = 2,
                        .module = -1, .only = NULL, .watchdog_ms = 200};
    if (cf_init(&cf, &link, &gsd, &opt, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return 1;
    }
    size_t n = cf_all_cases(cases, CF_MAX_CASES);
    cf_run(&cf, cases, n);
    bool ok = judge(argv[2]);
    cf_rig_close(&rig);
    return ok ? 0 : 1;
}
