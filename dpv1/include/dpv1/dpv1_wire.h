/* DP-V1 PDU layouts and codes, and the layouts of the two records the card serves through them:
 * data set 47 and I&M (protocol.md §A4, §A5, §A7, §B7-§B8, docs/dpv1.md). Constants only: the
 * card (dpv1/), the host master, replay and the dissector's checks all take their numbers from
 * here. */
#ifndef DPV1_DPV1_WIRE_H
#define DPV1_DPV1_WIRE_H

#include "dp_slave/dp_wire.h"

#define DPV1_SAP_C1 DP_SAP_MSAC1
#define DPV1_SAP_RM DP_SAP_MSAC2_RM
#define DPV1_C2_FIRST_SAP 0u

#define DPV1_FN_IDLE 0x48u
#define DPV1_FN_DATA_TRANSPORT 0x51u
#define DPV1_FN_RM 0x56u
#define DPV1_FN_INITIATE 0x57u
#define DPV1_FN_ABORT 0x58u
#define DPV1_FN_ALARM_ACK 0x5Cu
#define DPV1_FN_READ 0x5Eu
#define DPV1_FN_WRITE 0x5Fu
#define DPV1_FN_ERROR 0x80u

#define DPV1_ERROR_DECODE 0x80u
#define DPV1_ERR_INVALID_INDEX 0xB0u
#define DPV1_ERR_WRITE_LENGTH 0xB1u
#define DPV1_ERR_STATE_CONFLICT 0xB5u
#define DPV1_ERR_ACCESS_DENIED 0xB6u
#define DPV1_ERR_INVALID_RANGE 0xB7u
#define DPV1_ERR_NOT_SUPPORTED 0xA9u

#define DPV1_HEADER_LEN 4u   /* function, slot, index, length */
#define DPV1_MAX_DATA 240u
#define DPV1_MAX_PDU (DPV1_HEADER_LEN + DPV1_MAX_DATA)
#define DPV1_INITIATE_MIN 20u

#define DPV1_INDEX_DS47 47u
#define DPV1_INDEX_IM 255u

/* Abort: Subnet, Instance | Reason (instance 0x10 = MSAC_C2), reserved. */
#define DPV1_ABORT_INSTANCE_C2 0x10u
#define DPV1_ABORT_REASON_TIMEOUT 0x03u
#define DPV1_ABORT_REASON_RESOURCE 0x0Fu

/* Data set 47 (protocol.md §A5.2, §B7): request/response ids, attributes, formats. */
#define DS47_MAX_PARAMS 19u
#define DS47_ID_REQUEST 0x01u
#define DS47_ID_CHANGE 0x02u
#define DS47_ID_MOVILINK 0x40u
#define DS47_ID_ERROR 0x80u
#define DS47_ATTR_VALUE 0x10u
/* In a MOVILINK request (id 0x40) the attribute's high nibble is the MOVILINK service. */
#define DS47_ATTR_ML_SERVICE_SHIFT 4u
#define DS47_ATTR_ML_READ 0x10u
#define DS47_ATTR_ML_WRITE 0x20u
#define DS47_ATTR_ML_WRITE_VOLATILE 0x30u
#define DS47_FORMAT_ZERO 0x40u
#define DS47_FORMAT_DWORD 0x43u
#define DS47_FORMAT_ERROR 0x44u

/* I&M through the call service on index 255 (protocol.md §A7). */
#define IM_RECORD_LEN 64u
#define IM_CALL_HEADER_LEN 4u /* 08 00 FI_Index(u16) */
#define IM_FN_CALL 0x08u
#define IM_INDEX_0 65000u
#define IM_INDEX_LAST 65004u

#endif
