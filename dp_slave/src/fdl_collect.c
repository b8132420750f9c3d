#include "dp_slave/fdl_collect.h"

#include "dp_slave/fdl_gap.h"
#include "hal/hal_uart.h"

static void set_thresholds(fdl_collect_t *c)
{
    c->pause_us = fdl_gap_pause_us(c->strict, c->char_ns, c->relaxed_gap_us);
}

void fdl_collect_init(fdl_collect_t *c, uint8_t *buf, uint32_t baud, bool strict)
{
    *c = (fdl_collect_t){0};
    c->buf = buf;
    c->strict = strict;
    c->synced = true;
    c->relaxed_gap_us = FDL_RX_RELAXED_GAP_US_DEFAULT;
    c->relaxed_resync_us = FDL_RX_RELAXED_RESYNC_US_DEFAULT;
    fdl_collect_set_baud(c, baud);
}

void fdl_collect_set_baud(fdl_collect_t *c, uint32_t baud)
{
    c->char_ns = hal_uart_char_ns(baud != 0u ? baud : HAL_UART_BAUD_MAX);
    c->len = 0;
    c->expected = 0;
    c->synced = true;
    set_thresholds(c);
}

static unsigned drop(fdl_collect_t *c, fdl_rx_error_t e, hal_time_us_t t)
{
    c->len = 0;
    c->synced = false; /* wait for a pause before trusting a start delimiter again */
    c->error = e;
    c->error_t = t;
    return FDL_COLLECT_ERROR;
}

/* buf is c->buf, passed so that it is not read again after an octet was stored through it */
static unsigned complete(fdl_collect_t *c, const uint8_t *buf, hal_time_us_t t)
{
    /* DA..DU: the running sum without the delimiter (and LE, LEr, SD2 again), FCS and ED. */
    uint16_t n = c->len;
    uint32_t sum = c->sum;
    if (n >= FDL_SD1_LEN) {
        sum -= (uint32_t)buf[0] + buf[n - 2u] + buf[n - 1u];
        if (buf[0] == FDL_SD2) {
            sum -= (uint32_t)buf[1] + buf[2] + buf[3];
        }
    }
    c->telegram = (fdl_rx_telegram_t){.buf = buf, .len = n, .error = FDL_RX_OK, .end_t = t,
                                      .idle_before_ns = c->idle_before_ns,
                                      .sum_known = true, .sum = (uint8_t)sum};
    c->len = 0;
    c->synced = true;
    return FDL_COLLECT_TELEGRAM;
}

unsigned fdl_collect_step(fdl_collect_t *c, hal_time_us_t t)
{
    const uint8_t *b = c->buf;
    if (b[0] == FDL_SD2 && c->len == 3u) {
        if (b[1] != b[2] || b[1] < FDL_LE_MIN || b[1] > FDL_LE_MAX) {
            return drop(c, FDL_RX_ERR_LE, t);
        }
        c->expected = 4u;
        return 0u;
    }
    if (b[0] == FDL_SD2 && c->len == 4u) {
        if (b[3] != FDL_SD2) {
            return drop(c, FDL_RX_ERR_SD_REPEAT, t);
        }
        c->expected = (uint16_t)(b[1] + FDL_SD2_OVERHEAD);
        return 0u;
    }
    return complete(c, b, t);
}

/* Octets up to the slow path's next look; SD2 first stops at LE/LEr. 0: not a start delimiter. */
static uint16_t first_look(uint8_t sd)
{
    switch (sd) {
    case FDL_SD1: return FDL_SD1_LEN;
    case FDL_SD3: return FDL_SD3_LEN;
    case FDL_SD4: return FDL_SD4_LEN;
    case FDL_SC: return 1u;
    case FDL_SD2: return 3u;
    default: return 0u;
    }
}

unsigned fdl_collect_slow(fdl_collect_t *c, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    /* The gap, judged as fdl_rx_char judges it (fdl_gap.h). A gap fdl_rx_poll() would have
     * forgotten is an idle line of unknown length; so is a difference below -FDL_RX_FORGET_US,
     * which on a monotonic counter can only be 2^31 µs or more of silence, wrapped. A smaller
     * negative difference is clock jitter, which fdl_gap_judge() handles. */
    int32_t dt = hal_time_diff(t, c->last_t);
    bool known = c->have_last && /* -FDL_RX_FORGET_US < dt < FDL_RX_FORGET_US, in one compare */
                 (uint32_t)dt + (FDL_RX_FORGET_US - 1u) < 2u * FDL_RX_FORGET_US - 1u;
    fdl_gap_t gap = fdl_gap_judge(known, dt, c->strict, c->char_ns, c->pause_us,
                                  c->relaxed_resync_us);
    if (!known) {
        c->have_last = true; /* known implies it already: no store on the usual path (ISR) */
    }
    c->last_t = t;

    unsigned out = 0;
    if (c->len != 0u && gap.pause) {
        out = drop(c, FDL_RX_ERR_GAP, t); /* the character may start the next telegram */
    }
    if ((flags & (HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR | HAL_UART_RX_OVERRUN_ERR)) !=
        0u) {
        return drop(c, FDL_RX_ERR_CHAR, t);
    }
    if (c->len != 0u) { /* inside a telegram, no pause: a plain character after all */
        c->sum += byte;
        c->buf[c->len++] = byte;
        return c->len == c->expected ? fdl_collect_step(c, t) : 0u;
    }
    if (!c->synced && !gap.resync) {
        return out; /* still inside garbage: ignore until the line pauses */
    }
    uint16_t look = first_look(byte);
    if (look == 0u) {
        return drop(c, FDL_RX_ERR_SD, t);
    }
    uint8_t *buf = c->buf;
    buf[0] = byte;
    c->sum = byte;
    c->len = 1;
    c->expected = look;
    c->idle_before_ns = gap.idle_ns;
    return look == 1u ? (out | complete(c, buf, t)) : out;
}
