/* The monitor's receiver: characters as a port delivers them (a tty, a PTY, a port of the
 * virtual line), with the time they arrived, cut into telegrams for mon_telegram. The core's
 * collector (dp_slave/fdl_collect.h) finds the telegram ends by delimiter and LE, so a garbled
 * stream resynchronises at the next start delimiter; octets between telegrams and telegrams
 * that fail their check go to mon_garbled. */
#ifndef MONITOR_MON_CHARS_H
#define MONITOR_MON_CHARS_H

#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_collect.h"
#include "dp_slave/fdl_wire.h"
#include "monitor/monitor.h"

#define MON_GARBLE_MAX 64u /* octets of a garbled run kept for mon_garbled (the rest counted) */

typedef struct mon_chars {
    mon_t *mon;
    fdl_collect_t coll;
    uint8_t buf[2][FDL_FRAME_MAX];
    uint8_t which;
    uint32_t char_ns;
    uint64_t first_ns;    /* the telegram in progress: its first character's arrival */
    uint8_t garble[MON_GARBLE_MAX];
    size_t garble_len;    /* octets of the current garbled run (may exceed MON_GARBLE_MAX) */
    uint64_t garble_t_ns;
    uint64_t last_ns;
} mon_chars_t;

void mon_chars_init(mon_chars_t *c, mon_t *m, uint32_t baud);
/* n characters that arrived at t_ns (a chunk of one read()); flags as tty_port_decode gives
 * them (HAL_UART_* error bits), or NULL. */
void mon_chars_feed(mon_chars_t *c, const uint8_t *bytes, const uint8_t *flags, size_t n,
                    uint64_t t_ns);
/* Time passed without characters: ends a telegram cut short, then mon_idle. */
void mon_chars_idle(mon_chars_t *c, uint64_t now_ns);

#endif
