/* Decoding a checked telegram into addresses, SAPs and data, and encoding one. Used by the
 * slave for requests and replies and by the host master the other way round. */
#ifndef DP_SLAVE_FDL_FRAME_H
#define DP_SLAVE_FDL_FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

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

/* frame must be a telegram accepted by fdl_rx. */
fdl_parse_result_t fdl_parse(const uint8_t *frame, size_t len, fdl_msg_t *msg);

/* Encodes SD1 (no DU), SD3 (DU of exactly 8 octets including SAP octets) or SD2. With saps the
 * address bits 0x80 are set and DSAP, SSAP lead the DU. Returns the length, 0 if data does not
 * fit. out must hold FDL_FRAME_MAX octets. */
size_t fdl_encode(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *data, size_t data_len);

uint8_t fdl_fcs(const uint8_t *p, size_t n);

#endif
