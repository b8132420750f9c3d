/* PROFIBUS FDL (layer 2) wire format: delimiters, frame-control bits, function and response
 * codes. Values and names follow IEC 61158-4-3 as summarised in docs/protocol.md
 * (protocol.md §A1). Kept apart from the code so a reader can hold it against the standard. */
#ifndef DP_SLAVE_FDL_WIRE_H
#define DP_SLAVE_FDL_WIRE_H

/* Start and end delimiters. */
#define FDL_SD1 0x10u /* fixed length, no data:        10 DA SA FC FCS 16            */
#define FDL_SD2 0x68u /* variable length:               68 LE LEr 68 DA SA FC DU FCS 16 */
#define FDL_SD3 0xA2u /* fixed length, 8 data octets:   A2 DA SA FC DU[8] FCS 16       */
#define FDL_SD4 0xDCu /* token:                         DC DA SA                       */
#define FDL_SC  0xE5u /* short acknowledge                                             */
#define FDL_ED  0x16u

#define FDL_SD1_LEN 6u
#define FDL_SD3_LEN 14u
#define FDL_SD3_DU_LEN 8u
#define FDL_SD4_LEN 3u
#define FDL_SC_LEN 1u
#define FDL_SD1_SD3_HEADER_LEN 1u /* the delimiter: DA follows at offset 1 */
#define FDL_SD2_HEADER_LEN 4u     /* 68 LE LEr 68: DA follows at offset 4 */
#define FDL_ADDR_FC_LEN 3u        /* DA SA FC */
#define FDL_FC_FROM_DA 2u         /* FC follows DA and SA */
#define FDL_SAPS_LEN 2u           /* DSAP SSAP, one extension octet each, leading the DU */
#define FDL_TRAILER_LEN 2u        /* FCS ED */
#define FDL_SD2_OVERHEAD 6u /* 68 LE LEr 68 ... FCS 16 */
#define FDL_LE_MIN 4u       /* DA SA FC + at least one DU octet (LE counts DA..DU) */
#define FDL_LE_MAX 249u
#define FDL_FRAME_MAX (FDL_LE_MAX + FDL_SD2_OVERHEAD) /* 255 */
#define FDL_DU_MAX (FDL_LE_MAX - 3u)                  /* 246, SAP bytes included */
#define FDL_SD2_MIN_LEN (FDL_LE_MIN + FDL_SD2_OVERHEAD) /* 10 */

/* Addresses. */
#define FDL_ADDR_MASK 0x7Fu
#define FDL_ADDR_EXT 0x80u       /* DA/SA bit 7: an address-extension octet leads the DU */
#define FDL_ADDR_BROADCAST 127u
#define FDL_AE_MORE 0x80u        /* extension octet bit 7: another extension octet follows */
#define FDL_AE_SEGMENT 0x40u     /* extension octet bit 6: segment address instead of SAP */
#define FDL_AE_SAP_MASK 0x3Fu

/* Frame control octet. */
#define FDL_FC_REQUEST 0x40u
#define FDL_FC_FCB 0x20u
#define FDL_FC_FCV 0x10u
#define FDL_FC_CODE_MASK 0x0Fu
#define FDL_FC_STATION_MASK 0x30u

/* Request function codes (FC bit 6 = 1). */
#define FDL_REQ_TIME_EVENT 0x0u
#define FDL_REQ_SDA_LOW 0x3u
#define FDL_REQ_SDN_LOW 0x4u
#define FDL_REQ_SDA_HIGH 0x5u
#define FDL_REQ_SDN_HIGH 0x6u
#define FDL_REQ_MSRD 0x7u
#define FDL_REQ_FDL_STATUS 0x9u
#define FDL_REQ_SRD_LOW 0xCu
#define FDL_REQ_SRD_HIGH 0xDu
#define FDL_REQ_IDENT 0xEu
#define FDL_REQ_LSAP_STATUS 0xFu

/* Response codes (FC bit 6 = 0); station type bits 5..4 = 00 for a slave. */
#define FDL_RSP_OK 0x0u
#define FDL_RSP_UE 0x1u
#define FDL_RSP_RR 0x2u
#define FDL_RSP_RS 0x3u
#define FDL_RSP_DL 0x8u
#define FDL_RSP_NR 0x9u
#define FDL_RSP_DH 0xAu
#define FDL_RSP_RDL 0xCu
#define FDL_RSP_RDH 0xDu

/* Bus timing, in bit times. */
#define FDL_TSYN_BITS 33u
#define FDL_MIN_TSDR_DEFAULT_BITS 11u
#define FDL_CHAR_BITS 11u

#endif
