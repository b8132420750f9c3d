/* Compile-time bounds of the DP slave. Each can be overridden with -D; inconsistent choices stop
 * the build here rather than corrupting memory at run time. */
#ifndef DP_SLAVE_DP_CONFIG_H
#define DP_SLAVE_DP_CONFIG_H

#include "dp_slave/fdl_wire.h"

/* Largest output and input image (Data_Exchange DU). DP allows 244; the DFP21B needs 28. */
#ifndef DP_MAX_IO_LEN
#define DP_MAX_IO_LEN 244u
#endif
/* Largest Set_Prm DU accepted (7 standard + 3 DP-V1 + user parameters). */
#ifndef DP_MAX_PRM_LEN
#define DP_MAX_PRM_LEN 244u
#endif
/* Largest Chk_Cfg / Get_Cfg DU. */
#ifndef DP_MAX_CFG_LEN
#define DP_MAX_CFG_LEN 244u
#endif
/* Largest extended-diagnosis part (after the six standard octets). */
#ifndef DP_MAX_EXT_DIAG_LEN
#define DP_MAX_EXT_DIAG_LEN 32u
#endif
/* Number of masters whose FCB state and last reply are remembered, so that a retry from any of
 * them (class-1 master plus two class-2 masters in DP-V1) gets its cached reply. */
#ifndef FDL_FCB_SLOTS
#define FDL_FCB_SLOTS 3u
#endif

/* 1: telegrams may be fed character by character (fdl_rx_char, dp_slave_rx_char), which needs
 * an assembly buffer per station. 0: only whole telegrams a receiver collected are fed
 * (dp_slave_rx_telegram; the MCU's interrupt-level collector), and that buffer is left out. */
#ifndef FDL_RX_CHAR_INPUT
#define FDL_RX_CHAR_INPUT 1
#endif

#if DP_MAX_IO_LEN > 244u
#error "DP_MAX_IO_LEN: a Data_Exchange DU carries at most 244 octets"
#endif
#if DP_MAX_PRM_LEN > 244u || DP_MAX_PRM_LEN < 7u
#error "DP_MAX_PRM_LEN must be 7..244"
#endif
#if DP_MAX_CFG_LEN > 244u || DP_MAX_CFG_LEN < 1u
#error "DP_MAX_CFG_LEN must be 1..244"
#endif
#if DP_MAX_EXT_DIAG_LEN > (FDL_DU_MAX - 2u - 6u)
#error "DP_MAX_EXT_DIAG_LEN does not fit into one diagnosis telegram"
#endif
#if FDL_FCB_SLOTS < 1u || FDL_FCB_SLOTS > 16u
#error "FDL_FCB_SLOTS must be 1..16"
#endif

#endif
