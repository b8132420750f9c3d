/* DP-V1 PDU layouts and codes (protocol.md §A4, protocol.md §B7-§B8, docs/dpv1.md). */
#ifndef DPV1_DPV1_WIRE_H
#define DPV1_DPV1_WIRE_H

#define DPV1_SAP_C1 51u
#define DPV1_SAP_RM 49u
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

#endif
