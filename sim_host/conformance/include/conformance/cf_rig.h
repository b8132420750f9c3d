/* The suite's link (cf_link_t) over a rig: the tester is a station on the rig's medium.
 *   - the card in process on the in-memory bus (simulated time: answers timed to the bit, the
 *     rate changeable, the card can be power-cycled); the card runs without an inverter, so
 *     its PI words echo its PO words;
 *   - a tty or PTY (wall clock: arrival times only, no TSDR), a virtual segment over LCM.
 * The tester holds the line alone, as a test lab's master does: no token, no other master.
 *
 * cf_rig_t is large (it holds the rig): keep it in static storage. */
#ifndef CONFORMANCE_CF_RIG_H
#define CONFORMANCE_CF_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "conformance/cf.h"
#include "rig/rig.h"

#define CF_RIG_RX_MAX 512u

typedef struct cf_rig_cfg {
    rig_medium_t medium;
    /* RIG_MEDIUM_MEMBUS: the card's address (its DIP switches); the card is built with the
     * card library given at link time (a mutant card in the mutant tests). */
    uint8_t card_address;
    /* RIG_MEDIUM_TTY / RIG_MEDIUM_LCM, as rig_cfg_t. */
    const char *device;
    bool use_fd;
    int fd;
    const char *lcm_channel;
    const char *lcm_url;
    const uint8_t *lcm_key;
    bool echo_suppress;
    uint32_t baud;         /* the rate (9600 .. 12000000) */
    uint64_t start_ns;     /* in-memory bus: where simulated time starts */
    /* Wall-clock media: slot time and idle (0: the usb profile's, fdl_bus.h). */
    uint32_t slot_us;
    uint32_t idle_us;
} cf_rig_cfg_t;

typedef struct cf_rig {
    rig_t rig;
    cf_rig_cfg_t cfg;
    hal_uart_t uart;
    uint32_t baud;
    rig_card_t *card;      /* the card in process, NULL on other media */
    /* What the tester hears after its request. */
    uint8_t rx[CF_RIG_RX_MAX];
    size_t rx_len;
    bool rx_overflow;
    volatile int done;     /* a whole telegram came (ends a wall-clock wait early) */
    bool listening;
    hal_time_us_t last_rx_t; /* the last character's time (wall clock) */
    bool heard_any;
    uint32_t rx_chars; /* every character heard, listening or not (settle) */
    /* Frame times from the rig's tap (the in-memory bus: to the nanosecond). */
    size_t tx_len;
    uint64_t tx_start_ns;  /* the tester's request */
    uint64_t rx_start_ns;  /* the first frame after it */
    bool tx_seen;
    bool rx_seen;
    uint64_t line_free_ns; /* when the last frame on the medium ended */
    char err[256];
} cf_rig_t;

/* Opens the medium and attaches the tester (and, on the in-memory bus, the card). Returns 0, or
 * -1 with the reason in err. */
int cf_rig_open(cf_rig_t *cr, const cf_rig_cfg_t *cfg, char *err, size_t errlen);
void cf_rig_close(cf_rig_t *cr);
/* The link for cf_init. */
cf_link_t cf_rig_link(cf_rig_t *cr, const char *name);

#endif
