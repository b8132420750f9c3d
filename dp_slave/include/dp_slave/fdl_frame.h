/* Decoding a checked telegram into addresses, SAPs and data, and encoding one. Used by the
 * slave for requests and replies and by the host master the other way round. */
#ifndef DP_SLAVE_FDL_FRAME_H
#define DP_SLAVE_FDL_FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_wire.h"

typedef struct fdl_msg {
    uint8_t sd;
    uint8_t da; /* 7-bit addresses */
    uint8_t sa;
    uint8_t fc;
    bool has_dsap;
    bool has_ssap;
    uint8_t dsap;
    uint8_t ssap;
    const uint8_t *data; /* DU after the address-extension octets */
    uint8_t data_len;
} fdl_msg_t;

typedef enum fdl_parse_result {
    FDL_PARSE_OK = 0,
    FDL_PARSE_SHORT,    /* extension bit set but no extension octet */
    FDL_PARSE_SEGMENT,  /* segment addressing (not supported by DP slaves) */
    FDL_PARSE_NOT_DATA, /* SD4 token or SC: no DA/SA/FC */
} fdl_parse_result_t;

/* frame must be a telegram accepted by fdl_rx. When the result is SHORT or SEGMENT, msg still
 * holds DA, SA, FC and whatever SAPs were read before the extension chain went wrong. */
fdl_parse_result_t fdl_parse(const uint8_t *frame, size_t len, fdl_msg_t *msg);

/* The rule a finished record breaks, checked in this order (protocol.md §A1.2): delimiter, the
 * SD2 length octets and second delimiter, enough octets, ED, FCS, nothing after the end. */
typedef enum fdl_check_result {
    FDL_CHECK_OK = 0,
    FDL_CHECK_EMPTY,
    FDL_CHECK_UNKNOWN_SD,
    FDL_CHECK_SHORT,       /* fewer octets than the delimiter (and LE) call for */
    FDL_CHECK_LE_MISMATCH, /* SD2: LE != LEr */
    FDL_CHECK_LE_RANGE,    /* SD2: LE outside FDL_LE_MIN..FDL_LE_MAX */
    FDL_CHECK_SD2_REPEAT,  /* SD2: the fourth octet is not 0x68 */
    FDL_CHECK_ED,          /* the last octet of the telegram is not FDL_ED */
    FDL_CHECK_FCS,
    FDL_CHECK_LONG,        /* octets after the telegram's end */
} fdl_check_result_t;

typedef struct fdl_check_info {
    size_t frame_len;   /* octets the telegram has by its delimiter and LE ... */
    bool frame_len_min; /* ... or at least has (SD2 cut before LEr: FDL_SD2_MIN_LEN) */
    uint8_t found;      /* LE_MISMATCH: LEr; LE_RANGE: LE; SD2_REPEAT, ED, FCS: the octet */
    uint8_t expected;   /* LE_MISMATCH: LE; SD2_REPEAT: FDL_SD2; ED: FDL_ED; FCS: computed */
    fdl_parse_result_t parse; /* OK: fdl_parse's result (FDL_PARSE_NOT_DATA for SD4 and SC) */
} fdl_check_info_t;

/* Checks that octets[0..len) is exactly one telegram, for records that did not come through
 * fdl_rx (captures, logs). info and msg may be NULL; on OK msg is what fdl_parse returns. */
fdl_check_result_t fdl_check(const uint8_t *octets, size_t len, fdl_check_info_t *info,
                             fdl_msg_t *msg);

/* DA, SA, FC and SAPs of a record that may be damaged, as far as its octets reach: the DU ends
 * where the delimiter or LE says, or before the record's last two octets (taken for FCS and ED)
 * when the record is shorter; SAPs as fdl_parse reads them. SD4 yields DA and SA. Returns
 * false when not even DA and SA (and FC, for data telegrams) are there; msg->sd is always set
 * when len > 0. */
bool fdl_parse_damaged(const uint8_t *octets, size_t len, fdl_msg_t *msg);

/* Encodes a request as the open-source masters frame it: SD1 (no DU), SD3 (DU of exactly 8
 * octets including SAP octets) or SD2. With saps the address bits 0x80 are set and DSAP, SSAP
 * lead the DU. Returns the length, 0 if data does not fit. out must hold FDL_FRAME_MAX octets. */
size_t fdl_encode(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *data, size_t data_len);

/* Encodes a reply as the card frames it: SD1 without a DU, SD2 for any DU, never SD3 (real
 * slaves answer 8 DU octets with SD2: architecture.md, "Data replies are SD2"). Otherwise as
 * fdl_encode(). */
size_t fdl_encode_reply(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps,
                        uint8_t dsap, uint8_t ssap, const uint8_t *data, size_t data_len);

uint8_t fdl_fcs(const uint8_t *p, size_t n);

/* Room a reply buffer keeps ahead of its DU so that the longest header fits in front of it:
 * 68 LE LEr 68 DA SA FC DSAP SSAP. */
#define FDL_TX_HEADROOM 9u
/* A buffer for a reply with a DU of up to du_max octets (SAP octets not counted). */
#define FDL_TX_BUF_LEN(du_max) (FDL_TX_HEADROOM + (du_max) + FDL_TRAILER_LEN)

/* Frames in place the du_len octets at buf + FDL_TX_HEADROOM, whose octet sum mod 256 is
 * du_sum: the header goes in front, FCS and ED after. The octets are those fdl_encode_reply()
 * gives (SD1 without a DU, else SD2). Returns the frame's first octet inside buf; *len its
 * length. du_len + SAP octets must not exceed FDL_DU_MAX. */
const uint8_t *fdl_frame_in_place(uint8_t *buf, size_t du_len, uint8_t du_sum, uint8_t da,
                                  uint8_t sa, uint8_t fc, bool saps, uint8_t dsap, uint8_t ssap,
                                  size_t *len);

#endif
