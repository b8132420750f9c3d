/* Where a wall-clock station is: a tty or PTY (--port DEV), or a virtual segment over LCM
 * (--bus lcm:CHANNEL, with --lcm-url URL and --key FILE for a keyed segment). Shared by slave,
 * master and param. */
#ifndef DFP_SIM_MEDIUM_H
#define DFP_SIM_MEDIUM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cli_table.h"
#include "lcm_bridge/seg_auth.h"

typedef struct medium_opts {
    const char *dev;
    const char *bus;
    const char *lcm_url;
    const char *key_file;
    /* Filled by medium_check from key_file. */
    bool keyed;
    uint8_t key[DFP_SEG_KEY_BYTES];
    /* Not an option: the command opened the tty itself (slave --pty: the master side of its
     * own PTY pair, which has no path). dev is then NULL. */
    bool use_fd;
    int fd;
} medium_opts_t;

/* --port DEV, --bus lcm:CHANNEL, --lcm-url URL, --key FILE into a medium_opts_t. */
extern const cli_opt_t medium_options[4];
/* At most one of --port and --bus, a valid channel, --lcm-url and --key only with --bus, and
 * the key file read (seg_auth.h's rules); false after reporting. Whether one of them is
 * required is the command's business. */
bool medium_check(medium_opts_t *m, const char *cmd);
/* The key for rig_cfg_t.lcm_key: NULL unless keyed. */
const uint8_t *medium_key(const medium_opts_t *m);
/* A plain segment (no --key) must not drive a real drive: whoever can send to the LCM group
 * could. inverter: the --inverter text ("can:IFACE[:ADDR]" is a real one). False after
 * reporting why and how. Checked before anything is opened. */
bool medium_check_real_drive(const medium_opts_t *m, const char *cmd, const char *inverter);
/* The device, or "LCM segment CHANNEL (URL)" with the URL the segment opened. */
const char *medium_name(const medium_opts_t *m, const char *opened_url, char *buf, size_t n);

#endif
