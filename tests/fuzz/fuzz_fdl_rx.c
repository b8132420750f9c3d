/* Target fdl_rx: the telegram assembler fed a character stream with error flags and
 * timestamps, at any rate, in strict and relaxed timing.
 *
 * Input: mode (bit 0 relaxed, bits 1..4 rate index), a 32-bit start time (the µs clock wraps),
 * then operations, each an op octet:
 *   00xxxxxx  x+1 octets back to back (no error flags)
 *   01uuxxxx  pause, then one octet: pause = u16 * (1, 10, 100, 1000 µs by uu); after the
 *             longest pauses (uu = 3) the receiver is polled first, as a main loop would
 *   10000fff  one octet with UART error flags fff (parity, framing, overrun)
 *   10001xxx  one octet back to back whose time runs backwards by x µs (clock jitter)
 *   11kkkccc  a telegram built from the input (kk: 0 raw length+octets, 1 SD1, 2 SD2/SD3 with
 *             DU, 3 SC/SD4), sent after an idle line; ccc != 0 corrupts octet u8 % len by
 *             XOR (u8 | 1)
 *
 * Properties (abort on violation):
 *  - fdl_rx reports a telegram only on an error-free octet, and the telegram is exactly the
 *    last frame_len octets delivered, all error-free, with no pause above the gap tolerance
 *    between them in strict timing; it is valid by an independent check (SD, LE = LEr, range,
 *    repeated SD2, FCS, ED); frame_end_t is the last octet's time; idle_before_ns matches the
 *    pause in front of its first octet, or is "unknown" (UINT32_MAX) after a poll that came
 *    FDL_RX_FORGET_US or more after the previous octet;
 *  - a well-formed telegram sent after an idle line is always reported, at its last octet and
 *    not before (no valid request is lost, none is reported early);
 *  - the collected length never exceeds 255;
 *  - fdl_parse of every accepted telegram stays inside it (exact-size heap copy), its DU ends at
 *    the FCS, and canonical telegrams re-encode with fdl_encode to the same octets. */
#include "fuzz_common.h"

#define HIST 512u

typedef struct hist_entry {
    uint8_t byte;
    uint8_t flags;
    hal_time_us_t t;
    bool forgotten; /* a poll before this octet made fdl_rx forget the previous one */
} hist_entry_t;

typedef struct rig {
    fdl_rx_t rx;
    bool strict;
    uint32_t baud;
    uint32_t char_ns;
    hal_time_us_t t0;
    uint64_t t_ns; /* end of the last character, from t0 */
    hist_entry_t hist[HIST];
    size_t count; /* characters delivered */
    size_t frames;
} rig_t;

static hist_entry_t *hist_at(rig_t *r, size_t back) /* back = 0: the last character */
{
    return &r->hist[(r->count - 1u - back) % HIST];
}

static void check_frame(rig_t *r)
{
    fdl_rx_t *rx = &r->rx;
    size_t n = rx->frame_len;
    PROPERTY(n >= 1u && n <= FDL_FRAME_MAX && n <= r->count, "frame_len %zu", n);
    uint8_t bytes[FDL_FRAME_MAX];
    for (size_t k = 0; k < n; k++) {
        hist_entry_t *e = hist_at(r, n - 1u - k);
        bytes[k] = e->byte;
        PROPERTY(e->flags == 0u, "octet %zu of the accepted telegram had error flags %02X", k,
                 e->flags);
        if (k > 0u && r->strict) {
            hist_entry_t *p = hist_at(r, n - k);
            int32_t dt = hal_time_diff(e->t, p->t);
            uint64_t dt_ns = dt < 0 ? 0u : (uint64_t)dt * 1000u;
            /* at most the character time rounded up to the µs stamps, plus the tolerance */
            uint64_t char_up_ns = ((uint64_t)r->char_ns + 999u) / 1000u * 1000u;
            PROPERTY(dt_ns <= char_up_ns + FDL_RX_GAP_TOLERANCE_NS,
                     "strict timing accepted a %lld ns pause inside a telegram",
                     (long long)dt_ns - (long long)r->char_ns);
        }
    }
    PROPERTY(memcmp(bytes, rx->buf, n) == 0, "the telegram is not the last octets delivered");
    if (!fz_frame_valid(bytes, n)) {
        fz_hex("accepted", bytes, n);
    }
    PROPERTY(fz_frame_valid(bytes, n), "fdl_rx accepted an invalid telegram");
    PROPERTY(rx->frame_end_t == hist_at(r, 0)->t, "frame_end_t is not the last octet's time");
    if (n < r->count) {
        hist_entry_t *first = hist_at(r, n - 1u);
        hist_entry_t *before = hist_at(r, n);
        int32_t dt = hal_time_diff(first->t, before->t);
        uint64_t dt_ns = dt < 0 ? 0u : (uint64_t)dt * 1000u;
        uint64_t idle = dt_ns > r->char_ns ? dt_ns - r->char_ns : 0u;
        if (idle > UINT32_MAX - 1u) idle = UINT32_MAX - 1u;
        if (first->forgotten) idle = UINT32_MAX;
        PROPERTY(rx->idle_before_ns == idle, "idle_before_ns %u, the line was idle %llu ns",
                 rx->idle_before_ns, (unsigned long long)idle);
    } else {
        PROPERTY(rx->idle_before_ns == UINT32_MAX, "idle before the very first octet is known");
    }
    (void)fz_parse_checked(bytes, n, NULL);
    r->frames++;
}

/* Delivers one character dt_ns after the end of the previous one (its own duration included). */
static fdl_rx_result_t deliver(rig_t *r, uint8_t byte, uint8_t flags, uint64_t dt_ns,
                               int32_t jitter_us, bool poll_first)
{
    r->t_ns += dt_ns;
    hal_time_us_t t = (hal_time_us_t)(r->t0 + (hal_time_us_t)(r->t_ns / 1000u) + (uint32_t)jitter_us);
    bool forgotten = false;
    if (poll_first) {
        forgotten = r->count > 0u && hal_time_diff(t, hist_at(r, 0)->t) >= (int32_t)FDL_RX_FORGET_US;
        hal_time_us_t next = fdl_rx_poll(&r->rx, t);
        PROPERTY(!r->rx.have_last || hal_time_diff(next, t) > 0,
                 "fdl_rx_poll keeps the last octet but asks to be polled now");
        PROPERTY(r->rx.have_last == (r->count > 0u && !forgotten),
                 "fdl_rx_poll %s the last octet, %d us old", r->rx.have_last ? "kept" : "forgot",
                 r->count > 0u ? hal_time_diff(t, hist_at(r, 0)->t) : 0);
    }
    hist_entry_t *e = &r->hist[r->count % HIST];
    *e = (hist_entry_t){.byte = byte, .flags = flags, .t = t, .forgotten = forgotten};
    r->count++;
    fdl_rx_result_t res = fdl_rx_char(&r->rx, byte, flags, t);
    PROPERTY(r->rx.len <= FDL_FRAME_MAX && r->rx.expected <= FDL_FRAME_MAX,
             "collecting %u of %u octets", r->rx.len, r->rx.expected);
    if (res == FDL_RX_FRAME) {
        PROPERTY(flags == 0u, "a telegram completed on an octet with error flags %02X", flags);
        check_frame(r);
    }
    return res;
}

static size_t build_frame(fz_t *f, uint8_t kind, uint8_t *out)
{
    switch (kind) {
    case 0: { /* raw: whatever the input says */
        size_t n = (size_t)fz_u8(f) % FDL_FRAME_MAX + 1u;
        fz_bytes(f, out, n);
        return n;
    }
    case 1:
        return fdl_encode(out, fz_u8(f), fz_u8(f), fz_u8(f), false, 0, 0, NULL, 0);
    case 2: {
        uint8_t da = fz_u8(f);
        uint8_t sa = fz_u8(f);
        uint8_t fc = fz_u8(f);
        uint8_t opt = fz_u8(f);
        uint8_t du[FDL_DU_MAX];
        size_t len = (size_t)fz_u8(f) % (FDL_DU_MAX - 1u);
        fz_bytes(f, du, len);
        bool saps = (opt & 1u) != 0u;
        if (!saps && len == 0u) len = 1u;
        return fdl_encode(out, da, sa, fc, saps, (uint8_t)(opt >> 1), fz_u8(f), du, len);
    }
    default:
        if (fz_bool(f)) {
            out[0] = FDL_SC;
            return 1;
        }
        out[0] = FDL_SD4;
        out[1] = fz_u8(f);
        out[2] = fz_u8(f);
        return 3;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rig_t r;
    fz_t f = {data, size, 0};
    uint8_t mode = fz_u8(&f);
    memset(&r, 0, sizeof r);
    r.strict = (mode & 1u) == 0u;
    r.baud = hal_uart_bauds[(mode >> 1) % HAL_UART_NUM_BAUDS];
    r.char_ns = hal_uart_char_ns(r.baud);
    r.t0 = fz_u32(&f);
    fdl_rx_init(&r.rx, r.baud, r.strict);
    /* An idle line long enough for either timing model to trust the next start delimiter. */
    const uint64_t idle_ns = r.strict ? 100ull * r.char_ns : 25000000ull;

    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        switch (op >> 6) {
        case 0: {
            size_t n = (size_t)(op & 0x3Fu) + 1u;
            for (size_t k = 0; k < n; k++) {
                (void)deliver(&r, fz_u8(&f), 0, r.char_ns, 0, false);
            }
            break;
        }
        case 1: {
            static const uint32_t unit_us[4] = {1u, 10u, 100u, 1000u};
            uint64_t pause_us = (uint64_t)fz_u16(&f) * unit_us[(op >> 4) & 3u];
            (void)deliver(&r, fz_u8(&f), 0, r.char_ns + pause_us * 1000u, 0, (op & 0x30u) == 0x30u);
            break;
        }
        case 2:
            if ((op & 0x08u) == 0u) {
                uint8_t flags = (uint8_t)(op & 0x07u);
                (void)deliver(&r, fz_u8(&f), flags, r.char_ns, 0, false);
            } else {
                (void)deliver(&r, fz_u8(&f), 0, r.char_ns, -(int32_t)(op & 0x07u), false);
            }
            break;
        default: {
            uint8_t frame[FDL_FRAME_MAX];
            size_t n = build_frame(&f, (uint8_t)((op >> 3) & 3u), frame);
            if (n == 0u) break;
            uint8_t corrupt = (uint8_t)(op & 0x07u);
            if (corrupt != 0u) {
                frame[fz_u8(&f) % n] ^= (uint8_t)(fz_u8(&f) | 1u);
            }
            bool valid = fz_frame_valid(frame, n);
            for (size_t k = 0; k < n; k++) {
                fdl_rx_result_t res =
                    deliver(&r, frame[k], 0, k == 0u ? idle_ns + r.char_ns : r.char_ns, 0, false);
                if (!valid) continue;
                if (k + 1u < n) {
                    PROPERTY(res != FDL_RX_FRAME, "a telegram of %zu octets reported after %zu",
                             n, k + 1u);
                } else {
                    if (res != FDL_RX_FRAME) fz_hex("telegram", frame, n);
                    PROPERTY(res == FDL_RX_FRAME && r.rx.frame_len == n,
                             "a valid telegram after an idle line was not accepted (%s)",
                             fdl_rx_error_name(r.rx.last_error));
                }
            }
            break;
        }
        }
    }
    return 0;
}
