/* Where a wall-clock station is: a tty or PTY (--port DEV), or a virtual segment over LCM
 * (--bus lcm:CHANNEL, with --lcm-url URL). Shared by slave, master and param. */
#ifndef DFP_SIM_MEDIUM_H
#define DFP_SIM_MEDIUM_H

#include <stdbool.h>
#include <stddef.h>

typedef struct medium_opts {
    const char *dev;
    const char *bus;
    const char *lcm_url;
    /* Not an option: the command opened the tty itself (slave --pty: the master side of its
     * own PTY pair, which has no path). dev is then NULL. */
    bool use_fd;
    int fd;
} medium_opts_t;

/* --port / --bus / --lcm-url. Returns 1 when argv[*i] was one of them, 0 when not, -1 on a
 * usage error (reported). */
int medium_option(medium_opts_t *m, int argc, char **argv, int *i);
/* At most one of --port and --bus, a valid channel, --lcm-url only with --bus; false after
 * reporting. Whether one of them is required is the command's business. */
bool medium_check(const medium_opts_t *m, const char *cmd);
/* The device, or "LCM segment CHANNEL (URL)" with the URL the segment opened. */
const char *medium_name(const medium_opts_t *m, const char *opened_url, char *buf, size_t n);

#endif
