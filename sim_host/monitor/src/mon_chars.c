/* Characters into telegrams for the monitor. Unlike a slave's receiver, a monitor must keep
 * every octet: a telegram that fails its check is not dropped quietly but reported as garbled,
 * and the octets after its first one are looked at again, because the next telegram may start
 * inside a damaged one (a collision cuts a frame, the adapter starts listening mid-frame).
 * The end of a telegram follows from its delimiter and LE, as in dp_slave/fdl_collect.h; a
 * pause inside one (MON_CHARS_PAUSE_NS) ends it as garbled. */
#include "monitor/mon_chars.h"

#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "hal/hal_uart.h"

/* A pause inside a telegram that ends it. Generous: on a PTY or a USB adapter the characters
 * of one telegram may arrive in chunks milliseconds apart. */
#define MON_CHARS_PAUSE_NS 50000000ull

static bool is_start(uint8_t b)
{
    return b == FDL_SD1 || b == FDL_SD2 || b == FDL_SD3 || b == FDL_SD4 || b == FDL_SC;
}

static size_t length_of(uint8_t sd)
{
    switch (sd) {
    case FDL_SD1: return FDL_SD1_LEN;
    case FDL_SD3: return FDL_SD3_LEN;
    case FDL_SD4: return FDL_SD4_LEN;
    case FDL_SC: return FDL_SC_LEN;
    default: return FDL_SD2_HEADER_LEN; /* until LE is known */
    }
}

void mon_chars_init(mon_chars_t *c, mon_t *m, uint32_t baud)
{
    memset(c, 0, sizeof *c);
    c->mon = m;
    c->char_ns = baud != 0u ? (uint32_t)(FDL_CHAR_BITS * 1000000000ull / baud) : 0u;
}

static void garble_flush(mon_chars_t *c)
{
    if (c->garble_len == 0u) {
        return;
    }
    size_t kept = c->garble_len < MON_GARBLE_MAX ? c->garble_len : MON_GARBLE_MAX;
    mon_garbled(c->mon, c->garble, kept, c->garble_t_ns);
    /* Octets beyond what is kept still count on the line. */
    c->mon->line.octets += c->garble_len - kept;
    c->garble_len = 0u;
}

static void garble_add(mon_chars_t *c, uint8_t b, uint64_t t_ns)
{
    if (c->garble_len == 0u) {
        c->garble_t_ns = t_ns;
    }
    if (c->garble_len < MON_GARBLE_MAX) {
        c->garble[c->garble_len] = b;
    }
    c->garble_len++;
}

static void feed_one(mon_chars_t *c, uint8_t b, bool bad, uint64_t t_ns);

/* The telegram in progress is no telegram: its first octet is garbage, the rest is looked at
 * again from the start. */
static void resync(mon_chars_t *c, uint64_t t_ns)
{
    uint8_t again[FDL_FRAME_MAX];
    size_t n = c->have; /* octets collected */
    memcpy(again, c->buf, n);
    c->have = 0u;
    c->frame_len = 0u;
    garble_add(c, again[0], c->first_ns);
    for (size_t i = 1; i < n; i++) {
        feed_one(c, again[i], false, t_ns);
    }
}

static void complete(mon_chars_t *c, uint64_t t_ns)
{
    size_t n = c->have;
    if (fdl_check(c->buf, n, NULL, NULL) != FDL_CHECK_OK) {
        resync(c, t_ns);
        return;
    }
    garble_flush(c);
    uint64_t start = c->first_ns >= c->char_ns ? c->first_ns - c->char_ns : 0u;
    mon_telegram(c->mon, c->buf, n, start, t_ns);
    c->have = 0u;
    c->frame_len = 0u;
}

static void feed_one(mon_chars_t *c, uint8_t b, bool bad, uint64_t t_ns)
{
    if (c->have == 0u) {
        if (bad || !is_start(b)) {
            garble_add(c, b, t_ns);
            return;
        }
        c->first_ns = t_ns;
        c->frame_len = length_of(b);
    }
    c->buf[c->have++] = b;
    if (bad) {
        resync(c, t_ns);
        return;
    }
    if (c->have < c->frame_len) {
        return;
    }
    if (c->buf[0] == FDL_SD2 && c->frame_len == FDL_SD2_HEADER_LEN) {
        uint8_t le = c->buf[1];
        if (le != c->buf[2] || le < FDL_LE_MIN || le > FDL_LE_MAX || c->buf[3] != FDL_SD2) {
            resync(c, t_ns);
            return;
        }
        c->frame_len = (size_t)le + FDL_SD2_OVERHEAD;
        return;
    }
    complete(c, t_ns);
}

void mon_chars_feed(mon_chars_t *c, const uint8_t *bytes, const uint8_t *flags, size_t n,
                    uint64_t t_ns)
{
    if (n != 0u && c->have != 0u && t_ns - c->last_ns > MON_CHARS_PAUSE_NS) {
        resync(c, c->last_ns); /* a pause cut the telegram in progress */
    }
    for (size_t i = 0; i < n; i++) {
        bool bad = flags != NULL && (flags[i] & (HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR | HAL_UART_RX_OVERRUN_ERR)) != 0u;
        /* Characters of one chunk arrived together; each ended one character time after the
         * one before it, at the latest at t_ns. */
        uint64_t back = (uint64_t)c->char_ns * (n - 1u - i);
        feed_one(c, bytes[i], bad, t_ns >= back ? t_ns - back : 0u);
    }
    if (n != 0u) {
        c->last_ns = t_ns;
    }
}

void mon_chars_idle(mon_chars_t *c, uint64_t now_ns)
{
    if (c->have != 0u && now_ns - c->last_ns > MON_CHARS_PAUSE_NS) {
        resync(c, c->last_ns);
        /* What resync looked at again may have started another unfinished telegram. */
        while (c->have != 0u) {
            resync(c, c->last_ns);
        }
    }
    if (c->garble_len != 0u && now_ns - c->last_ns > MON_CHARS_PAUSE_NS) {
        garble_flush(c);
    }
    mon_idle(c->mon, now_ns);
}
