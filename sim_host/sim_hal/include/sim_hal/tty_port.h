/* The HAL UART on a Linux tty: a USB/RS-485 adapter, a native UART, or one end of a PTY pair.
 *
 * Unlike the in-memory bus, time here is the wall clock (tty_now_us()), and the kernel delivers
 * received bytes in chunks, so every byte of one read() carries the time that chunk arrived.
 * Character format is 8E1 as PROFIBUS requires; where the driver cannot do even parity (a PTY
 * silently clears PARENB) the port still works and parity_ok says so.
 *
 * One thread runs everything: tty_runner_run_until() waits on all ports with poll(), hands
 * received characters to each port's station and calls the stations' poll functions at their
 * deadlines (a deadline at most 100 us away is waited for by polling without blocking, since a
 * timed sleep returns tens of microseconds late). Other descriptors (a CAN socket) and port-less timers can join the same loop
 * (tty_runner_add_fd, tty_runner_add_timer). transmit() is called from inside those callbacks and blocks until its not_before
 * instant, so a frame always leaves in one piece.
 *
 * Structs are caller-owned; nothing is allocated. */
#ifndef SIM_HAL_TTY_PORT_H
#define SIM_HAL_TTY_PORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_rx.h"
#include "hal/hal_time.h"
#include "hal/hal_uart.h"
#include "sim_hal/sim_station.h"

#define TTY_RUNNER_MAX_PORTS 8u
/* Bytes of our own transmissions we may still expect to hear back (echo suppression). */
#define TTY_ECHO_MAX 1024u
/* How long after a frame's last byte its echo may still arrive (USB adapters batch for ms). */
#define TTY_ECHO_SLACK_US 50000u
/* A transmit gives up when the device accepts nothing for this long. */
#define TTY_WRITE_TIMEOUT_MS 1000

typedef struct tty_runner tty_runner_t;

typedef struct tty_port {
    int fd;
    uint32_t baud;
    char name[64]; /* device path, or "fd N", for error messages */
    /* What the driver accepted (informational; none of them is required). */
    bool parity_ok;      /* even parity stuck; false on a PTY */
    bool parmrk;         /* error characters arrive marked 0xFF 0x00 X, a data 0xFF as 0xFF 0xFF */
    bool rs485_ok;       /* TIOCSRS485 accepted */
    bool low_latency_ok; /* ASYNC_LOW_LATENCY accepted */
    /* Set by the caller after opening, for adapters that hear their own transmissions. */
    bool echo_suppress;
    /* Internal state. */
    uint8_t mark_state; /* position inside a 0xFF escape, kept across reads */
    uint8_t echo[TTY_ECHO_MAX];
    uint16_t echo_head;
    uint16_t echo_len;
    hal_time_us_t echo_expire;
    tty_runner_t *runner;
    uint8_t slot;
    /* Counters. */
    uint64_t frames_sent;
    uint64_t chars_received;
    uint64_t echo_dropped;
    uint64_t char_errors;
} tty_port_t;

/* Open a device and configure it: raw, 8E1, non-blocking, at baud; RS-485 mode and low-latency
 * where the driver has them. Returns 0, or -1 with a message in err (e.g. "cannot open
 * /dev/ttyUSB9: No such file or directory"). */
int tty_port_open(tty_port_t *p, const char *path, uint32_t baud, char *err, size_t errlen);
/* The same for an already open descriptor (e.g. a PTY master from posix_openpt). On success the
 * port owns fd and tty_port_close() closes it; on failure the caller still owns it. */
int tty_port_open_fd(tty_port_t *p, int fd, uint32_t baud, char *err, size_t errlen);
void tty_port_close(tty_port_t *p);
/* Change the rate at once (TCSANOW). 0 or -1 (errno set). */
int tty_port_set_baud(tty_port_t *p, uint32_t baud);
/* The rate the driver actually runs at (a real adapter may round a custom rate). 0 or -1. */
int tty_port_read_baud(const tty_port_t *p, uint32_t *baud);
/* The HAL view of the port: set_baud, and transmit that waits for not_before (tty_now_us()
 * clock; more than 10 s ahead is refused as a clock mix-up) and then writes the whole frame. */
hal_uart_t tty_port_uart(tty_port_t *p);

/* Turn raw bytes as read() returned them into characters and HAL error flags, undoing PARMRK
 * marking (state carries across calls, so an escape may be split between reads). bytes and flags
 * must hold n + 1 entries (a stray 0xFF held from the previous call comes out too); returns how
 * many characters were produced. Exposed for tests: a PTY cannot produce parity errors. */
size_t tty_port_decode(tty_port_t *p, const uint8_t *raw, size_t n, uint8_t *bytes,
                       uint8_t *flags);

/* CLOCK_MONOTONIC in microseconds, wrapping like every hal_time_us_t. */
hal_time_us_t tty_now_us(void);

typedef struct tty_runner_slot {
    tty_port_t *port;
    sim_station_t station;
    hal_time_us_t deadline;
    fdl_rx_t rx;               /* assembles received frames for the tap */
    uint64_t rx_frame_start_ns; /* arrival of the chunk holding the frame's first byte */
} tty_runner_slot_t;

/* Other descriptors the runner waits on (a CAN socket): readable() runs when poll() reports
 * the descriptor readable (or in error: the callback's read() then tells which), with the wall
 * clock as now. It must drain what it can without blocking. */
#define TTY_RUNNER_MAX_FDS 8u
typedef void (*tty_fd_readable_fn)(void *ctx, hal_time_us_t now);
/* Timers without a port (an emulated inverter's ramps, a link's response deadlines): poll()
 * returns the next instant it wants to run, like a station's poll. */
#define TTY_RUNNER_MAX_TIMERS 8u
typedef hal_time_us_t (*tty_timer_fn)(void *ctx, hal_time_us_t now);

typedef struct tty_runner_fd {
    int fd;
    tty_fd_readable_fn readable;
    void *ctx;
} tty_runner_fd_t;

typedef struct tty_runner_timer {
    tty_timer_fn poll;
    void *ctx;
    hal_time_us_t deadline;
} tty_runner_timer_t;

struct tty_runner {
    tty_runner_slot_t slots[TTY_RUNNER_MAX_PORTS];
    uint8_t num_slots;
    tty_runner_fd_t fds[TTY_RUNNER_MAX_FDS];
    uint8_t num_fds;
    tty_runner_timer_t timers[TTY_RUNNER_MAX_TIMERS];
    uint8_t num_timers;
    sim_frame_tap_t tap;
    void *tap_ctx;
    uint64_t t0_ns; /* CLOCK_MONOTONIC at init: the tap's time origin */
    char error[192];
};

void tty_runner_init(tty_runner_t *r);
/* Drive port p for station st (copied). The station is first polled when the runner next runs.
 * Returns 0, or -1 when the runner is full or the port already belongs to a runner. */
int tty_runner_add(tty_runner_t *r, tty_port_t *p, const sim_station_t *st);
/* Wait on fd as well and call readable(ctx, now) when it has data. After each such call every
 * station and timer is polled at once, since what arrived may be for them (a CAN frame with the
 * inverter's answer for the card). The caller keeps owning fd. Returns 0, or -1 when full. */
int tty_runner_add_fd(tty_runner_t *r, int fd, tty_fd_readable_fn readable, void *ctx);
/* Stop waiting on fd (before closing it). Returns 0, or -1 if it was not added. */
int tty_runner_remove_fd(tty_runner_t *r, int fd);
/* A timer: poll(ctx, now) first runs when the runner next runs, then at the instant it returns.
 * Returns 0, or -1 when full. */
int tty_runner_add_timer(tty_runner_t *r, tty_timer_fn poll, void *ctx);
/* Something changed outside a timer's own calls (a request was queued): run every timer at
 * the next loop turn instead of at its last returned deadline. */
void tty_runner_wake(tty_runner_t *r);
/* Remove the timer added with this poll and ctx. Returns 0, or -1 if there is none. */
int tty_runner_remove_timer(tty_runner_t *r, tty_timer_fn poll, const void *ctx);
/* For fd users and timers: end the current run with -1 and this message (the first one set in a
 * run is kept). */
void tty_runner_set_error(tty_runner_t *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Every frame transmitted by a port of this runner (from_local_station = true) and every valid
 * frame received on one (false) goes to tap; t_start_ns counts from tty_runner_init(). */
void tty_runner_set_tap(tty_runner_t *r, sim_frame_tap_t tap, void *ctx);
/* Run until the wall clock reaches t_end or *stop (may be NULL) becomes non-zero: returns 0.
 * A device that fails or hangs up (a PTY whose peer closed) ends the run with -1 and a message
 * from tty_runner_error(). */
int tty_runner_run_until(tty_runner_t *r, hal_time_us_t t_end, volatile const int *stop);
/* The last failure, "" if none. */
const char *tty_runner_error(const tty_runner_t *r);

#endif
