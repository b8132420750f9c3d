/* Between the two halves of the tty backend (private to sim_hal): the port (tty_port.c) tells
 * the runner it is attached to about baud changes and transmitted frames, and the runner
 * (tty_runner.c) asks the port whether a received character is its own echo. */
#ifndef SIM_HAL_TTY_INTERNAL_H
#define SIM_HAL_TTY_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "sim_hal/tty_port.h"

/* The port's rate changed: the runner's frame assembler for the tap follows it. */
void tty_runner_baud_changed(tty_port_t *p);
/* A frame went out at t_ns (host_clock_mono_ns): the tap sees it. */
void tty_runner_transmitted(tty_port_t *p, uint64_t t_ns, const uint8_t *frame, size_t len);
/* A write failed inside a station callback: the run ends at the next loop turn. */
void tty_runner_tx_failed(tty_port_t *p, const char *why);
/* True when this character is the expected echo of our own transmission and must not reach
 * the station. */
bool tty_port_echo_swallow(tty_port_t *p, uint8_t b, uint8_t f, hal_time_us_t t);

#endif
