/* Shared helpers of the unit tests: a fake UART that records what the station transmits, an
 * event recorder, a recording LED backend, and a "line" that feeds request characters to a
 * station at exact character times (strict timing), with a chosen idle time before each
 * request. Time is kept in nanoseconds on the line and handed to the station as the µs
 * instant the stop bit of each character ended (rounded down, as a µs timer would show it). */
#ifndef TESTS_UNIT_UNIT_RIG_H
#define TESTS_UNIT_UNIT_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "dp_slave/dp_slave.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_led.h"
#include "hal/hal_time.h"
#include "hal/hal_uart.h"

/* ---- fake UART ---------------------------------------------------------------------------- */

#define FAKE_UART_MAX_BAUDS 64u

typedef struct fake_uart {
    unsigned tx_count;
    uint8_t last[FDL_FRAME_MAX + 1u];
    size_t last_len;
    hal_time_us_t last_not_before;
    unsigned baud_count; /* rates taken */
    uint32_t bauds[FAKE_UART_MAX_BAUDS];
    uint32_t max_baud;   /* 0: every rate; else faster rates are refused, as a real UART's */
    unsigned refused;
} fake_uart_t;

static inline int fake_uart_set_baud(void *ctx, uint32_t baud)
{
    fake_uart_t *u = ctx;
    if (u->max_baud != 0u && baud > u->max_baud) {
        u->refused++;
        return -1;
    }
    if (u->baud_count < FAKE_UART_MAX_BAUDS) {
        u->bauds[u->baud_count] = baud;
    }
    u->baud_count++;
    return 0;
}

static inline int fake_uart_transmit(void *ctx, const uint8_t *frame, size_t len,
                                     hal_time_us_t not_before)
{
    fake_uart_t *u = ctx;
    u->tx_count++;
    u->last_len = len <= sizeof u->last ? len : sizeof u->last;
    memcpy(u->last, frame, u->last_len);
    u->last_not_before = not_before;
    return 0;
}

static const hal_uart_ops_t fake_uart_ops = {
    .set_baud = fake_uart_set_baud,
    .transmit = fake_uart_transmit,
};

static inline hal_uart_t fake_uart_hal(fake_uart_t *u)
{
    return (hal_uart_t){.ops = &fake_uart_ops, .ctx = u};
}

/* ---- recording LEDs ----------------------------------------------------------------------- */

#define LED_LOG_MAX 64u

typedef struct led_log {
    unsigned n;
    hal_led_id_t id[LED_LOG_MAX];
    hal_led_mode_t mode[LED_LOG_MAX];
    hal_led_mode_t now[HAL_LED_COUNT];
} led_log_t;

static inline void led_log_set(void *ctx, hal_led_id_t led, hal_led_mode_t mode)
{
    led_log_t *l = ctx;
    if (l->n < LED_LOG_MAX) {
        l->id[l->n] = led;
        l->mode[l->n] = mode;
    }
    l->n++;
    l->now[led] = mode;
}

static const hal_led_ops_t led_log_ops = {.set = led_log_set};

/* ---- event recorder ----------------------------------------------------------------------- */

#define EV_LOG_MAX 512u

typedef struct ev_log {
    unsigned n;
    dp_event_t ev[EV_LOG_MAX];
} ev_log_t;

static inline void ev_log_add(ev_log_t *l, const dp_event_t *ev)
{
    if (l->n < EV_LOG_MAX) {
        l->ev[l->n] = *ev;
    }
    l->n++;
}

static inline unsigned ev_count(const ev_log_t *l, dp_event_type_t type)
{
    unsigned c = 0;
    for (unsigned i = 0; i < l->n && i < EV_LOG_MAX; i++) {
        if (l->ev[i].type == type) {
            c++;
        }
    }
    return c;
}

/* Last event of a type, NULL if none. */
static inline const dp_event_t *ev_last(const ev_log_t *l, dp_event_type_t type)
{
    for (unsigned i = l->n < EV_LOG_MAX ? l->n : EV_LOG_MAX; i > 0; i--) {
        if (l->ev[i - 1u].type == type) {
            return &l->ev[i - 1u];
        }
    }
    return NULL;
}

/* ---- the line ----------------------------------------------------------------------------- */

typedef void (*line_rx_fn)(void *station, uint8_t byte, uint8_t flags, hal_time_us_t t);

typedef struct line {
    uint64_t now_ns; /* end of the last activity on the line */
    uint32_t baud;
    line_rx_fn rx;
    void *station;
    fake_uart_t *uart;          /* to notice replies; may be NULL */
    hal_time_us_t req_end_us;   /* stop bit of the last request character, as the station saw it */
    hal_time_us_t req_start_us; /* stop bit of the first request character */
} line_t;

#define LINE_T0_NS 1000000000ull /* start at t = 1 s */
#define LINE_IDLE_BITS 100u      /* default idle before a request: comfortably above TSYN */

static inline hal_time_us_t line_us(uint64_t ns) { return (hal_time_us_t)(ns / 1000u); }

static inline void line_init(line_t *l, uint32_t baud, line_rx_fn rx, void *station,
                             fake_uart_t *uart)
{
    *l = (line_t){.now_ns = LINE_T0_NS, .baud = baud, .rx = rx, .station = station,
                  .uart = uart};
}

static inline hal_time_us_t line_now_us(const line_t *l) { return line_us(l->now_ns); }

static inline void line_idle_bits(line_t *l, uint32_t bits)
{
    l->now_ns += ((uint64_t)bits * 1000000000ull + l->baud - 1u) / l->baud;
}

static inline void line_wait_us(line_t *l, uint64_t us) { l->now_ns += us * 1000u; }

/* Puts bytes on the line back to back after idle_bits of idle; flags[i] (or 0) per char. */
static inline void line_put(line_t *l, const uint8_t *p, size_t n, const uint8_t *flags,
                            uint32_t idle_bits)
{
    uint32_t char_ns = hal_uart_char_ns(l->baud);
    line_idle_bits(l, idle_bits);
    for (size_t i = 0; i < n; i++) {
        l->now_ns += char_ns;
        if (i == 0u) {
            l->req_start_us = line_us(l->now_ns);
        }
        l->rx(l->station, p[i], flags != NULL ? flags[i] : 0u, line_us(l->now_ns));
    }
    l->req_end_us = line_us(l->now_ns);
}

/* A request after idle_bits of idle. Returns true if the station transmitted a reply; the line
 * time then moves past the reply (not before not_before, then the reply's characters). */
static inline bool line_request_idle(line_t *l, const uint8_t *p, size_t n, uint32_t idle_bits)
{
    unsigned before = l->uart != NULL ? l->uart->tx_count : 0u;
    line_put(l, p, n, NULL, idle_bits);
    if (l->uart == NULL || l->uart->tx_count == before) {
        return false;
    }
    uint64_t start_ns = (uint64_t)l->uart->last_not_before * 1000u;
    if (start_ns < l->now_ns) {
        start_ns = l->now_ns;
    }
    l->now_ns = start_ns + (uint64_t)l->uart->last_len * hal_uart_char_ns(l->baud);
    return true;
}

static inline bool line_request(line_t *l, const uint8_t *p, size_t n)
{
    return line_request_idle(l, p, n, LINE_IDLE_BITS);
}

/* ---- a master's frame-control bookkeeping (§A1.5) ------------------------------------------ */

typedef struct tmaster {
    uint8_t addr;
    bool started;
    uint8_t fcb;
} tmaster_t;

/* Next SRD/SDA frame control: FCV=0/FCB=1 first, then FCV=1 with the FCB toggled. */
static inline uint8_t tm_fc(tmaster_t *m, uint8_t code)
{
    if (!m->started) {
        m->started = true;
        m->fcb = 1u;
        return (uint8_t)(FDL_FC_REQUEST | FDL_FC_FCB | code);
    }
    m->fcb ^= 1u;
    return (uint8_t)(FDL_FC_REQUEST | FDL_FC_FCV | (m->fcb ? FDL_FC_FCB : 0u) | code);
}

/* The frame control of the previous frame again (a retry). */
static inline uint8_t tm_fc_retry(const tmaster_t *m, uint8_t code)
{
    return (uint8_t)(FDL_FC_REQUEST | FDL_FC_FCV | (m->fcb ? FDL_FC_FCB : 0u) | code);
}

/* Request builders on top of fdl_encode (checked against protocol.md §A1.6 in test_fdl_rx). */
static inline size_t mk_sap_req(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, uint8_t dsap,
                                const uint8_t *data, size_t len)
{
    return fdl_encode(out, da, sa, fc, true, dsap, DP_SAP_MASTER, data, len);
}

static inline size_t mk_dx_req(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc,
                               const uint8_t *data, size_t len)
{
    return fdl_encode(out, da, sa, fc, false, 0, 0, data, len);
}

/* Set_Prm DU: 7 standard octets, then optional extra octets (DP-V1 status + user prm). */
static inline size_t mk_prm(uint8_t *out, uint8_t status, uint8_t f1, uint8_t f2, uint8_t tsdr,
                            uint16_t ident, uint8_t group, const uint8_t *extra, size_t extra_len)
{
    out[0] = status;
    out[1] = f1;
    out[2] = f2;
    out[3] = tsdr;
    out[4] = (uint8_t)(ident >> 8);
    out[5] = (uint8_t)(ident & 0xFFu);
    out[6] = group;
    if (extra_len > 0u) {
        memcpy(&out[7], extra, extra_len);
    }
    return 7u + extra_len;
}

/* DU of the station's last reply (after any SAP octets); len 0 and NULL for SC or no data. */
static inline const uint8_t *reply_du(const fake_uart_t *u, size_t *len, fdl_msg_t *m)
{
    *len = 0;
    if (u->last_len < FDL_SD1_LEN || fdl_parse(u->last, u->last_len, m) != FDL_PARSE_OK) {
        return NULL;
    }
    *len = m->data_len;
    return m->data;
}

#endif
