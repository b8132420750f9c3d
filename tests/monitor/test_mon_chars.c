/* The monitor's character receiver (mon_chars.h) on damaged streams: exact telegrams out and
 * exact garbled runs for a garbled run, a telegram cut short, an SD2 with a wrong LEr, a valid
 * telegram starting inside a damaged one, characters with a parity error, a pause inside a
 * telegram; and random streams that never crash it and yield only telegrams that pass
 * fdl_check (mon_telegram is wrapped at link time to see each one as it is handed on). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_uart.h"
#include "monitor/mon_chars.h"

#define BAUD 1500000u
#define PAUSE_NS 60000000u /* longer than any pause a telegram may have inside it */

static mon_t mon; /* large: keep it off the stack */
static mon_chars_t rx;
static uint64_t now_ns;

/* ---- what mon_chars hands on --------------------------------------------------------------- */

#define SEEN_MAX 16u
static uint8_t seen[SEEN_MAX][FDL_FRAME_MAX];
static size_t seen_len[SEEN_MAX];
static size_t seen_n;
static size_t seen_bad; /* handed on but failing fdl_check */

void __real_mon_telegram(mon_t *m, const uint8_t *f, size_t len, uint64_t t0, uint64_t t1);
void __wrap_mon_telegram(mon_t *m, const uint8_t *f, size_t len, uint64_t t0, uint64_t t1);

void __wrap_mon_telegram(mon_t *m, const uint8_t *f, size_t len, uint64_t t0, uint64_t t1)
{
    if (fdl_check(f, len, NULL, NULL) != FDL_CHECK_OK || t1 < t0) {
        seen_bad++;
    }
    if (seen_n < SEEN_MAX && len <= FDL_FRAME_MAX) {
        memcpy(seen[seen_n], f, len);
        seen_len[seen_n] = len;
    }
    seen_n++;
    __real_mon_telegram(m, f, len, t0, t1);
}

static void reset(void)
{
    mon_cfg_t cfg = {.baud = BAUD, .timing = true};
    mon_init(&mon, &cfg);
    mon_chars_init(&rx, &mon, BAUD);
    now_ns = 1000000u;
    seen_n = 0;
    seen_bad = 0;
}

/* n characters as one chunk, right after the ones before. */
static void feed(const uint8_t *b, const uint8_t *flags, size_t n)
{
    now_ns += (uint64_t)hal_uart_char_ns(BAUD) * n;
    mon_chars_feed(&rx, b, flags, n, now_ns);
}

static void pause_then_idle(void)
{
    now_ns += PAUSE_NS;
    mon_chars_idle(&rx, now_ns);
}

/* An SD1 request 2 -> da (6 octets) and an SD2 answer da -> 2 with a DU of n octets. */
static size_t sd1(uint8_t *out, uint8_t da)
{
    return fdl_encode(out, da, 2, FDL_FC_REQUEST | FDL_REQ_FDL_STATUS, false, 0, 0, NULL, 0);
}

static size_t sd2(uint8_t *out, uint8_t sa, size_t n)
{
    uint8_t du[32];
    for (size_t i = 0; i < n; i++) {
        du[i] = (uint8_t)(0x30u + i);
    }
    return fdl_encode(out, 2, sa, FDL_RSP_DL, false, 0, 0, du, n);
}

static void check_seen(size_t i, const uint8_t *f, size_t len)
{
    CHECK(i < seen_n);
    if (i < seen_n && i < SEEN_MAX) {
        CHECK_EQ(seen_len[i], len);
        CHECK(seen_len[i] == len && memcmp(seen[i], f, len) == 0);
    }
}

/* ---- damaged streams ----------------------------------------------------------------------- */

static void test_garbled_run(void)
{
    reset();
    uint8_t t[FDL_FRAME_MAX];
    size_t n = sd1(t, 10);
    const uint8_t noise[] = {0x00, 0x55, 0xAA, 0xFF, 0x16};
    feed(noise, NULL, sizeof noise);
    feed(t, NULL, n);
    pause_then_idle();
    CHECK_EQ(seen_n, 1);
    check_seen(0, t, n);
    CHECK_EQ(mon.line.telegrams, 1);
    CHECK_EQ(mon.line.garbled, 1);
    CHECK_EQ(mon.line.octets, sizeof noise + n);
    CHECK_EQ(seen_bad, 0);
}

static void test_cut_telegram(void)
{
    reset();
    uint8_t a[FDL_FRAME_MAX];
    uint8_t b[FDL_FRAME_MAX];
    size_t na = sd2(a, 10, 12);
    size_t nb = sd1(b, 11);
    feed(a, NULL, 7); /* header, DA, SA, FC: then the line goes quiet */
    pause_then_idle();
    CHECK_EQ(seen_n, 0);
    CHECK_EQ(mon.line.garbled, 1);
    feed(b, NULL, nb);
    pause_then_idle();
    CHECK_EQ(seen_n, 1);
    check_seen(0, b, nb);
    CHECK_EQ(mon.line.garbled, 1);
    CHECK_EQ(mon.line.octets, 7u + nb);
    (void)na;
}

static void test_wrong_ler(void)
{
    reset();
    uint8_t a[FDL_FRAME_MAX];
    uint8_t b[FDL_FRAME_MAX];
    size_t na = sd2(a, 10, 4);
    size_t nb = sd1(b, 12);
    a[2] = (uint8_t)(a[1] + 1u); /* LEr differs from LE */
    feed(a, NULL, na);
    feed(b, NULL, nb);
    pause_then_idle();
    CHECK_EQ(seen_n, 1);
    check_seen(0, b, nb);
    CHECK_EQ(mon.line.garbled, 1);
    CHECK_EQ(mon.line.octets, na + nb);
    CHECK_EQ(seen_bad, 0);
}

/* A long SD2 cut after its header by a whole valid telegram (the adapter joined mid-frame, or
 * a collision): the valid one is found inside what the SD2's LE took for its own. */
static void test_start_inside(void)
{
    reset();
    uint8_t a[FDL_FRAME_MAX];
    uint8_t b[FDL_FRAME_MAX];
    uint8_t c[FDL_FRAME_MAX];
    (void)sd2(a, 10, 20);
    size_t nb = sd1(b, 12);
    size_t nc = sd2(c, 12, 3);
    feed(a, NULL, 6);
    feed(b, NULL, nb);
    feed(c, NULL, nc);
    pause_then_idle();
    CHECK_EQ(seen_n, 2);
    check_seen(0, b, nb);
    check_seen(1, c, nc);
    CHECK_EQ(mon.line.garbled, 1);
    CHECK_EQ(mon.line.octets, 6u + nb + nc);
    CHECK_EQ(seen_bad, 0);
}

/* Characters the UART flagged: never part of a telegram, even when they look like one (E5). */
static void test_parity(void)
{
    reset();
    uint8_t b[FDL_FRAME_MAX];
    size_t nb = sd1(b, 12);
    uint8_t flags[FDL_FRAME_MAX] = {0};
    flags[3] = HAL_UART_RX_PARITY_ERR;
    feed(b, flags, nb); /* a valid telegram, one octet of it received with a parity error */
    const uint8_t sc_bad[] = {FDL_SD1, FDL_SC};
    const uint8_t sc_flags[] = {0, HAL_UART_RX_FRAMING_ERR};
    feed(sc_bad, sc_flags, sizeof sc_bad);
    const uint8_t lone_sc[] = {FDL_SC};
    const uint8_t lone_flag[] = {HAL_UART_RX_OVERRUN_ERR};
    feed(lone_sc, lone_flag, 1);
    pause_then_idle();
    CHECK_EQ(seen_n, 0);
    CHECK_EQ(mon.line.telegrams, 0);
    CHECK_EQ(mon.line.short_acks, 0);
    CHECK_EQ(mon.line.garbled, 1);
    CHECK_EQ(mon.line.octets, nb + 3u);
    /* the same telegram clean afterwards is one */
    feed(b, NULL, nb);
    pause_then_idle();
    CHECK_EQ(seen_n, 1);
    check_seen(0, b, nb);
}

/* A pause inside a telegram ends it: its two halves are two garbled runs, no telegram. */
static void test_pause_inside(void)
{
    reset();
    uint8_t b[FDL_FRAME_MAX];
    size_t nb = sd1(b, 12);
    feed(b, NULL, 3);
    now_ns += PAUSE_NS;
    feed(b + 3, NULL, nb - 3u);
    pause_then_idle();
    CHECK_EQ(seen_n, 0);
    CHECK_EQ(mon.line.garbled, 2);
    CHECK_EQ(mon.line.octets, nb);
    /* split in two chunks without a pause it is one telegram */
    feed(b, NULL, 3);
    feed(b + 3, NULL, nb - 3u);
    pause_then_idle();
    CHECK_EQ(seen_n, 1);
    check_seen(0, b, nb);
}

/* ---- random streams ------------------------------------------------------------------------ */

static uint64_t prng = 0x9E3779B97F4A7C15ull;

static uint32_t next_rand(void)
{
    prng ^= prng << 13;
    prng ^= prng >> 7;
    prng ^= prng << 17;
    return (uint32_t)(prng >> 32);
}

/* Noise mixed with valid telegrams (so that resynchronising is exercised), in chunks of 1..64
 * characters, now and then a flag or a pause: every octet is counted once, every telegram handed
 * on passes fdl_check, and the valid telegrams put in clean are found. */
static void test_random(void)
{
    reset();
    static uint8_t buf[64];
    static uint8_t flags[64];
    uint8_t t[FDL_FRAME_MAX];
    uint64_t total = 0;
    while (total < 1000000u) {
        size_t n = 1u + next_rand() % 64u;
        memset(flags, 0, sizeof flags);
        for (size_t i = 0; i < n; i++) {
            uint32_t r = next_rand();
            buf[i] = (r & 0x300u) == 0u ? (uint8_t[]){0x10, 0x68, 0xA2, 0xDC, 0xE5}[r % 5u]
                                        : (uint8_t)r;
            flags[i] = (r & 0xFF000u) == 0u ? HAL_UART_RX_PARITY_ERR : 0u;
        }
        feed(buf, (next_rand() & 1u) != 0u ? flags : NULL, n);
        total += n;
        if (next_rand() % 8u == 0u) {
            size_t k = (next_rand() & 1u) != 0u ? sd1(t, (uint8_t)(next_rand() % 126u))
                                                : sd2(t, 10, 1u + next_rand() % 30u);
            feed(t, NULL, k);
            total += k;
        }
        if (next_rand() % 64u == 0u) {
            pause_then_idle();
        }
    }
    pause_then_idle();
    CHECK_EQ(mon.line.octets, total);
    CHECK_EQ(seen_bad, 0);
    CHECK(seen_n > 10000u);
    CHECK_EQ(mon.line.telegrams, seen_n);
    CHECK_EQ(rx.have, 0);
    CHECK_EQ(rx.garble_len, 0);
}

int main(void)
{
    RUN_TEST(test_garbled_run);
    RUN_TEST(test_cut_telegram);
    RUN_TEST(test_wrong_ler);
    RUN_TEST(test_start_inside);
    RUN_TEST(test_parity);
    RUN_TEST(test_pause_inside);
    RUN_TEST(test_random);
    return check_report();
}
