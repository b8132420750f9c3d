/* Where a wall-clock station is: a tty or PTY (--port DEV), or a virtual segment over LCM
 * (--bus lcm:CHANNEL, with --lcm-url URL). Shared by slave, master and param. */
#ifndef DFP_SIM_MEDIUM_H
#define DFP_SIM_MEDIUM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dfp_lcm_bridge/lcm_segment.h"
#include "sim_hal/tty_port.h"

typedef struct medium_opts {
    const char *dev;
    const char *bus;
    const char *lcm_url;
} medium_opts_t;

/* --port / --bus / --lcm-url. Returns 1 when argv[*i] was one of them, 0 when not, -1 on a
 * usage error (reported). */
int medium_option(medium_opts_t *m, int argc, char **argv, int *i);
/* At most one of --port and --bus, a valid channel, --lcm-url only with --bus; false after
 * reporting. Whether one of them is required is the command's business. */
bool medium_check(const medium_opts_t *m, const char *cmd);
/* The device, or "LCM segment CHANNEL (URL)" with the URL the segment opened. */
const char *medium_name(const medium_opts_t *m, const char *opened_url, char *buf, size_t n);

/* One station alone on the medium, driven by its own runner (dfp-sim param's master; slave and
 * master go through the rig). */
typedef struct medium_link {
    bool lcm;
    tty_port_t port;
    dfp_lcm_segment_t segment;
    tty_runner_t runner;
} medium_link_t;

/* Opens the tty at baud, or the segment with station_address on our frames. Returns 0, or -1
 * with a one-line reason in err. */
int medium_link_open(medium_link_t *l, const medium_opts_t *m, int16_t station_address,
                     uint32_t baud, char *err, size_t errlen);
hal_uart_t medium_link_uart(medium_link_t *l);
/* Drives st from the runner; tap sees every frame sent and received. Returns 0 or -1. */
int medium_link_attach(medium_link_t *l, const sim_station_t *st, sim_frame_tap_t tap,
                       void *tap_ctx);
void medium_link_close(medium_link_t *l);

#endif
