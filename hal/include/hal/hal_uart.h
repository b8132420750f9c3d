/* The RS-485 UART as the PROFIBUS core needs it.
 *
 * Receive direction: the backend (interrupt handler, host thread, simulated bus) pushes every
 * character into the station with dp_slave_rx_char() together with its error flags and the time
 * its stop bit ended. The backend never delivers the station's own transmitted characters (an
 * RS-485 transceiver with receiver enabled during transmit must have them filtered out).
 *
 * Transmit direction: the core calls transmit() with a complete frame and the earliest instant
 * the first start bit may go out (end of the request + min TSDR). The backend sends the frame
 * without gaps between characters (PROFIBUS forbids idle inside a telegram) and drives the
 * RS-485 driver-enable line around it.
 *
 * Character format is fixed by PROFIBUS: 1 start, 8 data LSB first, even parity, 1 stop. */
#ifndef HAL_UART_H
#define HAL_UART_H

#include <stddef.h>
#include <stdint.h>

#include "hal/hal_time.h"

/* Per-character error flags, as a UART status register reports them. */
#define HAL_UART_RX_PARITY_ERR  0x01u
#define HAL_UART_RX_FRAMING_ERR 0x02u
#define HAL_UART_RX_OVERRUN_ERR 0x04u

/* The ten PROFIBUS rates, in the order the baud search walks them (highest first). */
#define HAL_UART_NUM_BAUDS 10u
extern const uint32_t hal_uart_bauds[HAL_UART_NUM_BAUDS];
/* The highest rate: where a station starts listening before it knows the bus's rate. */
#define HAL_UART_BAUD_MAX 12000000u

/* Start, 8 data, even parity, stop. */
#define HAL_UART_CHAR_BITS 11u
#define HAL_NS_PER_S 1000000000ull
#define HAL_US_PER_S 1000000ull

typedef struct hal_uart_ops {
    /* Switch the receiver and transmitter to a new rate. Returns 0 or a negative error. Called
     * by the baud search, so it must be quick and must not lose the character in progress. */
    int (*set_baud)(void *ctx, uint32_t baud);
    /* Queue a complete frame; the first start bit not before not_before. Returns 0 on success.
     * The buffer is only valid during the call. */
    int (*transmit)(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before);
} hal_uart_ops_t;

typedef struct hal_uart {
    const hal_uart_ops_t *ops;
    void *ctx;
} hal_uart_t;

/* Duration of one 11-bit character in nanoseconds at the given rate. */
static inline uint32_t hal_uart_char_ns(uint32_t baud)
{
    return (uint32_t)((HAL_UART_CHAR_BITS * HAL_NS_PER_S + baud / 2u) / baud);
}

/* n bit times in microseconds, rounded up. */
static inline uint32_t hal_uart_bits_us(uint32_t baud, uint32_t bits)
{
    return (uint32_t)(((uint64_t)bits * HAL_US_PER_S + baud - 1u) / baud);
}

#endif
