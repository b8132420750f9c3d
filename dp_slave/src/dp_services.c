/* The service table of dp_services.h. Rows follow IEC 61158-6-3's DP slave state machine as
 * summarised in protocol.md §A3.6; the choices the standard leaves to the implementation are the
 * VPC3+ ASIC's, listed with their reasons in docs/architecture.md ("Protocol decisions"). */
#include "dp_slave/dp_services.h"

#include "dp_slave/dp_wire.h"

#define X DP_RULE_EXECUTE
#define RS DP_RULE_RS

/* Columns: name, label, SDN, lock rule, then Wait_Prm, Wait_Cfg, Data_Exch.
 * The label is stored, not derived from the name: host tools, their tests, golden captures, the
 * Python client and the dissector print "Rd_Inp"/"Rd_Outp" where the standard writes
 * "DDLM_RD_Inp"/"DDLM_RD_Outp", and "MSAC1"/"MSAC2" (the dissector's names of the SAPs) for the
 * slave-side MSAC1S/MSAC2S. Every other label is the name without "DDLM_". */
const dp_service_rule_t dp_service_rules[DP_SERVICE_COUNT] = {
    /* Outputs are only taken from the master that parameterised the slave, in Data_Exch. */
    [DDLM_DATA_EXCHANGE] = {"DDLM_Data_Exchange", "Data_Exchange", false, DP_LOCK_OWNER_OR_RS,
                            {RS, RS, X}},
    /* A new Set_Prm is allowed in every state; it restarts the parameterisation. */
    [DDLM_SET_PRM] = {"DDLM_Set_Prm", "Set_Prm", false, DP_LOCK_OWNER_OR_RS, {X, X, X}},
    /* Before Set_Prm a configuration is acknowledged and dropped: Prm_Req in the next
     * diagnosis tells the master to start again. */
    [DDLM_CHK_CFG] = {"DDLM_Chk_Cfg", "Chk_Cfg", false, DP_LOCK_OWNER_OR_RS, {DP_RULE_SC, X, X}},
    /* Diagnosis and the configuration are readable by every master, also class 2. */
    [DDLM_SLAVE_DIAG] = {"DDLM_Slave_Diag", DP_SERVICE_LABEL_SLAVE_DIAG, false, DP_LOCK_ANY, {X, X, X}},
    [DDLM_GET_CFG] = {"DDLM_Get_Cfg", "Get_Cfg", false, DP_LOCK_ANY, {X, X, X}},
    /* Control commands reach only a slave in Data_Exch, and only from its own master. */
    [DDLM_GLOBAL_CONTROL] = {"DDLM_Global_Control", "Global_Control", true,
                             DP_LOCK_OWNER_OR_IGNORE, {DP_RULE_IGNORE, DP_RULE_IGNORE, X}},
    /* I/O images exist only once a configuration was accepted. */
    [DDLM_RD_OUTP] = {"DDLM_RD_Outp", "Rd_Outp", false, DP_LOCK_ANY, {RS, RS, X}},
    [DDLM_RD_INP] = {"DDLM_RD_Inp", "Rd_Inp", false, DP_LOCK_ANY, {RS, RS, X}},
    /* The address comes from the DIP switches (protocol.md §B1): never served. */
    [DDLM_SET_SLAVE_ADD] = {"DDLM_Set_Slave_Add", "Set_Slave_Add", false, DP_LOCK_ANY,
                            {RS, RS, RS}},
    /* DP-V1 keeps its own rules (connection state, MSAC1 only in Data_Exch with DPV1_Enable):
     * the table lets the request through and dpv1/ decides. */
    [MSAC1S] = {"MSAC1S", "MSAC1", false, DP_LOCK_ANY, {X, X, X}},
    [MSAC2S] = {"MSAC2S", "MSAC2", false, DP_LOCK_ANY, {X, X, X}},
    [DP_SERVICE_UNKNOWN] = {"SAP not served", "SAP not served", false, DP_LOCK_ANY,
                            {RS, RS, RS}},
};

#undef X
#undef RS

const char *dp_service_name(dp_service_t svc)
{
    return dp_service_rule(svc)->name;
}

const char *dp_service_label(dp_service_t svc)
{
    return dp_service_rule(svc)->label;
}
