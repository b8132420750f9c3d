/* Whole telegrams into an fdl_rx assembler, leaving it as its characters one by one would have
 * (the in-memory bus's telegram path, sim_hal/membus.h).
 *
 * The core's fdl_rx_telegram() takes a telegram a receiver collected, but it neither says
 * whether the characters would have been accepted the same way (a receiver inside a telegram
 * or inside garbage joins or drops them) nor records the last character's time, from which
 * fdl_rx_char judges the idle before the next telegram. These two functions do both for the
 * host; the core could offer them as one fdl_rx_telegram_timed(rx, tg, first_t). */
#ifndef DP_MASTER_RX_WHOLE_H
#define DP_MASTER_RX_WHOLE_H

#include <stdbool.h>
#include <stdint.h>

#include "dp_slave/fdl_rx.h"

typedef struct dp_master_whole {
    const uint8_t *data;
    uint16_t len;
    uint32_t char_ns;            /* on the line */
    hal_time_us_t first_t;       /* the timestamps fdl_rx_char would have had: the first, */
    hal_time_us_t before_last_t; /* the one before the last (first_t for one character), */
    hal_time_us_t end_t;         /* the last */
} dp_master_whole_t;

/* True when fdl_rx_char for each character would accept exactly this telegram: the assembler
 * is between telegrams and may start one, no pause inside, and the octets are one telegram. */
bool dp_master_whole_clean(const fdl_rx_t *rx, const dp_master_whole_t *w);
/* dp_master_whole_clean's two halves: what depends on the receiver (its assembler, the gaps at
 * its rate), and what the octets alone decide (the same for every listener, so a bus with many
 * of them may work it out once per telegram). */
bool dp_master_whole_fits(const fdl_rx_t *rx, const dp_master_whole_t *w);
bool dp_master_whole_octets_ok(const dp_master_whole_t *w);

/* The telegram for fdl_rx_telegram (or dp_slave_rx_telegram) with the idle before it, and the
 * assembler's record of the last character updated as fdl_rx_char updates it. Only after
 * dp_master_whole_clean, and only when the telegram does reach the assembler. */
fdl_rx_telegram_t dp_master_whole_take(fdl_rx_t *rx, const dp_master_whole_t *w);

#endif
