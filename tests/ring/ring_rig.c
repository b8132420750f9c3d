#include "ring_rig.h"

#include <stdio.h>
#include <string.h>

#include "dp_slave/fdl_wire.h"
#include "sim_stations/stations.h"

static void tap(void *ctx, uint64_t t_ns, const uint8_t *f, size_t len, bool local, uint32_t baud)
{
    (void)local;
    (void)baud;
    ring_rig_t *rr = ctx;
    if (len == FDL_SD4_LEN && f[0] == FDL_SD4) {
        rr->tokens_seen++;
    }
    if (!rr->tracing || rr->trace_len >= RING_TRACE_MAX) {
        return;
    }
    ring_frame_t *r = &rr->trace[rr->trace_len++];
    r->t_ns = t_ns;
    r->len = (uint8_t)(len > sizeof r->b ? sizeof r->b : len);
    r->full_len = (uint16_t)len;
    memcpy(r->b, f, r->len);
}

static void ring_event(void *ctx, const fdl_active_event_t *ev)
{
    ring_rig_t *rr = ctx;
    if ((unsigned)ev->type < sizeof rr->ring_events / sizeof rr->ring_events[0]) {
        rr->ring_events[ev->type]++;
    }
}

void ring_rig_init(ring_rig_t *rr, uint32_t baud, const uint8_t *cards, size_t num_cards)
{
    memset(rr, 0, sizeof *rr);
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .start_ns = 1000000u, .baud = baud};
    rig_init(&rr->rig, &rc);
    rig_tap_t t = {.ctx = rr, .frame = tap};
    (void)rig_add_tap(&rr->rig, &t);
    char err[256] = "";
    if (rig_open(&rr->rig, err, sizeof err) != 0) {
        fprintf(stderr, "rig_open: %s\n", err);
        return;
    }
    for (size_t i = 0; i < num_cards; i++) {
        card_options_t co = {.address = cards[i], .fixed_baud = baud, .strict_timing = true};
        if (rig_add_card(&rr->rig, &co, rig_now_us(&rr->rig)) == NULL) {
            fprintf(stderr, "no room for card %u\n", cards[i]);
        }
    }
    rr->tracing = true;
}

static bool takes(void *ctx, const membus_telegram_t *tg)
{
    dp_master_t *m = ctx;
    dp_master_whole_t w = {.data = tg->data, .len = (uint16_t)tg->len, .char_ns = tg->char_ns,
                           .first_t = membus_char_us(tg, 1),
                           .before_last_t = membus_char_us(tg, tg->len > 1 ? tg->len - 1 : 1),
                           .end_t = membus_char_us(tg, tg->len)};
    return dp_master_whole_clean(&m->rx, &w);
}

static bool rx_whole(void *ctx, const membus_telegram_t *tg)
{
    dp_master_whole_t w = {.data = tg->data, .len = (uint16_t)tg->len, .char_ns = tg->char_ns,
                           .first_t = membus_char_us(tg, 1),
                           .before_last_t = membus_char_us(tg, tg->len > 1 ? tg->len - 1 : 1),
                           .end_t = membus_char_us(tg, tg->len)};
    dp_master_rx_telegram(ctx, &w);
    return true;
}

dp_master_t *ring_rig_add_master(ring_rig_t *rr, uint8_t address, const fdl_bus_params_t *bus,
                                 const uint8_t *slaves, size_t num_slaves, uint32_t wd_ms)
{
    if (rr->num_masters >= RING_MAX_MASTERS) {
        return NULL;
    }
    dp_master_cfg_t mc = {.address = address, .baud = rr->rig.cfg.baud,
                          .strict_timing = true, .token_ring = true, .ring_event = ring_event,
                          .event_ctx = rr};
    if (bus != NULL) {
        mc.bus = *bus;
    }
    dp_master_t *m = &rr->extra[rr->num_masters];
    sim_station_t st = master_station(m);
    membus_port_t *p = membus_attach(&rr->rig.bus, &st, &mc.uart);
    if (p == NULL) {
        return NULL;
    }
    membus_whole_rx_t whole = {.ctx = m, .takes = takes, .rx = rx_whole};
    membus_set_whole_rx(p, &whole);
    dp_master_init(m, &mc, rig_now_us(&rr->rig));
    for (size_t i = 0; i < num_slaves; i++) {
        dp_master_slave_cfg_t sc = {.address = slaves[i]};
        sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, wd_ms,
                                                  dfp21b_user_prm_default,
                                                  sizeof dfp21b_user_prm_default);
        sc.cfg[0] = 0xF3; /* 3 PD + parameter channel */
        sc.cfg[1] = 0xF2;
        sc.cfg_len = 2;
        (void)dp_master_add_slave(m, &sc);
    }
    rr->m[rr->num_masters] = m;
    rr->port[rr->num_masters] = p;
    rr->num_masters++;
    return m;
}

void ring_rig_run_us(ring_rig_t *rr, uint64_t us)
{
    membus_run_for_us(&rr->rig.bus, us);
}

size_t ring_rig_trace_text(const ring_rig_t *rr, size_t from, size_t n, char *out, size_t cap)
{
    size_t used = 0;
    size_t lines = 0;
    out[0] = '\0';
    for (size_t i = from; i < rr->trace_len && lines < n; i++, lines++) {
        const ring_frame_t *f = &rr->trace[i];
        for (size_t k = 0; k < f->len && used + 4 < cap; k++) {
            used += (size_t)snprintf(out + used, cap - used, k ? " %02X" : "%02X", f->b[k]);
        }
        if (used + 2 < cap) {
            out[used++] = '\n';
            out[used] = '\0';
        }
    }
    return lines;
}

size_t ring_rig_count(const ring_rig_t *rr, const uint8_t *prefix, size_t len)
{
    size_t n = 0;
    for (size_t i = 0; i < rr->trace_len; i++) {
        if (rr->trace[i].len >= len && memcmp(rr->trace[i].b, prefix, len) == 0) {
            n++;
        }
    }
    return n;
}

bool ring_frame_is_token(const ring_frame_t *f, uint8_t da, uint8_t sa)
{
    return f->len == FDL_SD4_LEN && f->b[0] == FDL_SD4 && f->b[1] == da && f->b[2] == sa;
}

bool ring_frame_addr(const ring_frame_t *f, uint8_t *da, uint8_t *sa, uint8_t *fc)
{
    size_t at = 0;
    if ((f->b[0] == FDL_SD1 || f->b[0] == FDL_SD3) && f->len >= 4u) {
        at = 1;
    } else if (f->b[0] == FDL_SD2 && f->len >= 7u) {
        at = 4;
    } else {
        return false;
    }
    *da = f->b[at] & FDL_ADDR_MASK;
    *sa = f->b[at + 1u] & FDL_ADDR_MASK;
    *fc = f->b[at + 2u];
    return true;
}

uint64_t ring_frame_end_ns(const ring_rig_t *rr, const ring_frame_t *f)
{
    return f->t_ns + (uint64_t)hal_uart_char_ns(rr->rig.cfg.baud) * f->full_len;
}

void ring_rig_dump(const ring_rig_t *rr, size_t from, size_t n)
{
    char line[128];
    for (size_t i = from; i < rr->trace_len && i < from + n; i++) {
        (void)ring_rig_trace_text(rr, i, 1, line, sizeof line);
        fprintf(stderr, "    %4zu %12.3f %s", i, (double)rr->trace[i].t_ns / 1000.0, line);
    }
}

size_t ring_rig_find_token(const ring_rig_t *rr, size_t from, uint8_t da, uint8_t sa)
{
    for (size_t i = from; i < rr->trace_len; i++) {
        if (ring_frame_is_token(&rr->trace[i], da, sa)) {
            return i;
        }
    }
    return rr->trace_len;
}

static bool ring_complete(const ring_rig_t *rr, const uint8_t *cards_master)
{
    for (unsigned i = 0; i < rr->num_masters; i++) {
        const fdl_active_t *a = dp_master_ring(rr->m[i]);
        if (!rr->m[i]->running || a->state == FDL_MAC_OFFLINE) {
            continue; /* switched off, or off the bus (a duplicate address) */
        }
        if (!a->in_ring) {
            return false;
        }
        for (unsigned k = 0; k < rr->num_masters; k++) {
            const dp_master_t *o = rr->m[k];
            if (o->running && o->mac.state != FDL_MAC_OFFLINE &&
                !fdl_active_in_las(a, o->cfg.address)) {
                return false;
            }
        }
    }
    for (unsigned c = 0; c < rr->rig.num_cards; c++) {
        const dp_slave_t *s = &rr->rig.cards[c].cs.card.dp;
        if (cards_master[c] != 0u && (dp_slave_state(s) != DP_STATE_DATA_EXCH ||
                                      dp_slave_master(s) != cards_master[c])) {
            return false;
        }
    }
    return true;
}

bool ring_rig_settle(ring_rig_t *rr, const uint8_t *cards_master, uint64_t max_us)
{
    for (uint64_t t = 0; t < max_us; t += 1000u) {
        if (ring_complete(rr, cards_master)) {
            return true;
        }
        ring_rig_run_us(rr, 1000u);
    }
    return ring_complete(rr, cards_master);
}

unsigned ring_rig_foreign_senders(const ring_rig_t *rr, size_t from)
{
    unsigned bad = 0;
    int holder = -1;
    int passer = -1; /* repeats a token its successor did not take */
    for (size_t i = from; i < rr->trace_len; i++) {
        const ring_frame_t *f = &rr->trace[i];
        uint8_t da;
        uint8_t sa;
        uint8_t fc;
        if (f->b[0] == FDL_SD4) {
            bad += holder >= 0 && f->b[2] != holder && f->b[2] != passer;
            holder = f->b[1];
            passer = f->b[2];
        } else if (ring_frame_addr(f, &da, &sa, &fc) && holder >= 0) {
            bad += (fc & FDL_FC_REQUEST) != 0u ? sa != holder : da != holder;
            passer = -1;
        }
    }
    return bad;
}

bool ring_frame_is_data_exch(const ring_frame_t *f, uint8_t slave, uint8_t master)
{
    uint8_t da;
    uint8_t sa;
    uint8_t fc;
    return f->b[0] == FDL_SD2 && ring_frame_addr(f, &da, &sa, &fc) && da == slave &&
           sa == master && (f->b[4] & FDL_ADDR_EXT) == 0u && (fc == 0x5Du || fc == 0x7Du);
}
