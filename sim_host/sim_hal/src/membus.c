#include "sim_hal/membus.h"

#include <stddef.h>
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

static membus_whole_t *whole_in_flight(membus_t *bus)
{
    membus_whole_t *w = &bus->whole[bus->whole_slot];
    return w->active ? w : NULL;
}

static uint64_t whole_end(const membus_whole_t *w)
{
    return w->start_ns + (uint64_t)w->char_ns * w->len;
}

/* The telegram goes on as characters from here: none of them has reached anyone yet. */
static void split(membus_t *bus, membus_whole_t *w)
{
    w->active = false;
    bus->telegrams_split++;
    for (uint16_t i = 0; i < w->len; i++) {
        membus_char_t c = {
            .t_end_ns = w->start_ns + (uint64_t)w->char_ns * (i + 1u),
            .baud = w->baud,
            .byte = w->data[i],
            .sender = w->sender,
            .last_of_frame = i + 1u == w->len,
        };
        enqueue(bus, &c);
    }
}

static void put_characters(membus_t *bus, const membus_port_t *p, const uint8_t *frame,
                           size_t len, uint64_t start, bool collision)
{
    uint64_t char_ns = hal_uart_char_ns(p->baud);
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
}

/* Alone on a quiet line: the telegram may go whole (the listeners are asked later). */
static void put_whole(membus_t *bus, const membus_port_t *p, const uint8_t *frame, size_t len,
                      uint64_t start)
{
    bus->whole_slot ^= 1u; /* the other slot may be in the middle of its delivery */
    membus_whole_t *w = &bus->whole[bus->whole_slot];
    w->active = true;
    w->asked = false;
    w->sender = p->index;
    w->baud = p->baud;
    w->char_ns = hal_uart_char_ns(p->baud);
    w->start_ns = start;
    w->len = (uint16_t)len;
    w->memo = 0;
    memcpy(w->data, frame, len);
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
    membus_whole_t *w = whole_in_flight(bus);
    if (w != NULL) {
        split(bus, w); /* two transmissions overlap or follow closely: characters decide */
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
    uint64_t end = start + (uint64_t)hal_uart_char_ns(p->baud) * len;
    bool collision = bus->line_busy_until_ns > start && bus->line_busy_sender != p->index;
    if (collision) {
        bus->collisions++;
        for (size_t i = 0; i < bus->queue_len; i++) {
            if (bus->queue[i].t_end_ns > start) {
                bus->queue[i].corrupt = true;
            }
        }
    }
    if (!bus->characters_only && bus->queue_len == 0u && !collision &&
        len <= MEMBUS_TELEGRAM_MAX) {
        put_whole(bus, p, frame, len, start);
    } else {
        put_characters(bus, p, frame, len, start, collision);
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
    membus_catch_up(p);
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

void membus_set_whole_rx(membus_port_t *port, const membus_whole_rx_t *whole)
{
    port->whole = *whole;
}

static bool listens(const membus_port_t *p, uint8_t sender)
{
    return p->index != sender && !p->silenced && p->station.rx_char != NULL;
}

static membus_telegram_t view_of(membus_whole_t *w)
{
    return (membus_telegram_t){.data = w->data, .len = w->len, .start_ns = w->start_ns,
                               .char_ns = w->char_ns, .baud = w->baud, .memo = &w->memo};
}

void membus_set_key(membus_t *bus, membus_key_fn key, void *ctx)
{
    bus->key = key;
    bus->key_ctx = ctx;
}

void membus_sleep(membus_port_t *port, uint8_t key)
{
    if (port->whole.catch_up == NULL || port->asleep) {
        return;
    }
    port->asleep = true;
    port->key = key;
    /* called while the telegram whole_seq + 1 is delivered, which the station has taken */
    port->slept_after = port->bus->whole_seq + 1u;
    port->bus->sleepers++;
}

void membus_catch_up(membus_port_t *port)
{
    if (!port->asleep) {
        return;
    }
    membus_t *bus = port->bus;
    port->asleep = false;
    bus->sleepers--;
    uint64_t missed = bus->whole_seq - port->slept_after;
    if (missed == 0u) {
        return;
    }
    membus_telegram_t last = view_of(&bus->past[bus->whole_seq % 2u]);
    membus_telegram_t before = view_of(&bus->past[(bus->whole_seq - 1u) % 2u]);
    port->whole.catch_up(port->whole.ctx, &last, missed > 1u ? &before : NULL);
}

static void catch_up_all(membus_t *bus)
{
    for (uint8_t i = 0; i < bus->num_ports && bus->sleepers > 0u; i++) {
        membus_catch_up(&bus->ports[i]);
    }
}

/* A sleeper the telegram does not concern (it would take it, at its rate, and stay as it is). */
static bool sleeps_through(const membus_port_t *p, const membus_whole_t *w)
{
    return p->asleep && w->key != MEMBUS_KEY_ALL && w->key != p->key && p->baud == w->baud;
}

/* The end of the first character: every listener takes the telegram whole, or it is split. */
static void ask_listeners(membus_t *bus, membus_whole_t *w)
{
    membus_telegram_t tg = view_of(w);
    w->key = bus->key != NULL ? bus->key(bus->key_ctx, &tg) : MEMBUS_KEY_ALL;
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        membus_port_t *p = &bus->ports[i];
        if (!listens(p, w->sender) || sleeps_through(p, w)) {
            continue;
        }
        membus_catch_up(p);
        if (p->whole.rx == NULL || p->baud != w->baud || !p->whole.takes(p->whole.ctx, &tg)) {
            split(bus, w);
            return;
        }
    }
    w->asked = true;
}

static void deliver_whole(membus_t *bus, membus_whole_t *w)
{
    w->active = false;
    bus->telegrams_whole++;
    membus_telegram_t tg = view_of(w);
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        membus_port_t *p = &bus->ports[i];
        if (!listens(p, w->sender)) {
            continue;
        }
        bus->chars_delivered += w->len;
        if (p->asleep) {
            bus->slept_through++;
            continue; /* asked: it sleeps through this one (ask_listeners woke the others) */
        }
        bool poll = p->whole.rx(p->whole.ctx, &tg);
        if (poll) {
            p->deadline_ns = bus->now_ns; /* let it work on the telegram at once */
        }
    }
    /* kept for the sleepers' catch-up; the slot itself is written again two telegrams on */
    bus->whole_seq++;
    if (bus->sleepers > 0u) {
        membus_whole_t *past = &bus->past[bus->whole_seq % 2u];
        memcpy(past, w, offsetof(membus_whole_t, data) + w->len);
    }
}

static void deliver_char(membus_t *bus)
{
    membus_char_t c = bus->queue[0];
    memmove(&bus->queue[0], &bus->queue[1], (bus->queue_len - 1u) * sizeof c);
    bus->queue_len--;
    hal_time_us_t t_us = (hal_time_us_t)(c.t_end_ns / 1000u);
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        membus_port_t *p = &bus->ports[i];
        if (i == c.sender || p->silenced || p->station.rx_char == NULL) {
            continue;
        }
        membus_catch_up(p);
        bool garbled = c.corrupt || p->baud != c.baud;
        p->station.rx_char(p->station.ctx, garbled ? (uint8_t)0xFFu : c.byte,
                           garbled ? HAL_UART_RX_FRAMING_ERR : 0u, t_us);
        bus->chars_delivered++;
        if (c.last_of_frame) {
            p->deadline_ns = bus->now_ns; /* let it work on the telegram at once */
        }
    }
}

static uint64_t next_event(const membus_t *bus, uint64_t t_ns)
{
    uint64_t next = t_ns;
    if (bus->queue_len > 0u && bus->queue[0].t_end_ns < next) {
        next = bus->queue[0].t_end_ns;
    }
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        if (bus->ports[i].deadline_ns < next) {
            next = bus->ports[i].deadline_ns;
        }
    }
    return next;
}

/* The whole telegram before the other events (next): asked at the end of its first character
 * when nothing comes earlier, split when something comes before its end. False: it has gone
 * on as characters. */
static bool whole_first(membus_t *bus, membus_whole_t *w, uint64_t next)
{
    uint64_t first_end = w->start_ns + w->char_ns;
    if (!w->asked && next >= first_end) {
        if (first_end > bus->now_ns) {
            bus->now_ns = first_end;
        }
        ask_listeners(bus, w);
    }
    if (w->active && w->asked && next < whole_end(w)) {
        /* something happens while its characters come in: they must have come */
        split(bus, w);
    }
    return w->active;
}

/* One step at the next event. False when there was nothing to do at or before t_ns. */
static bool step(membus_t *bus, uint64_t t_ns)
{
    uint64_t next = next_event(bus, t_ns);
    membus_whole_t *w = whole_in_flight(bus);
    if (w != NULL && !whole_first(bus, w, next)) {
        return true; /* decide again: the split's first character may be due now */
    }
    if (w != NULL && w->asked && whole_end(w) < next) {
        next = whole_end(w);
    }
    if (next > bus->now_ns) {
        bus->now_ns = next;
    }
    bool did = false;
    if (w != NULL && w->asked && whole_end(w) <= bus->now_ns) {
        deliver_whole(bus, w);
        did = true;
    } else if (bus->queue_len > 0u && bus->queue[0].t_end_ns <= bus->now_ns) {
        deliver_char(bus);
        did = true;
    }
    for (uint8_t i = 0; i < bus->num_ports; i++) {
        if (bus->ports[i].deadline_ns <= bus->now_ns) {
            poll_port(bus, &bus->ports[i]);
            did = true;
        }
    }
    return did || bus->now_ns < t_ns;
}

void membus_run_until_ns(membus_t *bus, uint64_t t_ns)
{
    while (step(bus, t_ns)) {
    }
    catch_up_all(bus); /* the caller may look at any station now */
}
