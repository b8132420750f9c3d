#include "dp_master/rx_whole.h"

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_gap.h"

static fdl_gap_t gap_before(const fdl_rx_t *rx, hal_time_us_t first_t)
{
    return fdl_gap_judge(rx->have_last, hal_time_diff(first_t, rx->last_char_t), rx->strict,
                         rx->char_ns,
                         fdl_gap_pause_us(rx->strict, rx->char_ns, rx->relaxed_gap_us),
                         rx->relaxed_resync_us);
}

bool dp_master_whole_clean(const fdl_rx_t *rx, const dp_master_whole_t *w)
{
    return dp_master_whole_fits(rx, w) && dp_master_whole_octets_ok(w);
}

bool dp_master_whole_fits(const fdl_rx_t *rx, const dp_master_whole_t *w)
{
    if (rx->collecting || w->len == 0u) {
        return false;
    }
    if (!rx->synced && !gap_before(rx, w->first_t).resync) {
        return false;
    }
    /* Microsecond timestamps of back-to-back characters are at most this far apart. */
    uint32_t inner_us = (w->char_ns + 999u) / 1000u;
    return w->len <= 1u ||
           inner_us <= fdl_gap_pause_us(rx->strict, rx->char_ns, rx->relaxed_gap_us);
}

bool dp_master_whole_octets_ok(const dp_master_whole_t *w)
{
    return fdl_check(w->data, w->len, NULL, NULL) == FDL_CHECK_OK;
}

fdl_rx_telegram_t dp_master_whole_take(fdl_rx_t *rx, const dp_master_whole_t *w)
{
    fdl_gap_t gap = gap_before(rx, w->first_t);
    rx->have_last = true;
    rx->last_char_t = w->end_t;
    /* dp_master_whole_clean found the FCS right, so the octet sum is the FCS octet (second to last
     * in the telegrams that have one): the core need not add the octets up again. */
    return (fdl_rx_telegram_t){.buf = w->data, .len = w->len, .error = FDL_RX_OK,
                               .end_t = w->end_t, .idle_before_ns = gap.idle_ns,
                               .sum_known = true,
                               .sum = w->len >= FDL_TRAILER_LEN ? w->data[w->len - 2u] : 0u};
}
