/* The start-up every other case builds on, as a case of its own: a master's start-up with the
 * GSD's defaults reaches data exchange. */
#include "conformance/cf.h"
#include "conformance/cf_cases.h"

static void start_up(cf_t *cf)
{
    (void)cf_start_up(cf);
}

const cf_case_t cf_cases_core[] = {
    {"dp.start_up", "DP state machine", "IEC 61158-6-3 8.3 (DP slave start-up)",
     "Slave_Diag, Set_Prm and Chk_Cfg from the GSD, then Data_Exchange", start_up},
};
const size_t cf_cases_core_count = sizeof cf_cases_core / sizeof cf_cases_core[0];
