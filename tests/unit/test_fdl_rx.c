/* FDL receiver, parser and encoder, byte for byte against protocol.md §A1.
 *
 * The receiver is fed character by character at exact character times (1.5 Mbit/s unless a
 * test says otherwise); every check of §A1.1 "Receiver checks" is made to fail once. The
 * encoder is held against the worked frames of §A1.6, which are written out literally here. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "spec_frames.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_rx.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_uart.h"

#define BAUD 1500000u

/* ---- §A1.6 worked frames (master 2, slave 4) ----------------------------------------------- */
static const uint8_t F_FDL_REP[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
static const uint8_t F_DIAG_REP_SD2[] = {0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                                         0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16};
static const uint8_t F_DIAG_REP_SD3[] = {0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02,
                                         0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16};
static const uint8_t F_RS[] = {0x10, 0x02, 0x04, 0x03, 0x09, 0x16};
static const uint8_t F_C1_WRITE[] = {0x68, 0x13, 0x13, 0x68, 0x84, 0x82, 0x7D, 0x33, 0x33,
                                     0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x10,
                                     0x00, 0x20, 0x6C, 0x00, 0x00, 0x5F, 0x16};
static const uint8_t F_C1_READ[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x82, 0x5D, 0x33,
                                    0x33, 0x5E, 0x00, 0x2F, 0xF0, 0x46, 0x16};
static const uint8_t F_C1_NEG[] = {0x68, 0x09, 0x09, 0x68, 0x82, 0x84, 0x08, 0x33,
                                   0x33, 0xDE, 0x80, 0xB5, 0x00, 0x87, 0x16};
/* Data_Exchange with 14 output octets (Param + 3 PD) and its reply, FCS computed by hand. */
static const uint8_t DX14[] = {0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
                               0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34};
static const uint8_t F_DX14_REP[] = {0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x01,
                                     0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00, 0x00,
                                     0x06, 0x05, 0xDC, 0x12, 0x34, 0xC8, 0x16};
static const uint8_t DX8[] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
static const uint8_t F_DX0_REQ[] = {0x10, 0x04, 0x02, 0x5D, 0x63, 0x16};
static const uint8_t F_TOKEN[] = {0xDC, 0x04, 0x02};
static const uint8_t F_SC[] = {0xE5};

/* ---- feeding the receiver ----------------------------------------------------------------- */

typedef struct feeder {
    fdl_rx_t rx;
    uint32_t baud;
    uint64_t now_ns;
    unsigned frames; /* FDL_RX_FRAME results */
    unsigned errors; /* FDL_RX_ERROR results */
    int frame_at;    /* index (in the last feed) of the char that completed a frame, else -1 */
    int error_at;    /* index of the first char that returned FDL_RX_ERROR, else -1 */
} feeder_t;

static void feeder_init(feeder_t *f, uint32_t baud, bool strict)
{
    memset(f, 0, sizeof *f);
    fdl_rx_init(&f->rx, baud, strict);
    f->baud = baud;
    f->now_ns = 1000000000ull;
}

static void idle_bits(feeder_t *f, uint32_t bits)
{
    f->now_ns += ((uint64_t)bits * 1000000000ull + f->baud - 1u) / f->baud;
}

static hal_time_us_t now_us(const feeder_t *f) { return (hal_time_us_t)(f->now_ns / 1000u); }

/* n characters back to back after idle_bits of idle; optional per-character flags. */
static void feed_flags(feeder_t *f, const uint8_t *p, size_t n, const uint8_t *flags,
                       uint32_t idle)
{
    idle_bits(f, idle);
    f->frame_at = -1;
    f->error_at = -1;
    for (size_t i = 0; i < n; i++) {
        f->now_ns += hal_uart_char_ns(f->baud);
        fdl_rx_result_t r = fdl_rx_char(&f->rx, p[i], flags ? flags[i] : 0u, now_us(f));
        if (r == FDL_RX_FRAME) {
            f->frames++;
            if (f->frame_at < 0) {
                f->frame_at = (int)i;
            }
        } else if (r == FDL_RX_ERROR) {
            f->errors++;
            if (f->error_at < 0) {
                f->error_at = (int)i;
            }
        }
    }
}

static void feed(feeder_t *f, const uint8_t *p, size_t n) { feed_flags(f, p, n, NULL, 100u); }

/* A frame that must be accepted exactly at its last character, buffer identical. */
static void expect_frame(feeder_t *f, const uint8_t *p, size_t n)
{
    unsigned frames = f->frames;
    unsigned errors = f->errors;
    feed(f, p, n);
    CHECK_EQ(f->frames, frames + 1u);
    CHECK_EQ(f->errors, errors);
    CHECK_EQ(f->frame_at, (int)n - 1);
    CHECK_EQ(f->rx.frame_len, n);
    CHECK(memcmp(f->rx.buf, p, n) == 0);
    CHECK_EQ(f->rx.frame_end_t, now_us(f));
    CHECK_EQ(f->rx.last_error, FDL_RX_OK);
}

/* A frame that must be refused with error e at character index at; nothing accepted. */
static void expect_error(feeder_t *f, const uint8_t *p, size_t n, fdl_rx_error_t e, int at)
{
    unsigned frames = f->frames;
    uint32_t count = f->rx.error_count[e];
    feed(f, p, n);
    CHECK_EQ(f->frames, frames);
    CHECK_EQ(f->error_at, at);
    CHECK_EQ(f->rx.last_error, e);
    CHECK_EQ(f->rx.error_count[e], count + 1u);
}

/* ---- every frame type accepted ------------------------------------------------------------ */

static void test_sd1_accepted(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    expect_frame(&f, F_FDL_REQ, sizeof F_FDL_REQ);
    /* First character ever: the idle time before it is unknown. */
    CHECK_EQ(f.rx.idle_before_ns, UINT32_MAX);
    expect_frame(&f, F_FDL_REP, sizeof F_FDL_REP);
    /* 100 bit times = 66 667 ns of idle, measured with µs timestamps (±1 µs). */
    CHECK(f.rx.idle_before_ns >= 65667u && f.rx.idle_before_ns <= 67667u);
    expect_frame(&f, F_DX0_REQ, sizeof F_DX0_REQ);
}

static void test_sd2_accepted(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
    expect_frame(&f, F_DIAG_REP_SD2, sizeof F_DIAG_REP_SD2);
    expect_frame(&f, F_SET_PRM, sizeof F_SET_PRM);
    expect_frame(&f, F_CHK_CFG, sizeof F_CHK_CFG);
    expect_frame(&f, F_GC_SYNC, sizeof F_GC_SYNC);
    expect_frame(&f, F_DX14_REQ, sizeof F_DX14_REQ);
    expect_frame(&f, F_DX14_REP, sizeof F_DX14_REP);
    expect_frame(&f, F_C1_WRITE, sizeof F_C1_WRITE);
    expect_frame(&f, F_C1_READ, sizeof F_C1_READ);
    expect_frame(&f, F_C1_NEG, sizeof F_C1_NEG);
}

static void test_sd3_sd4_sc_accepted(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    expect_frame(&f, F_DIAG_REP_SD3, sizeof F_DIAG_REP_SD3);
    expect_frame(&f, F_DX8_REQ, sizeof F_DX8_REQ);
    expect_frame(&f, F_TOKEN, sizeof F_TOKEN);
    expect_frame(&f, F_SC, sizeof F_SC);
    /* SC straight after a request, as a reply would follow (11 bit times). */
    feed_flags(&f, F_SC, 1, NULL, 11u);
    CHECK_EQ(f.frame_at, 0);
    CHECK_EQ(f.rx.frame_len, 1u);
}

static void test_le_limits_accepted(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    /* LE = 4: one DU octet. */
    uint8_t le4[] = {0x68, 0x04, 0x04, 0x68, 0x04, 0x02, 0x5D, 0x55, 0xB8, 0x16};
    expect_frame(&f, le4, sizeof le4);
    /* LE = 249: the longest telegram, 255 octets. */
    uint8_t le249[255];
    le249[0] = 0x68;
    le249[1] = 249;
    le249[2] = 249;
    le249[3] = 0x68;
    le249[4] = 0x04;
    le249[5] = 0x02;
    le249[6] = 0x5D;
    for (size_t i = 7; i < 253; i++) {
        le249[i] = (uint8_t)i;
    }
    le249[253] = fdl_fcs(&le249[4], 249);
    le249[254] = 0x16;
    expect_frame(&f, le249, sizeof le249);
}

/* ---- each check failing ------------------------------------------------------------------- */

static void test_bad_sd(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    uint8_t bad[] = {0x55};
    expect_error(&f, bad, 1, FDL_RX_ERR_SD, 0);
    uint8_t ed_as_sd[] = {0x16};
    expect_error(&f, ed_as_sd, 1, FDL_RX_ERR_SD, 0);
    uint8_t resp_fc_as_sd[] = {0x08};
    expect_error(&f, resp_fc_as_sd, 1, FDL_RX_ERR_SD, 0);
    /* SD1 with a wrong first octet and otherwise correct content. */
    uint8_t sd1_wrong[] = {0x11, 0x04, 0x02, 0x49, 0x4F, 0x16};
    expect_error(&f, sd1_wrong, sizeof sd1_wrong, FDL_RX_ERR_SD, 0);
    /* After a pause the receiver is back. */
    expect_frame(&f, F_FDL_REQ, sizeof F_FDL_REQ);
}

static void test_le_errors(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    uint8_t le_ne[] = {0x68, 0x05, 0x06, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16};
    expect_error(&f, le_ne, sizeof le_ne, FDL_RX_ERR_LE, 2);
    uint8_t le3[] = {0x68, 0x03, 0x03, 0x68, 0x04, 0x02, 0x5D, 0x63, 0x16};
    expect_error(&f, le3, sizeof le3, FDL_RX_ERR_LE, 2);
    uint8_t le250[] = {0x68, 0xFA, 0xFA, 0x68, 0x04, 0x02, 0x5D};
    expect_error(&f, le250, sizeof le250, FDL_RX_ERR_LE, 2);
    uint8_t le0[] = {0x68, 0x00, 0x00, 0x68};
    expect_error(&f, le0, sizeof le0, FDL_RX_ERR_LE, 2);
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
}

static void test_sd2_repeat(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    uint8_t bad[] = {0x68, 0x05, 0x05, 0x69, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16};
    expect_error(&f, bad, sizeof bad, FDL_RX_ERR_SD_REPEAT, 3);
    uint8_t bad2[] = {0x68, 0x05, 0x05, 0x10, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16};
    expect_error(&f, bad2, sizeof bad2, FDL_RX_ERR_SD_REPEAT, 3);
}

static void test_fcs_wrong(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    uint8_t sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4E, 0x16};
    expect_error(&f, sd1, sizeof sd1, FDL_RX_ERR_FCS, 5);
    uint8_t sd2[sizeof F_SET_PRM];
    memcpy(sd2, F_SET_PRM, sizeof sd2);
    sd2[sizeof sd2 - 2u] ^= 0x01u;
    expect_error(&f, sd2, sizeof sd2, FDL_RX_ERR_FCS, (int)sizeof sd2 - 1);
    /* A data octet changed, FCS left: the sum no longer matches. */
    memcpy(sd2, F_SET_PRM, sizeof sd2);
    sd2[12] = 0x0C;
    expect_error(&f, sd2, sizeof sd2, FDL_RX_ERR_FCS, (int)sizeof sd2 - 1);
    uint8_t sd3[sizeof F_DX8_REQ];
    memcpy(sd3, F_DX8_REQ, sizeof sd3);
    sd3[12] = 0x00;
    expect_error(&f, sd3, sizeof sd3, FDL_RX_ERR_FCS, 13);
    /* FCS must not include the SD2 header: an FCS over 68 LE LEr 68 + body is wrong. */
    uint8_t hdr_sum[sizeof F_DIAG_REQ];
    memcpy(hdr_sum, F_DIAG_REQ, sizeof hdr_sum);
    hdr_sum[9] = fdl_fcs(hdr_sum, 9);
    expect_error(&f, hdr_sum, sizeof hdr_sum, FDL_RX_ERR_FCS, 10);
}

static void test_ed_wrong(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    uint8_t sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x17};
    expect_error(&f, sd1, sizeof sd1, FDL_RX_ERR_ED, 5);
    uint8_t sd2[sizeof F_DIAG_REQ];
    memcpy(sd2, F_DIAG_REQ, sizeof sd2);
    sd2[sizeof sd2 - 1u] = 0x00;
    expect_error(&f, sd2, sizeof sd2, FDL_RX_ERR_ED, (int)sizeof sd2 - 1);
    uint8_t sd3[sizeof F_DX8_REQ];
    memcpy(sd3, F_DX8_REQ, sizeof sd3);
    sd3[13] = 0xE5;
    expect_error(&f, sd3, sizeof sd3, FDL_RX_ERR_ED, 13);
}

static void test_char_flags(void)
{
    static const uint8_t flag_kinds[] = {HAL_UART_RX_PARITY_ERR, HAL_UART_RX_FRAMING_ERR,
                                         HAL_UART_RX_OVERRUN_ERR};
    for (size_t k = 0; k < sizeof flag_kinds; k++) {
        feeder_t f;
        feeder_init(&f, BAUD, true);
        uint8_t flags[sizeof F_SET_PRM] = {0};
        flags[9] = flag_kinds[k];
        feed_flags(&f, F_SET_PRM, sizeof F_SET_PRM, flags, 100u);
        CHECK_EQ(f.frames, 0u);
        CHECK_EQ(f.error_at, 9);
        CHECK_EQ(f.errors, 1u); /* the rest of the telegram is ignored, not a string of errors */
        CHECK_EQ(f.rx.error_count[FDL_RX_ERR_CHAR], 1u);
        /* Flag on the start delimiter itself. */
        uint8_t flags0[sizeof F_FDL_REQ] = {flag_kinds[k]};
        feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, flags0, 100u);
        CHECK_EQ(f.frames, 0u);
        CHECK_EQ(f.error_at, 0);
        CHECK_EQ(f.rx.error_count[FDL_RX_ERR_CHAR], 2u);
        /* Flag on the ED. */
        uint8_t flags5[sizeof F_FDL_REQ] = {0, 0, 0, 0, 0, flag_kinds[k]};
        feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, flags5, 100u);
        CHECK_EQ(f.frames, 0u);
        CHECK_EQ(f.error_at, 5);
        CHECK_EQ(f.rx.last_error, FDL_RX_ERR_CHAR);
        expect_frame(&f, F_FDL_REQ, sizeof F_FDL_REQ);
    }
}

/* The idle time is a 32-bit microsecond difference: after 2^31 µs (36 min) of silence it reads
 * as negative. Without fdl_rx_poll that is taken for clock jitter (no idle), so the telegram
 * after the silence fails TSYN; a poll in the silence forgets the old character instead. */
static void test_poll_forgets_after_long_silence(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    feed(&f, F_FDL_REQ, sizeof F_FDL_REQ);
    hal_time_us_t last = now_us(&f);
    CHECK_EQ(fdl_rx_poll(&f.rx, last), last + FDL_RX_FORGET_US);
    CHECK_EQ(fdl_rx_poll(&f.rx, last + FDL_RX_FORGET_US - 1u), last + FDL_RX_FORGET_US);
    CHECK(f.rx.have_last);
    /* 2400 s of silence, polled once at the deadline */
    CHECK_EQ(fdl_rx_poll(&f.rx, last + FDL_RX_FORGET_US), last + FDL_RX_FORGET_US + HAL_TIME_NO_DEADLINE_US);
    CHECK(!f.rx.have_last);
    f.now_ns += 2400000000000ull;
    CHECK_EQ(fdl_rx_poll(&f.rx, now_us(&f)), now_us(&f) + HAL_TIME_NO_DEADLINE_US);
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
    CHECK_EQ(f.rx.idle_before_ns, UINT32_MAX); /* unknown: long */

    /* The same silence without a poll: the difference is negative, the idle reads as 0. */
    feeder_init(&f, BAUD, true);
    feed(&f, F_FDL_REQ, sizeof F_FDL_REQ);
    f.now_ns += 2400000000000ull;
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
    CHECK_EQ(f.rx.idle_before_ns, 0u);

    /* A telegram cut off and followed by a silence of 1 s: the next one starts cleanly. */
    feeder_init(&f, BAUD, true);
    feed(&f, F_SET_PRM, 5);
    f.now_ns += 1000000000ull;
    (void)fdl_rx_poll(&f.rx, now_us(&f));
    expect_frame(&f, F_FDL_REQ, sizeof F_FDL_REQ);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 1u);
    CHECK_EQ(f.rx.idle_before_ns, UINT32_MAX);
    /* Time running backwards (jitter between two clocks) forgets nothing. */
    hal_time_us_t end = now_us(&f);
    CHECK_EQ(fdl_rx_poll(&f.rx, end - 5u), end + FDL_RX_FORGET_US);
    CHECK(f.rx.have_last);
}

static void test_gap_inside_strict(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    /* 5 bit times (3.3 µs) of idle between FC and FCS of an SD1. */
    feed(&f, F_FDL_REQ, 4);
    CHECK_EQ(f.errors, 0u);
    feed_flags(&f, &F_FDL_REQ[4], 2, NULL, 5u);
    CHECK_EQ(f.frames, 0u);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 1u);
    /* The character after the pause is taken as a new start (0x4F is no SD). */
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_SD], 1u);
    /* Gap after the SD2 header: 4 bit times (2.7 µs) are a pause at any sub-µs phase, since
     * the threshold is the character time rounded up to whole µs plus 1 µs (fdl_gap.h). */
    feed(&f, F_SET_PRM, 4);
    feed_flags(&f, &F_SET_PRM[4], sizeof F_SET_PRM - 4u, NULL, 4u);
    CHECK_EQ(f.frames, 0u);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 2u);
    /* A telegram broken by a gap, whose tail is itself a complete telegram, yields only that. */
    uint8_t two[] = {0x68, 0x05, 0x05};
    feed(&f, two, sizeof two);
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 40u);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 3u);
    CHECK_EQ(f.frames, 1u);
    CHECK_EQ(f.frame_at, 5);
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
}

static void test_gap_12m_within_tolerance(void)
{
    /* At 12 Mbit/s a character lasts 917 ns: µs timestamps jitter by one, which is no gap. */
    feeder_t f;
    feeder_init(&f, 12000000u, true);
    expect_frame(&f, F_SET_PRM, sizeof F_SET_PRM);
    expect_frame(&f, F_DX14_REQ, sizeof F_DX14_REQ);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 0u);
}

static void test_resync_after_garbage(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    /* Garbage directly followed (no pause) by a valid telegram: the telegram is not trusted. */
    uint8_t stream[3 + sizeof F_FDL_REQ] = {0x55, 0xAA, 0x33};
    memcpy(&stream[3], F_FDL_REQ, sizeof F_FDL_REQ);
    feed(&f, stream, sizeof stream);
    CHECK_EQ(f.frames, 0u);
    CHECK_EQ(f.errors, 1u);
    CHECK_EQ(f.error_at, 0);
    /* Another one straight behind, still no pause: still ignored. */
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 0u);
    CHECK_EQ(f.frames, 0u);
    CHECK_EQ(f.errors, 1u);
    /* After a pause of TSYN the next telegram is accepted. */
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 33u);
    CHECK_EQ(f.frames, 1u);
    CHECK_EQ(f.frame_at, 5);
    /* Same after an FCS error: the immediately following telegram is ignored. */
    uint8_t badfcs[] = {0x10, 0x04, 0x02, 0x49, 0x00, 0x16};
    feed(&f, badfcs, sizeof badfcs);
    CHECK_EQ(f.rx.last_error, FDL_RX_ERR_FCS);
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 0u);
    CHECK_EQ(f.frames, 1u);
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 33u);
    CHECK_EQ(f.frames, 2u);
}

static void test_relaxed_mode(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, false);
    /* A 5 ms hole in the middle of a telegram (PTY delivering in chunks) is tolerated. */
    feed(&f, F_SET_PRM, 10);
    f.now_ns += 5000000ull;
    feed_flags(&f, &F_SET_PRM[10], sizeof F_SET_PRM - 10u, NULL, 0u);
    CHECK_EQ(f.frames, 1u);
    CHECK_EQ(f.rx.frame_len, sizeof F_SET_PRM);
    CHECK(memcmp(f.rx.buf, F_SET_PRM, sizeof F_SET_PRM) == 0);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 0u);
    /* Chunks arriving with the same timestamp are fine too. */
    f.now_ns += 3000000ull;
    for (size_t i = 0; i < sizeof F_DIAG_REQ; i++) {
        (void)fdl_rx_char(&f.rx, F_DIAG_REQ[i], 0, now_us(&f));
    }
    CHECK_EQ(f.rx.frame_len, sizeof F_DIAG_REQ);
    CHECK(memcmp(f.rx.buf, F_DIAG_REQ, sizeof F_DIAG_REQ) == 0);
    /* A 25 ms hole is more than FDL_RX_RELAXED_GAP_US_DEFAULT: telegram aborted. */
    feed(&f, F_SET_PRM, 10);
    f.now_ns += 25000000ull;
    unsigned frames = f.frames;
    feed_flags(&f, &F_SET_PRM[10], sizeof F_SET_PRM - 10u, NULL, 0u);
    CHECK_EQ(f.frames, frames);
    CHECK_EQ(f.rx.error_count[FDL_RX_ERR_GAP], 1u);
    /* Relaxed resync: garbage, then a telegram 500 µs later is ignored, 1.5 ms later taken. */
    uint8_t garbage[] = {0x55};
    feed(&f, garbage, 1);
    f.now_ns += 500000ull;
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 0u);
    CHECK_EQ(f.frames, frames);
    feed(&f, garbage, 1);
    f.now_ns += 1500000ull;
    feed_flags(&f, F_FDL_REQ, sizeof F_FDL_REQ, NULL, 0u);
    CHECK_EQ(f.frames, frames + 1u);
}

static void test_reset_discards(void)
{
    feeder_t f;
    feeder_init(&f, BAUD, true);
    feed(&f, F_DIAG_REQ, 6);
    fdl_rx_reset(&f.rx);
    feed_flags(&f, &F_DIAG_REQ[6], sizeof F_DIAG_REQ - 6u, NULL, 0u);
    CHECK_EQ(f.frames, 0u);
    expect_frame(&f, F_DIAG_REQ, sizeof F_DIAG_REQ);
}

/* ---- fdl_parse ---------------------------------------------------------------------------- */

/* Receives a frame, then parses it from the receiver's buffer. m->data points into that
 * buffer, so every parse uses its own receiver (up to four live at a time). */
static fdl_parse_result_t rx_parse(const uint8_t *p, size_t n, fdl_msg_t *m)
{
    static feeder_t feeders[4];
    static unsigned next;
    feeder_t *f = &feeders[next++ % 4u];
    feeder_init(f, BAUD, true);
    feed(f, p, n);
    CHECK_EQ(f->frames, 1u);
    return fdl_parse(f->rx.buf, f->rx.frame_len, m);
}

static void test_parse_saps(void)
{
    fdl_msg_t m;
    CHECK_EQ(rx_parse(F_DIAG_REQ, sizeof F_DIAG_REQ, &m), FDL_PARSE_OK);
    CHECK_EQ(m.sd, 0x68);
    CHECK_EQ(m.da, 4);
    CHECK_EQ(m.sa, 2);
    CHECK_EQ(m.fc, 0x6D);
    CHECK(m.has_dsap);
    CHECK(m.has_ssap);
    CHECK_EQ(m.dsap, 60);
    CHECK_EQ(m.ssap, 62);
    CHECK_EQ(m.data_len, 0);

    CHECK_EQ(rx_parse(F_SET_PRM, sizeof F_SET_PRM, &m), FDL_PARSE_OK);
    CHECK_EQ(m.dsap, 61);
    CHECK_EQ(m.ssap, 62);
    CHECK_BYTES(m.data, m.data_len, 0x88, 0x01, 0x64, 0x0B, 0x60, 0x03, 0x00, 0x00, 0x00, 0x00,
                0x06, 0x81, 0x00, 0x00, 0x01, 0x01);

    CHECK_EQ(rx_parse(F_GC_SYNC, sizeof F_GC_SYNC, &m), FDL_PARSE_OK);
    CHECK_EQ(m.da, 127);
    CHECK_EQ(m.fc, 0x46);
    CHECK_EQ(m.dsap, 58);
    CHECK_BYTES(m.data, m.data_len, 0x20, 0x00);

    /* The SD2 and the SD3 form of the Slave_Diag reply carry the same message. */
    fdl_msg_t m3;
    CHECK_EQ(rx_parse(F_DIAG_REP_SD2, sizeof F_DIAG_REP_SD2, &m), FDL_PARSE_OK);
    CHECK_EQ(rx_parse(F_DIAG_REP_SD3, sizeof F_DIAG_REP_SD3, &m3), FDL_PARSE_OK);
    CHECK_EQ(m.sd, 0x68);
    CHECK_EQ(m3.sd, 0xA2);
    CHECK_EQ(m3.da, 2);
    CHECK_EQ(m3.sa, 4);
    CHECK_EQ(m3.fc, 0x08);
    CHECK_EQ(m3.dsap, 62);
    CHECK_EQ(m3.ssap, 60);
    CHECK_BYTES(m.data, m.data_len, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    CHECK_BYTES(m3.data, m3.data_len, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

static void test_parse_no_saps(void)
{
    fdl_msg_t m;
    CHECK_EQ(rx_parse(F_FDL_REQ, sizeof F_FDL_REQ, &m), FDL_PARSE_OK);
    CHECK_EQ(m.sd, 0x10);
    CHECK_EQ(m.da, 4);
    CHECK_EQ(m.sa, 2);
    CHECK_EQ(m.fc, 0x49);
    CHECK(!m.has_dsap);
    CHECK(!m.has_ssap);
    CHECK_EQ(m.data_len, 0);

    CHECK_EQ(rx_parse(F_DX8_REQ, sizeof F_DX8_REQ, &m), FDL_PARSE_OK);
    CHECK(!m.has_dsap);
    CHECK_BYTES(m.data, m.data_len, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88);

    CHECK_EQ(rx_parse(F_DX14_REQ, sizeof F_DX14_REQ, &m), FDL_PARSE_OK);
    CHECK_EQ(m.data_len, 14);
    CHECK(memcmp(m.data, DX14, sizeof DX14) == 0);

    CHECK_EQ(rx_parse(F_TOKEN, sizeof F_TOKEN, &m), FDL_PARSE_NOT_DATA);
    CHECK_EQ(rx_parse(F_SC, sizeof F_SC, &m), FDL_PARSE_NOT_DATA);
}

static size_t build_sd2(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, const uint8_t *du,
                        size_t n)
{
    out[0] = 0x68;
    out[1] = (uint8_t)(n + 3u);
    out[2] = out[1];
    out[3] = 0x68;
    out[4] = da;
    out[5] = sa;
    out[6] = fc;
    memcpy(&out[7], du, n);
    out[7 + n] = fdl_fcs(&out[4], n + 3u);
    out[8 + n] = 0x16;
    return n + 9u;
}

static void test_parse_extension_chain(void)
{
    uint8_t fr[64];
    fdl_msg_t m;
    /* DAE with "more" bit: SAP 60, then a second (network) octet; SAE SAP 62; data 11 22. */
    const uint8_t du1[] = {0xBC, 0x05, 0x3E, 0x11, 0x22};
    size_t n = build_sd2(fr, 0x84, 0x82, 0x6D, du1, sizeof du1);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_OK);
    CHECK(m.has_dsap);
    CHECK_EQ(m.dsap, 60);
    CHECK(m.has_ssap);
    CHECK_EQ(m.ssap, 62);
    CHECK_BYTES(m.data, m.data_len, 0x11, 0x22);
    /* SAE chain of three octets. */
    const uint8_t du2[] = {0x3D, 0xBE, 0x87, 0x01, 0x99};
    n = build_sd2(fr, 0x84, 0x82, 0x6D, du2, sizeof du2);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_OK);
    CHECK_EQ(m.dsap, 61);
    CHECK_EQ(m.ssap, 62);
    CHECK_BYTES(m.data, m.data_len, 0x99);
    /* Only the source has an extension: no DSAP (default SAP), SSAP 62. */
    const uint8_t du3[] = {0x3E, 0xAB};
    n = build_sd2(fr, 0x04, 0x82, 0x5D, du3, sizeof du3);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_OK);
    CHECK(!m.has_dsap);
    CHECK(m.has_ssap);
    CHECK_EQ(m.ssap, 62);
    CHECK_BYTES(m.data, m.data_len, 0xAB);
}

static void test_parse_missing_extension(void)
{
    uint8_t fr[64];
    fdl_msg_t m;
    /* SD1 with DA bit 7: an extension octet is announced, but SD1 has no DU. */
    uint8_t sd1[] = {0x10, 0x84, 0x02, 0x49, 0xCF, 0x16};
    CHECK_EQ(rx_parse(sd1, sizeof sd1, &m), FDL_PARSE_SHORT);
    /* DA and SA extended, only the DAE present. */
    const uint8_t du1[] = {0x3C};
    size_t n = build_sd2(fr, 0x84, 0x82, 0x6D, du1, sizeof du1);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_SHORT);
    /* DAE says "more follows" and the DU ends. */
    const uint8_t du2[] = {0xBC};
    n = build_sd2(fr, 0x84, 0x02, 0x6D, du2, sizeof du2);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_SHORT);
    /* SAE says "more follows" and the DU ends. */
    const uint8_t du3[] = {0x3C, 0xBE};
    n = build_sd2(fr, 0x84, 0x82, 0x6D, du3, sizeof du3);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_SHORT);
}

static void test_parse_segment(void)
{
    uint8_t fr[64];
    fdl_msg_t m;
    const uint8_t du1[] = {0x7C, 0x3E};
    size_t n = build_sd2(fr, 0x84, 0x82, 0x6D, du1, sizeof du1);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_SEGMENT);
    const uint8_t du2[] = {0x3C, 0x7E};
    n = build_sd2(fr, 0x84, 0x82, 0x6D, du2, sizeof du2);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_SEGMENT);
    const uint8_t du3[] = {0xBC, 0x41, 0x3E}; /* a segment octet further down the chain */
    n = build_sd2(fr, 0x84, 0x82, 0x6D, du3, sizeof du3);
    CHECK_EQ(rx_parse(fr, n, &m), FDL_PARSE_OK);
    CHECK_EQ(m.dsap, 60);
    CHECK_EQ(m.ssap, 62);
}

/* ---- fdl_encode against §A1.6 --------------------------------------------------------------- */

static void test_encode_spec_frames(void)
{
    uint8_t out[FDL_FRAME_MAX];
    size_t n;

    n = fdl_encode(out, 4, 2, 0x49, false, 0, 0, NULL, 0);
    CHECK_BYTES(out, n, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK(n == sizeof F_FDL_REQ && memcmp(out, F_FDL_REQ, n) == 0);
    n = fdl_encode(out, 2, 4, 0x00, false, 0, 0, NULL, 0);
    CHECK(n == sizeof F_FDL_REP && memcmp(out, F_FDL_REP, n) == 0);
    n = fdl_encode(out, 2, 4, 0x03, false, 0, 0, NULL, 0);
    CHECK(n == sizeof F_RS && memcmp(out, F_RS, n) == 0);

    n = fdl_encode(out, 4, 2, 0x6D, true, 60, 62, NULL, 0);
    CHECK(n == sizeof F_DIAG_REQ && memcmp(out, F_DIAG_REQ, n) == 0);

    /* 6 diag octets + 2 SAP octets = 8: the request encoder picks SD3, the reply encoder SD2,
     * the two forms of §A1.6. */
    const uint8_t diag[] = {0x02, 0x05, 0x00, 0xFF, 0x60, 0x03};
    n = fdl_encode(out, 2, 4, 0x08, true, 62, 60, diag, sizeof diag);
    CHECK(n == sizeof F_DIAG_REP_SD3 && memcmp(out, F_DIAG_REP_SD3, n) == 0);
    n = fdl_encode_reply(out, 2, 4, 0x08, true, 62, 60, diag, sizeof diag);
    CHECK(n == sizeof F_DIAG_REP_SD2 && memcmp(out, F_DIAG_REP_SD2, n) == 0);

    const uint8_t prm[] = {0x88, 0x01, 0x64, 0x0B, 0x60, 0x03, 0x00, 0x00,
                           0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
    n = fdl_encode(out, 4, 2, 0x5D, true, 61, 62, prm, sizeof prm);
    CHECK(n == sizeof F_SET_PRM && memcmp(out, F_SET_PRM, n) == 0);

    const uint8_t cfg[] = {0xF3, 0xF2};
    n = fdl_encode(out, 4, 2, 0x7D, true, 62, 62, cfg, sizeof cfg);
    CHECK(n == sizeof F_CHK_CFG && memcmp(out, F_CHK_CFG, n) == 0);

    const uint8_t gc[] = {0x20, 0x00};
    n = fdl_encode(out, 127, 2, 0x46, true, 58, 62, gc, sizeof gc);
    CHECK(n == sizeof F_GC_SYNC && memcmp(out, F_GC_SYNC, n) == 0);

    n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, DX14, sizeof DX14);
    CHECK(n == sizeof F_DX14_REQ && memcmp(out, F_DX14_REQ, n) == 0);
    n = fdl_encode(out, 2, 4, 0x08, false, 0, 0, DX14, sizeof DX14);
    CHECK(n == sizeof F_DX14_REP && memcmp(out, F_DX14_REP, n) == 0);

    const uint8_t c1w[] = {0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00,
                           0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
    n = fdl_encode(out, 4, 2, 0x7D, true, 51, 51, c1w, sizeof c1w);
    CHECK(n == sizeof F_C1_WRITE && memcmp(out, F_C1_WRITE, n) == 0);
    const uint8_t c1r[] = {0x5E, 0x00, 0x2F, 0xF0};
    n = fdl_encode(out, 4, 2, 0x5D, true, 51, 51, c1r, sizeof c1r);
    CHECK(n == sizeof F_C1_READ && memcmp(out, F_C1_READ, n) == 0);
    const uint8_t c1n[] = {0xDE, 0x80, 0xB5, 0x00};
    n = fdl_encode(out, 2, 4, 0x08, true, 51, 51, c1n, sizeof c1n);
    CHECK(n == sizeof F_C1_NEG && memcmp(out, F_C1_NEG, n) == 0);
}

static void test_encode_choice(void)
{
    uint8_t out[FDL_FRAME_MAX];
    size_t n;
    /* No DU: SD1. */
    n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, NULL, 0);
    CHECK(n == sizeof F_DX0_REQ && memcmp(out, F_DX0_REQ, n) == 0);
    /* Exactly 8 data octets without SAPs: SD3. */
    n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, DX8, sizeof DX8);
    CHECK(n == sizeof F_DX8_REQ && memcmp(out, F_DX8_REQ, n) == 0);
    /* 7 and 9 octets: SD2. */
    n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, DX8, 7);
    CHECK_BYTES(out, n, 0x68, 0x0A, 0x0A, 0x68, 0x04, 0x02, 0x5D, 0x11, 0x22, 0x33, 0x44, 0x55,
                0x66, 0x77, 0x3F, 0x16);
    const uint8_t d9[] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99};
    n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, d9, 9);
    CHECK_BYTES(out, n, 0x68, 0x0C, 0x0C, 0x68, 0x04, 0x02, 0x5D, 0x11, 0x22, 0x33, 0x44, 0x55,
                0x66, 0x77, 0x88, 0x99, 0x60, 0x16);
    /* 6 data octets with SAPs = 8: SD3 with address bits set. */
    const uint8_t d6[] = {0x01, 0x02, 0x03, 0x04, 0x05, 0x06};
    n = fdl_encode(out, 4, 2, 0x5D, true, 56, 62, d6, sizeof d6);
    CHECK_BYTES(out, n, 0xA2, 0x84, 0x82, 0x5D, 0x38, 0x3E, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06,
                0xEE, 0x16);
    /* SAPs only, no data: SD2 with LE 5. */
    n = fdl_encode(out, 4, 2, 0x6D, true, 59, 62, NULL, 0);
    CHECK_BYTES(out, n, 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3B, 0x3E, 0xEC, 0x16);
    /* Address and SAP values are masked to 7 and 6 bits. */
    n = fdl_encode(out, 0x84, 0x82, 0x6D, true, 0x7C, 0x7E, NULL, 0);
    CHECK(n == sizeof F_DIAG_REQ && memcmp(out, F_DIAG_REQ, n) == 0);
}

/* The card's replies: SD1 without a DU, SD2 for every DU, 8 octets included. */
static void test_encode_reply(void)
{
    uint8_t out[FDL_FRAME_MAX];
    size_t n = fdl_encode_reply(out, 2, 4, 0x00, false, 0, 0, NULL, 0);
    CHECK(n == sizeof F_FDL_REP && memcmp(out, F_FDL_REP, n) == 0);
    n = fdl_encode_reply(out, 2, 4, 0x08, false, 0, 0, DX8, sizeof DX8);
    CHECK_BYTES(out, n, 0x68, 0x0B, 0x0B, 0x68, 0x02, 0x04, 0x08, 0x11, 0x22, 0x33, 0x44, 0x55,
                0x66, 0x77, 0x88, 0x72, 0x16);
    n = fdl_encode_reply(out, 2, 4, 0x08, false, 0, 0, DX14, sizeof DX14);
    CHECK(n == sizeof F_DX14_REP && memcmp(out, F_DX14_REP, n) == 0);
    const uint8_t c1n[] = {0xDE, 0x80, 0xB5, 0x00};
    n = fdl_encode_reply(out, 2, 4, 0x08, true, 51, 51, c1n, sizeof c1n);
    CHECK(n == sizeof F_C1_NEG && memcmp(out, F_C1_NEG, n) == 0);
}

/* fdl_frame_in_place() makes exactly what fdl_encode_reply() makes, at every DU length, with
 * and without SAPs: the prebuilt replies and the copied ones cannot differ in form. */
static void test_frame_in_place(void)
{
    static uint8_t data[FDL_DU_MAX];
    static uint8_t buf[FDL_TX_BUF_LEN(FDL_DU_MAX)];
    static uint8_t want[FDL_FRAME_MAX];
    for (size_t i = 0; i < sizeof data; i++) {
        data[i] = (uint8_t)(i * 13u + 5u);
    }
    unsigned differ = 0;
    for (unsigned saps = 0; saps < 2u; saps++) {
        size_t max = FDL_DU_MAX - (saps != 0u ? FDL_SAPS_LEN : 0u);
        for (size_t len = 0; len <= max; len++) {
            memcpy(&buf[FDL_TX_HEADROOM], data, len);
            size_t n = 0;
            const uint8_t *f = fdl_frame_in_place(buf, len, fdl_fcs(data, len), 2, 4, 0x08,
                                                  saps != 0u, 62, 60, &n);
            size_t w = fdl_encode_reply(want, 2, 4, 0x08, saps != 0u, 62, 60, data, len);
            if (n != w || memcmp(f, want, w) != 0 || f[0] == FDL_SD3) {
                differ++;
            }
        }
    }
    CHECK_EQ(differ, 0u);
    /* The 8-octet case written out: Slave_Diag's six octets and two SAPs. */
    const uint8_t diag[] = {0x02, 0x05, 0x00, 0xFF, 0x60, 0x03};
    memcpy(&buf[FDL_TX_HEADROOM], diag, sizeof diag);
    size_t n = 0;
    const uint8_t *f = fdl_frame_in_place(buf, sizeof diag, fdl_fcs(diag, sizeof diag), 2, 4,
                                          0x08, true, 62, 60, &n);
    CHECK(n == sizeof F_DIAG_REP_SD2 && memcmp(f, F_DIAG_REP_SD2, n) == 0);
}

static void test_encode_limits(void)
{
    static uint8_t data[250];
    static uint8_t out[FDL_FRAME_MAX];
    for (size_t i = 0; i < sizeof data; i++) {
        data[i] = (uint8_t)(i * 7u);
    }
    /* 246 data octets = DU max: LE 249, 255 octets. */
    size_t n = fdl_encode(out, 4, 2, 0x5D, false, 0, 0, data, 246);
    CHECK_EQ(n, 255u);
    CHECK_EQ(out[1], 249);
    CHECK_EQ(out[2], 249);
    CHECK_EQ(out[253], fdl_fcs(&out[4], 249));
    CHECK_EQ(out[254], 0x16);
    /* The receiver takes the longest frame the encoder makes. */
    feeder_t f;
    feeder_init(&f, BAUD, true);
    expect_frame(&f, out, n);
    /* 247 octets, or 245 + two SAP octets: does not fit. */
    CHECK_EQ(fdl_encode(out, 4, 2, 0x5D, false, 0, 0, data, 247), 0u);
    CHECK_EQ(fdl_encode(out, 4, 2, 0x5D, true, 51, 51, data, 245), 0u);
    n = fdl_encode(out, 4, 2, 0x5D, true, 51, 51, data, 244);
    CHECK_EQ(n, 255u);
    CHECK_EQ(out[7], 51);
    CHECK_EQ(out[8], 51);
}

static void test_fcs(void)
{
    CHECK_EQ(fdl_fcs(&F_FDL_REQ[1], 3), 0x4F);
    CHECK_EQ(fdl_fcs(&F_SET_PRM[4], 0x15), 0xC2);
    const uint8_t wrap[] = {0xFF, 0xFF, 0x03};
    CHECK_EQ(fdl_fcs(wrap, 3), 0x01);
    CHECK_EQ(fdl_fcs(wrap, 0), 0x00);
}

int main(void)
{
    RUN_TEST(test_sd1_accepted);
    RUN_TEST(test_sd2_accepted);
    RUN_TEST(test_sd3_sd4_sc_accepted);
    RUN_TEST(test_le_limits_accepted);
    RUN_TEST(test_bad_sd);
    RUN_TEST(test_le_errors);
    RUN_TEST(test_sd2_repeat);
    RUN_TEST(test_fcs_wrong);
    RUN_TEST(test_ed_wrong);
    RUN_TEST(test_char_flags);
    RUN_TEST(test_gap_inside_strict);
    RUN_TEST(test_poll_forgets_after_long_silence);
    RUN_TEST(test_gap_12m_within_tolerance);
    RUN_TEST(test_resync_after_garbage);
    RUN_TEST(test_relaxed_mode);
    RUN_TEST(test_reset_discards);
    RUN_TEST(test_parse_saps);
    RUN_TEST(test_parse_no_saps);
    RUN_TEST(test_parse_extension_chain);
    RUN_TEST(test_parse_missing_extension);
    RUN_TEST(test_parse_segment);
    RUN_TEST(test_encode_spec_frames);
    RUN_TEST(test_encode_choice);
    RUN_TEST(test_encode_reply);
    RUN_TEST(test_frame_in_place);
    RUN_TEST(test_encode_limits);
    RUN_TEST(test_fcs);
    return check_report();
}
