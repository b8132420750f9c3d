/* The MCU collector (fdl_collect.h, then fdl_rx_telegram) against the per-character assembler
 * fdl_rx_char: the same character stream through both (fdl_collect_twin.h), every telegram
 * compared octet for octet with its length, end time and idle before it, every error counted.
 *
 * Named streams with exact expected values (times derived from the rate: one character is
 * 11 bit times, a µs timestamp is the end of its stop bit rounded down), the two differences
 * fdl_collect.h documents asserted side by side, then random streams of telegrams with
 * corruptions. */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "fdl_collect_twin.h"
#include "spec_frames.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_uart.h"

static const uint8_t F_TOKEN[] = {0xDC, 0x04, 0x02};
static const uint8_t F_SC[] = {0xE5};
/* SD2 with the shortest LE (4: DA SA FC + one DU octet). */
static const uint8_t F_SD2_LE4[] = {0x68, 0x04, 0x04, 0x68, 0x04, 0x02, 0x5D, 0x01, 0x64, 0x16};

#define LOG_MAX 48u

typedef struct logged {
    twin_event_t ev;
    size_t at; /* index of the character, from 0 */
} logged_t;

typedef struct line {
    twin_t tw;
    uint8_t store[TWIN_BUFS][FDL_FRAME_MAX];
    uint32_t baud;
    uint64_t now_ns; /* true time: end of the last character */
    size_t chars;
    uint64_t stamp_us[320]; /* true time of each character, µs */
    logged_t ref[LOG_MAX];
    logged_t col[LOG_MAX];
    size_t nref;
    size_t ncol;
} line_t;

static line_t L; /* one stream per test; big, so not on the stack */

static void line_init(uint32_t baud, bool strict, hal_time_us_t t0)
{
    memset(&L, 0, sizeof L);
    uint8_t *bufs[TWIN_BUFS] = {L.store[0], L.store[1], L.store[2]};
    twin_init(&L.tw, bufs, baud, strict, t0);
    L.baud = baud;
}

static void line_log(logged_t *log, size_t *n, const twin_side_t *s)
{
    for (unsigned k = 0; k < s->n && *n < LOG_MAX; k++) {
        log[*n] = (logged_t){.ev = s->ev[k], .at = L.chars};
        (*n)++;
    }
}

static void print_side(const char *label, const twin_side_t *s)
{
    fprintf(stderr, "    %s:", label);
    for (unsigned k = 0; k < s->n; k++) {
        if (s->ev[k].error == FDL_RX_OK) {
            fprintf(stderr, " [telegram %u octets, end %" PRIu32 ", idle %" PRIu32 "]",
                    s->ev[k].len, s->ev[k].end_t, s->ev[k].idle_before_ns);
        } else {
            fprintf(stderr, " [%s]", fdl_rx_error_name(s->ev[k].error));
        }
    }
    fprintf(stderr, "\n");
}

/* One character whose stop bit ended at at_ns (true time). */
static twin_verdict_t line_char_at(uint8_t byte, uint8_t flags, uint64_t at_ns)
{
    L.now_ns = at_ns;
    twin_verdict_t v = twin_char(&L.tw, byte, flags, (int64_t)(at_ns / 1000u));
    if (v == TWIN_MISMATCH) {
        fprintf(stderr, "  [%s] character %zu (%02X, flags %u): %s\n", check_test_name_, L.chars,
                byte, flags, L.tw.why);
        print_side("fdl_rx_char  ", &L.tw.ref_ev);
        print_side("fdl_collect  ", &L.tw.col_ev);
    }
    line_log(L.ref, &L.nref, &L.tw.ref_ev);
    line_log(L.col, &L.ncol, &L.tw.col_ev);
    if (L.chars < sizeof L.stamp_us / sizeof L.stamp_us[0]) {
        L.stamp_us[L.chars] = at_ns / 1000u;
    }
    L.chars++;
    return v;
}

static uint32_t char_ns(void) { return hal_uart_char_ns(L.baud); }

static uint64_t bits_ns(uint32_t bits)
{
    return ((uint64_t)bits * 1000000000ull + L.baud - 1u) / L.baud;
}

/* n characters back to back after idle_ns of idle. */
static void line_send(const uint8_t *p, size_t n, uint64_t idle_ns)
{
    L.now_ns += idle_ns;
    for (size_t k = 0; k < n; k++) {
        (void)line_char_at(p[k], 0, L.now_ns + char_ns());
    }
}

static void line_send_flag(const uint8_t *p, size_t n, size_t flag_at, uint8_t flags,
                           uint64_t idle_ns)
{
    L.now_ns += idle_ns;
    for (size_t k = 0; k < n; k++) {
        (void)line_char_at(p[k], k == flag_at ? flags : 0u, L.now_ns + char_ns());
    }
}

/* A character at an exact microsecond (for the gap boundaries). */
static void line_at_us(uint8_t byte, uint8_t flags, uint64_t us)
{
    (void)line_char_at(byte, flags, us * 1000u);
}

static void line_set_baud(uint32_t baud)
{
    twin_set_baud(&L.tw, baud);
    L.baud = baud;
}

/* ---- what the two sides reported --------------------------------------------------------- */

static void check_frame_ev(const logged_t *e, const uint8_t *p, size_t n, hal_time_us_t end_t,
                           uint32_t idle, size_t at)
{
    CHECK_EQ(e->ev.error, FDL_RX_OK);
    CHECK_EQ(e->ev.len, n);
    CHECK(e->ev.len == n && memcmp(e->ev.octets, p, n) == 0);
    CHECK_EQ(e->ev.end_t, end_t);
    CHECK_EQ(e->ev.idle_before_ns, idle);
    CHECK_EQ(e->at, at);
}

/* Entry k of both sides: the telegram p, n ending at end_t after idle, at character at. */
static void both_frame(size_t k, const uint8_t *p, size_t n, hal_time_us_t end_t, uint32_t idle,
                       size_t at)
{
    check_frame_ev(&L.ref[k], p, n, end_t, idle, at);
    check_frame_ev(&L.col[k], p, n, end_t, idle, at);
}

static void both_error(size_t k, fdl_rx_error_t e, size_t at)
{
    CHECK_EQ(L.ref[k].ev.error, e);
    CHECK_EQ(L.ref[k].at, at);
    CHECK_EQ(L.col[k].ev.error, e);
    CHECK_EQ(L.col[k].at, at);
}

static void both_count(size_t n)
{
    CHECK_EQ(L.nref, n);
    CHECK_EQ(L.ncol, n);
}

/* The verdicts of the whole stream: how many characters showed each documented difference and
 * each difference found beyond the documentation; never a mismatch. */
static void verdicts(unsigned long after_check, unsigned long pause_char, unsigned long gap_sd,
                     unsigned long long_silence, unsigned long relaxed_back)
{
    CHECK(twin_finish(&L.tw));
    CHECK_EQ(L.tw.count[TWIN_MISMATCH], 0u);
    CHECK_EQ(L.tw.count[TWIN_DOC_AFTER_CHECK], after_check);
    CHECK_EQ(L.tw.count[TWIN_DOC_PAUSE_CHAR], pause_char);
    CHECK_EQ(L.tw.count[TWIN_GAP_SD], gap_sd);
    CHECK_EQ(L.tw.count[TWIN_LONG_SILENCE], long_silence);
    CHECK_EQ(L.tw.count[TWIN_RELAXED_BACK], relaxed_back);
}

/* A telegram with a correct FCS: 68 LE LE 68 DA SA FC DU... FCS 16. */
static size_t make_sd2(uint8_t *out, uint8_t le, uint8_t seed)
{
    out[0] = FDL_SD2;
    out[1] = le;
    out[2] = le;
    out[3] = FDL_SD2;
    uint8_t sum = 0;
    for (size_t k = 0; k < le; k++) {
        out[4u + k] = (uint8_t)(seed + 7u * k);
        sum = (uint8_t)(sum + out[4u + k]);
    }
    out[4u + le] = sum;
    out[5u + le] = FDL_ED;
    return (size_t)le + FDL_SD2_OVERHEAD;
}

/* ---- every start delimiter --------------------------------------------------------------- */

static void test_each_start_delimiter(void)
{
    /* 1.5 Mbit/s: a character is 7333 ns, 33 bit times 22000 ns; the µs clock starts at 1000. */
    uint8_t sd2_max[FDL_FRAME_MAX];
    size_t n_max = make_sd2(sd2_max, FDL_LE_MAX, 0x11);
    CHECK_EQ(n_max, 255u);
    line_init(1500000u, true, 1000u);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_send(F_SD2_LE4, sizeof F_SD2_LE4, bits_ns(33));
    line_send(sd2_max, n_max, bits_ns(33));
    line_send(F_DX8_REQ, sizeof F_DX8_REQ, bits_ns(33));
    line_send(F_TOKEN, sizeof F_TOKEN, bits_ns(33));
    line_send(F_SC, sizeof F_SC, bits_ns(33));
    both_count(6);
    /* The first character ever: idle unknown. Then 33 bits + a character between stop bits:
     * 29 or 30 µs between the rounded timestamps, minus 7333 ns. */
    both_frame(0, F_FDL_REQ, sizeof F_FDL_REQ, 1043u, UINT32_MAX, 5);
    both_frame(1, F_SD2_LE4, sizeof F_SD2_LE4, 1139u, 22667u, 15);
    both_frame(2, sd2_max, n_max, 3031u, 21667u, 270);
    both_frame(3, F_DX8_REQ, sizeof F_DX8_REQ, 3155u, 21667u, 284);
    both_frame(4, F_TOKEN, sizeof F_TOKEN, 3199u, 22667u, 287);
    both_frame(5, F_SC, sizeof F_SC, 3229u, 22667u, 288);
    CHECK_EQ(L.tw.frames, 6u);
    /* Each telegram in the next of the three buffers, the last one (the 6th) in buffer 2. */
    CHECK_EQ(L.tw.held, 2);
    CHECK_EQ(L.store[2][0], FDL_SC);
    CHECK(memcmp(L.store[1], F_TOKEN, sizeof F_TOKEN) == 0);
    verdicts(0, 0, 0, 0, 0);
}

/* ---- back to back, with and without TSYN ------------------------------------------------- */

static void back_to_back(uint32_t baud, const hal_time_us_t end[5], const uint32_t idle[5])
{
    line_init(baud, true, 0u);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_send(F_DIAG_REQ, sizeof F_DIAG_REQ, 0);
    line_send(F_SC, sizeof F_SC, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    line_send(F_TOKEN, sizeof F_TOKEN, 0);
    both_count(5);
    both_frame(0, F_FDL_REQ, sizeof F_FDL_REQ, end[0], idle[0], 5);
    both_frame(1, F_DIAG_REQ, sizeof F_DIAG_REQ, end[1], idle[1], 16);
    both_frame(2, F_SC, sizeof F_SC, end[2], idle[2], 17);
    both_frame(3, F_FDL_REQ, sizeof F_FDL_REQ, end[3], idle[3], 23);
    both_frame(4, F_TOKEN, sizeof F_TOKEN, end[4], idle[4], 26);
    verdicts(0, 0, 0, 0, 0);
}

static void test_back_to_back_12m(void)
{
    /* 917 ns characters: back to back the rounded stamps differ by 1 µs (83 ns idle). */
    static const hal_time_us_t end[5] = {5, 15, 16, 24, 27};
    static const uint32_t idle[5] = {UINT32_MAX, 83, 83, 3083, 83};
    back_to_back(12000000u, end, idle);
}

static void test_back_to_back_9k6(void)
{
    /* 1145833 ns characters, 33 bits 3437500 ns. */
    static const hal_time_us_t end[5] = {6874, 19479, 20624, 30937, 34374};
    static const uint32_t idle[5] = {UINT32_MAX, 167, 0, 3438167, 167};
    back_to_back(9600u, end, idle);
}

/* ---- gaps inside a telegram (strict) ------------------------------------------------------ */

static void test_gap_inside_strict(void)
{
    /* 12 Mbit/s, 917 ns characters: the threshold is ceil(0.917) + 1 = 2 µs between stamps
     * (fdl_gap.h), so stamps 2 µs apart (1083 ns idle) are no gap, 3 µs apart (2083 ns) are.
     * The character after the gap is a start delimiter (SC): both count GAP, then the SC. */
    line_init(12000000u, true, 0u);
    line_at_us(0x10, 0, 100);
    line_at_us(0x04, 0, 102);
    line_at_us(0x02, 0, 103);
    line_at_us(FDL_SC, 0, 106);
    both_count(2);
    both_error(0, FDL_RX_ERR_GAP, 3);
    check_frame_ev(&L.ref[1], F_SC, 1, 106u, 2083u, 3);
    check_frame_ev(&L.col[1], F_SC, 1, 106u, 2083u, 3);
    /* fdl_rx_char returned FRAME for that character and only counted the GAP; the collector
     * reported both (FDL_COLLECT_ERROR | FDL_COLLECT_TELEGRAM). */
    CHECK_EQ(L.tw.ref.error_count[FDL_RX_ERR_GAP], 1u);
    CHECK_EQ(L.tw.core.error_count[FDL_RX_ERR_GAP], 1u);

    /* 9.6 kbit/s, 1145833 ns characters: threshold 1146 + 1 µs, so 1147 µs apart (1167 ns idle)
     * is no gap, 1148 µs (2167 ns) is. */
    line_init(9600u, true, 0u);
    uint64_t t = 5000;
    for (size_t k = 0; k < sizeof F_FDL_REQ; k++) {
        line_at_us(F_FDL_REQ[k], 0, t);
        t += k % 2u == 0u ? 1146u : 1147u;
    }
    both_count(1);
    both_frame(0, F_FDL_REQ, sizeof F_FDL_REQ, 5000u + 3u * 1146u + 2u * 1147u, UINT32_MAX, 5);
    t += 100000u;
    line_at_us(0x10, 0, t);
    line_at_us(0x04, 0, t + 1147u);
    line_at_us(FDL_SC, 0, t + 1147u + 1148u);
    both_count(3);
    both_error(1, FDL_RX_ERR_GAP, 8);
    both_frame(2, F_SC, 1, (hal_time_us_t)(t + 2295u), 2167u, 8);
    verdicts(0, 0, 0, 0, 0);
}

/* ---- receiver checks ---------------------------------------------------------------------- */

/* The stream p after TSYN idle fails with e at character at, the rest of it ignored; a good
 * telegram after TSYN idle is then taken by both. */
static void one_error(const uint8_t *p, size_t n, fdl_rx_error_t e, size_t at)
{
    line_init(1500000u, true, 0u);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_send(p, n, bits_ns(33));
    line_send(F_DIAG_REQ, sizeof F_DIAG_REQ, bits_ns(33));
    both_count(3);
    both_error(1, e, 6u + at);
    /* the idle before the good one: its first stamp minus the last before it, minus 7333 ns */
    uint32_t idle = (uint32_t)((L.stamp_us[6u + n] - L.stamp_us[5u + n]) * 1000u - 7333u);
    CHECK(idle == 21667u || idle == 22667u); /* 33 bits, by the µs rounding */
    both_frame(2, F_DIAG_REQ, sizeof F_DIAG_REQ, (hal_time_us_t)L.stamp_us[6u + n + 10u], idle,
               6u + n + 10u);
    CHECK_EQ(L.tw.ref.error_count[e], 1u);
    CHECK_EQ(L.tw.core.error_count[e], 1u);
}

static void test_receiver_checks(void)
{
    static const uint8_t le_ne_ler[] = {0x68, 0x05, 0x06, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                        0xED, 0x16};
    static const uint8_t le3[] = {0x68, 0x03, 0x03, 0x68, 0x84, 0x82, 0x6D, 0x73, 0x16};
    static const uint8_t le250[] = {0x68, 0xFA, 0xFA, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E};
    static const uint8_t bad_rep[] = {0x68, 0x05, 0x05, 0x69, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                      0xED, 0x16};
    static const uint8_t fcs_sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4E, 0x16};
    static const uint8_t fcs_sd2[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                      0xEE, 0x16};
    static const uint8_t fcs_sd3[] = {0xA2, 0x04, 0x02, 0x5D, 0x11, 0x22, 0x33,
                                      0x44, 0x55, 0x66, 0x77, 0x88, 0xC8, 0x16};
    static const uint8_t ed_sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x17};
    static const uint8_t ed_sd2[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                     0xED, 0x00};
    static const uint8_t ed_sd3[] = {0xA2, 0x04, 0x02, 0x5D, 0x11, 0x22, 0x33,
                                     0x44, 0x55, 0x66, 0x77, 0x88, 0xC7, 0x61};
    one_error(le_ne_ler, sizeof le_ne_ler, FDL_RX_ERR_LE, 2);
    verdicts(0, 0, 0, 0, 0);
    one_error(le3, sizeof le3, FDL_RX_ERR_LE, 2);
    verdicts(0, 0, 0, 0, 0);
    one_error(le250, sizeof le250, FDL_RX_ERR_LE, 2);
    verdicts(0, 0, 0, 0, 0);
    one_error(bad_rep, sizeof bad_rep, FDL_RX_ERR_SD_REPEAT, 3);
    verdicts(0, 0, 0, 0, 0);
    one_error(fcs_sd1, sizeof fcs_sd1, FDL_RX_ERR_FCS, 5);
    verdicts(0, 0, 0, 0, 0);
    CHECK_EQ(L.tw.windows, 1u); /* opened by the FCS, closed by the pause */
    one_error(fcs_sd2, sizeof fcs_sd2, FDL_RX_ERR_FCS, 10);
    verdicts(0, 0, 0, 0, 0);
    one_error(fcs_sd3, sizeof fcs_sd3, FDL_RX_ERR_FCS, 13);
    verdicts(0, 0, 0, 0, 0);
    one_error(ed_sd1, sizeof ed_sd1, FDL_RX_ERR_ED, 5);
    verdicts(0, 0, 0, 0, 0);
    one_error(ed_sd2, sizeof ed_sd2, FDL_RX_ERR_ED, 10);
    verdicts(0, 0, 0, 0, 0);
    one_error(ed_sd3, sizeof ed_sd3, FDL_RX_ERR_ED, 13);
    verdicts(0, 0, 0, 0, 0);
    /* A character error in the middle, at the SD and at the ED; every kind of flag. */
    static const uint8_t kinds[] = {HAL_UART_RX_PARITY_ERR, HAL_UART_RX_FRAMING_ERR,
                                    HAL_UART_RX_OVERRUN_ERR};
    static const size_t where[] = {0, 9, sizeof F_SET_PRM - 1u};
    for (size_t k = 0; k < sizeof kinds; k++) {
        for (size_t w = 0; w < 3; w++) {
            line_init(1500000u, true, 0u);
            line_send_flag(F_SET_PRM, sizeof F_SET_PRM, where[w], kinds[k], 0);
            line_send(F_SET_PRM, sizeof F_SET_PRM, bits_ns(33));
            both_count(2);
            both_error(0, FDL_RX_ERR_CHAR, where[w]);
            CHECK_EQ(L.ref[1].ev.error, FDL_RX_OK);
            CHECK_EQ(L.col[1].ev.error, FDL_RX_OK);
            CHECK_EQ(L.tw.frames, 1u);
            verdicts(0, 0, 0, 0, 0);
        }
    }
}

/* ---- garbage and resynchronisation -------------------------------------------------------- */

static void test_garbage(void)
{
    static const uint8_t garbage[] = {0x55, 0xAA, 0x33};
    /* Garbage, a pause, a good telegram: taken. */
    line_init(1500000u, true, 0u);
    line_send(garbage, sizeof garbage, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    both_count(2);
    both_error(0, FDL_RX_ERR_SD, 0);
    both_frame(1, F_FDL_REQ, sizeof F_FDL_REQ, 87u, 22667u, 8);
    verdicts(0, 0, 0, 0, 0);
    /* Garbage directly followed by a telegram, twice: ignored; after a pause: taken. */
    line_init(1500000u, true, 0u);
    line_send(garbage, sizeof garbage, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    both_count(1);
    both_error(0, FDL_RX_ERR_SD, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    both_count(2);
    CHECK_EQ(L.ref[1].ev.error, FDL_RX_OK);
    CHECK_EQ(L.col[1].ev.error, FDL_RX_OK);
    CHECK_EQ(L.ref[1].at, 20u);
    CHECK_EQ(L.tw.frames, 1u);
    verdicts(0, 0, 0, 0, 0);
}

/* ---- relaxed timing ---------------------------------------------------------------------- */

static void test_relaxed(void)
{
    line_init(19200u, false, 0u);
    /* A hole of 20000 µs between stamps inside a telegram is tolerated ... */
    uint64_t t = 1000;
    for (size_t k = 0; k < sizeof F_DIAG_REQ; k++) {
        line_at_us(F_DIAG_REQ[k], 0, t);
        t += k == 4u ? 20000u : 573u;
    }
    both_count(1);
    both_frame(0, F_DIAG_REQ, sizeof F_DIAG_REQ, (hal_time_us_t)(t - 573u), UINT32_MAX, 10);
    /* ... 20001 µs is a gap; the character after it (0x82, no SD) is judged as a start. */
    t += 30000u;
    line_at_us(F_DIAG_REQ[0], 0, t);
    line_at_us(F_DIAG_REQ[1], 0, t + 20001u);
    CHECK_EQ(L.nref, 3u);
    CHECK_EQ(L.ref[1].ev.error, FDL_RX_ERR_GAP);
    CHECK_EQ(L.ref[2].ev.error, FDL_RX_ERR_SD);
    CHECK_EQ(L.ncol, 2u); /* pause + no SD: see test_pause_then_no_start_delimiter */
    CHECK_EQ(L.col[1].ev.error, FDL_RX_ERR_SD);
    t += 20001u;
    /* Resync after an error: 999 µs after the previous character is not enough, 1000 µs is. */
    line_at_us(FDL_SC, 0, t + 999u);
    CHECK_EQ(L.nref, 3u);
    CHECK_EQ(L.ncol, 2u);
    line_at_us(FDL_SC, 0, t + 1999u);
    CHECK_EQ(L.nref, 4u);
    CHECK_EQ(L.ncol, 3u);
    check_frame_ev(&L.ref[3], F_SC, 1, (hal_time_us_t)(t + 1999u), 1000000u - 572917u, 14);
    check_frame_ev(&L.col[2], F_SC, 1, (hal_time_us_t)(t + 1999u), 1000000u - 572917u, 14);
    /* Chunks: a whole telegram with one timestamp. */
    for (size_t k = 0; k < sizeof F_SET_PRM; k++) {
        line_at_us(F_SET_PRM[k], 0, t + 9000u);
    }
    CHECK_EQ(L.nref, 5u);
    check_frame_ev(&L.ref[4], F_SET_PRM, sizeof F_SET_PRM, (hal_time_us_t)(t + 9000u),
                   7001000u - 572917u, 14u + sizeof F_SET_PRM);
    check_frame_ev(&L.col[3], F_SET_PRM, sizeof F_SET_PRM, (hal_time_us_t)(t + 9000u),
                   7001000u - 572917u, 14u + sizeof F_SET_PRM);
    verdicts(0, 0, 1, 0, 0);
}

/* ---- rate change, long silence, clock wrap ------------------------------------------------ */

static void test_baud_change_mid_telegram(void)
{
    line_init(1500000u, true, 0u);
    line_send(F_DX8_REQ, 3, 0);
    line_set_baud(12000000u);
    /* Both forgot the telegram; the rest of it at 12 Mbit/s starts with 0x5D: no SD. */
    line_send(&F_DX8_REQ[3], sizeof F_DX8_REQ - 3u, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    both_count(2);
    both_error(0, FDL_RX_ERR_SD, 3);
    /* idle with the new character time: 3 µs between stamps - 917 ns */
    both_frame(1, F_FDL_REQ, sizeof F_FDL_REQ, 40u, 2083u, 19);
    verdicts(0, 0, 0, 0, 0);
}

static void test_long_silence(void)
{
    /* 1.5 Mbit/s. 999 999 µs between stamps: known; 1 000 000 µs: unknown for both (fdl_rx
     * polled at its deadline, the collector by its own rule). */
    line_init(1500000u, true, 0u);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0); /* last stamp 43 µs */
    uint64_t t = 43u + 999999u;
    line_at_us(FDL_SC, 0, t);
    line_at_us(FDL_SC, 0, t + 1000000u);
    both_count(3);
    both_frame(1, F_SC, 1, (hal_time_us_t)t, 999999000u - 7333u, 6);
    both_frame(2, F_SC, 1, (hal_time_us_t)(t + 1000000u), UINT32_MAX, 7);
    /* A telegram cut off, then 2 s: GAP, and the next starts with idle unknown. */
    line_send(F_DIAG_REQ, 5, bits_ns(33));
    t = L.now_ns / 1000u + 2000000u;
    for (size_t k = 0; k < sizeof F_FDL_REQ; k++) {
        line_at_us(F_FDL_REQ[k], 0, t + k * 8u);
    }
    both_count(5);
    both_error(3, FDL_RX_ERR_GAP, 13);
    both_frame(4, F_FDL_REQ, sizeof F_FDL_REQ, (hal_time_us_t)(t + 40u), UINT32_MAX, 18);
    verdicts(0, 0, 0, 0, 0);
}

static void test_clock_wrap(void)
{
    /* The µs clock wraps inside the first telegram (at 51 µs) ... */
    line_init(1500000u, true, 0xFFFFFFFFu - 50u);
    line_send(F_DIAG_REQ, sizeof F_DIAG_REQ, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    both_count(2);
    both_frame(0, F_DIAG_REQ, sizeof F_DIAG_REQ, 29u, UINT32_MAX, 10);
    both_frame(1, F_FDL_REQ, sizeof F_FDL_REQ, 95u, 21667u, 16);
    verdicts(0, 0, 0, 0, 0);
    /* ... and inside the idle between two. */
    line_init(1500000u, true, 0xFFFFFFFFu - 149u);
    line_send(F_DIAG_REQ, sizeof F_DIAG_REQ, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(100));
    both_count(2);
    both_frame(0, F_DIAG_REQ, sizeof F_DIAG_REQ, 0xFFFFFFBAu, UINT32_MAX, 10);
    both_frame(1, F_FDL_REQ, sizeof F_FDL_REQ, 41u, 66667u, 16);
    verdicts(0, 0, 0, 0, 0);
}

/* ---- the differences fdl_collect.h documents ---------------------------------------------- */

static void test_doc_bad_check_then_start_without_pause(void)
{
    static const uint8_t fcs_sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4E, 0x16};
    static const uint8_t ed_sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x17};
    const uint8_t *bad[2] = {fcs_sd1, ed_sd1};
    const fdl_rx_error_t kind[2] = {FDL_RX_ERR_FCS, FDL_RX_ERR_ED};
    for (size_t b = 0; b < 2; b++) {
        /* Strict, 1.5 Mbit/s: the bad telegram, then a good one back to back. */
        line_init(1500000u, true, 0u);
        line_send(bad[b], 6, 0);
        line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
        /* fdl_rx: the error, then it waits for a pause and ignores the telegram. */
        CHECK_EQ(L.nref, 1u);
        CHECK_EQ(L.ref[0].ev.error, kind[b]);
        CHECK_EQ(L.ref[0].at, 5u);
        /* The collector takes it, with 83..1000 ns of idle before it ... */
        CHECK_EQ(L.ncol, 2u);
        CHECK_EQ(L.col[0].ev.error, kind[b]);
        check_frame_ev(&L.col[1], F_FDL_REQ, sizeof F_FDL_REQ, 87u, 667u, 11);
        /* ... which is less than TSYN, so the core refuses it as a request. */
        CHECK(twin_tsyn_violated(&L.tw, L.col[1].ev.idle_before_ns));
        /* After TSYN idle both take the next one again. */
        line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
        CHECK_EQ(L.nref, 2u);
        CHECK_EQ(L.ncol, 3u);
        CHECK_EQ(L.ref[1].ev.error, FDL_RX_OK);
        CHECK_EQ(L.col[2].ev.error, FDL_RX_OK);
        CHECK_EQ(L.ref[1].at, 17u);
        CHECK_EQ(L.col[2].at, 17u);
        CHECK(!twin_tsyn_violated(&L.tw, L.col[2].ev.idle_before_ns));
        verdicts(1, 0, 0, 0, 0);
    }
    /* A character that is no start delimiter in that place: fdl_rx ignores it, the collector
     * counts a bad SD (it does not wait for the pause either). */
    line_init(1500000u, true, 0u);
    line_send(fcs_sd1, sizeof fcs_sd1, 0);
    line_send(&F_FDL_REQ[1], 1, 0);
    CHECK_EQ(L.nref, 1u);
    CHECK_EQ(L.ncol, 2u);
    CHECK_EQ(L.col[1].ev.error, FDL_RX_ERR_SD);
    verdicts(1, 0, 0, 0, 0);
    /* Relaxed timing: the same, and the core judges no TSYN there, so the collector's
     * telegram would be served where fdl_rx's stream has none. */
    line_init(19200u, false, 0u);
    line_send(fcs_sd1, sizeof fcs_sd1, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    CHECK_EQ(L.nref, 1u);
    CHECK_EQ(L.ncol, 2u);
    CHECK_EQ(L.col[1].ev.error, FDL_RX_OK);
    CHECK_EQ(L.col[1].at, 11u);
    verdicts(1, 0, 0, 0, 0);
}

static void test_doc_pause_and_char_error(void)
{
    /* Strict, 1.5 Mbit/s: three octets of an SD1, 5 bit times of pause, a character with a
     * parity error: fdl_rx counts GAP and CHAR and returns CHAR; the collector reports CHAR. */
    line_init(1500000u, true, 0u);
    line_send(F_FDL_REQ, 3, 0);
    line_send_flag(&F_FDL_REQ[3], 1, 0, HAL_UART_RX_PARITY_ERR, bits_ns(5));
    CHECK_EQ(L.nref, 2u);
    CHECK_EQ(L.ref[0].ev.error, FDL_RX_ERR_GAP);
    CHECK_EQ(L.ref[1].ev.error, FDL_RX_ERR_CHAR);
    CHECK_EQ(L.tw.ref.last_error, FDL_RX_ERR_CHAR);
    CHECK_EQ(L.ncol, 1u);
    CHECK_EQ(L.col[0].ev.error, FDL_RX_ERR_CHAR);
    CHECK_EQ(L.col[0].at, 3u);
    CHECK_EQ(L.tw.core.last_error, FDL_RX_ERR_CHAR);
    /* Afterwards both wait for a pause alike. */
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, bits_ns(33));
    CHECK_EQ(L.nref, 3u);
    CHECK_EQ(L.ncol, 2u);
    CHECK_EQ(L.tw.frames, 1u);
    verdicts(0, 1, 0, 0, 0);
}

/* ---- the edges: a pause before a refused character, a wrapped silence, jitter ------------- */

/* Strict, 1.5 Mbit/s, µs clock from 0:
 *   10 04 02 49 back to back (stamps 7, 14, 21, 29), 4F at 36 µs + 5 bit times (stamp 39).
 * fdl_rx_char counts GAP and then SD (the character after the pause is judged as a start and
 * 0x4F is none) and returns ERROR/SD. fdl_collect_slow drops GAP, then drops SD into the same
 * c->error and returns FDL_COLLECT_ERROR once: fdl_rx_telegram counts SD only. A gap inside a
 * telegram followed by an ordinary octet, the usual shape of a gap, is never counted as GAP
 * on the collector path (error_count[FDL_RX_ERR_GAP] stays 0). */
static void test_pause_then_no_start_delimiter(void)
{
    line_init(1500000u, true, 0u);
    line_send(F_FDL_REQ, 4, 0);
    line_send(&F_FDL_REQ[4], 1, bits_ns(5));
    CHECK_EQ(L.nref, 2u);
    CHECK_EQ(L.ref[0].ev.error, FDL_RX_ERR_GAP);
    CHECK_EQ(L.ref[1].ev.error, FDL_RX_ERR_SD);
    CHECK_EQ(L.ncol, 1u);
    CHECK_EQ(L.col[0].ev.error, FDL_RX_ERR_SD);
    CHECK_EQ(L.tw.count[TWIN_GAP_SD], 1u);
    /* documented in fdl_collect.h: only the second error is reported */
    CHECK_EQ(L.tw.core.error_count[FDL_RX_ERR_GAP], 0u);
    CHECK_EQ(L.tw.ref.error_count[FDL_RX_ERR_GAP], 1u);
}

/* Strict, 1.5 Mbit/s: F_FDL_REQ (last stamp 43 µs), then 2400 s of silence (2.4e9 µs, more
 * than 2^31), then an SC. fdl_rx_char, polled at the deadline fdl_rx_poll gives (as fdl_rx.h
 * asks), reads the idle as unknown: UINT32_MAX, TSYN kept. The collector has no poll: it sees
 * hal_time_diff = 2.4e9 - 2^32, below -1 s, and reads it as the same unknown idle. */
static void test_silence_over_2e31_us(void)
{
    line_init(1500000u, true, 0u);
    line_send(F_FDL_REQ, sizeof F_FDL_REQ, 0);
    line_at_us(FDL_SC, 0, 43u + 2400000000ull);
    CHECK_EQ(L.nref, 2u);
    CHECK_EQ(L.ncol, 2u);
    CHECK_EQ(L.ref[1].ev.idle_before_ns, UINT32_MAX);
    CHECK_EQ(L.col[1].ev.idle_before_ns, UINT32_MAX);
    CHECK(!twin_tsyn_violated(&L.tw, L.col[1].ev.idle_before_ns));
    CHECK_EQ(L.tw.count[TWIN_LONG_SILENCE], 0u); /* no difference left to count */
}

/* Relaxed, 19.2 kbit/s: 55 at 1000 µs (bad SD for both, both now wait for a pause), E5 at
 * 999 µs (time running backwards by 1 µs, as two clocks' jitter can). fdl_rx_char computes
 * the resync pause as (uint32_t)hal_time_diff(t, last) >= relaxed_resync_us without clamping
 * the negative difference: 0xFFFFFFFF >= 1000, a resync, and it returns the SC as a telegram;
 * fdl_collect_slow takes a small negative difference as a resync too. */
static void test_relaxed_time_backwards(void)
{
    line_init(19200u, false, 0u);
    line_at_us(0x55, 0, 1000u);
    line_at_us(FDL_SC, 0, 999u);
    both_error(0, FDL_RX_ERR_SD, 0);
    CHECK_EQ(L.nref, 2u);
    CHECK_EQ(L.ref[1].ev.error, FDL_RX_OK);
    CHECK_EQ(L.ncol, 2u);
    CHECK_EQ(L.col[1].ev.error, FDL_RX_OK);
    CHECK_EQ(L.tw.count[TWIN_RELAXED_BACK], 0u); /* no difference left to count */
}

/* ---- random streams ----------------------------------------------------------------------- */

/* Streams of telegrams of every kind (and bits of garbage) with random idle before each, around
 * every threshold, at a random rate, strict or relaxed, the µs clock often about to wrap; about
 * half the telegrams corrupted: an octet changed, dropped or inserted, a pause inside, an error
 * flag, a timestamp running back, a rate change. Every character is judged by the twin; only
 * the documented differences may appear, and each
 * documented one must appear (else the streams do not reach it). Stream i uses seed base + i;
 * a failure prints the seed: `test_fdl_collect SEED` runs from it. */
#define RANDOM_STREAMS 10000u
#define RANDOM_TELEGRAMS 24u
#define RING 32u
#define PLAN_MAX (FDL_FRAME_MAX + 8u)

typedef struct rng {
    uint64_t s;
} rng_t;

static uint64_t rng_next(rng_t *r) /* splitmix64 */
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static uint32_t rng_below(rng_t *r, uint32_t n) { return (uint32_t)(rng_next(r) % n); }
static uint8_t rng_octet(rng_t *r) { return (uint8_t)rng_next(r); }

typedef struct step {
    uint8_t byte;
    uint8_t flags;
    uint8_t back_us;  /* the timestamp runs back by this much */
    uint32_t baud;    /* set before the character, 0: unchanged */
    uint64_t idle_ns; /* before the character */
} step_t;

typedef struct rstream {
    twin_t tw;
    uint8_t store[TWIN_BUFS][FDL_FRAME_MAX];
    uint64_t seed;
    uint32_t baud;
    bool strict;
    uint64_t now_ns;
    size_t chars;
    step_t ring[RING];
    int64_t ring_us[RING];
    bool failed;
} rstream_t;

static rstream_t R;

static void random_report(void)
{
    fprintf(stderr, "  [random] seed 0x%016" PRIX64 ": %s at character %zu (%s, %" PRIu32
            " bit/s): %s\n", R.seed, twin_verdict_names[TWIN_MISMATCH], R.chars - 1u,
            R.strict ? "strict" : "relaxed", R.baud, R.tw.why);
    print_side("fdl_rx_char  ", &R.tw.ref_ev);
    print_side("fdl_collect  ", &R.tw.col_ev);
    fprintf(stderr, "    the last characters (octet flags true-time-us):");
    size_t from = R.chars > RING ? R.chars - RING : 0u;
    for (size_t k = from; k < R.chars; k++) {
        const step_t *s = &R.ring[k % RING];
        fprintf(stderr, "%s%02X %u %" PRId64 "%s", (k - from) % 6u == 0u ? "\n      " : "  ",
                s->byte, s->flags, R.ring_us[k % RING], s->baud != 0u ? " (new rate)" : "");
    }
    fprintf(stderr, "\n");
}

static void random_char(const step_t *s)
{
    if (s->baud != 0u) {
        twin_set_baud(&R.tw, s->baud);
        R.baud = s->baud;
    }
    R.now_ns += s->idle_ns + hal_uart_char_ns(R.baud);
    int64_t us = (int64_t)(R.now_ns / 1000u) - s->back_us;
    R.ring[R.chars % RING] = *s;
    R.ring_us[R.chars % RING] = us;
    twin_verdict_t v = twin_char(&R.tw, s->byte, s->flags, us);
    R.chars++;
    if (v == TWIN_MISMATCH && !R.failed) {
        R.failed = true;
        random_report();
    }
}

/* An idle time whose µs stamps land within 2 µs of target_us between two characters. */
static uint64_t near_us(rng_t *r, uint32_t target_us)
{
    int64_t ns = ((int64_t)target_us - 2 + rng_below(r, 5)) * 1000 -
                 (int64_t)hal_uart_char_ns(R.baud) + rng_below(r, 1000);
    return ns > 0 ? (uint64_t)ns : 0u;
}

static uint64_t random_idle(rng_t *r)
{
    uint32_t c = hal_uart_char_ns(R.baud);
    uint64_t bit_ns = 1000000000ull / R.baud;
    if (rng_below(r, 60) == 0) {
        return 1000000000ull - 2000000u + rng_below(r, 4000000) +
               (rng_below(r, 2) == 0 ? 0u : rng_below(r, 2000000000u)); /* around 1 s and more */
    }
    switch (rng_below(r, 8)) {
    case 0: return 0;
    case 1: return rng_below(r, 3000);
    case 2: return 33u * bit_ns + rng_below(r, (uint32_t)bit_ns);
    case 3: return rng_below(r, 40) * bit_ns;
    case 4: return near_us(r, fdl_gap_pause_us(true, c, 0u)); /* strict pause */
    case 5: return near_us(r, FDL_RX_RELAXED_GAP_US_DEFAULT);
    case 6: return near_us(r, FDL_RX_RELAXED_RESYNC_US_DEFAULT);
    default: return rng_below(r, 30000000);
    }
}

static size_t random_telegram(rng_t *r, uint8_t *out)
{
    uint32_t kind = rng_below(r, 9);
    size_t n;
    uint8_t le;
    switch (kind) {
    case 0:
    case 1:
        out[0] = FDL_SD1;
        for (size_t k = 1; k < 4u; k++) out[k] = rng_octet(r);
        out[4] = (uint8_t)(out[1] + out[2] + out[3]);
        out[5] = FDL_ED;
        return FDL_SD1_LEN;
    case 2:
    case 3:
    case 4:
        le = kind == 4 ? (uint8_t)FDL_LE_MAX
                       : (uint8_t)(FDL_LE_MIN + rng_below(r, kind == 2 ? 20u : FDL_LE_MAX - 3u));
        n = make_sd2(out, le, rng_octet(r));
        return n;
    case 5: {
        out[0] = FDL_SD3;
        uint8_t sum = 0;
        for (size_t k = 1; k < 12u; k++) {
            out[k] = rng_octet(r);
            sum = (uint8_t)(sum + out[k]);
        }
        out[12] = sum;
        out[13] = FDL_ED;
        return FDL_SD3_LEN;
    }
    case 6:
        out[0] = FDL_SD4;
        out[1] = rng_octet(r);
        out[2] = rng_octet(r);
        return FDL_SD4_LEN;
    case 7: out[0] = FDL_SC; return 1;
    default:
        n = 1u + rng_below(r, 4);
        for (size_t k = 0; k < n; k++) out[k] = rng_octet(r);
        return n;
    }
}

static void corrupt(rng_t *r, step_t *plan, size_t *n)
{
    size_t k = rng_below(r, (uint32_t)*n);
    switch (rng_below(r, 16)) {
    case 0: case 1: case 2:
        plan[k].byte ^= (uint8_t)(1u + rng_below(r, 255));
        break;
    case 3: case 4:
        if (*n > 1u) {
            memmove(&plan[k], &plan[k + 1u], (*n - k - 1u) * sizeof *plan);
            (*n)--;
        }
        break;
    case 5: case 6: case 7: case 8:
        if (k > 0u) plan[k].idle_ns = random_idle(r);
        break;
    case 9: case 10: case 11:
        plan[k].flags = (uint8_t)(1u + rng_below(r, 7));
        break;
    case 12: case 13:
        if (*n < PLAN_MAX) {
            memmove(&plan[k + 1u], &plan[k], (*n - k) * sizeof *plan);
            plan[k] = (step_t){.byte = rng_octet(r)};
            (*n)++;
        }
        break;
    case 14:
        plan[k].back_us = (uint8_t)(1u + rng_below(r, 3));
        break;
    default:
        if (rng_below(r, 3) == 0) plan[k].baud = hal_uart_bauds[rng_below(r, HAL_UART_NUM_BAUDS)];
        break;
    }
}

static void random_stream(uint64_t seed)
{
    rng_t r = {seed};
    memset(&R, 0, sizeof R);
    R.seed = seed;
    R.strict = rng_below(&r, 4) != 0u;
    R.baud = hal_uart_bauds[rng_below(&r, HAL_UART_NUM_BAUDS)];
    hal_time_us_t t0 = rng_below(&r, 3) == 0u ? 0xFFFFFFFFu - rng_below(&r, 3000000)
                                               : (hal_time_us_t)rng_next(&r);
    uint8_t *bufs[TWIN_BUFS] = {R.store[0], R.store[1], R.store[2]};
    twin_init(&R.tw, bufs, R.baud, R.strict, t0);
    for (unsigned g = 0; g < RANDOM_TELEGRAMS && !R.failed; g++) {
        uint8_t octets[FDL_FRAME_MAX];
        step_t plan[PLAN_MAX];
        size_t n = random_telegram(&r, octets);
        for (size_t k = 0; k < n; k++) {
            plan[k] = (step_t){.byte = octets[k]};
        }
        plan[0].idle_ns = random_idle(&r);
        for (uint32_t c = rng_below(&r, 4); c > 1u; c--) { /* none half the time */
            corrupt(&r, plan, &n);
        }
        for (size_t k = 0; k < n && !R.failed; k++) {
            random_char(&plan[k]);
        }
    }
    if (!R.failed && !twin_finish(&R.tw)) {
        R.failed = true;
        random_report();
    }
}

static void random_streams(uint64_t base)
{
    check_test_name_ = "random_streams";
    if (base == 0u) {
        base = 0xC011EC7000000000ull;
    }
    unsigned long count[TWIN_VERDICTS] = {0};
    unsigned long frames = 0;
    unsigned long windows = 0;
    unsigned long chars = 0;
    unsigned failed = 0;
    unsigned streams = 0;
    for (uint64_t i = 0; i < RANDOM_STREAMS; i++) {
        streams++;
        random_stream(base + i);
        CHECK(!R.failed);
        failed += R.failed ? 1u : 0u;
        for (unsigned v = 0; v < TWIN_VERDICTS; v++) {
            count[v] += R.tw.count[v];
        }
        frames += R.tw.frames;
        windows += R.tw.windows;
        chars += (unsigned long)R.chars;
        if (failed >= 3u) {
            break;
        }
    }
    printf("random: %u streams from seed 0x%016" PRIX64 ", %lu characters, %lu telegrams alike,"
           " %lu windows after a bad FCS/ED\n", streams, base, chars, frames, windows);
    for (unsigned v = 1; v < TWIN_VERDICTS; v++) {
        printf("  characters with %s: %lu\n", twin_verdict_names[v], count[v]);
    }
    CHECK_EQ(count[TWIN_MISMATCH], 0u);
    CHECK(frames > 80000u);
    CHECK(count[TWIN_DOC_AFTER_CHECK] > 0u);
    CHECK(count[TWIN_DOC_PAUSE_CHAR] > 0u);
    CHECK_EQ(count[TWIN_LONG_SILENCE], 0u); /* idle stays below 2^31 µs */
}

int main(int argc, char **argv)
{
    RUN_TEST(test_each_start_delimiter);
    RUN_TEST(test_back_to_back_12m);
    RUN_TEST(test_back_to_back_9k6);
    RUN_TEST(test_gap_inside_strict);
    RUN_TEST(test_receiver_checks);
    RUN_TEST(test_garbage);
    RUN_TEST(test_relaxed);
    RUN_TEST(test_baud_change_mid_telegram);
    RUN_TEST(test_long_silence);
    RUN_TEST(test_clock_wrap);
    RUN_TEST(test_doc_bad_check_then_start_without_pause);
    RUN_TEST(test_doc_pause_and_char_error);
    RUN_TEST(test_pause_then_no_start_delimiter);
    RUN_TEST(test_silence_over_2e31_us);
    RUN_TEST(test_relaxed_time_backwards);
    random_streams(argc > 1 ? strtoull(argv[1], NULL, 0) : 0u);
    return check_report();
}
