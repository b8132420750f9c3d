/* A ring run must not depend on how the in-memory bus delivers it: the telegram path (whole
 * telegrams, the octets' check worked out once for all listeners, a card that is not the
 * addressee left unpolled and asleep until a telegram concerns it, then brought up to date:
 * membus.h, rig.c) against the character path (every character to every station, every station
 * polled after every telegram). Three masters share 15 cards (loopback, and two with the
 * emulated drive, which are polled after every telegram either way); from power-up through
 * start-up, Data_Exchange and GAP maintenance, then faults (a card's cable pulled and plugged
 * back, a card power-cycled, a master stopped and started again, Global_Control), every
 * telegram with its time and octets, every card event and LED change, and the cards' and
 * masters' states after each step must be the same. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
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
    uint64_t card_events[DP_EV_ADDRESSED + 1]; /* by type: the faults did happen */
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
    trace_t *t = ctx;
    uint64_t v[] = {card, ev->type, ev->t, ev->old_state, ev->new_state, ev->master, ev->value};
    mix(t, v, sizeof v);
    if ((unsigned)ev->type <= DP_EV_ADDRESSED) {
        t->card_events[ev->type]++;
    }
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

/* The cards' own record: state, rate search, receiver, counters; the masters' view of them. */
static void mix_state(trace_t *t, const ring_rig_t *r)
{
    for (unsigned i = 0; i < r->rig.num_cards; i++) {
        const dp_slave_t *s = &r->rig.cards[i].cs.card.dp;
        uint64_t v[] = {s->state, s->baud_state, s->baud_deadline, s->line_active,
                        s->telegrams_for_me, s->wd_deadline, s->rx.have_last, s->rx.last_char_t,
                        s->rx.synced, s->rx.idle_before_ns, s->rx.frame_end_t,
                        s->rx.frame_len, s->rx.last_error, s->cfg.address};
        mix(t, v, sizeof v);
        mix(t, s->rx.error_count, sizeof s->rx.error_count);
    }
    for (unsigned m = 0; m < r->num_masters; m++) {
        for (unsigned i = 0; i < r->m[m]->num_slaves; i++) {
            uint64_t v[] = {m, i, r->m[m]->slaves[i].phase};
            mix(t, v, sizeof v);
        }
    }
    mix(t, r->ring_events, sizeof r->ring_events);
}

/* Runs us of bus time and records the states after it. */
static void step(ring_rig_t *r, trace_t *t, uint64_t us)
{
    ring_rig_run_us(r, us);
    mix_state(t, r);
}

/* The faults, at odd times so they fall anywhere in a rotation. */
static void faults(ring_rig_t *r, trace_t *t)
{
    rig_t *rig = &r->rig;
    step(r, t, 1237u);
    rig_card_set_cable(&rig->cards[3], false);
    step(r, t, 150013u); /* past the card's watchdog of 100 ms */
    rig_card_set_cable(&rig->cards[3], true);
    step(r, t, 200003u);
    rig_card_power_cycle(&rig->cards[5], rig_now_us(rig));
    step(r, t, 200117u);
    dp_master_stop(r->m[1]);
    step(r, t, 250071u);
    dp_master_start(r->m[1], rig_now_us(rig));
    membus_wake(r->port[1]);
    step(r, t, 400009u);
    dp_master_global_control(r->m[0], DP_GC_SYNC, 0);
    step(r, t, 30011u);
    dp_master_global_control(r->m[2], DP_GC_FREEZE, 0);
    step(r, t, 30029u);
    dp_master_global_control(r->m[0], DP_GC_UNSYNC | DP_GC_UNFREEZE, 0);
    step(r, t, 30047u);
    dp_master_global_control(r->m[1], DP_GC_CLEAR_DATA, 0);
    step(r, t, 100003u);
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
    step(r, t, RUN_US);
}

static void test_same_trace_both_paths(void)
{
    static const uint32_t rates[] = {12000000u, 1500000u};
    for (size_t i = 0; i < sizeof rates / sizeof rates[0]; i++) {
        run(0, rates[i], false);
        run(1, rates[i], true);
        CHECK_EQ(tr[0].hash, tr[1].hash);
        for (unsigned c = 0; c < CARDS; c++) {
            CHECK_EQ(dp_slave_state(&rr[0].rig.cards[c].cs.card.dp), DP_STATE_DATA_EXCH);
        }
        faults(&rr[0], &tr[0]);
        faults(&rr[1], &tr[1]);
        CHECK(rr[0].rig.bus.telegrams_whole > 0u);
        CHECK_EQ(rr[1].rig.bus.telegrams_whole, 0u);
        CHECK_EQ(tr[0].telegrams, tr[1].telegrams);
        CHECK_EQ(tr[0].items, tr[1].items);
        CHECK_EQ(tr[0].hash, tr[1].hash);
        for (unsigned c = 0; c < CARDS; c++) {
            CHECK_EQ(dp_slave_state(&rr[0].rig.cards[c].cs.card.dp), DP_STATE_DATA_EXCH);
        }
        CHECK_EQ(rr[0].rig.bus.collisions, 0u);
        /* the cards slept through most telegrams; the faults reached them */
        CHECK(rr[0].rig.bus.slept_through > 10u * rr[0].rig.bus.telegrams_whole);
        CHECK_EQ(rr[1].rig.bus.slept_through, 0u);
        CHECK(tr[0].card_events[DP_EV_WD_EXPIRED] >= 1u + CARDS / MASTERS);
        /* a card takes Global_Control from its own master only */
        CHECK_EQ(tr[0].card_events[DP_EV_GLOBAL_CONTROL], 4u * CARDS / MASTERS);
    }
}

int main(void)
{
    RUN_TEST(test_same_trace_both_paths);
    return check_report();
}
