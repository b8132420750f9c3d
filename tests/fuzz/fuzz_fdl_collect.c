/* Target fdl_collect: the interrupt-level collector (fdl_collect.h) and fdl_rx_telegram held
 * against fdl_rx_char on one character stream, through tests/unit/fdl_collect_twin.h (the
 * unit test test_fdl_collect uses the same twin).
 *
 * Input: mode (bit 0 relaxed, bits 1..4 rate index), a 32-bit start time (the µs clock wraps),
 * then operations, each an op octet:
 *   00xxxxxx  x+1 octets back to back (no error flags)
 *   01uuxxxx  pause, then one octet: pause = u16 * (1, 10, 100, 1000 µs by uu)
 *   100fffxx  one octet with UART error flags fff (none if 0), xx * 300 ns after its character
 *             time (around the strict gap tolerance at the high rates)
 *   1010xxxx  one octet back to back whose time runs backwards by x µs (clock jitter)
 *   1011xxxx  a new rate, hal_uart_bauds[x % 10], for both receivers
 *   11kkkccc  a telegram after u8 bit times of idle; kkk: 0 raw length+octets, 1 SD1, 2 SD2 with
 *             a DU from the input, 3 SD3, 4 SD4, 5 SC, 6 SD2 with LE 249, 7 SD2 with LE and LEr
 *             from the input; ccc: 1 an octet XOR'd, 2 one dropped, 3 u8 * 100 ns of pause
 *             before one, 4 an error flag on one, 5 an octet inserted, 6 a pause of the strict
 *             tolerance's µs +- 1 before one, else intact
 * Pauses stay below 2^31 µs (the twin's "silence >= 2^31 us" cannot arise).
 *
 * Properties (abort on violation):
 *  - for every character the twin's verdict is no mismatch: both sides counted the same
 *    errors and reported the same telegrams (octets, length, end time, idle before), or the
 *    difference is one fdl_collect.h documents, with its documented outcome (strict timing,
 *    after a bad FCS/ED: what fdl_rx reports the collector reports too, and a telegram only
 *    the collector reports fails TSYN), or one of those tests/unit/test_fdl_collect.c shows in
 *    its test_DISCREPANCY_* tests (pause + no SD; relaxed timing with time running back);
 *  - the collector fills exactly the buffer it was given and leaves the one handed on before
 *    unchanged; its three buffers are FDL_FRAME_MAX octets on the heap, so AddressSanitizer
 *    sees any write past one; fdl_rx_telegram's frame is the telegram's buffer;
 *  - every telegram accepted through the collector is valid by the independent check and
 *    fdl_parse stays inside an exact-size copy of it. */
#include "../unit/fdl_collect_twin.h"
#include "fuzz_common.h"

typedef struct rig {
    twin_t tw;
    uint32_t baud;
    uint64_t t_ns; /* end of the last character, true time */
    size_t chars;
} rig_t;

static rig_t R;
static uint8_t *bufs[TWIN_BUFS];

static void deliver(uint8_t byte, uint8_t flags, uint64_t idle_ns, uint32_t back_us)
{
    R.t_ns += idle_ns + hal_uart_char_ns(R.baud);
    int64_t us = (int64_t)(R.t_ns / 1000u) - (int64_t)back_us;
    twin_verdict_t v = twin_char(&R.tw, byte, flags, us);
    TRACE("%zu: %02X flags %u at %lld us: %s\n", R.chars, byte, flags, (long long)us,
          twin_verdict_names[v]);
    R.chars++;
    if (v == TWIN_MISMATCH) {
        for (unsigned k = 0; k < R.tw.ref_ev.n; k++) {
            fprintf(stderr, "    fdl_rx_char: %s\n", fdl_rx_error_name(R.tw.ref_ev.ev[k].error));
        }
        for (unsigned k = 0; k < R.tw.col_ev.n; k++) {
            fprintf(stderr, "    collector:   %s\n", fdl_rx_error_name(R.tw.col_ev.ev[k].error));
        }
    }
    PROPERTY(v != TWIN_MISMATCH, "character %zu (%02X, flags %u, %s, %u bit/s): %s", R.chars - 1u,
             byte, flags, R.tw.strict ? "strict" : "relaxed", R.baud, R.tw.why);
    PROPERTY(v != TWIN_LONG_SILENCE, "a silence of 2^31 us the input cannot make");
    for (unsigned k = 0; k < R.tw.col_ev.n; k++) {
        const twin_event_t *e = &R.tw.col_ev.ev[k];
        if (e->error == FDL_RX_OK) {
            if (!fz_frame_valid(e->octets, e->len)) {
                fz_hex("accepted", e->octets, e->len);
            }
            PROPERTY(fz_frame_valid(e->octets, e->len), "the collector path accepted an invalid "
                     "telegram");
            (void)fz_parse_checked(e->octets, e->len, NULL);
        }
    }
}

static size_t build_frame(fz_t *f, uint8_t kind, uint8_t *out)
{
    uint8_t du[FDL_DU_MAX];
    switch (kind) {
    case 0: {
        size_t n = (size_t)fz_u8(f) % FDL_FRAME_MAX + 1u;
        fz_bytes(f, out, n);
        return n;
    }
    case 1: return fdl_encode(out, fz_u8(f), fz_u8(f), fz_u8(f), false, 0, 0, NULL, 0);
    case 2: {
        uint8_t da = fz_u8(f);
        uint8_t sa = fz_u8(f);
        uint8_t fc = fz_u8(f);
        size_t len = 1u + (size_t)fz_u8(f) % (FDL_DU_MAX - 2u);
        fz_bytes(f, du, len);
        return fdl_encode(out, da, sa, fc, true, fz_u8(f), fz_u8(f), du, len);
    }
    case 3:
        fz_bytes(f, du, FDL_SD3_DU_LEN);
        return fdl_encode(out, fz_u8(f), fz_u8(f), fz_u8(f), false, 0, 0, du, FDL_SD3_DU_LEN);
    case 4:
        out[0] = FDL_SD4;
        out[1] = fz_u8(f);
        out[2] = fz_u8(f);
        return FDL_SD4_LEN;
    case 5: out[0] = FDL_SC; return 1;
    case 6:
        fz_bytes(f, du, FDL_DU_MAX - 2u);
        return fdl_encode(out, fz_u8(f), fz_u8(f), fz_u8(f), true, 1, 2, du, FDL_DU_MAX - 2u);
    default: {
        /* LE = LEr from the input, 0..255: the range check; the DU as far as LE says */
        uint8_t le = fz_u8(f);
        size_t n = (size_t)le + FDL_SD2_OVERHEAD;
        if (n > FDL_FRAME_MAX) n = FDL_FRAME_MAX;
        out[0] = FDL_SD2;
        out[1] = le;
        out[2] = le;
        out[3] = FDL_SD2;
        fz_bytes(f, &out[4], n - 4u);
        if (le >= FDL_LE_MIN && n == (size_t)le + FDL_SD2_OVERHEAD) {
            out[n - 2u] = fdl_fcs(&out[4], le);
            out[n - 1u] = FDL_ED;
        }
        return n;
    }
    }
}

static void send_telegram(fz_t *f, uint8_t op)
{
    uint8_t frame[FDL_FRAME_MAX + 1u];
    size_t n = build_frame(f, (uint8_t)((op >> 3) & 7u), frame);
    if (n == 0u) {
        return;
    }
    uint64_t bit_ns = 1000000000ull / R.baud;
    uint64_t idle0 = (uint64_t)fz_u8(f) * bit_ns;
    uint8_t how = (uint8_t)(op & 7u);
    size_t at = (size_t)fz_u8(f) % n;
    uint8_t flags_at = 0;
    uint64_t pause_at = 0;
    if (how == 1u) {
        frame[at] ^= (uint8_t)(fz_u8(f) | 1u);
    } else if (how == 2u && n > 1u) {
        memmove(&frame[at], &frame[at + 1u], n - at - 1u);
        n--;
    } else if (how == 3u) {
        pause_at = (uint64_t)fz_u8(f) * 100u;
    } else if (how == 4u) {
        flags_at = (uint8_t)(1u + fz_u8(f) % 7u);
    } else if (how == 5u) {
        memmove(&frame[at + 1u], &frame[at], n - at);
        frame[at] = fz_u8(f);
        n++;
    } else if (how == 6u) {
        /* stamps (the strict pause threshold - 1 .. + 1) apart, sub-µs phase from the input */
        uint32_t c = hal_uart_char_ns(R.baud);
        uint64_t target = ((uint64_t)fdl_gap_pause_us(true, c, 0u) - 1u + fz_u8(f) % 3u) * 1000u;
        pause_at = target > c ? target - c + fz_u8(f) % 1000u : 0u;
    }
    for (size_t k = 0; k < n; k++) {
        uint64_t idle = k == 0u ? idle0 : 0u;
        if (k == at && k > 0u) {
            idle += pause_at;
        }
        deliver(frame[k], k == at ? flags_at : 0u, idle, 0);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (bufs[0] == NULL) {
        for (unsigned k = 0; k < TWIN_BUFS; k++) {
            bufs[k] = malloc(FDL_FRAME_MAX); /* exactly: ASan reports a write past the end */
        }
    }
    fz_t f = {data, size, 0};
    uint8_t mode = fz_u8(&f);
    memset(&R, 0, sizeof R);
    R.baud = hal_uart_bauds[(mode >> 1) % HAL_UART_NUM_BAUDS];
    twin_init(&R.tw, bufs, R.baud, (mode & 1u) == 0u, fz_u32(&f));
    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        if ((op & 0xC0u) == 0x00u) {
            for (size_t k = 0; k <= (op & 0x3Fu); k++) {
                deliver(fz_u8(&f), 0, 0, 0);
            }
        } else if ((op & 0xC0u) == 0x40u) {
            static const uint32_t unit_us[4] = {1u, 10u, 100u, 1000u};
            uint64_t pause_us = (uint64_t)fz_u16(&f) * unit_us[(op >> 4) & 3u];
            deliver(fz_u8(&f), 0, pause_us * 1000u, 0);
        } else if ((op & 0xE0u) == 0x80u) {
            deliver(fz_u8(&f), (uint8_t)((op >> 2) & 7u), (uint64_t)(op & 3u) * 300u, 0);
        } else if ((op & 0xF0u) == 0xA0u) {
            deliver(fz_u8(&f), 0, 0, op & 0x0Fu);
        } else if ((op & 0xF0u) == 0xB0u) {
            R.baud = hal_uart_bauds[(op & 0x0Fu) % HAL_UART_NUM_BAUDS];
            twin_set_baud(&R.tw, R.baud);
        } else {
            send_telegram(&f, op);
        }
    }
    PROPERTY(twin_finish(&R.tw), "%s", R.tw.why);
    return 0;
}
