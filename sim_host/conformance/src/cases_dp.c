/* The "DP state machine" group: its table of cases (the cases live in cases_dp_*.c). Each case
 * brings the DUT where it needs it itself (cf_reset, cf_start_up) and judges by the standard
 * named in its clause, never by what this project's card does. */
#include "conformance/cf_cases_dp.h"

#include "cases_dp_internal.h"

#define GROUP "DP state machine"
#define SM DPX_STATE_MACHINE
#define SET_PRM "EN 50170 vol. 2 DP Send Parameter Data (Set_Prm), protocol.md A3.2"
#define GC "EN 50170 vol. 2 DP Global Control, protocol.md A3.5"

const cf_case_t cf_cases_dp[] = {
    {"dp.diag.wait_prm", GROUP, SM ", Slave_Diag (protocol.md A3.4)",
     "after unlock: Station_Not_Ready, Prm_Req, the always-one bit, Master_Add 255, the ident",
     dpc_diag_wait_prm},
    {"dp.wait_prm.services", GROUP, SM " (Wait_Prm, protocol.md A3.6)",
     "in Wait_Prm: diagnosis and Get_Cfg answered, Data_Exchange RS, Set_Slave_Add RS unless "
     "claimed; Global_Control and Chk_Cfg change nothing", dpc_wait_prm_services},
    {"dp.wait_cfg.data_exchange", GROUP, SM " (Wait_Cfg: default SAP not activated, FDL RS)",
     "Data_Exchange in Wait_Cfg is refused with RS; Chk_Cfg then still leads to Data_Exch",
     dpc_wait_cfg_data_exchange},
    {"dp.wait_cfg.services", GROUP, SM " (Wait_Cfg, protocol.md A3.6)",
     "in Wait_Cfg: diagnosis with Master_Add, Get_Cfg, a second Set_Prm accepted, Chk_Cfg leads "
     "to Data_Exch", dpc_wait_cfg_services},
    {"dp.data_exch.services", GROUP, SM " (Data_Exch); RD_Inp, RD_Outp mandatory slave functions",
     "in Data_Exch: Get_Cfg, Rd_Inp/Rd_Outp of the module's lengths, Chk_Cfg and Set_Prm "
     "accepted", dpc_data_exch_services},
    {"dp.set_prm.lock", GROUP, SET_PRM "; FDL RS for a SAP bound to another master (A3.6)",
     "a second class-1 master's Set_Prm is refused with RS while locked; Master_Add the owner",
     dpc_set_prm_lock},
    {"dp.set_prm.unlock", GROUP, SET_PRM " (Lock_Req 0, Unlock_Req 1)",
     "unlock releases the slave: Wait_Prm, Master_Add 255, another master may lock it",
     dpc_set_prm_unlock},
    {"dp.set_prm.min_tsdr_only", GROUP, SET_PRM " (Lock_Req 0, Unlock_Req 0; ident exception)",
     "lock 0 unlock 0 changes only min TSDR, also with another ident: no fault, Data_Exch kept",
     dpc_set_prm_min_tsdr_only},
    {"dp.set_prm.repeated", GROUP, SM "; " SET_PRM,
     "several Set_Prm in a row, in Wait_Prm/Wait_Cfg and in Data_Exch, then Chk_Cfg: Data_Exch",
     dpc_set_prm_repeated},
    {"dp.set_prm.wrong_ident", GROUP, SET_PRM " (Ident_Number)",
     "Set_Prm with another Ident_Number: Prm_Fault, stays in Wait_Prm", dpc_set_prm_wrong_ident},
    {"dp.set_prm.user_prm", GROUP, SET_PRM "; GSD specification ExtUserPrmData",
     "every value the GSD allows accepted to Data_Exch; values outside it refused with "
     "Prm_Fault", dpc_set_prm_user_prm},
    {"dp.set_prm.watchdog_off", GROUP, SET_PRM " (WD_On 0)",
     "without WD_On the slave stays in Data_Exch through a silence longer than the factors say",
     dpc_set_prm_watchdog_off},
    {"dp.watchdog.expiry", GROUP, SET_PRM " (TWD = base x WD_Fact_1 x WD_Fact_2); " SM,
     "with WD_On the slave keeps Data_Exch while polled within TWD and leaves it after TWD",
     dpc_watchdog_expiry},
    {"dp.chk_cfg.right", GROUP, "EN 50170 vol. 2 DP Check Configuration Data; " SM,
     "the configured module's Chk_Cfg is accepted: ready diagnosis, Data_Exchange with its "
     "lengths", dpc_chk_cfg_right},
    {"dp.chk_cfg.wrong", GROUP, "EN 50170 vol. 2 DP Check Configuration Data; " SM,
     "a configuration beyond the GSD: Cfg_Fault, back to Wait_Prm, Data_Exchange RS",
     dpc_chk_cfg_wrong},
    {"dp.get_cfg", GROUP, "EN 50170 vol. 2 DP Read Configuration Data, protocol.md A3.3",
     "Get_Cfg answered in every state with well-formed identifiers, the module's lengths in "
     "Data_Exch", dpc_get_cfg},
    {"dp.diag.data_exch", GROUP, SM ", Slave_Diag (protocol.md A3.4)",
     "in Data_Exch: no fault bits, WD_On as parameterised, Master_Add the owner, the ident",
     dpc_diag_data_exch},
    {"dp.global_control.clear", GROUP, GC " (Clear_Data)",
     "Clear_Data clears the outputs (Rd_Outp all 0); the slave stays in Data_Exch",
     dpc_global_control_clear},
    {"dp.global_control.sync", GROUP, GC " (Sync, Unsync); Slave_Diag Sync_Mode",
     "Sync sets Sync_Mode and holds the outputs until the next Sync; Unsync ends it",
     dpc_global_control_sync},
    {"dp.global_control.freeze", GROUP, GC " (Freeze, Unfreeze); Slave_Diag Freeze_Mode",
     "Freeze sets Freeze_Mode and freezes the inputs until the next Freeze; Unfreeze ends it",
     dpc_global_control_freeze},
    {"dp.global_control.groups", GROUP, GC " (Group_Select AND Group_Ident)",
     "a command to another group changes nothing; one to the slave's group takes effect",
     dpc_global_control_groups},
    {"dp.class2.read", GROUP, SM "; Slave_Diag, Get_Cfg, RD_Inp, RD_Outp for class-2 masters",
     "a class-2 master reads diagnosis (Master_Add the owner), Get_Cfg and the I/O of a locked "
     "slave", dpc_class2_read},
    {"dp.second_master", GROUP, SET_PRM "; FDL RS for a SAP bound to another master (A3.6)",
     "a second class-1 master sees the owner in Master_Add; its Chk_Cfg and Data_Exchange get "
     "RS", dpc_second_master},
};
const size_t cf_cases_dp_count = sizeof cf_cases_dp / sizeof cf_cases_dp[0];
