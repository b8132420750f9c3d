/* The DP slave machine as one table: for every DDLM service (IEC 61158-6-3 names) which DP
 * state lets it run, what the slave answers otherwise, and whether another master may use it
 * while a master holds the lock (protocol.md §A3.1 SAP map, §A3.6 state machine).
 *
 * The slave (dp_slave.c) routes every request through dp_service_rule(); host tools (master,
 * replay decoder, logs) name services with dp_service_of() and dp_service_label(), and the
 * Wireshark dissector's SAP names are checked against the labels
 * (tests/wireshark/check_wire_constants.py), so a rule and its names are found in one place. */
#ifndef DP_SLAVE_DP_SERVICES_H
#define DP_SLAVE_DP_SERVICES_H

#include <stdbool.h>
#include <stdint.h>

#include "dp_slave/dp_wire.h"

typedef enum dp_service {
    DDLM_DATA_EXCHANGE = 0, /* no SAP ("default SAP") */
    DDLM_SET_PRM,           /* SAP 61 */
    DDLM_CHK_CFG,           /* SAP 62 */
    DDLM_SLAVE_DIAG,        /* SAP 60 */
    DDLM_GET_CFG,           /* SAP 59 */
    DDLM_GLOBAL_CONTROL,    /* SAP 58, SDN (broadcast or multicast allowed) */
    DDLM_RD_OUTP,           /* SAP 57 */
    DDLM_RD_INP,            /* SAP 56 */
    DDLM_SET_SLAVE_ADD,     /* SAP 55 */
    MSAC1S,                 /* SAP 51: DP-V1 class-1 acyclic (Read/Write/Alarm_Ack) */
    MSAC2S,                 /* the other SAPs below 55: 49 the MSAC2 resource manager, 0..48
                             * connections; the DP-V1 layer refuses the ones it did not assign */
    DP_SERVICE_UNKNOWN,     /* SAP 63: nothing is served there */
    DP_SERVICE_COUNT
} dp_service_t;

/* What the slave does with a request its state does not allow. */
typedef enum dp_state_rule {
    DP_RULE_EXECUTE = 0, /* the service runs */
    DP_RULE_RS,          /* FDL RS: "service not activated" */
    DP_RULE_SC,          /* acknowledged with SC, otherwise ignored */
    DP_RULE_IGNORE,      /* nothing at all (services sent without reply) */
} dp_state_rule_t;

/* Who may use a service while a master has parameterised the slave (Lock_Req). */
typedef enum dp_lock_rule {
    DP_LOCK_ANY = 0,        /* any master (diagnosis, configuration and I/O reads) */
    DP_LOCK_OWNER_OR_RS,    /* only the owner; others get RS and a DP_EV_LOCKED_OUT event */
    DP_LOCK_OWNER_OR_IGNORE /* only the owner; others are ignored silently (no reply exists) */
} dp_lock_rule_t;

#define DP_STATE_COUNT 3u /* Wait_Prm, Wait_Cfg, Data_Exch: indexes of in_state[] */

typedef struct dp_service_rule {
    const char *name;    /* the standard's name, e.g. "DDLM_Set_Prm" */
    const char *label;   /* what host tools print, e.g. "Set_Prm" (see dp_services.c) */
    bool sdn;            /* sent as SDN (send data with no acknowledge) rather than SRD */
    dp_lock_rule_t lock;
    dp_state_rule_t in_state[DP_STATE_COUNT];
} dp_service_rule_t;

/* The table (dp_services.c); inline lookups, as they are on every reply path. */
extern const dp_service_rule_t dp_service_rules[DP_SERVICE_COUNT];

/* The service a request addresses: by its DSAP, or Data_Exchange when it has none. */
static inline dp_service_t dp_service_of(bool has_dsap, uint8_t dsap)
{
    if (!has_dsap) {
        return DDLM_DATA_EXCHANGE;
    }
    switch (dsap) {
    case DP_SAP_SET_PRM: return DDLM_SET_PRM;
    case DP_SAP_CHK_CFG: return DDLM_CHK_CFG;
    case DP_SAP_SLAVE_DIAG: return DDLM_SLAVE_DIAG;
    case DP_SAP_GET_CFG: return DDLM_GET_CFG;
    case DP_SAP_GLOBAL_CONTROL: return DDLM_GLOBAL_CONTROL;
    case DP_SAP_RD_OUTP: return DDLM_RD_OUTP;
    case DP_SAP_RD_INP: return DDLM_RD_INP;
    case DP_SAP_SET_SLAVE_ADD: return DDLM_SET_SLAVE_ADD;
    case DP_SAP_MSAC1: return MSAC1S;
    default: break;
    }
    return dsap < DP_SAP_SET_SLAVE_ADD ? MSAC2S : DP_SERVICE_UNKNOWN;
}

static inline const dp_service_rule_t *dp_service_rule(dp_service_t svc)
{
    return &dp_service_rules[(unsigned)svc < DP_SERVICE_COUNT ? svc : DP_SERVICE_UNKNOWN];
}
const char *dp_service_name(dp_service_t svc);
/* The short name host tools print (logs, replay report, dissector): the standard's name without
 * "DDLM_", in the spelling those tools have always used. */
const char *dp_service_label(dp_service_t svc);
/* Slave_Diag's label as a literal, for names composed at compile time (the host master's
 * "Slave_Diag (check)" phase). */
#define DP_SERVICE_LABEL_SLAVE_DIAG "Slave_Diag"

#endif
