#include "dp_slave/fdl_frame.h"

#include <string.h>

#include "dp_slave/fdl_wire.h"

uint8_t fdl_fcs(const uint8_t *p, size_t n)
{
    uint8_t sum = 0;
    for (size_t i = 0; i < n; i++) {
        sum = (uint8_t)(sum + p[i]);
    }
    return sum;
}

/* One address extension: the first octet carries the SAP; further octets (bit 7 chain) are
 * segment/network addresses a DP slave does not route on, so they are skipped. */
static fdl_parse_result_t take_extension(const uint8_t *du, size_t du_len, size_t *pos,
                                         uint8_t *sap)
{
    if (*pos >= du_len) {
        return FDL_PARSE_SHORT;
    }
    uint8_t ae = du[(*pos)++];
    if ((ae & FDL_AE_SEGMENT) != 0u) {
        return FDL_PARSE_SEGMENT;
    }
    *sap = (uint8_t)(ae & FDL_AE_SAP_MASK);
    while ((ae & FDL_AE_MORE) != 0u) {
        if (*pos >= du_len) {
            return FDL_PARSE_SHORT;
        }
        ae = du[(*pos)++];
    }
    return FDL_PARSE_OK;
}

fdl_parse_result_t fdl_parse(const uint8_t *frame, size_t len, fdl_msg_t *msg)
{
    *msg = (fdl_msg_t){0};
    msg->sd = frame[0];
    size_t hdr;
    size_t du_len;
    switch (frame[0]) {
    case FDL_SD1:
        hdr = 1u;
        du_len = 0u;
        break;
    case FDL_SD3:
        hdr = 1u;
        du_len = FDL_SD3_DU_LEN;
        break;
    case FDL_SD2:
        hdr = 4u;
        du_len = (size_t)frame[1] - 3u;
        break;
    default:
        return FDL_PARSE_NOT_DATA;
    }
    (void)len;
    uint8_t da = frame[hdr];
    uint8_t sa = frame[hdr + 1u];
    msg->da = (uint8_t)(da & FDL_ADDR_MASK);
    msg->sa = (uint8_t)(sa & FDL_ADDR_MASK);
    msg->fc = frame[hdr + 2u];
    const uint8_t *du = &frame[hdr + 3u];
    size_t pos = 0;
    /* DAE octets come first, then SAE octets. */
    fdl_parse_result_t r = FDL_PARSE_OK;
    if ((da & FDL_ADDR_EXT) != 0u) {
        r = take_extension(du, du_len, &pos, &msg->dsap);
        msg->has_dsap = r == FDL_PARSE_OK;
    }
    if (r == FDL_PARSE_OK && (sa & FDL_ADDR_EXT) != 0u) {
        r = take_extension(du, du_len, &pos, &msg->ssap);
        msg->has_ssap = r == FDL_PARSE_OK;
    }
    if (r != FDL_PARSE_OK) {
        return r;
    }
    msg->data = &du[pos];
    msg->data_len = (uint8_t)(du_len - pos);
    return FDL_PARSE_OK;
}

size_t fdl_encode(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *data, size_t data_len)
{
    size_t du_len = data_len + (saps ? 2u : 0u);
    if (du_len > FDL_DU_MAX) {
        return 0;
    }
    uint8_t addr_bits = saps ? FDL_ADDR_EXT : 0u;
    size_t p;
    if (du_len == 0u) {
        out[0] = FDL_SD1;
        p = 1;
    } else if (du_len == FDL_SD3_DU_LEN) {
        out[0] = FDL_SD3;
        p = 1;
    } else {
        out[0] = FDL_SD2;
        out[1] = (uint8_t)(du_len + 3u);
        out[2] = out[1];
        out[3] = FDL_SD2;
        p = 4;
    }
    size_t start = p;
    out[p++] = (uint8_t)((da & FDL_ADDR_MASK) | addr_bits);
    out[p++] = (uint8_t)((sa & FDL_ADDR_MASK) | addr_bits);
    out[p++] = fc;
    if (saps) {
        out[p++] = (uint8_t)(dsap & FDL_AE_SAP_MASK);
        out[p++] = (uint8_t)(ssap & FDL_AE_SAP_MASK);
    }
    if (data_len > 0u) {
        memcpy(&out[p], data, data_len);
        p += data_len;
    }
    out[p] = fdl_fcs(&out[start], p - start);
    p++;
    out[p++] = FDL_ED;
    return p;
}
