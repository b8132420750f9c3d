/* A virtual RS-485 segment shared by several stations: the rules of the line without any I/O,
 * so they can be tested at given times. `dfp-sim line` puts PTY ports and the in-memory bus on
 * it (README.md).
 *
 * The line is a queue of character slots. A slot is one 11-bit character on the wire, ending at
 * t_end_ns, with the stations that drove it. A write puts its characters on the line one after
 * another from its start; the line delivers each slot to every station that did not drive it
 * (half duplex: a talker does not hear itself), at the slot's end with pacing (timing) or at the
 * next delivery without it.
 *
 * Who talks when:
 * - A station's write follows its own characters still on the line, and otherwise starts when
 *   the line is free (start = max(arrival, the end of the line's last character)).
 * - A write that arrives while characters of another station are still undelivered collides:
 *   the writer could not have heard the end of that transmission, so on a cable both drive the
 *   line at once. Its characters land on the other's slots from the arrival on (each slot gets
 *   line_garble() of the two) and go on after them; every station in the overlap counts a
 *   collision, and line_take_collision() reports it (never silently merged).
 * Without pacing every character is delivered at the next line_deliver(), so only writes that
 * arrive between two deliveries (written before the writer could have heard the other) collide;
 * the occupancy still orders the line's timeline (and the times of a capture).
 *
 * Everything lives in the caller's line_t; time is passed in (ns on any monotonic timeline the
 * caller keeps). */
#ifndef LINE_LINE_H
#define LINE_LINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define LINE_MAX_STATIONS 32u
#ifndef LINE_QUEUE
#define LINE_QUEUE 8192u /* slots on the line; a write beyond them is dropped and counted */
#endif
#define LINE_COLLISION_LOG 16u
#define LINE_CHAR_BITS 11u

typedef struct line_slot {
    uint64_t t_end_ns;
    uint32_t drivers; /* bit s: station s drove this character */
    uint8_t byte;
} line_slot_t;

typedef struct line_station_stats {
    uint64_t tx_octets;  /* written onto the line */
    uint64_t tx_writes;  /* writes (a PTY write is usually one telegram) */
    uint64_t tx_dropped; /* octets that found the line's queue full */
    uint64_t rx_octets;  /* delivered to the station */
    uint64_t rx_dropped; /* the station did not take them (nobody reading, buffer full) */
    uint64_t collisions; /* transmissions of this station hit by another's */
} line_station_stats_t;

/* One collision: the first overlapping character's start, the stations in it and how many
 * characters were garbled. */
typedef struct line_collision {
    uint64_t t_ns;
    uint32_t stations;
    uint32_t octets;
} line_collision_t;

typedef struct line {
    uint32_t baud;
    uint32_t char_ns;
    bool timing;
    unsigned n_stations;
    uint32_t deaf;           /* stations that are never delivered to (they hear elsewhere) */
    uint64_t busy_until_ns;  /* the end of the line's last character */
    line_slot_t q[LINE_QUEUE];
    size_t head;             /* ring of undelivered slots, in time order */
    size_t len;
    line_station_stats_t st[LINE_MAX_STATIONS];
    uint64_t collisions;
    line_collision_t col[LINE_COLLISION_LOG]; /* not yet taken */
    size_t col_head;
    size_t col_len;
    uint64_t col_lost; /* reports that found the log full (the counts above still have them) */
} line_t;

/* n_stations 1..LINE_MAX_STATIONS, baud > 0. timing: deliver each character at its end. */
void line_init(line_t *l, unsigned n_stations, uint32_t baud, bool timing);
/* One 11-bit character at baud, in ns (rounded). */
uint32_t line_char_ns(uint32_t baud);
/* What a listener receives when a and b are on the line at once: the AND of the two (what a
 * wired-AND line shows), but never a or b: where one covers the other's 1-bits, the complement
 * of the AND, and for 0x00 against 0xFF (the complement is one of them) 0x55. So every slot of
 * an overlap differs from what each talker sent. */
uint8_t line_garble(uint8_t a, uint8_t b);
/* Station from writes len octets, arrived at now_ns (the line's start is later when the line is
 * busy with from's own characters or not free). *start_ns (if not NULL): when its first
 * character starts on the line. Returns true when it collided (the report is queued for
 * line_take_collision). */
bool line_write(line_t *l, unsigned from, const uint8_t *data, size_t len, uint64_t now_ns,
                uint64_t *start_ns);
/* When the next character is due (now_ns when one is due already); UINT64_MAX: none. */
uint64_t line_next_due(const line_t *l, uint64_t now_ns);
/* Takes data for station to and returns how many octets it accepted (the rest are counted as
 * dropped for it). */
typedef size_t line_deliver_fn(void *ctx, unsigned to, const uint8_t *data, size_t len);
/* Delivers every character due at now_ns; returns how many slots went. */
size_t line_deliver(line_t *l, uint64_t now_ns, line_deliver_fn *fn, void *ctx);
/* The oldest collision not yet taken: true and *out, or false when none. */
bool line_take_collision(line_t *l, line_collision_t *out);

#endif
