/* The idle time between two characters, judged by one rule for both receive paths: the
 * per-character assembler fdl_rx_char (fdl_rx.h) and the MCU's interrupt-level collector
 * (fdl_collect.h), so the two cannot drift apart.
 *
 * IEC 61158-4-3 (protocol.md §A1.1): the characters of one telegram follow each other without
 * idle time, and a request follows at least TSYN (33 bit times) of idle. A timestamp marks the
 * end of a character, so the idle time before one is the distance to the previous timestamp
 * minus the character's own 11 bits. From it:
 *  - idle_ns: kept as the idle before a telegram's first character; the FDL layer judges TSYN
 *    with it (fdl_station.c), since a response may follow after only min TSDR;
 *  - pause: idle inside a telegram, which ends it (FDL_RX_ERR_GAP); the character after it may
 *    start the next telegram;
 *  - resync: enough silence after an error to trust a start delimiter again.
 * Strict timing (exact timestamps: MCU, in-memory bus) tolerates FDL_RX_GAP_TOLERANCE_NS of idle
 * beyond the rounding of the character time to the µs timestamps (an interrupt's latency);
 * resync needs a pause. Relaxed timing (an OS delivers bytes in
 * chunks with one timestamp) counts a distance above relaxed_gap_us as a pause and one of
 * relaxed_resync_us as a resync. A timestamp earlier than the previous one is clock jitter
 * (two clocks): no idle and no pause, but in relaxed timing a resync, since timestamps that run
 * backwards cannot show that the line stayed busy.
 *
 * Whether the previous character still counts is the caller's to say (known): fdl_rx forgets
 * it in fdl_rx_poll, the collector by the size of the difference (fdl_collect.c). */
#ifndef DP_SLAVE_FDL_GAP_H
#define DP_SLAVE_FDL_GAP_H

#include <stdbool.h>
#include <stdint.h>

#include "dp_slave/fdl_rx.h"

/* The tolerance is a whole number of µs, so the pause threshold in µs below is exact. */
_Static_assert(FDL_RX_GAP_TOLERANCE_NS % 1000u == 0u, "tolerance in whole microseconds");

typedef struct fdl_gap {
    uint32_t idle_ns; /* UINT32_MAX: unknown (long); a known idle time saturates one below */
    bool pause;
    bool resync;
} fdl_gap_t;

/* The longest distance between two characters' timestamps, in µs, that is no pause. Strict
 * timing allows the tolerance on top of the character time rounded up to whole µs: stamps are
 * whole µs, so back-to-back characters are stamped ceil(character time) apart at a sub-µs phase
 * where the first stamp is late, and the tolerance is then all an interrupt's latency may add
 * (at least 1 µs at every rate; rounded down, the character time would leave 1 - frac of it,
 * 83 ns at 19.2 kbit/s). A per-character fast path compares against it without computing
 * idle_ns. */
static inline uint32_t fdl_gap_pause_us(bool strict, uint32_t char_ns, uint32_t relaxed_gap_us)
{
    uint32_t char_us_up = char_ns / 1000u + (char_ns % 1000u != 0u ? 1u : 0u);
    return strict ? char_us_up + FDL_RX_GAP_TOLERANCE_NS / 1000u : relaxed_gap_us;
}

/* dt_us: hal_time_diff(this timestamp, the previous one); pause_us from fdl_gap_pause_us(). */
static inline fdl_gap_t fdl_gap_judge(bool known, int32_t dt_us, bool strict, uint32_t char_ns,
                                      uint32_t pause_us, uint32_t relaxed_resync_us)
{
    fdl_gap_t g = {.idle_ns = UINT32_MAX, .pause = true, .resync = true};
    if (!known) {
        return g;
    }
    uint32_t d = dt_us < 0 ? 0u : (uint32_t)dt_us;
    if (d <= UINT32_MAX / 1000u) {
        /* 32 bits suffice below 4.29 s, the collector's whole range: no 64-bit arithmetic in
         * its interrupt (the compiler drops the other branch there) */
        uint32_t dt_ns = d * 1000u;
        g.idle_ns = dt_ns - char_ns;
        if (g.idle_ns > dt_ns) {
            g.idle_ns = 0u; /* the character took longer than the distance: no idle */
        }
    } else {
        uint64_t idle = (uint64_t)d * 1000u - char_ns;
        g.idle_ns = idle < UINT32_MAX ? (uint32_t)idle : UINT32_MAX - 1u;
    }
    g.pause = d > pause_us;
    g.resync = strict ? g.pause : (dt_us < 0 || d >= relaxed_resync_us);
    return g;
}

#endif
