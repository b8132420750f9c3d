#include "sim_hal/membus.h"

#include <string.h>

static int membus_set_baud(void *ctx, uint32_t baud)
{
    membus_port_t *p = ctx;
    if (baud == 0u) {
        return -1;
    }
    p->baud = baud;
    return 0;
}

static void enqueue(membus_t *bus, const membus_char_t *c)
{
    if (bus->queue_len >= MEMBUS_MAX_INFLIGHT) {
        bus->dropped_overflow++;
        return;
    }
    size_t i = bus->queue_len;
    while (i > 0u && bus->queue[i - 1u].t_end_ns > c->t_end_ns) {
        bus->queue[i] = bus->queue[i - 1u];
        i--;
    }
    bus->queue[i] = *c;
    bus->queue_len++;
}

static int membus_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    membus_port_t *p = ctx;
    membus_t *bus = p->bus;
    if (len == 0u || p->baud == 0u) {
        return -1;
    }
    if (p->silenced) {
        return 0;
    }
    hal_time_us_t now_us = (hal_time_us_t)(bus->now_ns / 1000u);
    int32_t wait_us = hal_time_diff(not_before, now_us);
    uint64_t start = bus->now_ns;
    if (wait_us > 0) {
        uint64_t nb = (bus->now_ns / 1000u + (uint64_t)wait_us) * 1000u;
        if (nb > start) {
            start = nb;
        }
    }
    uint64_t char_ns = hal_uart_char_ns(p->baud);
    uint64_t end = start + char_ns * len;
    bool collision = bus->line_busy_until_ns > start && bus->line_busy_sender != p->index;
    if (collision) {
        bus->collisions++;
        for (size_t i = 0; i < bus->queue_len; i++) {
            if (bus->queue[i].t_end_ns > start) {
                bus->queue[i].corrupt = true;
            }
        }
    }
    for (size_t i = 0; i < len; i++) {
        membus_char_t c = {
            .t_end_ns = start + char_ns * (i + 1u),
            .baud = p->baud,
            .byte = frame[i],
            .sender = p->index,
            .corrupt = collision && start + char_ns * (i + 1u) <= bus->line_busy_until_ns,
            .last_of_frame = i + 1u == len,
        };
        enqueue(bus, &c);
    }
    if (end > bus->line_busy_until_ns) {
        bus->line_busy_until_ns = end;
        bus->line_busy_sender = p->index;
    }
    bus->frames_sent++;
    if (bus->tap != NULL) {
        bus->tap(bus->tap_ctx, start, frame, len, true, p->baud);
    }
    return 0;
}

static const hal_uart_ops_t membus_uart_ops = {
    .set_baud = membus_set_baud,
    .transmit = membus_transmit,
};

void membus_init(membus_t *bus)
{
    memset(bus, 0, sizeof *bus);
}

membus_port_t *membus_attach(membus_t *bus, const sim_station_t *station, hal_uart_t *uart_out)
{
    if (bus->num_ports >= MEMBUS_MAX_STATIONS) {
        return NULL;
    }
    membus_port_t *p = &bus->ports[bus->num_ports];
    *p = (membus_port_t){.bus = bus, .station = *station, .index = bus->num_ports,
                         .deadline_ns = bus->now_ns};
    bus->num_ports++;
    uart_out->ops = &membus_uart_ops;
    uart_out->ctx = p;
    return p;
}

void membus_set_tap(membus_t *bus, sim_frame_tap_t tap, void *ctx)
{
    bus->tap = tap;
    bus->tap_ctx = ctx;
}

static void poll_port(membus_t *bus, membus_port_t *p)
{
    if (p->station.poll == NULL) {
        p->deadline_ns = UINT64_MAX;
        return;
    }
    hal_time_us_t now_us = (hal_time_us_t)(bus->now_ns / 1000u);
    hal_time_us_t next = p->station.poll(p->station.ctx, now_us);
    int32_t d = hal_time_diff(next, now_us);
    if (d < 0) {
        d = 0;
    }
    /* Round up to the next whole microsecond so a station is never polled before its deadline. */
    p->deadline_ns = ((bus->now_ns + 999u) / 1000u + (uint64_t)d) * 1000u;
    if (p->deadline_ns <= bus->now_ns) {
        p->deadline_ns = bus->now_ns + 1000u;
    }
}

void membus_run_until_ns(membus_t *bus, uint64_t t_ns)
{
    for (;;) {
        uint64_t next = t_ns;
        if (bus->queue_len > 0u && bus->queue[0].t_end_ns < next) {
            next = bus->queue[0].t_end_ns;
        }
        for (uint8_t i = 0; i < bus->num_ports; i++) {
            if (bus->ports[i].deadline_ns < next) {
                next = bus->ports[i].deadline_ns;
            }
        }
        if (next > bus->now_ns) {
            bus->now_ns = next;
        }
        bool did = false;
        if (bus->queue_len > 0u && bus->queue[0].t_end_ns <= bus->now_ns) {
            membus_char_t c = bus->queue[0];
            memmove(&bus->queue[0], &bus->queue[1], (bus->queue_len - 1u) * sizeof c);
            bus->queue_len--;
            hal_time_us_t t_us = (hal_time_us_t)(c.t_end_ns / 1000u);
            for (uint8_t i = 0; i < bus->num_ports; i++) {
                membus_port_t *p = &bus->ports[i];
                if (i == c.sender || p->silenced || p->station.rx_char == NULL) {
                    continue;
                }
                bool garbled = c.corrupt || p->baud != c.baud;
                p->station.rx_char(p->station.ctx, garbled ? (uint8_t)0xFFu : c.byte,
                                   garbled ? HAL_UART_RX_FRAMING_ERR : 0u, t_us);
                bus->chars_delivered++;
                if (c.last_of_frame) {
                    p->deadline_ns = bus->now_ns; /* let it work on the telegram at once */
                }
            }
            did = true;
        }
        for (uint8_t i = 0; i < bus->num_ports; i++) {
            if (bus->ports[i].deadline_ns <= bus->now_ns) {
                poll_port(bus, &bus->ports[i]);
                did = true;
            }
        }
        if (!did && bus->now_ns >= t_ns) {
            break;
        }
    }
}
