/* DP-V0 service access points and PDU layouts (protocol.md §A3). */
#ifndef DP_SLAVE_DP_WIRE_H
#define DP_SLAVE_DP_WIRE_H

/* Slave-side SAPs (protocol.md §A3.1). Data_Exchange uses no SAP (the "default SAP"). Below 55
 * DP-V1: MSAC1 on 51, the MSAC2 resource manager on 49, MSAC2 connections on SAPs 0..48. */
#define DP_SAP_MSAC2_RM 49u
#define DP_SAP_MSAC1 51u
#define DP_SAP_SET_SLAVE_ADD 55u
#define DP_SAP_RD_INP 56u
#define DP_SAP_RD_OUTP 57u
#define DP_SAP_GLOBAL_CONTROL 58u
#define DP_SAP_GET_CFG 59u
#define DP_SAP_SLAVE_DIAG 60u
#define DP_SAP_SET_PRM 61u
#define DP_SAP_CHK_CFG 62u
#define DP_SAP_MASTER 62u /* the SSAP a class-1 master uses for DP-V0 services */

/* Set_Prm DU. */
#define DP_PRM_STATION_STATUS 0u
#define DP_PRM_WD_FACT_1 1u
#define DP_PRM_WD_FACT_2 2u
#define DP_PRM_MIN_TSDR 3u
#define DP_PRM_IDENT_HIGH 4u
#define DP_PRM_IDENT_LOW 5u
#define DP_PRM_GROUP_IDENT 6u
#define DP_PRM_DPV1_STATUS_1 7u
#define DP_PRM_DPV1_STATUS_2 8u
#define DP_PRM_DPV1_STATUS_3 9u
#define DP_PRM_LEN_STANDARD 7u
#define DP_PRM_LEN_DPV1 10u

#define DP_PRM_LOCK_REQ 0x80u
#define DP_PRM_UNLOCK_REQ 0x40u
#define DP_PRM_SYNC_REQ 0x20u
#define DP_PRM_FREEZE_REQ 0x10u
#define DP_PRM_WD_ON 0x08u
#define DP_PRM_STATION_RESERVED 0x07u

#define DP_DPV1_1_ENABLE 0x80u
#define DP_DPV1_1_FAIL_SAFE 0x40u
#define DP_DPV1_1_PUBLISHER 0x20u
#define DP_DPV1_1_RESERVED 0x18u
#define DP_DPV1_1_WD_BASE_1MS 0x04u
#define DP_DPV1_1_DIS_STOP_CONTROL 0x02u
#define DP_DPV1_1_DIS_START_CONTROL 0x01u

#define DP_DPV1_3_PRM_STRUCTURE 0x08u
#define DP_DPV1_3_ALARM_MODE_MASK 0x07u

/* The watchdog counts WD_Fact_1 x WD_Fact_2 in units of 10 ms, or of 1 ms with
 * DP_DPV1_1_WD_BASE_1MS. */
#define DP_WD_BASE_MS 10u
#define DP_WD_BASE_1MS_MS 1u

/* Slave_Diag DU: six standard octets. */
#define DP_DIAG_STATUS_1 0u
#define DP_DIAG_STATUS_2 1u
#define DP_DIAG_STATUS_3 2u
#define DP_DIAG_MASTER_ADD 3u
#define DP_DIAG_IDENT_HIGH 4u
#define DP_DIAG_IDENT_LOW 5u
#define DP_DIAG_STD_LEN 6u

#define DP_DIAG1_STATION_NON_EXISTENT 0x01u /* set by the master only */
#define DP_DIAG1_STATION_NOT_READY 0x02u
#define DP_DIAG1_CFG_FAULT 0x04u
#define DP_DIAG1_EXT_DIAG 0x08u
#define DP_DIAG1_NOT_SUPPORTED 0x10u
#define DP_DIAG1_INVALID_SLAVE_RESPONSE 0x20u /* set by the master only */
#define DP_DIAG1_PRM_FAULT 0x40u
#define DP_DIAG1_MASTER_LOCK 0x80u /* set by the master only */

#define DP_DIAG2_PRM_REQ 0x01u
#define DP_DIAG2_STAT_DIAG 0x02u
#define DP_DIAG2_ALWAYS_ONE 0x04u
#define DP_DIAG2_WD_ON 0x08u
#define DP_DIAG2_FREEZE_MODE 0x10u
#define DP_DIAG2_SYNC_MODE 0x20u
#define DP_DIAG2_DEACTIVATED 0x80u /* set by the master only */

#define DP_DIAG3_EXT_DIAG_OVERFLOW 0x80u
#define DP_MASTER_ADD_NONE 0xFFu

/* Global_Control DU: Control_Command, Group_Select. */
#define DP_GC_CLEAR_DATA 0x02u
#define DP_GC_UNFREEZE 0x04u
#define DP_GC_FREEZE 0x08u
#define DP_GC_UNSYNC 0x10u
#define DP_GC_SYNC 0x20u
#define DP_GC_RESERVED 0xC1u
#define DP_GC_LEN 2u

/* Configuration identifier octet. */
#define DP_CFG_CONSISTENT 0x80u
#define DP_CFG_WORDS 0x40u
#define DP_CFG_DIR_MASK 0x30u
#define DP_CFG_DIR_SPECIAL 0x00u
#define DP_CFG_DIR_IN 0x10u
#define DP_CFG_DIR_OUT 0x20u
#define DP_CFG_DIR_INOUT 0x30u
#define DP_CFG_LEN_MASK 0x0Fu
/* A general identifier: flags, direction and units - 1 in the low nibble. */
#define DP_CFG_GENERAL(flags, units) ((flags) | ((units) - 1u))

/* Special identifier format (protocol.md §A3.3): bits 7..6 say which length octets follow,
 * bits 3..0 how many manufacturer octets (15: none). A length octet counts 1..64 units. */
#define DP_CFG_SPECIAL_KIND_SHIFT 6u
#define DP_CFG_SPECIAL_OUT 2u
#define DP_CFG_SPECIAL_IN 1u
#define DP_CFG_SPECIAL_INOUT 3u
#define DP_CFG_SPECIAL_VENDOR_MASK 0x0Fu
#define DP_CFG_SPECIAL_NO_VENDOR 15u
#define DP_CFG_SPECIAL_LEN_MASK 0x3Fu

/* The largest input or output image a configuration may describe (a Data_Exchange DU). */
#define DP_IO_LEN_LIMIT 244u

#endif
