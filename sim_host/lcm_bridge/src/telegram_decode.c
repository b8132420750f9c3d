#include "lcm_bridge/telegram_decode.h"

#include <stdio.h>
#include <string.h>

static uint64_t fingerprint(void)
{
    return (uint64_t)__dfp_lcm_telegram_t_get_hash();
}

bool dfp_lcm_is_telegram(const void *buf, size_t len)
{
    if (len < 8u) {
        return false;
    }
    const uint8_t *p = buf;
    uint64_t h = 0;
    for (unsigned i = 0; i < 8u; i++) {
        h = h << 8 | p[i];
    }
    return h == fingerprint();
}

int dfp_lcm_telegram_decode_checked(const void *buf, size_t len, dfp_lcm_telegram_t *out,
                                    char *why, size_t why_max)
{
    memset(out, 0, sizeof *out);
    if (!dfp_lcm_is_telegram(buf, len)) {
        snprintf(why, why_max, "not a dfp_lcm.telegram_t (other fingerprint)");
        return -1;
    }
    if (len < DFP_LCM_TELEGRAM_FIXED) {
        snprintf(why, why_max, "telegram_t cut short: %zu of at least %u octets", len,
                 DFP_LCM_TELEGRAM_FIXED);
        return -1;
    }
    const uint8_t *p = buf;
    int16_t n = (int16_t)(uint16_t)(p[DFP_LCM_TELEGRAM_FIXED - 2u] << 8 |
                                    p[DFP_LCM_TELEGRAM_FIXED - 1u]);
    if (n < 0) {
        snprintf(why, why_max, "telegram_t length field %d", n);
        return -1;
    }
    /* lcm-gen's decoder hands memcpy the NULL that lcm_malloc(0) returns; and no telegram is
     * shorter than SC's one octet anyway. */
    if (n == 0) {
        snprintf(why, why_max, "telegram_t length 0: a telegram has at least one octet");
        return -1;
    }
    size_t want = DFP_LCM_TELEGRAM_FIXED + (size_t)n;
    if (len != want) {
        snprintf(why, why_max, "telegram_t of %zu octets, its length field %d needs %zu", len,
                 n, want);
        return -1;
    }
    if (len > (size_t)INT32_MAX ||
        dfp_lcm_telegram_t_decode(buf, 0, (int)len, out) != (int)len) {
        dfp_lcm_telegram_t_decode_cleanup(out);
        memset(out, 0, sizeof *out);
        snprintf(why, why_max, "telegram_t cannot be decoded");
        return -1;
    }
    return 0;
}
