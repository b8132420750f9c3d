/* The line's rules (line.h). */
#include "line/line.h"

#include <string.h>

#define DELIVER_CHUNK 512u

void line_init(line_t *l, unsigned n_stations, uint32_t baud, bool timing)
{
    memset(l, 0, sizeof *l);
    l->n_stations = n_stations > LINE_MAX_STATIONS ? LINE_MAX_STATIONS : n_stations;
    l->baud = baud;
    l->char_ns = line_char_ns(baud);
    l->timing = timing;
}

uint32_t line_char_ns(uint32_t baud)
{
    return baud == 0u ? 0u
                      : (uint32_t)(((uint64_t)LINE_CHAR_BITS * 1000000000ull + baud / 2u) / baud);
}

uint8_t line_garble(uint8_t a, uint8_t b)
{
    uint8_t x = (uint8_t)(a & b);
    if (x != a && x != b) {
        return x;
    }
    x = (uint8_t)~x;
    return x != a && x != b ? x : (uint8_t)0x55u;
}

static line_slot_t *slot(line_t *l, size_t i)
{
    return &l->q[(l->head + i) % LINE_QUEUE];
}

static void report_collision(line_t *l, uint64_t t_ns, uint32_t stations, uint32_t octets)
{
    l->collisions++;
    for (unsigned s = 0; s < l->n_stations; s++) {
        if ((stations & (1u << s)) != 0u) {
            l->st[s].collisions++;
        }
    }
    if (l->col_len == LINE_COLLISION_LOG) {
        l->col_lost++;
        return;
    }
    l->col[(l->col_head + l->col_len) % LINE_COLLISION_LOG] =
        (line_collision_t){.t_ns = t_ns, .stations = stations, .octets = octets};
    l->col_len++;
}

/* The first undelivered slot from's write can land on: after from's own characters (it cannot
 * drive two at once) and not one that had ended before the write arrived (the writer could have
 * heard it). */
static size_t first_overlap(line_t *l, uint32_t me, uint64_t now_ns)
{
    size_t p = 0;
    for (size_t i = 0; i < l->len; i++) {
        if ((slot(l, i)->drivers & me) != 0u) {
            p = i + 1u;
        }
    }
    while (p < l->len && slot(l, p)->t_end_ns <= now_ns) {
        p++;
    }
    return p;
}

bool line_write(line_t *l, unsigned from, const uint8_t *data, size_t len, uint64_t now_ns,
                uint64_t *start_ns)
{
    if (from >= l->n_stations || len == 0u) {
        return false;
    }
    const uint32_t me = 1u << from;
    line_station_stats_t *st = &l->st[from];
    st->tx_writes++;
    size_t p = first_overlap(l, me, now_ns);
    uint32_t others = 0;
    size_t k = 0;
    for (; k < len && p + k < l->len; k++) {
        line_slot_t *s = slot(l, p + k);
        others |= s->drivers;
        s->byte = line_garble(s->byte, data[k]);
        s->drivers |= me;
    }
    uint64_t t = l->busy_until_ns > now_ns ? l->busy_until_ns : now_ns;
    if (start_ns != NULL) {
        *start_ns = k > 0u ? slot(l, p)->t_end_ns - l->char_ns : t;
    }
    if (k > 0u) {
        report_collision(l, slot(l, p)->t_end_ns - l->char_ns, others | me, (uint32_t)k);
    }
    for (; k < len; k++) {
        if (l->len == LINE_QUEUE) {
            st->tx_dropped += len - k;
            len = k;
            break;
        }
        t += l->char_ns;
        *slot(l, l->len) = (line_slot_t){.t_end_ns = t, .drivers = me, .byte = data[k]};
        l->len++;
        l->busy_until_ns = t;
    }
    st->tx_octets += len;
    return others != 0u;
}

uint64_t line_next_due(const line_t *l, uint64_t now_ns)
{
    if (l->len == 0u) {
        return UINT64_MAX;
    }
    uint64_t t = l->q[l->head].t_end_ns;
    return !l->timing || t <= now_ns ? now_ns : t;
}

/* One chunk of due slots to every listener: each gets the characters it did not drive. */
static void deliver_chunk(line_t *l, const uint8_t *bytes, const uint32_t *drivers, size_t n,
                          line_deliver_fn *fn, void *ctx)
{
    uint8_t out[DELIVER_CHUNK];
    for (unsigned to = 0; to < l->n_stations; to++) {
        const uint32_t bit = 1u << to;
        if ((l->deaf & bit) != 0u) {
            continue;
        }
        size_t m = 0;
        for (size_t i = 0; i < n; i++) {
            if ((drivers[i] & bit) == 0u) {
                out[m++] = bytes[i];
            }
        }
        if (m == 0u) {
            continue;
        }
        size_t got = fn(ctx, to, out, m);
        if (got > m) {
            got = m;
        }
        l->st[to].rx_octets += got;
        l->st[to].rx_dropped += m - got;
    }
}

size_t line_deliver(line_t *l, uint64_t now_ns, line_deliver_fn *fn, void *ctx)
{
    size_t total = 0;
    for (;;) {
        uint8_t bytes[DELIVER_CHUNK];
        uint32_t drivers[DELIVER_CHUNK];
        size_t n = 0;
        while (n < DELIVER_CHUNK && l->len > 0u) {
            const line_slot_t *s = &l->q[l->head];
            if (l->timing && s->t_end_ns > now_ns) {
                break;
            }
            bytes[n] = s->byte;
            drivers[n] = s->drivers;
            n++;
            l->head = (l->head + 1u) % LINE_QUEUE;
            l->len--;
        }
        if (n == 0u) {
            return total;
        }
        deliver_chunk(l, bytes, drivers, n, fn, ctx);
        total += n;
    }
}

bool line_take_collision(line_t *l, line_collision_t *out)
{
    if (l->col_len == 0u) {
        return false;
    }
    *out = l->col[l->col_head];
    l->col_head = (l->col_head + 1u) % LINE_COLLISION_LOG;
    l->col_len--;
    return true;
}
