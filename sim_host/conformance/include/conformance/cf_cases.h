/* The case tables of the suite's groups (cf_all_cases joins them in this order). */
#ifndef CONFORMANCE_CF_CASES_H
#define CONFORMANCE_CF_CASES_H

#include <stddef.h>

#include "conformance/cf.h"
#include "conformance/cf_cases_dp.h"
#include "conformance/cf_cases_fdl.h"
#include "conformance/cf_cases_v1t.h"

extern const cf_case_t cf_cases_core[];
extern const size_t cf_cases_core_count;

#define CF_CASE_TABLES                                                                            \
    {cf_cases_gsd, &cf_cases_gsd_count}, {cf_cases_fdl, &cf_cases_fdl_count},                    \
        {cf_cases_core, &cf_cases_core_count}, {cf_cases_dp, &cf_cases_dp_count},                \
        {cf_cases_timing, &cf_cases_timing_count}, {cf_cases_dpv1, &cf_cases_dpv1_count}

#endif
