/* Where the monitor listens: a tty or PTY (a USB/RS-485 adapter, a port of the virtual line) or
 * a virtual segment over LCM, through a station that only receives (its UART is never asked to
 * transmit, so the monitor cannot disturb the line it watches), or a capture file. The times a
 * live source gives the monitor are nanoseconds since its first character or poll (wall
 * clock), a file's are the records' own from its first. */
#ifndef MONITOR_MON_LIVE_H
#define MONITOR_MON_LIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "monitor/mon_chars.h"
#include "monitor/monitor.h"
#include "sim_hal/sim_station.h"

typedef struct mon_live {
    mon_t *mon;
    mon_chars_t chars;
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

/* The receiver for m on a line at baud; tick, tick_ctx and tick_ms are the caller's to set. */
void mon_live_init(mon_live_t *l, mon_t *m, uint32_t baud);
/* The station that listens for it: rx_char feeds the receiver, poll runs the monitor's idle
 * time and the caller's tick; nothing ever transmits. Give it to the medium (the rig's
 * rig_attach_listener, a tty_runner). */
sim_station_t mon_live_station(mon_live_t *l);

/* A capture file (any format capture.h reads) through the monitor, offline. baud: the line's
 * rate when the file does not say (0: unknown). Each record is one telegram (or a garbled
 * run) that began at its time. Returns the records read, or -1 with the reason in err. */
int64_t mon_file_run(mon_t *m, const char *path, uint32_t baud, volatile const int *stop,
                     char *err, size_t n);

#endif
