/* An FDL active station: the medium access control of a PROFIBUS master (IEC 61158-4-3 Type 3,
 * "token bus" part; PROFIBUS Specification, Normative Parts 4, 1997, §4.1: token handling, the
 * List of Active Stations, GAP maintenance, ring initialisation and recovery).
 *
 * The station decides when its user (a DP master) may transmit and does the ring's own work:
 *   - the token (SD4 DC DA SA) is taken from the predecessor (PS) and passed to the successor
 *     (NS); a lone station passes it to itself, as a PLC alone on its bus does;
 *   - the real rotation time TRR is measured from one token receipt to the next; the token
 *     holding time TTH = TTR - TRR allows high-priority message cycles, then low-priority ones,
 *     while the token is early; a late token (TTH <= 0) allows exactly one high-priority cycle;
 *   - GAP maintenance: G rotations after the last sweep, a sweep asks the addresses between TS
 *     and NS (up to HSA) with Request FDL Status, one per token visit, from TS+1 on (a claim
 *     starts one at once); a master answering "ready to enter the ring"
 *     becomes the new NS; what every address answered is the live list;
 *   - FDL status requests to this station are answered: master not ready / ready to enter the
 *     ring / in the ring (FC 0x10 / 0x20 / 0x30);
 *   - token-pass retries: no activity within TSL after a token pass repeats it (twice), then
 *     the NS is skipped and the next station of the LAS gets the token;
 *   - lost token: a bus idle for TTO = 6·TSL + 2·TS·TSL (every station a different time-out, the
 *     lowest address first) makes the station claim the token (two tokens to itself) and rebuild
 *     the ring by GAP maintenance;
 *   - joining: after start the station listens (Listen_Token) until it has heard two identical
 *     token rotations, then waits in Active_Idle for its PS to let it in;
 *   - double token: a holder that hears another station's request or token, or any character
 *     when no answer is due (a collision), drops its token;
 *     duplicate address: a telegram from our own address that we did not send takes the
 *     station off the bus (Offline).
 *
 * Like the card, it is a library with time passed in and a deadline out; nothing is allocated
 * and there are no globals, so the in-memory bus runs rings of many stations deterministically.
 * The user feeds it every character time (fdl_active_activity) and every valid telegram heard
 * (fdl_active_frame), reports its own transmissions (fdl_active_sent), asks before each message
 * cycle (fdl_active_may_start) and hands the token back (fdl_active_release). */
#ifndef FDL_ACTIVE_FDL_ACTIVE_H
#define FDL_ACTIVE_FDL_ACTIVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_time.h"
#include "hal/hal_uart.h"

#define FDL_ACTIVE_ADDRESSES 128u
#define FDL_ACTIVE_HSA_MAX 126u
/* Repeats of a token pass the successor did not take (three sends in all, as profirust and
 * PLCs do), independent of the message retry limit. */
#define FDL_TOKEN_PASS_REPEATS 2u
/* fdl_active_event_t.address when the other station is not known (a garbled telegram). */
#define FDL_ACTIVE_NO_ADDRESS 0xFFu

/* The bus parameters every master of a segment must share (a PLC's hardware configuration
 * shows them as "bus parameters"); times in bit times at baud. */
typedef struct fdl_bus_params {
    uint32_t baud;
    uint32_t tsl_bits;      /* slot time: longest wait for a reply's first character */
    uint16_t min_tsdr_bits; /* a responder waits at least this long before answering */
    uint32_t max_tsdr_bits; /* a responder answers within this */
    uint8_t tset_bits;      /* setup time */
    uint8_t tqui_bits;      /* quiet time of the transmitter (repeaters, driver turn-around) */
    uint32_t ttr_bits;      /* target rotation time */
    uint8_t gap_factor;     /* G: rotations between two GAP maintenance rounds */
    uint8_t hsa;            /* highest station address asked in GAP maintenance */
    uint8_t max_retry;      /* repeats of an unanswered request or token pass */
} fdl_bus_params_t;

typedef enum fdl_bus_profile {
    FDL_BUS_PROFILE_DP = 0, /* the DP profile's values per rate (what PLC tools propose) */
    FDL_BUS_PROFILE_USB,    /* a USB/RS-485 adapter or a PTY: slot time and TSDR in ms */
} fdl_bus_profile_t;

/* The profile's defaults at baud (one of the ten PROFIBUS rates; others get 19.2k's). */
void fdl_bus_params_default(fdl_bus_params_t *p, uint32_t baud, fdl_bus_profile_t profile);
/* The rules between the parameters (TSL above max TSDR and TID1, HSA <= 126, G >= 1, ...).
 * False with the broken rule in why. */
bool fdl_bus_params_check(const fdl_bus_params_t *p, char *why, size_t n);
/* A station above HSA is asked by no master's GAP maintenance: it could join no ring it did not
 * start itself. False with the reason in why. */
bool fdl_bus_address_ok(const fdl_bus_params_t *p, uint8_t ts, char *why, size_t n);
/* Idle before a request: TID1 after a reply or token, TID2 after a telegram no one answers. */
uint32_t fdl_bus_tid1_bits(const fdl_bus_params_t *p);
uint32_t fdl_bus_tid2_bits(const fdl_bus_params_t *p);
/* The lost-token time-out of station ts: 6·TSL + 2·ts·TSL. */
uint32_t fdl_bus_tto_bits(const fdl_bus_params_t *p, uint8_t ts);
uint32_t fdl_bus_us(const fdl_bus_params_t *p, uint32_t bits);

typedef enum fdl_mac_state {
    FDL_MAC_OFFLINE = 0,          /* not started, stopped, or a duplicate address was heard */
    FDL_MAC_LISTEN_TOKEN,         /* learning the LAS from the tokens heard */
    FDL_MAC_ACTIVE_IDLE,          /* in the ring (or waiting to be let in), not holding */
    FDL_MAC_CLAIM_TOKEN,          /* the bus was silent for TTO: claiming the token */
    FDL_MAC_USE_TOKEN,            /* holding: the user's message cycles */
    FDL_MAC_AWAIT_STATUS_RESPONSE, /* holding: a GAP address was asked for its FDL status */
    FDL_MAC_PASS_TOKEN,           /* holding: the token goes out once the line is idle */
    FDL_MAC_CHECK_TOKEN_PASS,     /* passed: waiting TSL for the successor's first character */
} fdl_mac_state_t;

/* What an address answered to Request FDL Status (the live list). */
typedef enum fdl_station_kind {
    FDL_STATION_UNKNOWN = 0, /* never asked, or not asked since it stopped answering */
    FDL_STATION_NONE,        /* asked, no answer */
    FDL_STATION_PASSIVE,     /* FC station type 00: a slave */
    FDL_STATION_NOT_READY,   /* 01: a master not ready to enter the ring */
    FDL_STATION_READY,       /* 10: a master ready to enter the ring */
    FDL_STATION_IN_RING,     /* 11: a master in the ring (or: heard passing the token) */
} fdl_station_kind_t;

typedef enum fdl_active_event_type {
    FDL_EV_STATE = 0,      /* old_state -> state */
    FDL_EV_IN_RING,        /* the first token after joining: the station is in the ring */
    FDL_EV_LAS,            /* the LAS changed: address joined (kind IN_RING) or left (NONE) */
    FDL_EV_LIVE,           /* GAP maintenance found address as kind (a change only) */
    FDL_EV_NEW_SUCCESSOR,  /* address is the NS now */
    FDL_EV_PASS_FAILED,    /* address did not take the token: skipped */
    FDL_EV_CLAIM,          /* the token was lost: claimed */
    FDL_EV_DOUBLE_TOKEN,   /* another station transmitted while we held the token: dropped */
    FDL_EV_DUPLICATE_ADDRESS, /* address is our own: off the bus */
    FDL_EV_LATE_TOKEN,     /* the token came late: trr_us above TTR */
} fdl_active_event_type_t;

typedef struct fdl_active_event {
    fdl_active_event_type_t type;
    hal_time_us_t t;
    fdl_mac_state_t old_state;
    fdl_mac_state_t state;
    uint8_t address;
    fdl_station_kind_t kind;
    uint32_t trr_us;
} fdl_active_event_t;

typedef struct fdl_active_cfg {
    uint8_t address; /* TS, 0..126 */
    fdl_bus_params_t bus;
    hal_uart_t uart;
    void (*event)(void *ctx, const fdl_active_event_t *ev);
    void *event_ctx;
} fdl_active_cfg_t;

typedef struct fdl_active_stats {
    uint32_t tokens_received;
    uint32_t tokens_passed;   /* to another station */
    uint32_t tokens_to_self;
    uint32_t token_retries;
    uint32_t stations_skipped;
    uint32_t late_tokens;
    uint32_t claims;
    uint32_t gap_requests;
    uint32_t double_tokens;
    uint32_t status_answers; /* FDL status requests answered */
    uint32_t trr_us;         /* the last measured rotation */
    uint32_t trr_max_us;
} fdl_active_stats_t;

typedef struct fdl_active {
    fdl_active_cfg_t cfg;
    fdl_mac_state_t state;
    uint8_t las[FDL_ACTIVE_ADDRESSES / 8u];      /* active stations (in the ring) */
    uint8_t listen_set[FDL_ACTIVE_ADDRESSES / 8u]; /* tokens heard in this rotation */
    uint8_t listen_prev[FDL_ACTIVE_ADDRESSES / 8u];
    uint8_t live[FDL_ACTIVE_ADDRESSES];           /* fdl_station_kind_t per address */
    bool listen_started;    /* a token to a lower address was heard: rotations count */
    uint8_t listen_rotations;
    bool in_ring;
    uint8_t ns;
    uint8_t ps;
    uint8_t foreign_ps; /* a token from a station other than PS, refused once */
    /* Holding the token. */
    hal_time_us_t token_t;     /* the token's receipt (end of its last character) */
    bool have_token_t;
    hal_time_us_t tth_end;     /* the token is early until here */
    bool late;
    bool high_done;            /* a late token's one high-priority cycle went out */
    uint32_t visit;            /* counts token receipts; the user serves each slave once */
    /* GAP maintenance. */
    uint8_t gap_rotations;
    bool gap_sweep;            /* G rotations passed: one address per visit until the GAP ends */
    uint8_t gap_next;
    bool gap_asked_this_visit;
    uint8_t gap_asked;         /* the address in AWAIT_STATUS_RESPONSE */
    /* Passing. */
    bool gap_pending;          /* released: one GAP request before the token goes */
    bool leaving;              /* fdl_active_leave: Offline once the token is passed on */
    uint8_t pass_to;
    uint8_t pass_tries;
    uint8_t claim_tokens;      /* tokens to itself sent in Claim_Token */
    /* Time. */
    hal_time_us_t tx_start;      /* our last transmission's start */
    bool reply_expected;         /* it asked for an answer that has not ended yet */
    hal_time_us_t last_activity; /* last character heard or sent (its end) */
    hal_time_us_t line_free;     /* the earliest start of our next transmission */
    hal_time_us_t deadline;      /* the state's timer */
    bool activity_seen;          /* a character since deadline was set */
    /* A status answer to send (from the receive path, sent in poll). */
    bool answer_pending;
    uint8_t answer_to;
    hal_time_us_t answer_at;
    fdl_active_stats_t stats;
} fdl_active_t;

void fdl_active_init(fdl_active_t *s, const fdl_active_cfg_t *cfg, hal_time_us_t now);
/* Offline -> Listen_Token: the station starts to take part in the ring. */
void fdl_active_start(fdl_active_t *s, hal_time_us_t now);
/* Leaves the ring at once (it stops taking tokens; its PS skips it): Offline. */
void fdl_active_stop(fdl_active_t *s, hal_time_us_t now);
/* Leaves the ring as a program that ends should: a station holding the token passes it on to
 * its NS first (no GAP request, no more message cycles; the pass checked and repeated as any),
 * then goes Offline; one that does not hold it goes Offline at once (its PS skips it after its
 * repeats). */
void fdl_active_leave(fdl_active_t *s, hal_time_us_t now);

/* A character was heard; t: its stop bit's end. */
void fdl_active_activity(fdl_active_t *s, hal_time_us_t t);
/* A valid telegram was heard (the octets as fdl_rx delivered them); first_t/end_t: its first
 * and last characters' ends. The user calls it for every telegram, its own replies too. */
void fdl_active_frame(fdl_active_t *s, const uint8_t *f, size_t len, hal_time_us_t first_t,
                      hal_time_us_t end_t);
/* The user put a telegram on the line from start to end; reply: an answer is expected. */
void fdl_active_sent(fdl_active_t *s, hal_time_us_t start, hal_time_us_t end, bool reply);
/* Runs the station's timers and its own transmissions; returns its next deadline. */
hal_time_us_t fdl_active_poll(fdl_active_t *s, hal_time_us_t now);

/* The user holds the token and may start a message cycle of this priority now (the line is
 * idle, TTH allows it). */
bool fdl_active_holds_token(const fdl_active_t *s);
bool fdl_active_may_start(const fdl_active_t *s, hal_time_us_t now, bool high);
/* When the line is idle enough for the user's next request. */
hal_time_us_t fdl_active_line_free(const fdl_active_t *s);
/* The user starts a message cycle (call before transmitting it). */
void fdl_active_cycle(fdl_active_t *s, bool high);
/* The user has nothing more for this visit: GAP maintenance, then the token is passed. */
void fdl_active_release(fdl_active_t *s, hal_time_us_t now);

bool fdl_active_in_las(const fdl_active_t *s, uint8_t address);
fdl_station_kind_t fdl_active_station(const fdl_active_t *s, uint8_t address);
const char *fdl_mac_state_name(fdl_mac_state_t st);
const char *fdl_station_kind_name(fdl_station_kind_t k);

#endif
