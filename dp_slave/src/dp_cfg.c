#include "dp_slave/dp_cfg.h"

#include "dp_slave/dp_wire.h"

static uint16_t units_to_bytes(uint8_t len_octet_or_id, bool special_length_octet)
{
    uint8_t units = special_length_octet ? (uint8_t)((len_octet_or_id & DP_CFG_SPECIAL_LEN_MASK) + 1u)
                                         : (uint8_t)((len_octet_or_id & DP_CFG_LEN_MASK) + 1u);
    bool words = (len_octet_or_id & DP_CFG_WORDS) != 0u;
    return (uint16_t)(words ? units * 2u : units);
}

bool dp_cfg_io_lengths(const uint8_t *cfg, size_t len, uint16_t *out_len, uint16_t *in_len)
{
    uint16_t out = 0;
    uint16_t in = 0;
    size_t i = 0;
    while (i < len) {
        uint8_t id = cfg[i++];
        uint8_t dir = (uint8_t)(id & DP_CFG_DIR_MASK);
        if (dir != DP_CFG_DIR_SPECIAL) {
            uint16_t n = units_to_bytes(id, false);
            if ((dir & DP_CFG_DIR_OUT) != 0u) {
                out = (uint16_t)(out + n);
            }
            if ((dir & DP_CFG_DIR_IN) != 0u) {
                in = (uint16_t)(in + n);
            }
            continue;
        }
        uint8_t kind = (uint8_t)(id >> DP_CFG_SPECIAL_KIND_SHIFT);
        uint8_t vendor = (uint8_t)(id & DP_CFG_SPECIAL_VENDOR_MASK);
        if (kind == DP_CFG_SPECIAL_OUT || kind == DP_CFG_SPECIAL_INOUT) {
            if (i >= len) {
                return false;
            }
            out = (uint16_t)(out + units_to_bytes(cfg[i++], true));
        }
        if (kind == DP_CFG_SPECIAL_IN || kind == DP_CFG_SPECIAL_INOUT) {
            if (i >= len) {
                return false;
            }
            in = (uint16_t)(in + units_to_bytes(cfg[i++], true));
        }
        if (vendor != DP_CFG_SPECIAL_NO_VENDOR) {
            if (len - i < vendor) {
                return false;
            }
            i += vendor;
        }
    }
    if (out > DP_IO_LEN_LIMIT || in > DP_IO_LEN_LIMIT) {
        return false;
    }
    *out_len = out;
    *in_len = in;
    return true;
}
