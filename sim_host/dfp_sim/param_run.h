/* dfp-sim param: what one run asks for and what it got, shared by the run and its way to the
 * slave (cmd_param.c, a rig with the master on the medium) and the output (param_print.c). */
#ifndef DFP_SIM_PARAM_RUN_H
#define DFP_SIM_PARAM_RUN_H

#include <stdbool.h>
#include <stdint.h>

#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"

typedef enum via { VIA_CHANNEL = 0, VIA_MOVILINK, VIA_PROFIDRIVE, VIA_C2 } via_t;
typedef enum op { OP_READ = 0, OP_WRITE, OP_IM0 } op_t;

extern const char *const param_via_names[4];

typedef enum stage {
    ST_START = 0,  /* waiting for data exchange / opening the connection */
    ST_RUNNING,    /* the service is on its way */
    ST_ABORTING,   /* class 2: closing the connection after the result */
    ST_DONE,
} stage_t;

/* One parameter's outcome: a data set 47 answer fails or succeeds parameter by parameter. */
typedef struct param_result {
    bool ok;
    bool have_value;
    uint32_t value;
    char error[32];  /* "0x0815", "DP-V1 0xB0", "timeout", "failed" */
    char text[256];
} param_result_t;

typedef struct run {
    op_t op;
    via_t via;
    uint8_t n;  /* parameters: 1, or up to DS47_MAX_PARAMS for a data set 47 read */
    uint16_t index[DS47_MAX_PARAMS];
    uint32_t value;
    bool volatile_write;
    bool json;
    stage_t stage;
    /* result: the whole run's (ok only if every parameter's is), then each parameter's */
    bool ok;
    param_result_t r[DS47_MAX_PARAMS];
    dp_master_im0_t im0;
    /* paths */
    dp_master_param_t pc;
    uint8_t out[14];
    dp_master_call_t call;
    dp_master_ds47_req_t req;
    dp_master_c2_t c2;
    bool c2_open_done;
    bool c2_open_ok;
    bool c2_abort_done;
    uint32_t cycles_at_start;
} run_t;

#define IPOS_FIRST 11000u /* H0; H0..H511 are 11000 + n */
#define IPOS_COUNT 512u

/* One line (or JSON object) per parameter, in the order asked, on stdout. */
void param_print_results(const run_t *run);

#endif
