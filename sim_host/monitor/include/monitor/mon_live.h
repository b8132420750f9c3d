/* Where the monitor listens: a tty or PTY (a USB/RS-485 adapter, a port of the virtual line),
 * a virtual segment over LCM, or a capture file. A live source runs the tty_runner loop with a
 * station that only receives: its UART is never asked to transmit, so the monitor cannot
 * disturb the line it watches. The times it gives the monitor are nanoseconds since the source
 * was opened (wall clock), a file's are the records' own. */
#ifndef MONITOR_MON_LIVE_H
#define MONITOR_MON_LIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "lcm_bridge/lcm_segment.h"
#include "monitor/mon_chars.h"
#include "monitor/monitor.h"
#include "sim_hal/tty_port.h"

typedef struct mon_live {
    mon_t *mon;
    mon_chars_t chars;
    tty_runner_t runner;
    tty_port_t port;
    bool port_open;
    dfp_lcm_segment_t seg;
    bool lcm_open;
    /* hal_time_us_t (32 bits, wrapping) extended to 64 bits from the first one seen */
    bool have_t;
    uint32_t last_us;
    uint64_t now_us;
    /* The caller's turn (view, reports, the API): every tick_ms, with the monitor's time. */
    void (*tick)(void *ctx, uint64_t now_ns);
    void *tick_ctx;
    uint32_t tick_ms;
    uint64_t chars_in;
    uint64_t char_errors;
} mon_live_t;

/* A tty or PTY at baud (8E1, raw; a PTY ignores the rate). 0, or -1 with the reason in err. */
int mon_live_open_port(mon_live_t *l, mon_t *m, const char *dev, uint32_t baud, char *err,
                       size_t n);
/* An LCM segment (url NULL: LCM's default); key NULL for a plain one. */
int mon_live_open_lcm(mon_live_t *l, mon_t *m, const char *url, const char *channel,
                      const uint8_t *key, uint32_t baud, char *err, size_t n);
/* Runs until seconds have passed (0: no limit) or *stop becomes non-zero: 0; -1 when the
 * device fails or its peer hangs up (the message in err). */
int mon_live_run(mon_live_t *l, uint32_t seconds, volatile const int *stop, char *err, size_t n);
void mon_live_close(mon_live_t *l);

/* A capture file (any format capture.h reads) through the monitor, offline. baud: the line's
 * rate when the file does not say (0: unknown). Each record is one telegram (or a garbled
 * run) that began at its time. Returns the records read, or -1 with the reason in err. */
int64_t mon_file_run(mon_t *m, const char *path, uint32_t baud, volatile const int *stop,
                     char *err, size_t n);

#endif
