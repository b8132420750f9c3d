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
/* Initiate (protocol.md §A4.4): the request's Send_Timeout (u16, in 10 ms) at octet 4; the
 * response's 12-octet head, Features_Supported_1 b0 = DPV1_RW. */
#define DPV1_INITIATE_SEND_TIMEOUT 4u
#define DPV1_SEND_TIMEOUT_UNIT_US 10000u
#define DPV1_INITIATE_RES_HEAD_LEN 12u
#define DPV1_FEATURES_1_DPV1_RW 0x01u

#define DPV1_INDEX_DS47 47u
#define DPV1_INDEX_IM 255u

/* Abort: Subnet, Instance | Reason (instance 0x10 = MSAC_C2), reserved. */
#define DPV1_ABORT_INSTANCE_C2 0x10u
#define DPV1_ABORT_REASON_FE 0x02u /* the request PDU is malformed */
#define DPV1_ABORT_REASON_TIMEOUT 0x03u
#define DPV1_ABORT_REASON_RESOURCE 0x0Fu

/* Data set 47 (protocol.md §A5.2, §B7): request/response ids, attributes, formats. */
#define DS47_MAX_PARAMS 19u
#define DS47_ID_REQUEST 0x01u
#define DS47_ID_CHANGE 0x02u
#define DS47_ID_MOVILINK 0x40u
#define DS47_ID_ERROR 0x80u
#define DS47_ATTR_VALUE 0x10u
#define DS47_ATTR_DESCRIPTION 0x20u
#define DS47_ATTR_TEXT 0x30u
/* In a MOVILINK request (id 0x40) the attribute's high nibble is the MOVILINK service. */
#define DS47_ATTR_ML_SERVICE_SHIFT 4u
#define DS47_ATTR_ML_READ 0x10u
#define DS47_ATTR_ML_WRITE 0x20u
#define DS47_ATTR_ML_WRITE_VOLATILE 0x30u
/* Value formats: PROFIdrive data types 0x01..0x0A, then Zero, Byte, Word, DWord, Error. */
#define DS47_FORMAT_BOOLEAN 0x01u
#define DS47_FORMAT_INTEGER8 0x02u
#define DS47_FORMAT_INTEGER16 0x03u
#define DS47_FORMAT_INTEGER32 0x04u
#define DS47_FORMAT_UNSIGNED8 0x05u
#define DS47_FORMAT_UNSIGNED16 0x06u
#define DS47_FORMAT_UNSIGNED32 0x07u
#define DS47_FORMAT_FLOAT 0x08u
#define DS47_FORMAT_VISIBLE_STRING 0x09u
#define DS47_FORMAT_OCTET_STRING 0x0Au
#define DS47_FORMAT_ZERO 0x40u
#define DS47_FORMAT_BYTE 0x41u
#define DS47_FORMAT_WORD 0x42u
#define DS47_FORMAT_DWORD 0x43u
#define DS47_FORMAT_ERROR 0x44u
/* Request header: Request Reference, Request/Response ID, Axis, number of parameters; then an
 * address block per parameter, then a value block per writing parameter (format, count,
 * values). A response entry: format, count and the DWORD value, or an error word. */
#define DS47_HEADER_LEN 4u
#define DS47_ADDRESS_LEN 6u
#define DS47_VALUE_HEADER_LEN 2u
#define DS47_READ_ENTRY_LEN 6u
#define DS47_ERROR_ENTRY_LEN 4u
#define DS47_WRITE_ENTRY_LEN 2u

/* PROFIdrive error numbers the card answers (protocol.md §A5.3, §B7.4); MOVILINK errors other
 * than the mapped class-8 codes go to the manufacturer range at 0x80 + their code octet. */
#define PD_ERR_PARAMETER_NUMBER 0x00u
#define PD_ERR_READ_ONLY 0x01u
#define PD_ERR_LIMIT_EXCEEDED 0x02u
#define PD_ERR_SUBINDEX 0x03u
#define PD_ERR_NO_ARRAY 0x04u
#define PD_ERR_DATA_TYPE 0x05u
#define PD_ERR_NO_DESCRIPTION 0x09u
#define PD_ERR_NO_TEXT 0x0Fu
#define PD_ERR_OPERATING_STATE 0x11u
#define PD_ERR_VALUE_IMPERMISSIBLE 0x14u
#define PD_ERR_ADDRESS 0x16u
#define PD_ERR_FORMAT 0x17u
#define PD_ERR_VALUE_COUNT 0x18u
#define PD_ERR_AXIS_NONEXISTENT 0x19u
#define PD_ERR_MANUFACTURER_BASE 0x80u

/* I&M through the call service on index 255 (protocol.md §A7). */
#define IM_RECORD_LEN 64u
#define IM_CALL_HEADER_LEN 4u /* 08 00 FI_Index(u16) */
#define IM_FN_CALL 0x08u
#define IM_INDEX_0 65000u
#define IM_INDEX_LAST 65004u
/* I&M0 record layout (protocol.md §A7): a 10-octet manufacturer header, then the fields below
 * in order, texts blank-padded. IM_SUPPORTED 0x001E: I&M1..I&M4. */
#define IM0_HEADER_LEN 10u
#define IM0_ORDER_ID_LEN 20u
#define IM0_SERIAL_LEN 16u
#define IM0_SOFTWARE_REVISION_LEN 4u
#define IM0_VERSION_MAJOR 0x01u
#define IM0_VERSION_MINOR 0x01u
#define IM0_SUPPORTED_IM1_TO_IM4 0x001Eu
/* The application's error class for a write that could not be stored (Error_Code_1). */
#define DPV1_ERR_WRITE_ERROR 0xA1u

#endif
