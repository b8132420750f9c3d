/* A virtual PROFIBUS segment over LCM: stations in different processes, or on different
 * machines, share one bus (dfp-sim slave|master --bus lcm:CHANNEL).
 *
 * Each transmitted frame is one dfp_lcm telegram_t message on the segment's channel, stamped
 * with the sender's rate and a random source id. Every process hears every message, ignores its
 * own (by source id) and hands the octets to its station with the wall-clock time they arrived,
 * all with one timestamp, as a tty delivers a chunk: the stations run with relaxed timing
 * (fdl_rx.h). A station whose UART is at another rate than the message receives its octets with
 * framing errors, which is what a real UART mostly sees and all the card's baud search needs.
 * There is no line model: no collisions, no character times; who talks when is the master's
 * business, as on a token-less single-master segment.
 *
 * The segment joins a tty_runner (sim_hal/tty_port.h) as one extra descriptor (LCM's fileno)
 * and one timer (the station's poll), so the station is driven exactly as on a tty: received
 * characters, then a poll; transmit() blocks until its not_before instant (tty_now_us clock).
 * One station per segment object; a process may open several.
 *
 * Keyed (dfp_lcm_segment_set_key, --key FILE): every frame goes out as a signed_telegram_t and
 * only signed ones with a good tag, in the clock window and not seen before are heard
 * (seg_auth.h); without a key, signed ones are dropped. Drops are counted per reason and
 * logged through the log function (the first at once, then a summary at most every second). */
#ifndef DFP_LCM_BRIDGE_LCM_SEGMENT_H
#define DFP_LCM_BRIDGE_LCM_SEGMENT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_uart.h"
#include "lcm_bridge/seg_auth.h"
#include "sim_hal/sim_station.h"
#include "sim_hal/tty_port.h"

#include <lcm/lcm.h>

/* Messages waiting in LCM for this process before the oldest are dropped (LCM's default, 30,
 * loses frames when 33 processes share two cores). */
#define DFP_LCM_SEGMENT_QUEUE 4096

typedef struct dfp_lcm_segment {
    lcm_t *lcm;
    void *subscription;
    char url[200];
    char channel[64];
    int64_t source_id;
    int32_t process_id;
    int16_t station_address; /* telegram_t.station of our frames; -1 none */
    uint32_t baud;           /* the station's UART rate */
    sim_station_t station;
    tty_runner_t *runner;
    bool station_attached;
    sim_frame_tap_t tap; /* every frame sent, and every frame received at our rate */
    void *tap_ctx;
    uint64_t t0_ns;      /* CLOCK_MONOTONIC at open: the tap's time origin */
    /* Counters. */
    uint64_t frames_sent;
    uint64_t frames_received;    /* from other processes */
    uint64_t frames_other_baud;  /* of those, at a rate other than ours (framing errors) */
    uint64_t own_ignored;        /* our own frames coming back */
    uint64_t send_failures;
    /* Keyed segments; drops of both kinds (drops.total[why]: a plain segment counts signed
     * and malformed messages there). */
    bool keyed;
    dfp_seg_auth_t auth;
    dfp_seg_drops_t drops;
    dfp_seg_log_fn log; /* NULL: standard error */
    void *log_ctx;
} dfp_lcm_segment_t;

/* Opens url ("" or NULL: $LCM_DEFAULT_URL, else LCM's default udpm://239.255.76.67:7667?ttl=0)
 * and subscribes to channel. station_address goes into every message sent (-1: none); baud is
 * the UART's rate until the station sets another. Returns 0, or -1 with a one-line reason. */
int dfp_lcm_segment_open(dfp_lcm_segment_t *s, const char *url, const char *channel,
                         int16_t station_address, uint32_t baud, char *err, size_t errlen);
/* The UART for the station: set_baud, transmit (publishes one message per frame). */
hal_uart_t dfp_lcm_segment_uart(dfp_lcm_segment_t *s);
/* Drive station st on runner r: LCM's descriptor and the station's poll as a timer. Returns 0,
 * or -1 when the runner has no room. */
int dfp_lcm_segment_attach(dfp_lcm_segment_t *s, tty_runner_t *r, const sim_station_t *st);
/* For --capture: called with every frame sent (local) and received at our rate without error,
 * t_start_ns from dfp_lcm_segment_open. */
void dfp_lcm_segment_set_tap(dfp_lcm_segment_t *s, sim_frame_tap_t tap, void *ctx);
/* Makes the segment keyed: every frame sent is signed with key, only telegrams signed with it
 * are heard. Returns 0, or -1 when libsodium cannot start. */
int dfp_lcm_segment_set_key(dfp_lcm_segment_t *s, const uint8_t key[DFP_SEG_KEY_BYTES]);
/* Where the drop lines go (and the totals at close). */
void dfp_lcm_segment_set_log(dfp_lcm_segment_t *s, dfp_seg_log_fn log, void *ctx);
/* One message as LCM delivered it on the channel (what the subscription calls; tests feed
 * octets with it). */
void dfp_lcm_segment_receive(dfp_lcm_segment_t *s, const uint8_t *buf, size_t len);
/* Leaves the runner, logs the totals of a keyed segment or one that dropped anything
 * ("segment CH: N telegrams taken, M dropped (...)"), wipes the key and closes LCM. */
void dfp_lcm_segment_close(dfp_lcm_segment_t *s);
/* "lcm:CHANNEL" → CHANNEL (1..63 characters of [A-Za-z0-9_.-]); NULL when text is not one. */
const char *dfp_lcm_segment_channel(const char *text);

#endif
