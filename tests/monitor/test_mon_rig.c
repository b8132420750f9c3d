/* The monitor on the in-memory bus: one master with three DFP21B cards at 1.5 Mbit/s, and the
 * faults the rig injects (cable pulled, power cycle, drive fault, the master switched off so the
 * cards' watchdogs expire). Each check compares the monitor's live list, states, counters and
 * events with what the master and the cards did (their own state, the tap's own tally). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dfp21b/dfp21b.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "ring_mon.h"

static ring_mon_t r; /* large: keep it off the stack */

static const uint8_t cards[] = {10, 11, 12};
static const uint8_t owner[] = {2, 2, 2};
#define MASTER 2u
#define WD_MS 100u

static const mon_station_t *st(uint8_t a)
{
    return &r.mon.st[a];
}

static dp_master_t *master(void)
{
    return r.rr.m[0];
}

static rig_card_t *card(unsigned i)
{
    return &r.rr.rig.cards[i];
}

/* One master, three cards, in data exchange, and 100 ms more of it. */
static void one_master(void)
{
    ring_mon_init(&r, 1500000u, cards, 3);
    (void)ring_rig_add_master(&r.rr, MASTER, NULL, cards, 3, WD_MS);
    CHECK(ring_rig_settle(&r.rr, owner, 3000000u));
    ring_mon_run_ms(&r, 100);
}

static void check_slave_settled(unsigned i)
{
    uint8_t a = cards[i];
    const mon_station_t *s = st(a);
    const dp_master_slave_cfg_t *sc = &master()->slaves[i].cfg;
    CHECK_EQ(s->role, MON_ROLE_PASSIVE);
    CHECK(s->dp);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, MASTER);
    CHECK(s->ident_known);
    CHECK_EQ(s->ident, DFP21B_IDENT);
    CHECK_EQ(s->prm_len, sc->prm_len);
    CHECK(memcmp(s->prm, sc->prm, sc->prm_len) == 0);
    CHECK_EQ(s->cfg_len, sc->cfg_len);
    CHECK(memcmp(s->cfg, sc->cfg, sc->cfg_len) == 0);
    CHECK_EQ(s->watchdog_ms, WD_MS);
    uint8_t min_tsdr = sc->prm[DP_PRM_MIN_TSDR];
    CHECK_EQ(s->min_tsdr_bits, min_tsdr != 0u ? min_tsdr : FDL_MIN_TSDR_DEFAULT_BITS);
    /* the card's diagnosis: ready, watchdog on, master 2, ident 0x6003 */
    CHECK_EQ(s->diag_len, DP_DIAG_STD_LEN);
    CHECK_BYTES(s->diag, s->diag_len, 0x00, DP_DIAG2_ALWAYS_ONE | DP_DIAG2_WD_ON, 0x00, MASTER,
                0x60, 0x03);
    /* 3 PD out, 3 PD in (the parameter channel's 8 octets first) */
    CHECK_EQ(s->out_len, 14);
    CHECK_EQ(s->in_len, 14);
    CHECK(s->dx_count > 10u);
    CHECK_EQ(s->dx_cycle.n, s->dx_count - 1u);
    /* TSDR measured on every answer, within [min TSDR, slot time] */
    uint64_t bit_ns = 1000000000ull / 1500000u;
    CHECK_EQ(s->tsdr.n, s->answers);
    CHECK(s->tsdr.min_ns + bit_ns / 2u >= s->min_tsdr_bits * bit_ns);
    CHECK(s->tsdr.max_ns <= r.mon.slot_ns);
    CHECK_EQ(s->tsdr_below_min, 0);
    CHECK_EQ(s->tsdr_over_slot, 0);
    CHECK_EQ(s->missing, 0);
    CHECK_EQ(s->repeats_received, 0);
    CHECK_EQ(s->garbled, 0);
    CHECK_EQ(s->rs + s->rr + s->ue, 0);
    CHECK_EQ(s->requests_received, r.requests_to[a]);
    /* the run may stop between a request and its answer */
    bool in_flight = r.mon.pending && r.mon.pend_da == a;
    CHECK_EQ(s->answers + in_flight, r.requests_to[a]);
    CHECK_EQ(s->diag_changes, 1); /* Wait_Prm's diagnosis, then the one of a ready slave */
}

/* 1: the live list after start-up, exactly. */
static void test_settled(void)
{
    int failed0 = check_failed_;
    one_master();
    uint8_t live[MON_STATIONS];
    size_t n = ring_mon_live(&r, live, sizeof live);
    CHECK_BYTES(live, n, MASTER, 10, 11, 12);
    const mon_station_t *m = st(MASTER);
    CHECK_EQ(m->role, MON_ROLE_ACTIVE);
    CHECK(m->in_ring);
    CHECK_EQ(m->next_station, MASTER); /* alone: it passes the token to itself */
    CHECK(m->tokens_sent > 10u);
    CHECK_EQ(m->rotation.n + 1u, m->tokens_sent);
    CHECK_EQ(m->token_repeats, 0); /* alone, it passes to itself: never a repeat */
    CHECK_EQ(m->repeats_sent, 0);
    CHECK_EQ(m->unanswered_sent, 0);
    CHECK(!m->dp);
    for (unsigned i = 0; i < 3u; i++) {
        check_slave_settled(i);
    }
    /* nothing else was addressed but the GAP's free addresses (FDL status, never answered) */
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        CHECK(!st((uint8_t)a)->addressed || a == 10u || a == 11u || a == 12u);
    }
    const mon_line_t *l = &r.mon.line;
    CHECK_EQ(l->garbled, 0);
    CHECK_EQ(l->illegal, 0);
    CHECK_EQ(l->unanswered, 0);
    CHECK_EQ(l->lost_tokens, 0);
    /* events: the master first and in the ring, then per slave heard and in data exchange */
    CHECK(r.num_ev > 0u && r.ev[0].type == MON_EV_NEW_STATION && r.ev[0].station == MASTER);
    size_t enter = ring_mon_find(&r, 0, MON_EV_RING_ENTER, MASTER);
    CHECK(enter < r.num_ev);
    CHECK_EQ(ring_mon_count(&r, 0, MON_EV_RING_ENTER, MASTER), 1);
    for (unsigned i = 0; i < 3u; i++) {
        size_t heard = ring_mon_find(&r, 0, MON_EV_NEW_STATION, cards[i]);
        size_t dx = ring_mon_find(&r, 0, MON_EV_DX_ENTER, cards[i]);
        CHECK(enter < heard && heard < dx && dx < r.num_ev);
        CHECK_EQ(ring_mon_count(&r, 0, MON_EV_DX_ENTER, cards[i]), 1);
        CHECK_EQ(r.ev[dx].other, MASTER);
    }
    const mon_event_type_t never[] = {MON_EV_DX_LEAVE, MON_EV_NO_ANSWER, MON_EV_LOST_TOKEN,
                                      MON_EV_RING_LEAVE, MON_EV_ILLEGAL, MON_EV_LATE_ANSWER,
                                      MON_EV_RETRY_STORM, MON_EV_DUPLICATE_TOKEN,
                                      MON_EV_PRM_FAULT, MON_EV_STAT_DIAG};
    for (size_t k = 0; k < sizeof never / sizeof never[0]; k++) {
        CHECK_EQ(ring_mon_count_type(&r, 0, never[k]), 0);
    }
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, 0);
    }
}

/* Events for other stations than a from index from on: none expected (faults stay local). */
static unsigned events_of_others(size_t from, uint8_t a)
{
    unsigned n = 0;
    for (size_t i = from; i < r.num_ev; i++) {
        n += r.ev[i].station != a;
    }
    return n;
}

/* The events from index from on are exactly these types, all for station a. */
static void check_sequence(size_t from, uint8_t a, const mon_event_type_t *types, size_t n)
{
    CHECK_EQ(r.num_ev - from, n);
    for (size_t i = 0; i < n && from + i < r.num_ev; i++) {
        CHECK_STR(mon_event_name(r.ev[from + i].type), mon_event_name(types[i]));
        CHECK_EQ(r.ev[from + i].station, a);
    }
}

/* What the master's start-up of a slave in Wait_Prm shows: its diagnosis without a master, then
 * (the master's Set_Prm and Chk_Cfg, from its old owner: no master change) the diagnosis of a
 * ready slave, Data_Exchange. */
static const mon_event_type_t restart[] = {MON_EV_DIAG_CHANGE, MON_EV_DIAG_CHANGE,
                                           MON_EV_DX_ENTER};

/* 2a: the cable of card 11 pulled past its watchdog, then plugged in again. */
static void test_cable(void)
{
    int failed0 = check_failed_;
    one_master();
    const mon_station_t *s = st(11);
    uint64_t req0 = r.requests_to[11];
    uint64_t same0 = r.same_octets_to[11];
    uint64_t answers0 = s->answers;
    uint64_t diag0 = s->diag_changes;
    size_t ev0 = r.num_ev;
    rig_card_set_cable(card(1), false);
    ring_mon_run_ms(&r, 300);
    uint64_t sent = r.requests_to[11] - req0;
    CHECK(sent >= MON_MISSING_IN_A_ROW);
    /* every request while it was off the bus went unanswered, and each is counted once */
    CHECK_EQ(s->missing, sent);
    CHECK_EQ(s->missing_in_a_row, sent);
    CHECK_EQ(st(MASTER)->unanswered_sent, sent);
    CHECK_EQ(r.mon.line.unanswered, sent);
    CHECK_EQ(s->answers, answers0);
    CHECK_EQ(s->repeats_received, r.same_octets_to[11] - same0);
    CHECK(s->repeats_received >= 1u);
    CHECK_EQ(st(MASTER)->repeats_sent, s->repeats_received);
    size_t quiet = ring_mon_find(&r, ev0, MON_EV_NO_ANSWER, 11);
    size_t leave = ring_mon_find(&r, ev0, MON_EV_DX_LEAVE, 11);
    CHECK_EQ(quiet, ev0);
    CHECK_EQ(leave, ev0 + 1u);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_NO_ANSWER, 11), 1);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_DX_LEAVE, 11), 1);
    CHECK(quiet < r.num_ev && r.ev[quiet].other == MASTER);
    CHECK_EQ(s->dp_state, MON_DP_UNKNOWN);
    CHECK_EQ(events_of_others(ev0, 11), 0);
    /* back: Slave_Diag says Wait_Prm and no master, Set_Prm, Chk_Cfg, a ready diagnosis */
    size_t ev1 = r.num_ev;
    rig_card_set_cable(card(1), true);
    CHECK(ring_rig_settle(&r.rr, owner, 3000000u));
    ring_mon_run_ms(&r, 50);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, MASTER);
    CHECK_EQ(s->missing_in_a_row, 0);
    CHECK_EQ(s->diag_changes - diag0, 2);
    check_sequence(ev1, 11, restart, sizeof restart / sizeof restart[0]);
    CHECK_EQ(r.ev[ev1].other, MON_NO_MASTER); /* the diagnosis's master octet */
    CHECK_EQ(r.ev[ev1 + 1u].other, MASTER);
    CHECK_EQ(st(10)->missing + st(12)->missing, 0);
    CHECK_EQ(st(10)->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(st(12)->dp_state, MON_DP_DATA_EXCH);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

/* 2b: card 12 power-cycled: it answers again at once, in Wait_Prm. */
static void test_power_cycle(void)
{
    int failed0 = check_failed_;
    one_master();
    const mon_station_t *s = st(12);
    /* right after its answer: a request to it on the line would rightly go unanswered */
    uint64_t answers0 = s->answers;
    for (unsigned k = 0; k < 100000u && s->answers == answers0; k++) {
        ring_rig_run_us(&r.rr, 1);
    }
    size_t ev0 = r.num_ev;
    rig_card_power_cycle(card(2), rig_now_us(&r.rr.rig));
    ring_mon_run_ms(&r, 200);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, MASTER);
    /* its first Data_Exchange after the restart is refused (RS): it left, then the start-up */
    CHECK(ev0 < r.num_ev && r.ev[ev0].type == MON_EV_DX_LEAVE && r.ev[ev0].station == 12);
    CHECK(ev0 < r.num_ev && r.ev[ev0].value == MON_DP_WAIT_PRM);
    check_sequence(ev0 + 1u, 12, restart, sizeof restart / sizeof restart[0]);
    CHECK_EQ(s->rs, 1);
    CHECK_EQ(s->missing, 0);
    CHECK_EQ(s->repeats_received, r.same_octets_to[12]);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

/* 2c: a drive fault: the DFP21B reports it in status word 1 (bit 5, the fault number in the high
 * octet: the first PD after the 8 octets of the parameter channel), not in its diagnosis while
 * the diagnosis alarm is off (dfp21b_user_prm_default). The slave stays in data exchange. */
static void test_drive_fault(void)
{
    int failed0 = check_failed_;
    one_master();
    const mon_station_t *s = st(10);
    CHECK_EQ(s->inputs[9] & 0x20u, 0);
    uint64_t diag0 = s->diag_changes;
    size_t ev0 = r.num_ev;
    rig_card_inject_fault(card(0), 14);
    ring_mon_run_ms(&r, 100);
    CHECK_EQ(s->in_len, 14);
    CHECK_EQ(s->inputs[8], 14);
    CHECK_EQ(s->inputs[9] & 0x20u, 0x20);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->diag_changes, diag0);
    CHECK_EQ(r.num_ev, ev0);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

/* 2d: the master switched off: the line falls silent and each card's watchdog (100 ms) takes it
 * out of data exchange. The monitor hears nothing more, but knows the watchdog from Set_Prm. */
static void test_watchdog(void)
{
    int failed0 = check_failed_;
    one_master();
    size_t ev0 = r.num_ev;
    dp_master_stop(master());
    ring_mon_run_ms(&r, WD_MS / 2u);
    CHECK_EQ(r.num_ev, ev0); /* not yet */
    ring_mon_run_ms(&r, WD_MS);
    for (unsigned i = 0; i < 3u; i++) {
        CHECK_EQ(dp_slave_state(&card(i)->cs.card.dp), DP_STATE_WAIT_PRM);
        CHECK_EQ(st(cards[i])->dp_state, MON_DP_WAIT_PRM);
        CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_DX_LEAVE, cards[i]), 1);
        CHECK_EQ(st(cards[i])->missing, 0);
    }
    CHECK_EQ(r.num_ev, ev0 + 3u);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

int main(void)
{
    RUN_TEST(test_settled);
    RUN_TEST(test_cable);
    RUN_TEST(test_power_cycle);
    RUN_TEST(test_drive_fault);
    RUN_TEST(test_watchdog);
    return check_report();
}
