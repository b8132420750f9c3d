#include "dp_slave/fdl_frame.h"

#include <string.h>

#include "dp_slave/fdl_wire.h"

/* The FCS is on the reply path twice (the request's check, the reply's encoding), so it adds
 * four octets per step: two 16-bit lanes per word hold the even and the odd octets, and a lane
 * cannot overflow within a telegram (64 words x 255 < 65536). */
#define ALTERNATE_OCTETS 0x00FF00FFu

uint8_t fdl_fcs(const uint8_t *p, size_t n)
{
    uint32_t even = 0;
    uint32_t odd = 0;
    size_t i = 0;
    for (; i + 4u <= n && i < FDL_FRAME_MAX; i += 4u) {
        uint32_t w;
        __builtin_memcpy(&w, &p[i], sizeof w); /* one load: the core is built without builtins */
        even += w & ALTERNATE_OCTETS;
        odd += (w >> 8) & ALTERNATE_OCTETS;
    }
    uint32_t sum = even + (even >> 16) + odd + (odd >> 16);
    for (; i < n; i++) {
        sum += p[i];
    }
    return (uint8_t)sum;
}

/* One address extension: the first octet carries the SAP; further octets (bit 7 chain) are
 * segment/network addresses a DP slave does not route on, so they are skipped. The SAP is
 * recorded even when the chain then proves bad, so a damaged record still shows it. */
static fdl_parse_result_t take_extension(const uint8_t *du, size_t du_len, size_t *pos,
                                         bool *has_sap, uint8_t *sap)
{
    if (*pos >= du_len) {
        return FDL_PARSE_SHORT;
    }
    uint8_t ae = du[(*pos)++];
    *has_sap = true;
    *sap = (uint8_t)(ae & FDL_AE_SAP_MASK);
    fdl_parse_result_t r = (ae & FDL_AE_SEGMENT) != 0u ? FDL_PARSE_SEGMENT : FDL_PARSE_OK;
    while ((ae & FDL_AE_MORE) != 0u) {
        if (*pos >= du_len) {
            return r == FDL_PARSE_OK ? FDL_PARSE_SHORT : r;
        }
        ae = du[(*pos)++];
    }
    return r;
}

/* DA SA FC at addr[0..2] and the du_len octets after them: DAE octets come first, then SAE
 * octets (protocol.md §A1.3). The first error found is returned. */
/* Inlined into fdl_parse(): it is on every reply path. */
static inline __attribute__((always_inline)) fdl_parse_result_t
parse_addressing(const uint8_t *addr, size_t du_len, fdl_msg_t *msg)
{
    uint8_t da = addr[0];
    uint8_t sa = addr[1];
    msg->da = (uint8_t)(da & FDL_ADDR_MASK);
    msg->sa = (uint8_t)(sa & FDL_ADDR_MASK);
    msg->fc = addr[2];
    const uint8_t *du = &addr[FDL_ADDR_FC_LEN];
    /* Every DP SAP request: both extensions, one octet each, plain SAPs. */
    if ((da & sa & FDL_ADDR_EXT) != 0u && du_len >= FDL_SAPS_LEN &&
        ((du[0] | du[1]) & (FDL_AE_MORE | FDL_AE_SEGMENT)) == 0u) {
        msg->has_dsap = true;
        msg->dsap = du[0];
        msg->has_ssap = true;
        msg->ssap = du[1];
        msg->data = &du[FDL_SAPS_LEN];
        msg->data_len = (uint8_t)(du_len - FDL_SAPS_LEN);
        return FDL_PARSE_OK;
    }
    size_t pos = 0;
    fdl_parse_result_t r = FDL_PARSE_OK;
    if ((da & FDL_ADDR_EXT) != 0u) {
        r = take_extension(du, du_len, &pos, &msg->has_dsap, &msg->dsap);
    }
    if ((sa & FDL_ADDR_EXT) != 0u) {
        fdl_parse_result_t rs = take_extension(du, du_len, &pos, &msg->has_ssap, &msg->ssap);
        if (r == FDL_PARSE_OK) {
            r = rs;
        }
    }
    msg->data = &du[pos];
    msg->data_len = (uint8_t)(du_len - pos);
    return r;
}

/* Where DA sits behind a data telegram's delimiter; 0 for SD4, SC and unknown octets. */
static size_t da_offset(uint8_t sd)
{
    switch (sd) {
    case FDL_SD1:
    case FDL_SD3: return FDL_SD1_SD3_HEADER_LEN;
    case FDL_SD2: return FDL_SD2_HEADER_LEN;
    default: return 0u;
    }
}

/* DA..DU as the delimiter (and for SD2 the LE octet) announces it. */
static size_t addressed_len(const uint8_t *frame)
{
    switch (frame[0]) {
    case FDL_SD1: return FDL_ADDR_FC_LEN;
    case FDL_SD3: return FDL_ADDR_FC_LEN + FDL_SD3_DU_LEN;
    default: return frame[1];
    }
}

fdl_parse_result_t fdl_parse(const uint8_t *frame, size_t len, fdl_msg_t *msg)
{
    /* Field by field: a zeroing struct assignment is a memset call on the reply path. */
    msg->sd = frame[0];
    msg->has_dsap = false;
    msg->has_ssap = false;
    msg->dsap = 0;
    msg->ssap = 0;
    msg->data = NULL;
    msg->data_len = 0;
    (void)len;
    size_t da_at = da_offset(frame[0]);
    if (da_at == 0u) {
        return FDL_PARSE_NOT_DATA;
    }
    return parse_addressing(&frame[da_at], addressed_len(frame) - FDL_ADDR_FC_LEN, msg);
}

/* ---- records that did not come through fdl_rx ----------------------------------------------- */

/* A telegram of frame_len octets ending in FCS (over [fcs_from, frame_len - 2)) and ED. */
static fdl_check_result_t check_framed(const uint8_t *octets, size_t len, size_t frame_len,
                                       size_t fcs_from, fdl_check_info_t *info)
{
    info->frame_len = frame_len;
    if (len < frame_len) {
        return FDL_CHECK_SHORT;
    }
    uint8_t ed = octets[frame_len - 1u];
    if (ed != FDL_ED) {
        info->found = ed;
        info->expected = FDL_ED;
        return FDL_CHECK_ED;
    }
    size_t fcs_at = frame_len - FDL_TRAILER_LEN;
    uint8_t fcs = fdl_fcs(&octets[fcs_from], fcs_at - fcs_from);
    if (octets[fcs_at] != fcs) {
        info->found = octets[fcs_at];
        info->expected = fcs;
        return FDL_CHECK_FCS;
    }
    return len > frame_len ? FDL_CHECK_LONG : FDL_CHECK_OK;
}

/* SD4 and SC: no FCS, no ED. */
static fdl_check_result_t check_unframed(size_t len, size_t frame_len, fdl_check_info_t *info)
{
    info->frame_len = frame_len;
    if (len < frame_len) {
        return FDL_CHECK_SHORT;
    }
    return len > frame_len ? FDL_CHECK_LONG : FDL_CHECK_OK;
}

static fdl_check_result_t check_sd2(const uint8_t *octets, size_t len, fdl_check_info_t *info)
{
    if (len < FDL_SD2_HEADER_LEN) {
        info->frame_len = FDL_SD2_MIN_LEN;
        info->frame_len_min = true;
        return FDL_CHECK_SHORT;
    }
    uint8_t le = octets[1];
    if (octets[2] != le) {
        info->found = octets[2];
        info->expected = le;
        return FDL_CHECK_LE_MISMATCH;
    }
    if (le < FDL_LE_MIN || le > FDL_LE_MAX) {
        info->found = le;
        return FDL_CHECK_LE_RANGE;
    }
    if (octets[3] != FDL_SD2) {
        info->found = octets[3];
        info->expected = FDL_SD2;
        return FDL_CHECK_SD2_REPEAT;
    }
    return check_framed(octets, len, (size_t)le + FDL_SD2_OVERHEAD, FDL_SD2_HEADER_LEN, info);
}

static fdl_check_result_t check_framing(const uint8_t *octets, size_t len,
                                        fdl_check_info_t *info)
{
    switch (octets[0]) {
    case FDL_SD1:
        return check_framed(octets, len, FDL_SD1_LEN, FDL_SD1_SD3_HEADER_LEN, info);
    case FDL_SD3:
        return check_framed(octets, len, FDL_SD3_LEN, FDL_SD1_SD3_HEADER_LEN, info);
    case FDL_SD2: return check_sd2(octets, len, info);
    case FDL_SD4: return check_unframed(len, FDL_SD4_LEN, info);
    case FDL_SC: return check_unframed(len, FDL_SC_LEN, info);
    default: return FDL_CHECK_UNKNOWN_SD;
    }
}

fdl_check_result_t fdl_check(const uint8_t *octets, size_t len, fdl_check_info_t *info,
                             fdl_msg_t *msg)
{
    fdl_check_info_t unused_info;
    fdl_msg_t unused_msg;
    if (info == NULL) {
        info = &unused_info;
    }
    if (msg == NULL) {
        msg = &unused_msg;
    }
    *info = (fdl_check_info_t){.parse = FDL_PARSE_NOT_DATA};
    *msg = (fdl_msg_t){0};
    if (octets == NULL || len == 0u) {
        return FDL_CHECK_EMPTY;
    }
    fdl_check_result_t r = check_framing(octets, len, info);
    if (r == FDL_CHECK_OK) {
        info->parse = fdl_parse(octets, len, msg);
    }
    return r;
}

bool fdl_parse_damaged(const uint8_t *octets, size_t len, fdl_msg_t *msg)
{
    *msg = (fdl_msg_t){0};
    if (len == 0u) {
        return false;
    }
    msg->sd = octets[0];
    if (octets[0] == FDL_SD4) {
        if (len < FDL_SD4_LEN) {
            return false;
        }
        msg->da = (uint8_t)(octets[1] & FDL_ADDR_MASK);
        msg->sa = (uint8_t)(octets[2] & FDL_ADDR_MASK);
        return true;
    }
    size_t da_at = da_offset(octets[0]);
    size_t du_at = da_at + FDL_ADDR_FC_LEN;
    if (da_at == 0u || len < du_at) {
        return false;
    }
    size_t end = da_at + addressed_len(octets);
    size_t present = len >= du_at + FDL_TRAILER_LEN ? len - FDL_TRAILER_LEN : len;
    if (present < end) {
        end = present;
    }
    (void)parse_addressing(&octets[da_at], end > du_at ? end - du_at : 0u, msg);
    return true;
}

/* The one encoder behind fdl_encode() and fdl_encode_reply(): sd3 says whether a DU of exactly
 * 8 octets takes the fixed-length form. */
static size_t encode(uint8_t *out, bool sd3, uint8_t da, uint8_t sa, uint8_t fc, bool saps,
                     uint8_t dsap, uint8_t ssap, const uint8_t *data, size_t data_len)
{
    size_t du_len = data_len + (saps ? FDL_SAPS_LEN : 0u);
    if (du_len > FDL_DU_MAX) {
        return 0;
    }
    uint8_t addr_bits = saps ? FDL_ADDR_EXT : 0u;
    size_t p;
    if (du_len == 0u) {
        out[0] = FDL_SD1;
        p = 1;
    } else if (sd3 && du_len == FDL_SD3_DU_LEN) {
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

size_t fdl_encode(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *data, size_t data_len)
{
    return encode(out, true, da, sa, fc, saps, dsap, ssap, data, data_len);
}

size_t fdl_encode_reply(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps,
                        uint8_t dsap, uint8_t ssap, const uint8_t *data, size_t data_len)
{
    return encode(out, false, da, sa, fc, saps, dsap, ssap, data, data_len);
}

const uint8_t *fdl_frame_in_place(uint8_t *buf, size_t du_len, uint8_t du_sum, uint8_t da,
                                  uint8_t sa, uint8_t fc, bool saps, uint8_t dsap, uint8_t ssap,
                                  size_t *len)
{
    uint8_t *end = &buf[FDL_TX_HEADROOM + du_len];
    uint8_t *p = &buf[FDL_TX_HEADROOM];
    uint8_t addr_bits = saps ? FDL_ADDR_EXT : 0u;
    uint32_t sum = du_sum;
    if (saps) {
        *--p = (uint8_t)(ssap & FDL_AE_SAP_MASK);
        *--p = (uint8_t)(dsap & FDL_AE_SAP_MASK);
        sum += p[0] + p[1];
    }
    *--p = fc;
    *--p = (uint8_t)((sa & FDL_ADDR_MASK) | addr_bits);
    *--p = (uint8_t)((da & FDL_ADDR_MASK) | addr_bits);
    sum += (uint32_t)p[0] + p[1] + p[2];
    size_t total_du = du_len + (saps ? FDL_SAPS_LEN : 0u);
    if (total_du == 0u) {
        *--p = FDL_SD1;
    } else {
        uint8_t le = (uint8_t)(total_du + FDL_ADDR_FC_LEN);
        p -= FDL_SD2_HEADER_LEN;
        p[0] = FDL_SD2;
        p[1] = le;
        p[2] = le;
        p[3] = FDL_SD2;
    }
    end[0] = (uint8_t)sum;
    end[1] = FDL_ED;
    *len = (size_t)(end + FDL_TRAILER_LEN - p);
    return p;
}
