/* How the host programs run PROFIBUS stations (the card, the master, test probes) on a medium.
 *
 * A station is two callbacks: every received character, and a poll that runs its timers and
 * returns its next deadline. A medium (the in-memory bus with simulated time, or real ttys/PTYs
 * with wall-clock time) hands each attached station a hal_uart_t for transmitting and calls the
 * station back. The same station code therefore runs in a test at simulated time, in `dfp-sim
 * demo` on the in-memory bus, and in `dfp-sim slave` against a PLC. */
#ifndef SIM_HAL_SIM_STATION_H
#define SIM_HAL_SIM_STATION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_time.h"
#include "hal/hal_uart.h"

typedef struct sim_station {
    void *ctx;
    void (*rx_char)(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t);
    hal_time_us_t (*poll)(void *ctx, hal_time_us_t now);
} sim_station_t;

/* Called for every frame a station puts on the medium (and, on a tty, every frame received),
 * for captures and logs. t_start_ns counts from the medium's start. */
typedef void (*sim_frame_tap_t)(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len,
                                bool from_local_station, uint32_t baud);

#endif
