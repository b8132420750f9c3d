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
    uint8_t len;
    uint8_t b[24]; /* the first octets */
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

#endif
