/* The master's Set_Prm builders and its phases' names. */
#include <string.h>

#include "dp_master/dp_master.h"
#include "dp_slave/dp_services.h"
#include "dp_slave/dp_wire.h"

/* A phase that sends a DDLM service is named by the service table (dp_services.h); the phases
 * around them are the master's own. */
const char *dp_master_phase_name(dp_master_phase_t p)
{
    switch (p) {
    case DP_MASTER_PHASE_BACKOFF: return "back-off";
    case DP_MASTER_PHASE_FDL_STATUS: return "FDL status";
    case DP_MASTER_PHASE_DIAG_1: return dp_service_label(DDLM_SLAVE_DIAG);
    case DP_MASTER_PHASE_SET_PRM: return dp_service_label(DDLM_SET_PRM);
    case DP_MASTER_PHASE_CHK_CFG: return dp_service_label(DDLM_CHK_CFG);
    case DP_MASTER_PHASE_DATA_EXCH: return dp_service_label(DDLM_DATA_EXCHANGE);
    case DP_MASTER_PHASE_DIAG_2: return DP_SERVICE_LABEL_SLAVE_DIAG " (check)";
    case DP_MASTER_PHASE_DIAG_DX: return DP_SERVICE_LABEL_SLAVE_DIAG " (DH)";
    }
    return "?";
}

size_t dp_master_build_prm(uint8_t *out, uint16_t ident, uint32_t wd_ms, const uint8_t *user,
                     size_t user_len)
{
    uint32_t units = (wd_ms + 9u) / 10u; /* 10 ms base */
    uint8_t f1 = 1;
    uint8_t f2 = 1;
    bool wd = wd_ms > 0u;
    if (wd) {
        if (units < 2u) units = 2u; /* 1 x 1 is not allowed */
        if (units > 255u * 255u) units = 255u * 255u;
        f1 = (uint8_t)((units + 254u) / 255u);
        if (f1 < 1u) f1 = 1u;
        f2 = (uint8_t)((units + f1 - 1u) / f1);
        if (f1 == 1u && f2 == 1u) f2 = 2u;
    }
    out[DP_PRM_STATION_STATUS] = (uint8_t)(DP_PRM_LOCK_REQ | (wd ? DP_PRM_WD_ON : 0u));
    out[DP_PRM_WD_FACT_1] = f1;
    out[DP_PRM_WD_FACT_2] = f2;
    out[DP_PRM_MIN_TSDR] = FDL_MIN_TSDR_DEFAULT_BITS;
    out[DP_PRM_IDENT_HIGH] = (uint8_t)(ident >> 8);
    out[DP_PRM_IDENT_LOW] = (uint8_t)(ident & 0xFFu);
    out[DP_PRM_GROUP_IDENT] = 0;
    if (user_len > DP_MASTER_MAX_PRM - DP_PRM_LEN_STANDARD) {
        user_len = DP_MASTER_MAX_PRM - DP_PRM_LEN_STANDARD;
    }
    memcpy(&out[DP_PRM_LEN_STANDARD], user, user_len);
    return DP_PRM_LEN_STANDARD + user_len;
}

size_t dp_master_build_prm_dpv1(uint8_t *out, uint16_t ident, uint32_t wd_ms, const uint8_t *user,
                          size_t user_len)
{
    uint8_t u[DP_MASTER_MAX_PRM - DP_PRM_LEN_STANDARD] = {0};
    if (user_len > sizeof u) {
        user_len = sizeof u;
    }
    if (user_len > 0u) {
        memcpy(u, user, user_len);
    }
    size_t n = user_len < 3u ? 3u : user_len; /* DPV1_Status_1..3 at least */
    u[0] |= DP_DPV1_1_ENABLE;
    return dp_master_build_prm(out, ident, wd_ms, u, n);
}

bool dp_master_prm_is_dpv1(const uint8_t *prm, size_t len)
{
    return len >= DP_PRM_LEN_DPV1 && (prm[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_ENABLE) != 0u;
}
