/* The "Timing" and "DP-V1" groups of the conformance suite (src/cases_timing.c,
 * src/cases_dpv1*.c), joined by cf_all_cases (cf_cases.h). */
#ifndef CONFORMANCE_CF_CASES_V1T_H
#define CONFORMANCE_CF_CASES_V1T_H

#include <stddef.h>

#include "conformance/cf.h"

extern const cf_case_t cf_cases_timing[];
extern const size_t cf_cases_timing_count;
extern const cf_case_t cf_cases_dpv1[];
extern const size_t cf_cases_dpv1_count;

#endif
