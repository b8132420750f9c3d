/* Rings of masters with cards on the in-memory bus: the rig holds the cards and the first
 * master; further masters join as plain stations. A tap keeps the telegrams for the checks. */
#ifndef TESTS_RING_RING_RIG_H
#define TESTS_RING_RING_RIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rig/rig.h"

#define RING_MAX_MASTERS 8u
#define RING_TRACE_MAX 4096u

typedef struct ring_frame {
    uint64_t t_ns;
    uint8_t len;      /* octets kept in b */
    uint16_t full_len; /* octets on the line */
    uint8_t b[24];    /* the first octets */
} ring_frame_t;

typedef struct ring_rig {
    rig_t rig;
    dp_master_t *m[RING_MAX_MASTERS];
    dp_master_t extra[RING_MAX_MASTERS];
    membus_port_t *port[RING_MAX_MASTERS];
    unsigned num_masters;
    ring_frame_t trace[RING_TRACE_MAX];
    size_t trace_len;
    bool tracing;
    uint64_t tokens_seen;
    unsigned ring_events[16];
} ring_rig_t;

/* baud for all; cards at the given addresses (fixed rate), no masters yet. */
void ring_rig_init(ring_rig_t *rr, uint32_t baud, const uint8_t *cards, size_t num_cards);
/* A master at address with bus parameters bus (NULL: the DP profile) and its slaves (each a
 * DFP21B with 3 PD + parameter channel, watchdog wd_ms). */
dp_master_t *ring_rig_add_master(ring_rig_t *rr, uint8_t address, const fdl_bus_params_t *bus,
                                 const uint8_t *slaves, size_t num_slaves, uint32_t wd_ms);
void ring_rig_run_us(ring_rig_t *rr, uint64_t us);
/* The trace as text, one telegram per line ("DC 02 02"), from index from, at most n lines. */
size_t ring_rig_trace_text(const ring_rig_t *rr, size_t from, size_t n, char *out, size_t cap);
/* Number of telegrams in the trace whose octets start with prefix. */
size_t ring_rig_count(const ring_rig_t *rr, const uint8_t *prefix, size_t len);

/* A token from sa to da. */
bool ring_frame_is_token(const ring_frame_t *f, uint8_t da, uint8_t sa);
/* DA, SA (without the SAP bit) and FC of an SD1/SD2/SD3 telegram; false for a token or SC. */
bool ring_frame_addr(const ring_frame_t *f, uint8_t *da, uint8_t *sa, uint8_t *fc);
/* The end of the telegram's last character on the line. */
uint64_t ring_frame_end_ns(const ring_rig_t *rr, const ring_frame_t *f);
/* The trace with times (µs from the bus start) on stderr: what a failed check looks at. */
void ring_rig_dump(const ring_rig_t *rr, size_t from, size_t n);
/* Index of the first token from sa to da at or after from, or rr->trace_len. */
size_t ring_rig_find_token(const ring_rig_t *rr, size_t from, uint8_t da, uint8_t sa);
/* Requests or tokens from a station that does not hold the token, or replies to one, from
 * trace index from on (the holder: the DA of the last token). */
unsigned ring_rig_foreign_senders(const ring_rig_t *rr, size_t from);
/* A Data_Exchange request (SRD high, no SAP) from master to slave. */
bool ring_frame_is_data_exch(const ring_frame_t *f, uint8_t slave, uint8_t master);
/* Runs in steps of 1 ms until every running master is in the ring with the others in its LAS
 * and every card is in Data_Exchange with the master at cards_master[i] (0: not checked), at
 * most max_us. True when reached. */
bool ring_rig_settle(ring_rig_t *rr, const uint8_t *cards_master, uint64_t max_us);

#endif
