#include "sim_hal/memcan.h"

#include <string.h>

void memcan_init(memcan_t *bus)
{
    memset(bus, 0, sizeof *bus);
}

/* xorshift32: deterministic loss pattern for a given seed. */
static uint32_t next_random(memcan_t *bus)
{
    uint32_t x = bus->rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    bus->rng = x;
    return x;
}

static bool lose_this_one(memcan_t *bus)
{
    if (bus->drop_next > 0u) {
        bus->drop_next--;
        return true;
    }
    return bus->loss_permille > 0u && next_random(bus) % 1000u < bus->loss_permille;
}

static int memcan_send(void *ctx, const hal_can_frame_t *frame)
{
    memcan_node_t *n = ctx;
    memcan_t *bus = n->bus;
    if (frame == NULL || frame->id > HAL_CAN_ID_MASK || frame->len > HAL_CAN_MAX_DLC ||
        bus->len >= MEMCAN_QUEUE) {
        bus->send_refused++;
        return -1;
    }
    n->frames_sent++;
    bus->frames_sent++;
    if (n->offline || lose_this_one(bus)) {
        bus->frames_lost++;
        return 0; /* the sender cannot tell: nobody acknowledges on a real bus either */
    }
    memcan_pending_t *p = &bus->queue[(bus->head + bus->len) % MEMCAN_QUEUE];
    memset(p, 0, sizeof *p);
    p->frame.id = frame->id;
    p->frame.len = frame->len;
    memcpy(p->frame.data, frame->data, frame->len);
    p->sender = n->index;
    bus->len++;
    return 0;
}

static const hal_can_ops_t memcan_ops = {.send = memcan_send};

memcan_node_t *memcan_attach(memcan_t *bus, hal_can_rx_fn rx, void *ctx, hal_can_t *can_out)
{
    if (bus->num_nodes >= MEMCAN_MAX_NODES) {
        return NULL;
    }
    memcan_node_t *n = &bus->nodes[bus->num_nodes];
    memset(n, 0, sizeof *n);
    n->bus = bus;
    n->rx = rx;
    n->ctx = ctx;
    n->index = bus->num_nodes;
    bus->num_nodes++;
    if (can_out != NULL) {
        *can_out = (hal_can_t){.ops = &memcan_ops, .ctx = n};
    }
    return n;
}

size_t memcan_deliver(memcan_t *bus, size_t max_frames)
{
    size_t done = 0;
    while (bus->len > 0u && (max_frames == 0u || done < max_frames)) {
        /* Copy out first: a receiver may send, and the ring slot is then free for reuse. */
        memcan_pending_t p = bus->queue[bus->head];
        bus->head = (bus->head + 1u) % MEMCAN_QUEUE;
        bus->len--;
        for (uint8_t i = 0; i < bus->num_nodes; i++) {
            memcan_node_t *n = &bus->nodes[i];
            if (i == p.sender || n->offline) {
                continue;
            }
            n->frames_received++;
            if (n->rx != NULL) {
                n->rx(n->ctx, &p.frame);
            }
        }
        bus->frames_delivered++;
        done++;
    }
    return done;
}

void memcan_drop_next(memcan_t *bus, uint32_t n)
{
    bus->drop_next = n;
}

void memcan_set_loss(memcan_t *bus, uint32_t permille, uint32_t seed)
{
    bus->loss_permille = permille > 1000u ? 1000u : permille;
    bus->rng = seed != 0u ? seed : 0x9E3779B9u; /* xorshift must not start at 0 */
}
