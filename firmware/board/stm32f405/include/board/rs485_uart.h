/* RS-485 UART driver for an STM32F4 USART: the hal_uart_t of the board.
 *
 * Character format: 9-bit word (M=1) with even parity (PCE=1, PS=0) = 8 data bits + parity,
 * 1 start and 1 stop bit: the 11-bit PROFIBUS character. Receive is by interrupt (RXNEIE, PEIE,
 * EIE): the interrupt only stores every character with its own error flags (PE, FE, ORE, read
 * from SR before DR) and the time it took it, from the board's µs time base, in a ring, and
 * calls rx_pending(); rs485_uart_rx_drain() hands them to rx() in a context of lower priority.
 * So the USART interrupt never runs protocol code and need never be masked: characters are not
 * lost and a reply does not stall while the main loop works on the card (see board.h). Transmit
 * copies the frame, waits until not_before (see transmit in the .c: bounded spin, the reply
 * path's only wait), raises the driver-enable pin, switches the receiver off (so the station
 * never hears itself), and feeds DR from TXE interrupts; TC drops DE and switches the receiver
 * back on.
 *
 * The driver touches only the register blocks it was given, so tests run it against fakes. */
#ifndef BOARD_RS485_UART_H
#define BOARD_RS485_UART_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "hal/hal_uart.h"

/* Longest frame the core transmits (SD2 with 244 DU octets + 11). */
#define RS485_TX_MAX 256u
/* transmit(): a not_before further ahead than this is a clock mix-up; the frame goes out now.
 * 255 bit times (largest min TSDR) at 9600 bit/s are 26.6 ms. */
#define RS485_MAX_WAIT_US 30000u
/* Characters the interrupt can hold for rx_drain (a power of two): one longest telegram and
 * then some, i.e. 213 µs of a stalled drain at 12 Mbit/s, 1.9 ms at 1.5 Mbit/s. More is an
 * overflow: the next character stored carries HAL_UART_RX_OVERRUN_ERR, so the telegram it
 * belongs to is dropped like one after a hardware overrun. */
#define RS485_RX_RING 256u
_Static_assert((RS485_RX_RING & (RS485_RX_RING - 1u)) == 0u,
               "the free-running 32-bit ring indices need a power-of-two size");

typedef void (*rs485_rx_fn)(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t);
typedef hal_time_us_t (*rs485_now_fn)(void);
typedef void (*rs485_pending_fn)(void *ctx);

typedef struct rs485_uart_cfg {
    usart_regs_t *regs;
    gpio_regs_t *de_port; /* driver-enable pin, active high (NULL: none) */
    uint8_t de_pin;
    uint32_t pclk_hz;     /* the USART's bus clock */
    uint32_t baud;        /* initial rate */
    rs485_now_fn now;
    rs485_rx_fn rx;        /* called by rs485_uart_rx_drain, per character, in order */
    void *rx_ctx;
    rs485_pending_fn rx_pending; /* called by the interrupt after storing (NULL: none) */
} rs485_uart_cfg_t;

typedef struct rs485_rx_entry {
    hal_time_us_t t;
    uint8_t byte;
    uint8_t flags;
} rs485_rx_entry_t;

typedef struct rs485_uart {
    rs485_uart_cfg_t cfg;
    uint32_t baud;
    uint8_t tx_buf[RS485_TX_MAX];
    volatile uint16_t tx_len;
    volatile uint16_t tx_pos;
    volatile bool tx_busy;
    /* Single producer (the interrupt writes head), single consumer (rx_drain writes tail). */
    rs485_rx_entry_t rx_ring[RS485_RX_RING];
    _Atomic uint32_t rx_head;
    _Atomic uint32_t rx_tail;
    bool rx_lost; /* interrupt side: the ring was full, mark the next character */
    /* Counters (read by tests and the debugger). */
    uint32_t rx_chars;
    uint32_t rx_parity_errors;
    uint32_t rx_framing_errors;
    uint32_t rx_overruns;
    uint32_t rx_ring_overflows; /* characters the ring could not hold */
    uint32_t tx_frames;
    uint32_t tx_refused;     /* transmit while a frame was still going out, or too long */
    uint32_t tx_stale;       /* transmit refused: characters after the request were waiting */
    uint32_t tx_clock_mixups; /* not_before too far ahead */
    uint32_t baud_refused;
} rs485_uart_t;

/* BRR value for a rate, and whether OVER8 is needed. Returns false when the rate cannot be made
 * within 0.3 % (PROFIBUS tolerance) from pclk, e.g. 12 Mbit/s from 84 MHz (needs 96 MHz). */
bool rs485_uart_brr(uint32_t pclk_hz, uint32_t baud, uint32_t *brr, bool *over8);

/* Configures the USART (9 bit + even parity, RX interrupts on, DE low). Returns 0 or -1 when
 * the initial rate cannot be made. The NVIC is the caller's business. */
int rs485_uart_init(rs485_uart_t *u, const rs485_uart_cfg_t *cfg);
hal_uart_t rs485_uart_hal(rs485_uart_t *u);
/* The USART interrupt: receive with flags into the ring, and the transmit steps. */
void rs485_uart_isr(rs485_uart_t *u);
/* Hands the stored characters to rx(); returns how many. Never concurrently with itself. */
unsigned rs485_uart_rx_drain(rs485_uart_t *u);
/* Refused (-1) while a frame is going out: the interrupt owns CR1 then. */
int rs485_uart_set_baud(rs485_uart_t *u, uint32_t baud);
/* Refused (-1) while a frame is going out, and when characters that came after the request
 * are still waiting in the ring (a late reply would collide with them). */
int rs485_uart_transmit(rs485_uart_t *u, const uint8_t *frame, size_t len,
                        hal_time_us_t not_before);

#endif
