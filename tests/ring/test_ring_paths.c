/* A ring run must not depend on how the in-memory bus delivers it: the telegram path (whole
 * telegrams, the octets' check worked out once for all listeners, a card that is not the
 * addressee left unpolled: membus.h, rig.c) against the character path (every character to
 * every station, every station polled after every telegram). Three masters share 15 cards
 * (loopback, and two with the emulated drive, which are polled after every telegram either
 * way); from power-up through start-up, Data_Exchange and GAP maintenance, every telegram with
 * its time and octets, every card event and LED change, and the cards' states at the end must
 * be the same. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/fdl_wire.h"
#include "ring_rig.h"
#include "sim_stations/stations.h"

#define MASTERS 3u
#define CARDS 15u
#define RUN_US 300000u

typedef struct trace {
    uint64_t hash;
    uint64_t items;
    uint64_t telegrams;
} trace_t;

static ring_rig_t rr[2]; /* large: keep them off the stack */
static trace_t tr[2];

static void mix(trace_t *t, const void *p, size_t n)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++) {
        t->hash = (t->hash ^ b[i]) * 1099511628211ull;
    }
    t->items++;
}

static void on_frame(void *ctx, uint64_t t_ns, const uint8_t *frame, size_t len, bool local,
                     uint32_t baud)
{
    (void)local;
    trace_t *t = ctx;
    uint64_t v[] = {t_ns, len, baud};
    mix(t, v, sizeof v);
    mix(t, frame, len);
    t->telegrams++;
}

static void on_card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    uint64_t v[] = {card, ev->type, ev->t, ev->old_state, ev->new_state, ev->master, ev->value};
    mix(ctx, v, sizeof v);
}

static void on_led(void *ctx, unsigned card, hal_led_id_t led, hal_led_mode_t mode)
{
    uint64_t v[] = {card, led, mode};
    mix(ctx, v, sizeof v);
}

static void on_ring_event(void *ctx, const fdl_active_event_t *ev)
{
    uint64_t v[] = {ev->type};
    mix(ctx, v, sizeof v);
}

/* The cards' own record at the end: state, rate search, receiver, counters. */
static void mix_cards(trace_t *t, const ring_rig_t *r)
{
    for (unsigned i = 0; i < r->rig.num_cards; i++) {
        const dp_slave_t *s = &r->rig.cards[i].cs.card.dp;
        uint64_t v[] = {s->state, s->baud_state, s->baud_deadline, s->line_active,
                        s->telegrams_for_me, s->wd_deadline, s->rx.have_last, s->rx.last_char_t,
                        s->rx.synced, s->rx.idle_before_ns, s->rx.frame_end_t,
                        s->rx.frame_len};
        mix(t, v, sizeof v);
        mix(t, s->rx.error_count, sizeof s->rx.error_count);
    }
}

static void run(unsigned k, uint32_t baud, bool characters_only)
{
    ring_rig_t *r = &rr[k];
    trace_t *t = &tr[k];
    *t = (trace_t){.hash = 1469598103934665603ull};
    uint8_t cards[CARDS];
    for (unsigned i = 0; i < CARDS; i++) {
        cards[i] = (uint8_t)(10u + i);
    }
    /* the ring rig's cards: loopback; two more with the emulated drive are added below */
    ring_rig_init(r, baud, cards, CARDS - 2u);
    for (unsigned i = CARDS - 2u; i < CARDS; i++) {
        card_options_t co = {.address = cards[i], .fixed_baud = baud, .strict_timing = true,
                             .inverter = CARD_INVERTER_SIM};
        CHECK(rig_add_card(&r->rig, &co, rig_now_us(&r->rig)) != NULL);
    }
    r->rig.bus.characters_only = characters_only;
    rig_tap_t tap = {.ctx = t, .frame = on_frame, .card_event = on_card_event, .led = on_led,
                     .ring_event = on_ring_event};
    CHECK_EQ(rig_add_tap(&r->rig, &tap), 0);
    for (unsigned m = 0; m < MASTERS; m++) {
        uint8_t mine[CARDS];
        size_t n = 0;
        for (unsigned i = m; i < CARDS; i += MASTERS) {
            mine[n++] = cards[i];
        }
        CHECK(ring_rig_add_master(r, (uint8_t)(2u + m), NULL, mine, n, 100) != NULL);
    }
    ring_rig_run_us(r, RUN_US);
    mix_cards(t, r);
}

static void test_same_trace_both_paths(void)
{
    static const uint32_t rates[] = {12000000u, 1500000u};
    for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++) {
        run(0, rates[i], false);
        run(1, rates[i], true);
        CHECK(rr[0].rig.bus.telegrams_whole > 0u);
        CHECK_EQ(rr[1].rig.bus.telegrams_whole, 0u);
        CHECK_EQ(tr[0].telegrams, tr[1].telegrams);
        CHECK_EQ(tr[0].items, tr[1].items);
        CHECK_EQ(tr[0].hash, tr[1].hash);
        for (unsigned c = 0; c < CARDS; c++) {
            CHECK_EQ(dp_slave_state(&rr[0].rig.cards[c].cs.card.dp), DP_STATE_DATA_EXCH);
        }
        CHECK_EQ(rr[0].rig.bus.collisions, 0u);
    }
}

int main(void)
{
    RUN_TEST(test_same_trace_both_paths);
    return check_report();
}
