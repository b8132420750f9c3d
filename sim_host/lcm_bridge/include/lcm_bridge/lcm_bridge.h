/* Publishing what a simulated card does to LCM (sim_host/lcm_bridge/README.md lists the channels
 * and the messages): every telegram the card sent or heard, the card's state when it changed, and
 * every parameter service the card ran with its inverter.
 *
 * Everything goes through an explicit context, so a program may publish for several cards or
 * to several URLs. Time is passed in (utime, µs since the Unix epoch): a card on a tty uses the
 * wall clock, the demo wall clock at start plus simulated time, a replay the capture's times.
 *
 * Publishing must never stop the card: every call returns -1 on failure, counts it and keeps the
 * first reason in error[]; the caller reports it (once) and goes on.
 *
 * Typical use from a loop that has telegrams and a card (dfp-sim replay):
 *     dfp_lcm_bridge_t b;
 *     if (dfp_lcm_bridge_open(&b, url, card_address, err, sizeof err) != 0) ...;
 *     for each telegram: dfp_lcm_bridge_telegram(&b, utime, bytes, len, from_local, baud, 0);
 *                        dfp_lcm_bridge_card_state(&b, utime, &card);   (cheap when unchanged)
 *     card_options_t.param_observer = dfp_lcm_bridge_param_observer, ..._ctx = &b (needs
 *         b.clock for the answer's time, see below);
 *     dfp_lcm_bridge_close(&b); */
#ifndef DFP_LCM_BRIDGE_LCM_BRIDGE_H
#define DFP_LCM_BRIDGE_LCM_BRIDGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dfp21b/dfp21b.h"
#include "movilink/movilink_wire.h"

#include <lcm/lcm.h>

#define DFP_LCM_CH_TELEGRAM "DFP_TELEGRAM"
#define DFP_LCM_CH_CARD_STATE "DFP_CARD_STATE"
#define DFP_LCM_CH_PARAM "DFP_PARAM"
#define DFP_LCM_CH_API "DFP_API"
/* A card's state goes out at most this often (ms) unless the context says otherwise. */
#define DFP_LCM_STATE_INTERVAL_MS_DEFAULT 100u

/* The part of a card's state whose change is worth a message. */
typedef struct dfp_lcm_state_snapshot {
    uint8_t dp_state;
    uint8_t led_run;
    uint8_t led_bus_fault;
    uint8_t address;
    uint32_t baud;
    bool pd_valid;
    bool param_channel;
    uint8_t pd_words;
    uint32_t p819_ms;
    uint16_t po[DFP21B_MAX_PD];
    uint16_t pi[DFP21B_MAX_PD];
} dfp_lcm_state_snapshot_t;

typedef struct dfp_lcm_bridge {
    lcm_t *lcm;
    char url[200];
    int64_t source_id;  /* random, never 0: telegram_t.source_id of everything published here */
    int32_t process_id;
    int16_t station;    /* FDL address of the card (or station) published for; -1 none */
    uint32_t state_interval_ms;
    /* utime of "now" for callbacks that carry no time (the parameter observer); NULL: the
     * wall clock. */
    int64_t (*clock)(void *ctx);
    void *clock_ctx;
    /* The card state last published and when. */
    bool state_published;
    int64_t state_utime;
    dfp_lcm_state_snapshot_t last;
    bool state_pending; /* a change is waiting for state_interval_ms to pass */
    uint64_t messages;  /* published */
    uint64_t failures;
    char error[320];    /* the first failure, "" if none */
} dfp_lcm_bridge_t;

/* Opens url (lcm_create: "udpm://239.255.76.67:7667?ttl=0", "memq://", "file://x.log?mode=w",
 * "" for $LCM_DEFAULT_URL or LCM's default). station is the card's address (or -1). Returns 0,
 * or -1 with a one-line reason in err. */
int dfp_lcm_bridge_open(dfp_lcm_bridge_t *b, const char *url, int16_t station, char *err,
                        size_t errlen);
void dfp_lcm_bridge_close(dfp_lcm_bridge_t *b);

/* One telegram as the station saw it: from_local = it sent it (direction TX), else it received
 * it (RX). error_flags: HAL_UART_RX_*_ERR of its octets. Returns 0 or -1. */
int dfp_lcm_bridge_telegram(dfp_lcm_bridge_t *b, int64_t utime, const uint8_t *frame,
                            size_t len, bool from_local, uint32_t baud, uint16_t error_flags);

/* Publishes the card's state if it differs from the last one published and state_interval_ms
 * has passed since; a change that came too soon sets state_pending and goes out with a later
 * call (call this at least every state_interval_ms while state_pending). The first call always
 * publishes. Returns 1 published, 0 not (unchanged or too soon), -1 failure. */
int dfp_lcm_bridge_card_state(dfp_lcm_bridge_t *b, int64_t utime, const dfp21b_t *card);

/* One completed parameter service on link channel (0 cyclic channel, 1 MSAC1, 2/3 MSAC2,
 * 4 the card's status poll): the request as it went to the inverter and its response. The card
 * address is b->station. Returns 0 or -1. */
int dfp_lcm_bridge_param_service(dfp_lcm_bridge_t *b, int64_t utime, uint8_t channel,
                                 const uint8_t req[ML_TELEGRAM_LEN],
                                 const uint8_t rsp[ML_TELEGRAM_LEN]);
/* The same with the shape of card_options_t.param_observer (ctx = the bridge; time from
 * b->clock). */
/* Publishes an event of the control API (api_event_t on DFP_API). level: "warn", "info"...
 * Returns 0, or -1 (counted in failures). */
int dfp_lcm_bridge_api_event(dfp_lcm_bridge_t *b, int64_t utime, int64_t t_us, int64_t seq,
                             const char *level, const char *kind, const char *text);
void dfp_lcm_bridge_param_observer(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                                   const uint8_t rsp[ML_TELEGRAM_LEN]);

/* "channel", "c1-ds47", "c2-ds47-1", "c2-ds47-2", "status-poll"; "?" otherwise. */
const char *dfp_lcm_param_path(uint8_t channel);
/* What lcm_create(NULL) opens: $LCM_DEFAULT_URL, else LCM 1.3's udpm default. */
const char *dfp_lcm_default_url(void);
/* CLOCK_REALTIME in µs since the Unix epoch. */
int64_t dfp_lcm_wall_us(void);
/* A random non-zero id for telegram_t.source_id. */
int64_t dfp_lcm_new_source_id(void);

#endif
