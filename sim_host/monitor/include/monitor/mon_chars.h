/* The monitor's receiver: characters as a port delivers them (a tty, a PTY, a port of the
 * virtual line), with the time they arrived, cut into telegrams for mon_telegram. Telegram
 * ends follow from the delimiter and LE; a garbled stream resynchronises at the next start
 * delimiter: octets between telegrams and telegrams that fail their check go to mon_garbled,
 * and the octets of a failed one after its first are looked at again. */
#ifndef MONITOR_MON_CHARS_H
#define MONITOR_MON_CHARS_H

#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_wire.h"
#include "monitor/monitor.h"

#define MON_GARBLE_MAX 64u /* octets of a garbled run kept for mon_garbled (the rest counted) */

typedef struct mon_chars {
    mon_t *mon;
    uint8_t buf[FDL_FRAME_MAX];
    size_t have;          /* octets of the telegram in progress so far */
    size_t frame_len;     /* octets it has by its delimiter (and LE) */
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
