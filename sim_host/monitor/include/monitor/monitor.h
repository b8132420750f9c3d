/* A bus monitor: what a receive-only station learns from the telegrams on a line, the way a
 * commissioning engineer's analyser shows it — the live list (every station heard, active or
 * passive), each DP slave's master, DP state, configuration, user parameters and diagnosis as
 * the traffic shows them, the token ring, statistics per station, and the events worth a
 * person's attention.
 *
 * Pure: no I/O, no allocation, no threads; time is passed in (nanoseconds on the caller's
 * clock, never going back). Feed it whole telegrams (mon_telegram, from a capture or the
 * in-memory bus) or characters (mon_chars.h, from a tty, a PTY or a port of the virtual line);
 * call mon_idle when time passes without a telegram. Memory is fixed (sizeof(mon_t)), whatever
 * the line carries for however long: events are a ring, figures are counts and running sums.
 *
 * Nothing here transmits: the monitor never answers, so it can sit on a plant's bus. */
#ifndef MONITOR_MONITOR_H
#define MONITOR_MONITOR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define MON_STATIONS 128u     /* addresses 0..127 (127 only ever seen as a DA: broadcast) */
#define MON_EVENTS 512u       /* the newest events kept; older ones counted as dropped */
#define MON_EVENT_TEXT 120u
#define MON_PRM_MAX 244u      /* Set_Prm DU: 7 standard octets + up to 237 user octets */
#define MON_CFG_MAX 244u
#define MON_DIAG_MAX 244u
#define MON_IO_MAX 244u
#define MON_NO_MASTER 255u    /* a slave's master as its diagnosis says: none */
#define MON_MAX_GSD 16u       /* GSD files (one per ident) the caller may give */
/* A DP slave whose master gets this many requests in a row unanswered is taken as gone. */
#define MON_MISSING_IN_A_ROW 3u

/* What a station is, from what it sent. */
typedef enum mon_role {
    MON_ROLE_UNKNOWN = 0, /* only addressed so far, never heard */
    MON_ROLE_ACTIVE,      /* a master: sent a token or a request, or said so in FDL status */
    MON_ROLE_PASSIVE,     /* a slave: only ever answers */
} mon_role_t;

/* A DP slave's state as the traffic shows it (IEC 61158-6-3 DP slave state machine). */
typedef enum mon_dp_state {
    MON_DP_UNKNOWN = 0, /* no DP service seen yet */
    MON_DP_WAIT_PRM,    /* diagnosis asks for parameters, or a Set_Prm was refused */
    MON_DP_WAIT_CFG,    /* Set_Prm accepted, no Chk_Cfg yet */
    MON_DP_DATA_EXCH,   /* Data_Exchange answered with data */
} mon_dp_state_t;

/* min / mean / max of a duration, in ns. */
typedef struct mon_span {
    uint64_t n;
    uint64_t min_ns;
    uint64_t max_ns;
    uint64_t sum_ns;
} mon_span_t;

typedef struct mon_station {
    bool seen;           /* sent at least one telegram (not only addressed) */
    bool addressed;      /* some telegram was addressed to it */
    mon_role_t role;
    uint64_t first_ns;   /* first telegram from it */
    uint64_t last_ns;    /* last telegram from it */

    /* ---- as an active station: token ring ---- */
    bool in_ring;
    uint8_t next_station;  /* NS: DA of its last token */
    bool fdl_status_known; /* it answered Request FDL Status */
    uint8_t fdl_status;    /* the station type and state octet of that answer (FC 0x00/0x10/0x20/0x30) */
    uint64_t tokens_sent;
    uint64_t token_repeats;   /* the same token passed again: the successor did not take it */
    uint64_t last_token_ns;   /* its last token (not a repeat) */
    mon_span_t rotation;      /* from one of its tokens to its next (token rotation time) */
    uint64_t rotations_over_ttr;

    /* ---- as a requester (a master) ---- */
    uint64_t requests_sent;
    uint64_t repeats_sent;    /* FCB repeats: the same request again */
    uint64_t unanswered_sent; /* its requests that got no answer */

    /* ---- as a responder ---- */
    uint64_t requests_received;
    uint64_t answers;         /* any answer: SC, SD1/SD2/SD3 response */
    uint64_t missing;         /* requests to it that got no answer */
    uint32_t missing_in_a_row;
    uint64_t repeats_received;
    uint64_t rs;              /* FC RS: service not activated (SAP not served, locked out) */
    uint64_t rr;              /* FC RR: no resource */
    uint64_t ue;              /* user error */
    uint64_t garbled;         /* damaged telegrams whose SA could still be read as this station */
    mon_span_t tsdr;          /* station delay: the request's last character to the answer's first */
    uint64_t tsdr_below_min;  /* answered sooner than the min TSDR of its Set_Prm */
    uint64_t tsdr_over_max;   /* later than max_tsdr_bits (GSD) */
    uint64_t tsdr_over_slot;  /* later than the slot time */

    /* ---- as a DP slave ---- */
    bool dp;                  /* a DP service to it was seen */
    mon_dp_state_t dp_state;
    uint8_t master;           /* MON_NO_MASTER: none known (or its diagnosis says none) */
    uint8_t owner;            /* the last master it had (MON_NO_MASTER: never one) */
    bool ident_known;
    uint16_t ident;
    uint8_t prm[MON_PRM_MAX]; /* the last accepted Set_Prm DU */
    uint8_t prm_len;
    uint8_t cfg[MON_CFG_MAX]; /* the last accepted Chk_Cfg DU */
    uint8_t cfg_len;
    uint8_t diag[MON_DIAG_MAX]; /* the last Slave_Diag answer DU */
    uint8_t diag_len;
    uint64_t diag_changes;
    uint64_t stat_diag;       /* diagnosis answers with Stat_Diag set */
    uint8_t outputs[MON_IO_MAX]; /* the last Data_Exchange request DU */
    uint8_t out_len;
    uint8_t inputs[MON_IO_MAX];  /* the last Data_Exchange answer DU */
    uint8_t in_len;
    uint64_t dx_count;
    mon_span_t dx_cycle;      /* from one Data_Exchange request to it to the next */
    uint64_t last_dx_ns;
    uint32_t min_tsdr_bits;   /* from its Set_Prm (0: none seen) */
    uint32_t max_tsdr_bits;   /* from its GSD at the line's rate (0: none given) */
    uint32_t watchdog_ms;     /* from its Set_Prm (0: off) */

    /* the retry storm detector: repeats in the current second */
    uint64_t storm_window_ns;
    uint32_t storm_count;
    bool storm;

    /* internal: the last request to it (FCB when FCV was set, a hash of its octets), from whom,
     * and whether it went unanswered: a repeat is the same FCB again after no answer, or the
     * same request octets again */
    uint8_t last_req_sa;
    bool last_fcb_known;
    bool last_fcb;
    bool last_req_unanswered;
    uint32_t last_req_hash;
    uint64_t late_event_ns;   /* the last LATE_ANSWER event (at most one a second) */
    uint64_t prev_token_ns;   /* the token before last_token_ns */
    uint64_t token_received_ns; /* the last token another station passed to it */
} mon_station_t;

typedef enum mon_event_type {
    MON_EV_NEW_STATION = 0, /* station: heard for the first time */
    MON_EV_RING_ENTER,      /* station: passed its first token (or again after leaving) */
    MON_EV_RING_LEAVE,      /* station: a whole rotation went by without its token */
    MON_EV_LOST_TOKEN,      /* station: the one that claimed it; value: the silence in µs */
    MON_EV_DX_ENTER,        /* station: a slave answered Data_Exchange with data; other: master */
    MON_EV_DX_LEAVE,        /* station: left data exchange (the text says why) */
    MON_EV_MASTER_CHANGE,   /* station: slave; other: its new master; value: the one before
                             * (MON_NO_MASTER: its first) */
    MON_EV_STAT_DIAG,       /* station: its diagnosis has Stat_Diag set */
    MON_EV_DIAG_CHANGE,     /* station: its diagnosis octets changed */
    MON_EV_PRM_FAULT,       /* station: its diagnosis says Prm_Fault or Cfg_Fault */
    MON_EV_RETRY_STORM,     /* station: a slave that got value repeats in one second */
    MON_EV_LATE_ANSWER,     /* station: answered later than the slot time (value: TSDR in bit times) */
    MON_EV_NO_ANSWER,       /* station: MON_MISSING_IN_A_ROW requests in a row unanswered */
    MON_EV_ILLEGAL,         /* a telegram of no known form, SA 127, an address above 126 */
    MON_EV_DUPLICATE_TOKEN, /* station: passed a token while another station held it */
    MON_EV_COUNT
} mon_event_type_t;

typedef enum mon_level {
    MON_LEVEL_INFO = 0,
    MON_LEVEL_WARN,
    MON_LEVEL_ERROR,
} mon_level_t;

typedef struct mon_event {
    uint64_t seq; /* counts from 0; seq of the next one is mon_t.events_total */
    uint64_t t_ns;
    mon_event_type_t type;
    mon_level_t level;
    uint8_t station;
    uint8_t other;
    uint32_t value;
    char text[MON_EVENT_TEXT]; /* one line for a person: "slave 5 left data exchange: ..." */
} mon_event_t;

/* Counts over the whole line. */
typedef struct mon_line {
    uint64_t telegrams;       /* valid telegrams */
    uint64_t octets;          /* every octet, valid or not */
    uint64_t tokens;
    uint64_t requests;
    uint64_t answers;
    uint64_t short_acks;      /* SC */
    uint64_t broadcasts;      /* requests to DA 127 */
    uint64_t garbled;         /* octet runs that were no valid telegram */
    uint64_t illegal;         /* valid frames with SA 127 or a function no standard defines */
    uint64_t unanswered;
    uint64_t lost_tokens;
    uint64_t first_ns;
    uint64_t last_ns;
    uint64_t busy_ns;         /* sum of telegram durations (line load) */
} mon_line_t;

typedef struct mon_cfg {
    /* The line's rate: bit times (TSDR, slot time) need it; 0 = unknown, such figures are then
     * only kept in ns. */
    uint32_t baud;
    /* The telegram times are the line's own (in process, the virtual line with --timing, a
     * capture with true times): TSDR and the slot time are judged. False (a PTY, a USB adapter
     * that batches): they are shown "not measurable". */
    bool timing;
    /* Slot time and target rotation time in bit times (0: the DP profile's for baud; TTR 0:
     * rotations are not judged). */
    uint32_t tsl_bits;
    uint32_t ttr_bits;
    /* How long after a request's end its answer may still come (0: the slot time when
     * timing, else 200 ms). A live source sets it: the kernel and adapters deliver late. */
    uint64_t answer_wait_ns;
    /* The max TSDR the GSD files give for the line's rate, by ident: a slave whose ident
     * becomes known gets it as max_tsdr_bits. */
    struct {
        uint16_t ident;
        uint32_t max_tsdr_bits;
    } gsd[MON_MAX_GSD];
    size_t n_gsd;
    /* Repeats to one slave within one second that make a retry storm (0: 10). */
    uint32_t storm_repeats;
    /* Called for every event as it happens (may be NULL). */
    void (*on_event)(void *ctx, const mon_event_t *ev);
    /* Called with every telegram and every garbled run as it is taken in (a pcapng file
     * written as it goes); may be NULL. */
    void (*on_frame)(void *ctx, const uint8_t *f, size_t len, uint64_t t_start_ns, bool garbled);
    void *ctx;
} mon_cfg_t;

typedef struct mon {
    mon_cfg_t cfg;
    uint64_t slot_ns;      /* TSL in ns (from cfg) */
    mon_line_t line;
    mon_station_t st[MON_STATIONS];
    mon_event_t events[MON_EVENTS]; /* events[seq % MON_EVENTS] */
    uint64_t events_total;
    /* the request waiting for its answer */
    bool pending;
    uint8_t pend[16];      /* its first octets (header, SAPs) */
    uint8_t pend_len;
    uint8_t pend_sa, pend_da, pend_fc;
    uint8_t pend_dsap, pend_ssap;
    bool pend_saps;
    uint8_t pend_du[MON_IO_MAX]; /* its DU (after the SAP octets) */
    uint8_t pend_du_len;
    uint64_t pend_end_ns;
    /* the token ring */
    uint8_t holder;        /* who holds the token (the DA of the last token), 255: nobody known */
    uint8_t last_token_sa, last_token_da;
    bool last_was_token;
    uint64_t claim_ns;     /* the last claim after a lost token: the ring starts afresh */
    uint64_t last_garbled_ns; /* the last garbled run (line.garbled 0: none): maybe a token */
    uint64_t last_end_ns;  /* end of the last telegram (or garble) on the line */
    uint64_t wd_due_ns;    /* no slave's watchdog can run out before this (mon_idle) */
} mon_t;

void mon_init(mon_t *m, const mon_cfg_t *cfg);
/* One whole telegram as it was on the line: its first character began at t_start_ns, its last
 * ended at t_end_ns (equal when only one instant is known). Anything that is not exactly one
 * valid telegram is counted as garbled (as mon_garbled). */
void mon_telegram(mon_t *m, const uint8_t *f, size_t len, uint64_t t_start_ns, uint64_t t_end_ns);
/* Octets that formed no telegram (a collision, noise, a cut frame). */
void mon_garbled(mon_t *m, const uint8_t *f, size_t len, uint64_t t_ns);
/* Time passed without a telegram: a request's answer that is due and did not come, and a slave
 * in data exchange whose watchdog ran out (its master fell silent). Call it at least every few
 * milliseconds, also while telegrams come. */
void mon_idle(mon_t *m, uint64_t now_ns);

/* The event with this seq, or NULL when it is not held (too old, or not yet). */
const mon_event_t *mon_event(const mon_t *m, uint64_t seq);
/* How many events are no longer held. */
uint64_t mon_events_dropped(const mon_t *m);

const char *mon_role_name(mon_role_t r);           /* "active", "passive", "unknown" */
const char *mon_dp_state_name(mon_dp_state_t s);   /* "Wait_Prm", "Wait_Cfg", "Data_Exch", "-" */
const char *mon_event_name(mon_event_type_t t);    /* "new_station", "ring_enter", ... */
/* Mean of a span in ns (0 when empty). */
uint64_t mon_span_mean(const mon_span_t *s);

#endif
