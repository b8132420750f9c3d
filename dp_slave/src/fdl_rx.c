#include "dp_slave/fdl_rx.h"

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_gap.h"
#include "hal/hal_uart.h"

void fdl_rx_init(fdl_rx_t *rx, uint32_t baud, bool strict)
{
    *rx = (fdl_rx_t){0};
    rx->strict = strict;
    rx->synced = true;
    rx->relaxed_gap_us = FDL_RX_RELAXED_GAP_US_DEFAULT;
    rx->relaxed_resync_us = FDL_RX_RELAXED_RESYNC_US_DEFAULT;
    rx->idle_before_ns = UINT32_MAX;
    fdl_rx_set_baud(rx, baud);
}

void fdl_rx_set_baud(fdl_rx_t *rx, uint32_t baud)
{
    rx->char_ns = hal_uart_char_ns(baud != 0u ? baud : HAL_UART_BAUD_MAX);
    uint64_t tsyn_ns = (uint64_t)FDL_TSYN_BITS * rx->char_ns / FDL_CHAR_BITS;
    rx->tsyn_short_ns =
        tsyn_ns > FDL_RX_GAP_TOLERANCE_NS ? (uint32_t)(tsyn_ns - FDL_RX_GAP_TOLERANCE_NS) : 0u;
    fdl_rx_reset(rx);
}

void fdl_rx_reset(fdl_rx_t *rx)
{
    rx->collecting = false;
    rx->len = 0;
    rx->expected = 0;
    rx->synced = true;
}

const char *fdl_rx_error_name(fdl_rx_error_t e)
{
    static const char *const names[FDL_RX_ERR_COUNT] = {
        "ok", "character error", "bad start delimiter", "LE/LEr", "SD2 repeat", "FCS", "ED",
        "gap inside telegram", "no TSYN idle before request",
    };
    return (unsigned)e < FDL_RX_ERR_COUNT ? names[e] : "?";
}

static fdl_rx_result_t fail(fdl_rx_t *rx, fdl_rx_error_t e)
{
    rx->collecting = false;
    rx->len = 0;
    rx->expected = 0;
    rx->synced = false; /* wait for a pause before trusting a start delimiter again */
    rx->last_error = e;
    rx->error_count[e]++;
    return FDL_RX_ERROR;
}

static fdl_rx_result_t accept(fdl_rx_t *rx, const uint8_t *frame, uint16_t n, hal_time_us_t t,
                              uint32_t idle_before_ns)
{
    rx->frame = frame;
    rx->frame_len = n;
    rx->frame_end_t = t;
    rx->idle_before_ns = idle_before_ns;
#if FDL_RX_CHAR_INPUT
    rx->collecting = false; /* the character assembler's state; whole telegrams never touch it */
    rx->len = 0;
    rx->expected = 0;
#endif
    rx->synced = true;
    rx->last_error = FDL_RX_OK;
    return FDL_RX_FRAME;
}

static uint16_t length_for_sd(uint8_t sd)
{
    switch (sd) {
    case FDL_SD1: return FDL_SD1_LEN;
    case FDL_SD3: return FDL_SD3_LEN;
    case FDL_SD4: return FDL_SD4_LEN;
    case FDL_SC: return 1u;
    case FDL_SD2: return 0u; /* known after LE */
    default: return UINT16_MAX;
    }
}

/* A telegram's length (the collector's rules, checked again: a telegram handed over by a driver
 * is input like any other, and a wrong length here would read past its end), then its check
 * octets, in one pass over the header as the delimiter directs. sum, when known, is the octet
 * sum of DA..DU. Errors in the order a receiver meets them: length, FCS, ED. */
static fdl_rx_error_t check_telegram(const uint8_t *b, uint16_t n, bool sum_known, uint8_t sum)
{
    if (n == 0u || n > FDL_FRAME_MAX) {
        return FDL_RX_ERR_SD;
    }
    size_t from = FDL_SD1_SD3_HEADER_LEN;
    switch (b[0]) {
    case FDL_SD1:
        if (n != FDL_SD1_LEN) {
            return FDL_RX_ERR_SD;
        }
        break;
    case FDL_SD3:
        if (n != FDL_SD3_LEN) {
            return FDL_RX_ERR_SD;
        }
        break;
    case FDL_SD2:
        if (n < FDL_SD2_OVERHEAD || b[1] != b[2] || b[1] < FDL_LE_MIN || b[1] > FDL_LE_MAX) {
            return FDL_RX_ERR_LE;
        }
        if (b[3] != FDL_SD2) {
            return FDL_RX_ERR_SD_REPEAT;
        }
        if (n != b[1] + FDL_SD2_OVERHEAD) {
            return FDL_RX_ERR_LE;
        }
        from = FDL_SD2_HEADER_LEN;
        break;
    default: /* SD4 and SC carry no check octets */
        return length_for_sd(b[0]) == n ? FDL_RX_OK : FDL_RX_ERR_SD;
    }
    size_t fcs_at = n - FDL_TRAILER_LEN;
    if ((sum_known ? sum : fdl_fcs(&b[from], fcs_at - from)) != b[fcs_at]) {
        return FDL_RX_ERR_FCS;
    }
    return b[n - 1u] == FDL_ED ? FDL_RX_OK : FDL_RX_ERR_ED;
}

#if FDL_RX_CHAR_INPUT
static fdl_rx_result_t complete(fdl_rx_t *rx, hal_time_us_t t)
{
    fdl_rx_error_t e = check_telegram(rx->buf, rx->len, false, 0);
    if (e != FDL_RX_OK) {
        return fail(rx, e);
    }
    return accept(rx, rx->buf, rx->len, t, rx->idle_before_pending_ns);
}
#endif

fdl_rx_result_t fdl_rx_telegram(fdl_rx_t *rx, const fdl_rx_telegram_t *tg)
{
    fdl_rx_error_t e = tg->error;
    if (e == FDL_RX_OK) {
        e = check_telegram(tg->buf, tg->len, tg->sum_known, tg->sum);
    }
    if (e != FDL_RX_OK) {
        fdl_rx_result_t r = fail(rx, e);
        rx->synced = true; /* the collector, not this assembler, waits for the pause */
        return r;
    }
    return accept(rx, tg->buf, tg->len, tg->end_t, tg->idle_before_ns);
}

hal_time_us_t fdl_rx_poll(fdl_rx_t *rx, hal_time_us_t now)
{
    if (!rx->have_last) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    hal_time_us_t forget_at = rx->last_char_t + FDL_RX_FORGET_US;
    if (!hal_time_reached(now, forget_at)) {
        return forget_at;
    }
    rx->have_last = false;
    return now + HAL_TIME_NO_DEADLINE_US;
}

#if FDL_RX_CHAR_INPUT
fdl_rx_result_t fdl_rx_char(fdl_rx_t *rx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    /* The collector judges the same way (fdl_gap.h); fdl_rx_poll() clears have_last. */
    fdl_gap_t gap = fdl_gap_judge(rx->have_last, hal_time_diff(t, rx->last_char_t), rx->strict,
                                  rx->char_ns,
                                  fdl_gap_pause_us(rx->strict, rx->char_ns, rx->relaxed_gap_us),
                                  rx->relaxed_resync_us);
    rx->have_last = true;
    rx->last_char_t = t;

    if (rx->collecting && gap.pause) {
        (void)fail(rx, FDL_RX_ERR_GAP);
        /* the character after the pause may begin the next telegram: fall through */
    }
    if ((flags & (HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR | HAL_UART_RX_OVERRUN_ERR)) !=
        0u) {
        return fail(rx, FDL_RX_ERR_CHAR);
    }

    if (!rx->collecting) {
        if (!rx->synced && !gap.resync) {
            return FDL_RX_NOTHING; /* still inside garbage: ignore until the line pauses */
        }
        uint16_t need = length_for_sd(byte);
        if (need == UINT16_MAX) {
            return fail(rx, FDL_RX_ERR_SD);
        }
        rx->collecting = true;
        rx->idle_before_pending_ns = gap.idle_ns;
        rx->buf[0] = byte;
        rx->len = 1;
        rx->expected = need;
        if (need == 1u) {
            return complete(rx, t);
        }
        return FDL_RX_NOTHING;
    }

    rx->buf[rx->len++] = byte;
    if (rx->buf[0] == FDL_SD2 && rx->expected == 0u) {
        if (rx->len == 3u) {
            uint8_t le = rx->buf[1];
            if (le != rx->buf[2] || le < FDL_LE_MIN || le > FDL_LE_MAX) {
                return fail(rx, FDL_RX_ERR_LE);
            }
        } else if (rx->len == 4u) {
            if (byte != FDL_SD2) {
                return fail(rx, FDL_RX_ERR_SD_REPEAT);
            }
            rx->expected = (uint16_t)(rx->buf[1] + FDL_SD2_OVERHEAD);
        }
        return FDL_RX_NOTHING;
    }
    if (rx->len >= rx->expected) {
        return complete(rx, t);
    }
    return FDL_RX_NOTHING;
}
#endif
