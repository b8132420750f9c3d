/* The "DP state machine" group of the conformance suite (src/cases_dp*.c): every DP service in
 * every state, Set_Prm with lock, unlock and user parameters, the watchdog, Chk_Cfg, Get_Cfg,
 * the diagnosis bits, Global_Control and a second class-1 and a class-2 master. */
#ifndef CONFORMANCE_CF_CASES_DP_H
#define CONFORMANCE_CF_CASES_DP_H

#include <stddef.h>

#include "conformance/cf.h"

extern const cf_case_t cf_cases_dp[];
extern const size_t cf_cases_dp_count;

#endif
