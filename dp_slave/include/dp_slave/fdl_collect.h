/* Telegram collection where characters arrive: in the UART interrupt of an MCU, one call per
 * character, the way a DP ASIC assembles a telegram in hardware before the CPU sees it.
 *
 * The length of a telegram follows from its start delimiter (SD1 6, SD3 14, SD4 3, SC 1 octets)
 * or, for SD2, from LE (LE + 6), so the end is known without waiting for idle. Per character the
 * fast path only measures the gap to the previous one, stores the octet and compares the count
 * (fdl_collect_char); everything else (a start delimiter, LE/LEr, the repeated SD2, a pause, a
 * character error, the end) is the slow path, once per telegram. Each octet is also added to a
 * running sum, so the telegram is handed on with the sum its FCS must equal; comparing them,
 * and the ED, is left to fdl_rx_telegram() in the core, which gets the finished telegram with
 * its idle-before time.
 *
 * The rules are fdl_rx's (fdl_rx.h, strict and relaxed timing alike; the time between characters
 * is judged by the same code, fdl_gap.h), with two differences a per-telegram check brings: a
 * telegram with a bad FCS or ED does not make the collector wait for a pause before the next
 * start delimiter (in strict timing the core still refuses a request without TSYN idle before
 * it), and when a pause ends a telegram and the character after it is refused too (an error
 * flag, or not a start delimiter), only that second error is reported (fdl_rx counts both and
 * reports the second). Without a poll, the collector reads a silence of 2^31 µs or more from the
 * wrapped counter difference (below -1 s) as fdl_rx_poll would.
 *
 * The caller owns the buffers: after FDL_COLLECT_TELEGRAM it must give a new one with
 * fdl_collect_give_buffer() before the next character (the telegram's stays the caller's until
 * served). Time is in microseconds like the rest of the core. */
#ifndef DP_SLAVE_FDL_COLLECT_H
#define DP_SLAVE_FDL_COLLECT_H

#include <stdbool.h>
#include <stdint.h>

#include "dp_slave/fdl_rx.h"
#include "hal/hal_time.h"

/* fdl_collect_char()/fdl_collect_slow() results, as bits: both can come from one character (a
 * pause ended a telegram with an error, and the character was a complete SC). */
#define FDL_COLLECT_TELEGRAM 1u /* telegram is ready: hand it on, then give a new buffer */
#define FDL_COLLECT_ERROR 2u    /* error and error_t say what was dropped */

typedef struct fdl_collect {
    uint8_t *buf;      /* FDL_FRAME_MAX octets for the telegram in progress */
    uint16_t len;      /* octets so far; 0 between telegrams */
    uint16_t expected; /* the count at which the slow path looks again (LE, SD2, the end) */
    hal_time_us_t last_t;
    uint32_t pause_us; /* a gap above this ends a telegram (fdl_gap_pause_us) */
    bool have_last;
    bool synced; /* between telegrams, or a pause followed the last error */
    bool strict;
    uint32_t char_ns;
    uint32_t relaxed_gap_us;
    uint32_t relaxed_resync_us;
    uint32_t idle_before_ns; /* of the telegram in progress */
    uint32_t sum;            /* of its octets so far */
    fdl_rx_telegram_t telegram; /* after FDL_COLLECT_TELEGRAM */
    fdl_rx_error_t error;       /* after FDL_COLLECT_ERROR */
    hal_time_us_t error_t;
} fdl_collect_t;

void fdl_collect_init(fdl_collect_t *c, uint8_t *buf, uint32_t baud, bool strict);
/* A new rate (baud search): forgets the telegram in progress. */
void fdl_collect_set_baud(fdl_collect_t *c, uint32_t baud);
static inline void fdl_collect_give_buffer(fdl_collect_t *c, uint8_t *buf) { c->buf = buf; }
/* Everything but a plain character inside a telegram; flags are hal_uart.h's HAL_UART_RX_*. */
unsigned fdl_collect_slow(fdl_collect_t *c, uint8_t byte, uint8_t flags, hal_time_us_t t);
/* The count reached expected: LE known, SD2 repeated, or the telegram complete. */
unsigned fdl_collect_step(fdl_collect_t *c, hal_time_us_t t);

/* One error-free character, t = when it was received. */
static inline unsigned fdl_collect_char(fdl_collect_t *c, uint8_t byte, hal_time_us_t t)
{
    if (c->len == 0u || (uint32_t)(t - c->last_t) > c->pause_us) {
        return fdl_collect_slow(c, byte, 0u, t);
    }
    c->last_t = t;
    c->sum += byte;
    c->buf[c->len++] = byte;
    return c->len == c->expected ? fdl_collect_step(c, t) : 0u;
}

#endif
