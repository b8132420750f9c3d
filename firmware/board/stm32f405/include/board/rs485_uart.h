/* RS-485 UART driver for an STM32F4 USART: the hal_uart_t of the board.
 *
 * Character format: 9-bit word (M=1) with even parity (PCE=1, PS=0) = 8 data bits + parity,
 * 1 start and 1 stop bit: the 11-bit PROFIBUS character.
 *
 * Receive works like a DP ASIC: the USART interrupt assembles whole telegrams itself with the
 * core's collector (dp_slave/fdl_collect.h), one character per interrupt, taking its time from
 * a free-running 32-bit microsecond counter (TIM2: one register read, no clock arithmetic). A
 * character inside a telegram costs the collector's fast path; the length comes from SD/LE, so
 * the telegram is complete with its last character, not after an idle time. Finished telegrams
 * (and what the collector dropped, as errors) go into a queue with their buffer, rx_pending()
 * is called, and rs485_uart_rx_drain() hands them to rx() in a context of lower priority, which
 * releases the buffer after rx() returns. So the USART interrupt never runs the protocol and
 * need never be masked: a main loop holding the core off loses nothing until the buffers run
 * out (then the telegram is reported as an overrun).
 *
 * Transmit sends the frame in place (no copy: the core's reply buffers stay unchanged until it
 * is handed the next telegram, hal_uart.h), waits until not_before (bounded spin, the reply
 * path's only wait), raises the driver-enable pin, switches the receiver off (so the station
 * never hears itself), and feeds DR from TXE interrupts; TC drops DE and switches the receiver
 * back on.
 *
 * The driver touches only the register blocks and counter it was given, so tests run it against
 * fakes. */
#ifndef BOARD_RS485_UART_H
#define BOARD_RS485_UART_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "dp_slave/fdl_collect.h"
#include "hal/hal_uart.h"

/* Longest frame the core transmits (SD2 with 244 DU octets + 11). */
#define RS485_TX_MAX 256u
/* transmit(): a not_before further ahead than this is a clock mix-up; the frame goes out now.
 * 255 bit times (largest min TSDR) at 9600 bit/s are 26.6 ms. */
#define RS485_MAX_WAIT_US 30000u
/* Telegram buffers: one being filled and two waiting for the core, i.e. the core may be held
 * off for two telegrams (a main-loop pass is far shorter than two 12 Mbit/s SD1 telegrams of
 * other stations plus their TSYN). A third completed telegram finds no buffer and is reported
 * as an overrun. */
#define RS485_RX_BUFFERS 3u
/* Queue entries (a power of two): every buffer plus collector errors in between. */
#define RS485_RX_QUEUE 8u
_Static_assert((RS485_RX_QUEUE & (RS485_RX_QUEUE - 1u)) == 0u,
               "the free-running 32-bit queue indices need a power-of-two size");

typedef void (*rs485_rx_fn)(void *ctx, const fdl_rx_telegram_t *tg);
typedef void (*rs485_pending_fn)(void *ctx);

typedef struct rs485_uart_cfg {
    usart_regs_t *regs;
    gpio_regs_t *de_port; /* driver-enable pin, active high (NULL: none) */
    uint8_t de_pin;
    uint32_t pclk_hz;     /* the USART's bus clock */
    uint32_t baud;        /* initial rate */
    bool strict_timing;   /* fdl_rx.h: exact timestamps (a real line) or relaxed (QEMU, PTY) */
    const volatile uint32_t *clock_us; /* free-running microsecond counter (TIM2 CNT) */
    rs485_rx_fn rx;        /* called by rs485_uart_rx_drain, per telegram or error, in order */
    void *rx_ctx;
    rs485_pending_fn rx_pending; /* called by the interrupt after queuing (NULL: none) */
} rs485_uart_cfg_t;

typedef struct rs485_uart {
    rs485_uart_cfg_t cfg;
    uint32_t baud;
    const uint8_t *tx_frame;
    volatile uint16_t tx_len;
    volatile uint16_t tx_pos;
    volatile bool tx_busy;
    /* Interrupt side: the collector and the buffer it fills. */
    fdl_collect_t collect;
    uint8_t rx_buf[RS485_RX_BUFFERS][FDL_FRAME_MAX];
    volatile bool rx_buf_busy[RS485_RX_BUFFERS]; /* set by the interrupt, cleared by rx_drain */
    /* Single producer (the interrupt writes head), single consumer (rx_drain writes tail). */
    fdl_rx_telegram_t rx_queue[RS485_RX_QUEUE];
    _Atomic uint32_t rx_head;
    _Atomic uint32_t rx_tail;
    /* Counters (read by tests and the debugger). */
    uint32_t rx_chars;
    uint32_t rx_parity_errors;
    uint32_t rx_framing_errors;
    uint32_t rx_overruns;
    uint32_t rx_telegrams;
    uint32_t rx_buffer_overflows; /* telegrams dropped because every buffer was waiting */
    uint32_t tx_frames;
    uint32_t tx_refused;     /* transmit while a frame was still going out, or too long */
    uint32_t tx_stale;       /* transmit refused: telegrams after the request were waiting */
    uint32_t tx_clock_mixups; /* not_before too far ahead */
    uint32_t baud_refused;
} rs485_uart_t;

/* The interrupt's paths other than an error-free received character, out of line. */
void rs485_uart_isr_other(rs485_uart_t *u, uint32_t sr);
void rs485_uart_rx_hand_over(rs485_uart_t *u, unsigned collected);

/* The USART interrupt. Inline, so an error-free character inside a telegram costs the status
 * and data reads, one counter read and the collector's fast path, without a call. */
static inline void rs485_uart_isr(rs485_uart_t *u)
{
    usart_regs_t *r = u->cfg.regs;
    uint32_t sr = r->SR;
    if ((sr & (USART_SR_RXNE | USART_SR_PE | USART_SR_FE | USART_SR_ORE)) != USART_SR_RXNE) {
        rs485_uart_isr_other(u, sr); /* an error flag, or no character: transmit */
        return;
    }
    uint8_t byte = (uint8_t)r->DR; /* SR then DR; bit 8 is the parity bit */
    unsigned collected = fdl_collect_char(&u->collect, byte, *u->cfg.clock_us);
    if (collected != 0u) {
        rs485_uart_rx_hand_over(u, collected);
    }
}

/* Spins until the counter has reached t (min TSDR before a reply). */
void rs485_wait_until(const volatile uint32_t *clock_us, hal_time_us_t t);

/* BRR value for a rate, and whether OVER8 is needed. Returns false when the rate cannot be made
 * within 0.3 % (PROFIBUS tolerance) from pclk, e.g. 12 Mbit/s from 84 MHz (needs 96 MHz). */
bool rs485_uart_brr(uint32_t pclk_hz, uint32_t baud, uint32_t *brr, bool *over8);

/* Configures the USART (9 bit + even parity, RX interrupts on, DE low). Returns 0 or -1 when
 * the initial rate cannot be made. The NVIC is the caller's business. */
int rs485_uart_init(rs485_uart_t *u, const rs485_uart_cfg_t *cfg);
hal_uart_t rs485_uart_hal(rs485_uart_t *u);
/* Hands the queued telegrams and errors to rx(); returns how many. Never concurrently with
 * itself. */
unsigned rs485_uart_rx_drain(rs485_uart_t *u);
/* Refused (-1) while a frame is going out: the interrupt owns CR1 then. */
int rs485_uart_set_baud(rs485_uart_t *u, uint32_t baud);
/* Refused (-1) while a frame is going out, and when a telegram that came after the request is
 * waiting or being received (a late reply would collide with it). frame must stay unchanged
 * until the frame has gone out. */
int rs485_uart_transmit(rs485_uart_t *u, const uint8_t *frame, size_t len,
                        hal_time_us_t not_before);

#endif
