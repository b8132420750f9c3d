/* Shared pieces of the libFuzzer targets (tests/fuzz/README.md): a reader that turns the fuzzer's
 * bytes into structured operations, the PROPERTY() check that aborts on a violation (libFuzzer
 * then stores the input as crash-*), and the reply checks every target that sees card frames
 * uses: a reply must re-assemble with fdl_rx, parse with fdl_parse and re-encode with
 * fdl_encode_reply to the same bytes (so it is never SD3). */
#ifndef TESTS_FUZZ_FUZZ_COMMON_H
#define TESTS_FUZZ_FUZZ_COMMON_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_rx.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_uart.h"

/* A property of the code under test does not hold: say which and why, then abort so libFuzzer
 * keeps the input. */
#define PROPERTY(cond, ...)                                                                    \
    do {                                                                                       \
        if (!(cond)) {                                                                         \
            fprintf(stderr, "\nPROPERTY VIOLATED at %s:%d: %s\n    ", __FILE__, __LINE__,     \
                    #cond);                                                                    \
            fprintf(stderr, __VA_ARGS__);                                                      \
            fputc('\n', stderr);                                                               \
            abort();                                                                           \
        }                                                                                      \
    } while (0)

/* FUZZ_TRACE=1 in the environment: the targets say what they do (for reading a reproducer). */
static inline bool fz_trace_on(void)
{
    static int on = -1;
    if (on < 0) {
        const char *e = getenv("FUZZ_TRACE");
        on = e != NULL && e[0] != '\0' && e[0] != '0';
    }
    return on != 0;
}
#define TRACE(...)                                                                             \
    do {                                                                                       \
        if (fz_trace_on()) {                                                                   \
            fprintf(stderr, __VA_ARGS__);                                                      \
        }                                                                                      \
    } while (0)

/* ---- input reader: past the end every read returns zeros --------------------------------- */

typedef struct fz {
    const uint8_t *p;
    size_t n;
    size_t i;
} fz_t;

static inline bool fz_more(const fz_t *f) { return f->i < f->n; }
static inline size_t fz_left(const fz_t *f) { return f->n - f->i; }

static inline uint8_t fz_u8(fz_t *f) { return f->i < f->n ? f->p[f->i++] : 0u; }

static inline uint16_t fz_u16(fz_t *f)
{
    uint16_t hi = fz_u8(f);
    return (uint16_t)((hi << 8) | fz_u8(f));
}

static inline uint32_t fz_u32(fz_t *f)
{
    uint32_t hi = fz_u16(f);
    return (hi << 16) | fz_u16(f);
}

static inline bool fz_bool(fz_t *f) { return (fz_u8(f) & 1u) != 0u; }

/* Copies n octets (zeros past the end of the input). */
static inline void fz_bytes(fz_t *f, uint8_t *out, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        out[k] = fz_u8(f);
    }
}

/* ---- frames ------------------------------------------------------------------------------- */

static inline void fz_hex(const char *label, const uint8_t *p, size_t n)
{
    fprintf(stderr, "    %s (%zu):", label, n);
    for (size_t k = 0; k < n; k++) {
        fprintf(stderr, " %02X", p[k]);
    }
    fputc('\n', stderr);
}

/* The expected total length of a telegram starting with sd (0 = unknown start delimiter). */
static inline size_t fz_frame_len_for(const uint8_t *b, size_t avail)
{
    switch (b[0]) {
    case FDL_SD1: return FDL_SD1_LEN;
    case FDL_SD3: return FDL_SD3_LEN;
    case FDL_SD4: return FDL_SD4_LEN;
    case FDL_SC: return 1u;
    case FDL_SD2: return avail >= 2u ? (size_t)b[1] + FDL_SD2_OVERHEAD : 0u;
    default: return 0u;
    }
}

/* An independent statement of what a valid telegram is (protocol.md §A1.2), written without
 * looking at fdl_rx's state machine: used to judge what fdl_rx accepts. */
static inline bool fz_frame_valid(const uint8_t *b, size_t n)
{
    if (n == 0u) {
        return false;
    }
    uint8_t sum = 0;
    switch (b[0]) {
    case FDL_SC: return n == 1u;
    case FDL_SD4: return n == FDL_SD4_LEN;
    case FDL_SD1:
        if (n != FDL_SD1_LEN) return false;
        for (size_t k = 1; k < 4u; k++) sum = (uint8_t)(sum + b[k]);
        return sum == b[4] && b[5] == FDL_ED;
    case FDL_SD3:
        if (n != FDL_SD3_LEN) return false;
        for (size_t k = 1; k < 12u; k++) sum = (uint8_t)(sum + b[k]);
        return sum == b[12] && b[13] == FDL_ED;
    case FDL_SD2:
        if (n < 4u + FDL_SD2_OVERHEAD || b[1] != b[2] || b[3] != FDL_SD2 || b[1] < FDL_LE_MIN ||
            b[1] > FDL_LE_MAX || n != (size_t)b[1] + FDL_SD2_OVERHEAD) {
            return false;
        }
        for (size_t k = 4; k < n - 2u; k++) sum = (uint8_t)(sum + b[k]);
        return sum == b[n - 2u] && b[n - 1u] == FDL_ED;
    default: return false;
    }
}

/* The octets a frame of this shape would have if fdl_encode built it: both addresses extended
 * or neither, single SAP octets (no further extension, no segment bit), SD3 exactly when the DU
 * has 8 octets. Only such frames can round-trip through parse + encode. */
static inline bool fz_frame_canonical(const uint8_t *b, size_t n, const fdl_msg_t *m)
{
    size_t hdr = b[0] == FDL_SD2 ? 4u : 1u;
    size_t du_len = b[0] == FDL_SD1 ? 0u : b[0] == FDL_SD3 ? 8u : (size_t)b[1] - 3u;
    (void)n;
    bool da_ext = (b[hdr] & FDL_ADDR_EXT) != 0u;
    bool sa_ext = (b[hdr + 1u] & FDL_ADDR_EXT) != 0u;
    if (da_ext != sa_ext) return false;
    if (da_ext) {
        const uint8_t *du = &b[hdr + 3u];
        if ((du[0] & 0xC0u) != 0u || (du[1] & 0xC0u) != 0u) return false;
        if (m->data_len + 2u != du_len) return false;
    }
    if (b[0] == FDL_SD2 && du_len == FDL_SD3_DU_LEN) return false;
    return true;
}

/* A frame as fdl_rx accepted it: parse it from an exactly sized heap copy (so AddressSanitizer
 * sees any read past its end), check where the DU landed, and re-encode canonical frames. */
static inline fdl_parse_result_t fz_parse_checked(const uint8_t *frame, size_t len, fdl_msg_t *out)
{
    uint8_t *copy = malloc(len);
    memcpy(copy, frame, len);
    fdl_msg_t m;
    fdl_parse_result_t r = fdl_parse(copy, len, &m);
    if (frame[0] == FDL_SD4 || frame[0] == FDL_SC) {
        PROPERTY(r == FDL_PARSE_NOT_DATA, "SD4/SC parsed as data (%d)", (int)r);
    }
    if (r == FDL_PARSE_OK) {
        size_t hdr = frame[0] == FDL_SD2 ? 4u : 1u;
        const uint8_t *du_start = copy + hdr + 3u;
        const uint8_t *du_end = copy + len - 2u; /* FCS */
        PROPERTY(m.data >= du_start && m.data + m.data_len == du_end,
                 "DU of the parsed message outside the frame's DU (offset %td, len %u, frame %zu)",
                 m.data - copy, m.data_len, len);
        PROPERTY(m.da == (frame[hdr] & FDL_ADDR_MASK) && m.sa == (frame[hdr + 1u] & FDL_ADDR_MASK) &&
                     m.fc == frame[hdr + 2u],
                 "DA/SA/FC not the frame's");
        if (fz_frame_canonical(copy, len, &m)) {
            uint8_t enc[FDL_FRAME_MAX];
            size_t n = fdl_encode(enc, m.da, m.sa, m.fc, m.has_dsap, m.dsap, m.ssap, m.data,
                                  m.data_len);
            if (n != len || memcmp(enc, copy, len) != 0) {
                fz_hex("frame    ", copy, len);
                fz_hex("re-encode", enc, n);
            }
            PROPERTY(n == len && memcmp(enc, copy, len) == 0,
                     "a canonical frame does not re-encode to itself");
        }
    }
    if (out != NULL) {
        *out = m;
        if (r == FDL_PARSE_OK) {
            /* point into the caller's frame, not the copy that is freed here */
            out->data = frame + (m.data - copy);
        }
    }
    free(copy);
    return r;
}

/* A frame the card transmitted: it must be a complete telegram for fdl_rx (fed with exact
 * character timing after an idle line, it completes at its last octet and not before), parse,
 * and be exactly what fdl_encode_reply makes of its own fields: SD1 or SD2, never SD3. Returns the parsed message (data
 * points into frame); SC returns false with *is_sc set. */
static inline bool fz_check_reply(const uint8_t *frame, size_t len, uint32_t baud, bool *is_sc,
                                  fdl_msg_t *msg)
{
    *is_sc = false;
    PROPERTY(len >= 1u && len <= FDL_FRAME_MAX, "reply length %zu", len);
    fdl_rx_t rx;
    fdl_rx_init(&rx, baud, true);
    uint32_t char_ns = hal_uart_char_ns(baud);
    uint64_t t_ns = 1000000000ull;
    fdl_rx_result_t r = FDL_RX_NOTHING;
    for (size_t k = 0; k < len; k++) {
        t_ns += char_ns;
        r = fdl_rx_char(&rx, frame[k], 0, (hal_time_us_t)(t_ns / 1000u));
        if (k + 1u < len) {
            if (r != FDL_RX_NOTHING) fz_hex("reply", frame, len);
            PROPERTY(r == FDL_RX_NOTHING, "the reply is a complete telegram (or an error) at octet "
                     "%zu of %zu (rx result %d, %s)", k + 1u, len, (int)r,
                     fdl_rx_error_name(rx.last_error));
        }
    }
    if (r != FDL_RX_FRAME) fz_hex("reply", frame, len);
    PROPERTY(r == FDL_RX_FRAME && rx.frame_len == len, "the reply does not re-assemble (%s)",
             fdl_rx_error_name(rx.last_error));
    PROPERTY(fz_frame_valid(frame, len), "the reply is not a valid telegram");
    if (frame[0] == FDL_SC) {
        *is_sc = true;
        return false;
    }
    PROPERTY(frame[0] != FDL_SD4, "the card sent a token");
    PROPERTY(frame[0] != FDL_SD3, "the card sent SD3 (its data replies are SD2)");
    fdl_msg_t m;
    fdl_parse_result_t pr = fz_parse_checked(frame, len, &m);
    PROPERTY(pr == FDL_PARSE_OK, "the reply does not parse (%d)", (int)pr);
    uint8_t enc[FDL_FRAME_MAX];
    size_t n = fdl_encode_reply(enc, m.da, m.sa, m.fc, m.has_dsap && m.has_ssap, m.dsap,
                                m.ssap, m.data, m.data_len);
    if (n != len || memcmp(enc, frame, len) != 0) {
        fz_hex("reply    ", frame, len);
        fz_hex("re-encode", enc, n);
    }
    PROPERTY(n == len && memcmp(enc, frame, len) == 0,
             "the reply does not re-encode to the same octets");
    PROPERTY(m.has_dsap == m.has_ssap, "a reply with only one SAP");
    *msg = m;
    return true;
}

#endif
