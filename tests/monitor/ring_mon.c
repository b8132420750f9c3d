#include "ring_mon.h"

#include <stdio.h>
#include <string.h>

#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_uart.h"

static void on_event(void *ctx, const mon_event_t *ev)
{
    ring_mon_t *r = ctx;
    if (r->num_ev < MON_RIG_EVENTS) {
        r->ev[r->num_ev++] = (ring_mon_ev_t){.type = ev->type, .station = ev->station,
                                            .other = ev->other, .value = ev->value,
                                            .t_ns = ev->t_ns};
    }
}

/* A request (SD1/SD2/SD3 with the request bit): counted per DA, and whether its octets equal
 * the request before it to that DA. */
static void tally(ring_mon_t *r, const uint8_t *f, size_t len)
{
    ring_frame_t rf = {.len = (uint8_t)(len < 24u ? len : 24u), .full_len = (uint16_t)len};
    memcpy(rf.b, f, rf.len);
    uint8_t da;
    uint8_t sa;
    uint8_t fc;
    if (!ring_frame_addr(&rf, &da, &sa, &fc) || (fc & FDL_FC_REQUEST) == 0u || da >= 127u) {
        return;
    }
    r->requests_to[da]++;
    r->req[sa][da]++;
    if (rf.b[0] == FDL_SD2 && rf.len > 7u && (rf.b[4] & FDL_ADDR_EXT) != 0u &&
        rf.b[7] == DP_SAP_SET_PRM) {
        r->set_prm[sa][da]++;
    }
    if ((fc & FDL_FC_FCV) == 0u) {
        r->last_req_len[da] = 0; /* FCV 0 starts the FCB sequence again: no repeat */
        return;
    }
    if (r->last_req_len[da] == rf.len && memcmp(r->last_req[da], rf.b, rf.len) == 0) {
        r->same_octets_to[da]++;
    }
    memcpy(r->last_req[da], rf.b, rf.len);
    r->last_req_len[da] = rf.len;
}

static void tap(void *ctx, uint64_t t_ns, const uint8_t *f, size_t len, bool local, uint32_t baud)
{
    (void)local;
    ring_mon_t *r = ctx;
    uint64_t end = t_ns + (uint64_t)hal_uart_char_ns(baud) * len;
    mon_telegram(&r->mon, f, len, t_ns, end);
    tally(r, f, len);
}

void ring_mon_init(ring_mon_t *r, uint32_t baud, const uint8_t *cards, size_t num_cards)
{
    memset(r, 0, sizeof *r);
    /* the cards as ring_rig_init makes them, each with an emulated MOVIDRIVE (drive faults) */
    ring_rig_init(&r->rr, baud, NULL, 0);
    for (size_t i = 0; i < num_cards; i++) {
        card_options_t co = {.address = cards[i], .fixed_baud = baud, .strict_timing = true,
                             .inverter = CARD_INVERTER_SIM};
        if (rig_add_card(&r->rr.rig, &co, rig_now_us(&r->rr.rig)) == NULL) {
            fprintf(stderr, "no room for card %u\n", cards[i]);
        }
    }
    mon_cfg_t cfg = {.baud = baud, .timing = true, .on_event = on_event, .ctx = r};
    mon_init(&r->mon, &cfg);
    rig_tap_t t = {.ctx = r, .frame = tap};
    if (rig_add_tap(&r->rr.rig, &t) != 0) {
        fprintf(stderr, "no room for the monitor's tap\n");
    }
}

void ring_mon_run_ms(ring_mon_t *r, unsigned ms)
{
    for (unsigned i = 0; i < ms; i++) {
        ring_rig_run_us(&r->rr, 1000u);
        if (r->rr.trace_len > RING_TRACE_MAX / 2u) {
            r->rr.trace_len = 0; /* the monitor is what is checked here, not the trace */
        }
        mon_idle(&r->mon, rig_elapsed_ns(&r->rr.rig));
    }
}

size_t ring_mon_find(const ring_mon_t *r, size_t from, mon_event_type_t type, uint8_t station)
{
    for (size_t i = from; i < r->num_ev; i++) {
        if (r->ev[i].type == type && r->ev[i].station == station) {
            return i;
        }
    }
    return r->num_ev;
}

unsigned ring_mon_count(const ring_mon_t *r, size_t from, mon_event_type_t type, uint8_t station)
{
    unsigned n = 0;
    for (size_t i = from; i < r->num_ev; i++) {
        n += r->ev[i].type == type && r->ev[i].station == station;
    }
    return n;
}

unsigned ring_mon_count_type(const ring_mon_t *r, size_t from, mon_event_type_t type)
{
    unsigned n = 0;
    for (size_t i = from; i < r->num_ev; i++) {
        n += r->ev[i].type == type;
    }
    return n;
}

size_t ring_mon_live(const ring_mon_t *r, uint8_t *out, size_t cap)
{
    size_t n = 0;
    for (unsigned a = 0; a < MON_STATIONS && n < cap; a++) {
        if (r->mon.st[a].seen) {
            out[n++] = (uint8_t)a;
        }
    }
    return n;
}

void ring_mon_dump_events(const ring_mon_t *r, size_t from)
{
    for (size_t i = from; i < r->num_ev; i++) {
        const ring_mon_ev_t *e = &r->ev[i];
        fprintf(stderr, "    %4zu %12.3f ms %-15s st %3u other %3u value %u\n", i,
                (double)e->t_ns / 1e6, mon_event_name(e->type), e->station, e->other, e->value);
    }
}
