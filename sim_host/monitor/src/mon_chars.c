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

/* One clean octet into the telegram in progress: a finished telegram goes to the monitor. True
 * when the telegram in progress turned out to be none (its octets are to be looked at again). */
static bool take(mon_chars_t *c, uint8_t b, uint64_t t_ns)
{
    if (c->have == 0u) {
        if (!is_start(b)) {
            garble_add(c, b, t_ns);
            return false;
        }
        c->first_ns = t_ns;
        c->frame_len = length_of(b);
    }
    c->buf[c->have++] = b;
    if (c->have < c->frame_len) {
        return false;
    }
    if (c->buf[0] == FDL_SD2 && c->frame_len == FDL_SD2_HEADER_LEN) {
        uint8_t le = c->buf[1];
        if (le != c->buf[2] || le < FDL_LE_MIN || le > FDL_LE_MAX || c->buf[3] != FDL_SD2) {
            return true;
        }
        c->frame_len = (size_t)le + FDL_SD2_OVERHEAD;
        return false;
    }
    if (fdl_check(c->buf, c->have, NULL, NULL) != FDL_CHECK_OK) {
        return true;
    }
    garble_flush(c);
    uint64_t start_ns = c->first_ns >= c->char_ns ? c->first_ns - c->char_ns : 0u;
    uint64_t end_ns = t_ns;
    mon_telegram(c->mon, c->buf, c->have, start_ns, end_ns);
    c->have = 0u;
    c->frame_len = 0u;
    return false;
}

/* The telegram in progress is no telegram: its first octet is garbage and the rest is looked
 * at again from the start. A telegram found in there may fail too; it always began after the
 * one before it, so the octets looked at again are a shrinking tail of the same copy and the
 * loop ends. */
static void resync(mon_chars_t *c, uint64_t t_ns)
{
    uint8_t again[FDL_FRAME_MAX];
    size_t n = c->have;
    memcpy(again, c->buf, n);
    size_t failed_at = 0;
    for (;;) {
        garble_add(c, again[failed_at], c->first_ns);
        c->have = 0u;
        c->frame_len = 0u;
        size_t begun = n;
        bool failed = false;
        for (size_t i = failed_at + 1u; i < n && !failed; i++) {
            if (c->have == 0u) {
                begun = i;
            }
            failed = take(c, again[i], t_ns);
        }
        if (!failed) {
            return;
        }
        failed_at = begun;
    }
}

static void feed_one(mon_chars_t *c, uint8_t b, bool bad, uint64_t t_ns)
{
    if (bad) {
        /* A flagged character belongs to no telegram, though it may look like a delimiter (E5):
         * it ends the one in progress, whose octets are looked at again without it. */
        while (c->have != 0u) {
            resync(c, t_ns);
        }
        garble_add(c, b, t_ns);
        return;
    }
    if (take(c, b, t_ns)) {
        resync(c, t_ns);
    }
}

/* A pause: the telegram in progress was cut short (what resync looks at again may start another
 * unfinished one), and the garbled run ends with it. */
static void pause_cut(mon_chars_t *c)
{
    while (c->have != 0u) {
        resync(c, c->last_ns);
    }
    garble_flush(c);
}

void mon_chars_feed(mon_chars_t *c, const uint8_t *bytes, const uint8_t *flags, size_t n,
                    uint64_t t_ns)
{
    const uint8_t errors = HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR |
                           HAL_UART_RX_OVERRUN_ERR;
    if (n != 0u && t_ns - c->last_ns > MON_CHARS_PAUSE_NS) {
        pause_cut(c);
    }
    for (size_t i = 0; i < n; i++) {
        bool bad = flags != NULL && (flags[i] & errors) != 0u;
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
    if (now_ns - c->last_ns > MON_CHARS_PAUSE_NS) {
        pause_cut(c);
    }
    mon_idle(c->mon, now_ns);
}
