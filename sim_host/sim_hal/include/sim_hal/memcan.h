/* An in-memory CAN bus: any number of nodes in one process (hal/hal_can.h backend).
 *
 * Model: send() queues the frame; memcan_deliver() hands queued frames, in send order, to every
 * node except the sender (CAN has no self-reception unless asked for, like SocketCAN's default).
 * Frames sent from inside an rx callback join the end of the queue and are delivered in the same
 * memcan_deliver() call, so a request and its answer both arrive in one call. There is no time
 * and no arbitration: the order is the order of send() calls, so every run is the same.
 *
 * send() refuses what a CAN controller cannot put on the wire: an identifier above 0x7FF (only
 * 11-bit identifiers here) or more than 8 data octets; and a full queue (MEMCAN_QUEUE frames not
 * yet delivered), like a full transmit mailbox.
 *
 * Loss injection for tests: memcan_drop_next() loses the next n frames sent, memcan_set_loss()
 * loses frames at random with a fixed seed (deterministic). A lost frame reaches nobody.
 *
 * Structs are caller-owned; nothing is allocated. */
#ifndef SIM_HAL_MEMCAN_H
#define SIM_HAL_MEMCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"

#ifndef MEMCAN_MAX_NODES
#define MEMCAN_MAX_NODES 16u
#endif
#ifndef MEMCAN_QUEUE
#define MEMCAN_QUEUE 512u
#endif

typedef struct memcan memcan_t;

typedef struct memcan_node {
    memcan_t *bus;
    hal_can_rx_fn rx;
    void *ctx;
    uint8_t index;
    bool offline; /* pulled off the bus: its frames are lost, it hears nothing */
    uint64_t frames_sent;
    uint64_t frames_received;
} memcan_node_t;

typedef struct memcan_pending {
    hal_can_frame_t frame;
    uint8_t sender;
} memcan_pending_t;

struct memcan {
    memcan_node_t nodes[MEMCAN_MAX_NODES];
    uint8_t num_nodes;
    memcan_pending_t queue[MEMCAN_QUEUE]; /* ring */
    size_t head;
    size_t len;
    /* Loss injection. */
    uint32_t drop_next;
    uint32_t loss_permille;
    uint32_t rng;
    /* Counters. */
    uint64_t frames_sent;
    uint64_t frames_delivered; /* frames, not receptions */
    uint64_t frames_lost;
    uint64_t send_refused;
};

void memcan_init(memcan_t *bus);
/* A new node whose received frames go to rx(ctx, frame); *can_out is its HAL handle. NULL when
 * the bus is full. */
memcan_node_t *memcan_attach(memcan_t *bus, hal_can_rx_fn rx, void *ctx, hal_can_t *can_out);
/* Deliver queued frames, including those sent meanwhile by the receivers, until the queue is
 * empty or max_frames were delivered (a guard against two nodes answering each other forever;
 * 0 = no limit). Returns the number delivered. */
size_t memcan_deliver(memcan_t *bus, size_t max_frames);
static inline size_t memcan_pending(const memcan_t *bus) { return bus->len; }
/* Lose the next n frames sent (counted from now). */
void memcan_drop_next(memcan_t *bus, uint32_t n);
/* Lose each frame with probability permille/1000, from a generator seeded with seed. */
void memcan_set_loss(memcan_t *bus, uint32_t permille, uint32_t seed);

#endif
