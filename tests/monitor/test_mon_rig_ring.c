/* The monitor on a token ring of masters with their cards on the in-memory bus: the ring's
 * members, rotations, a master switched off and on, the token holder dying (a lost token and its
 * claim), and a second master asking for a slave another owns (tests/ring/test_ring_faults.c
 * makes the same faults and checks the masters; here the monitor's view of them is checked). */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/fdl_wire.h"
#include "ring_mon.h"

static ring_mon_t r; /* large: keep it off the stack */

static const uint8_t cards[] = {10, 11, 12};
static const uint8_t owners[] = {2, 3, 4};
#define BAUD 1500000u

static const mon_station_t *st(uint8_t a)
{
    return &r.mon.st[a];
}

static const fdl_active_t *mac(unsigned i)
{
    return dp_master_ring(r.rr.m[i]);
}

/* Masters 2, 3, 4 with cards 10, 11, 12, settled, and 100 ms more. */
static void ring_of_three(void)
{
    ring_mon_init(&r, BAUD, cards, 3);
    for (unsigned i = 0; i < 3u; i++) {
        (void)ring_rig_add_master(&r.rr, owners[i], NULL, &cards[i], 1, 100);
    }
    CHECK(ring_rig_settle(&r.rr, owners, 3000000u));
    ring_mon_run_ms(&r, 100);
}

static void check_quiet_line(size_t from)
{
    const mon_event_type_t never[] = {MON_EV_LOST_TOKEN, MON_EV_ILLEGAL, MON_EV_LATE_ANSWER,
                                      MON_EV_RETRY_STORM, MON_EV_DUPLICATE_TOKEN};
    for (size_t k = 0; k < sizeof never / sizeof never[0]; k++) {
        CHECK_EQ(ring_mon_count_type(&r, from, never[k]), 0);
    }
    CHECK_EQ(r.mon.line.garbled, 0);
    CHECK_EQ(r.mon.line.illegal, 0);
}

/* 3a: three masters in the ring, each with its card. */
static void test_ring_settled(void)
{
    int failed0 = check_failed_;
    ring_of_three();
    uint8_t live[MON_STATIONS];
    size_t n = ring_mon_live(&r, live, sizeof live);
    CHECK_BYTES(live, n, 2, 3, 4, 10, 11, 12);
    for (unsigned i = 0; i < 3u; i++) {
        const mon_station_t *m = st(owners[i]);
        CHECK_EQ(m->role, MON_ROLE_ACTIVE);
        CHECK(m->in_ring);
        CHECK_EQ(m->next_station, owners[(i + 1u) % 3u]);
        CHECK(m->rotation.n > 10u);
        CHECK_EQ(m->rotation.n + 1u, m->tokens_sent);
        /* a token its successor did not take, passed again: as the master counted them */
        CHECK_EQ(m->token_repeats, mac(i)->stats.token_retries);
        CHECK_EQ(ring_mon_count(&r, 0, MON_EV_RING_ENTER, owners[i]), 1);
        CHECK_EQ(ring_mon_count(&r, 0, MON_EV_RING_LEAVE, owners[i]), 0);
        const mon_station_t *s = st(cards[i]);
        CHECK_EQ(s->role, MON_ROLE_PASSIVE);
        CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
        CHECK_EQ(s->master, owners[i]);
        CHECK_EQ(s->missing, 0);
        CHECK_EQ(ring_mon_count(&r, 0, MON_EV_DX_ENTER, cards[i]), 1);
        /* the run may stop between a request and its answer */
        bool in_flight = r.mon.pending && r.mon.pend_da == cards[i];
        CHECK_EQ(s->answers + in_flight, r.requests_to[cards[i]]);
    }
    /* the FDL status each master answered to the others' GAP: "master ready for the ring" */
    CHECK(st(3)->fdl_status_known && st(4)->fdl_status_known);
    CHECK_EQ(st(3)->fdl_status, 0x20);
    CHECK_EQ(st(4)->fdl_status, 0x20);
    CHECK_EQ(r.mon.line.unanswered, 0);
    CHECK_EQ(r.mon.line.lost_tokens, 0);
    check_quiet_line(0);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, 0);
    }
}

/* 3b: master 3 switched off past its card's watchdog, then on again. */
static void test_switched_off(void)
{
    int failed0 = check_failed_;
    ring_of_three();
    /* 2 holds the token: 3 is idle */
    for (unsigned k = 0; k < 100000u && !fdl_active_holds_token(mac(0)); k++) {
        ring_rig_run_us(&r.rr, 1);
    }
    uint64_t repeats2 = st(2)->token_repeats;
    uint32_t retries2 = mac(0)->stats.token_retries;
    size_t ev0 = r.num_ev;
    dp_master_stop(r.rr.m[1]);
    ring_mon_run_ms(&r, 300);
    /* 2 passed to 3 and repeated it twice (FDL_TOKEN_PASS_REPEATS), then skipped it; 4 (3 its
     * PS) refused 2's first token and took the repeat */
    CHECK_EQ(st(2)->token_repeats - repeats2, FDL_TOKEN_PASS_REPEATS + 1u);
    CHECK_EQ(st(2)->token_repeats - repeats2, mac(0)->stats.token_retries - retries2);
    CHECK_EQ(st(2)->next_station, 4);
    CHECK_EQ(st(4)->next_station, 2);
    CHECK(!st(3)->in_ring);
    CHECK(st(2)->in_ring && st(4)->in_ring);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_RING_LEAVE, 3), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_RING_LEAVE), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_RING_ENTER), 0);
    /* its card: nobody polls it, its watchdog of 100 ms takes it out of data exchange */
    CHECK_EQ(st(11)->dp_state, MON_DP_WAIT_PRM);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_DX_LEAVE, 11), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_DX_LEAVE), 1);
    /* 2's GAP asks 3 for its FDL status: the answers missing are counted once as an event */
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_NO_ANSWER, 3), 1);
    CHECK_EQ(r.num_ev, ev0 + 3u);
    check_quiet_line(ev0);
    /* on again: 2's GAP finds it, it is back in the ring and its card in data exchange */
    size_t ev1 = r.num_ev;
    dp_master_start(r.rr.m[1], rig_now_us(&r.rr.rig));
    membus_wake(r.rr.port[1]);
    CHECK(ring_rig_settle(&r.rr, owners, 3000000u));
    ring_mon_run_ms(&r, 100);
    CHECK(st(3)->in_ring);
    CHECK_EQ(st(2)->next_station, 3);
    CHECK_EQ(ring_mon_count(&r, ev1, MON_EV_RING_ENTER, 3), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev1, MON_EV_RING_ENTER), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev1, MON_EV_RING_LEAVE), 0);
    CHECK_EQ(st(11)->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(ring_mon_count(&r, ev1, MON_EV_DX_ENTER, 11), 1);
    check_quiet_line(ev1);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

/* Runs until master 3 holds the token and has sent a request. */
static void until_3_requests(void)
{
    for (unsigned k = 0; k < 400000u; k++) {
        ring_rig_run_us(&r.rr, 1);
        if (r.rr.trace_len > RING_TRACE_MAX / 2u) {
            r.rr.trace_len = 0;
        }
        const ring_frame_t *f = r.rr.trace_len > 0u ? &r.rr.trace[r.rr.trace_len - 1u] : NULL;
        uint8_t da;
        uint8_t sa;
        uint8_t fc;
        if (fdl_active_holds_token(mac(1)) && f != NULL && ring_frame_addr(f, &da, &sa, &fc) &&
            sa == 3u && (fc & FDL_FC_REQUEST) != 0u) {
            return;
        }
    }
}

/* 3c: master 3 dies holding the token: silence, 2 claims after its TTO (6 TSL + 2 x 2 TSL),
 * the ring goes on with 2 and 4. */
static void test_holder_dies(void)
{
    int failed0 = check_failed_;
    ring_of_three();
    until_3_requests();
    CHECK(fdl_active_holds_token(mac(1)));
    size_t ev0 = r.num_ev;
    dp_master_stop(r.rr.m[1]);
    ring_mon_run_ms(&r, 300);
    CHECK_EQ(r.mon.line.lost_tokens, 1);
    size_t lost = ring_mon_find(&r, ev0, MON_EV_LOST_TOKEN, 2);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_LOST_TOKEN), 1);
    CHECK(lost < r.num_ev);
    if (lost < r.num_ev) {
        uint64_t tto_us = (6u + 2u * 2u) * (uint64_t)mac(0)->cfg.bus.tsl_bits * 1000000u / BAUD;
        CHECK_EQ(r.ev[lost].other, 2); /* the claim: a token to itself */
        CHECK(r.ev[lost].value >= tto_us && r.ev[lost].value <= tto_us + 5u);
    }
    CHECK(!st(3)->in_ring);
    CHECK(st(2)->in_ring && st(4)->in_ring);
    /* the claim starts the ring afresh with 2 alone: after its two claim tokens it passes to
     * itself once more (a rotation without 3 and 4), then its GAP finds 4 again */
    size_t leave3 = ring_mon_find(&r, ev0, MON_EV_RING_LEAVE, 3);
    size_t leave4 = ring_mon_find(&r, ev0, MON_EV_RING_LEAVE, 4);
    size_t enter4 = ring_mon_find(&r, ev0, MON_EV_RING_ENTER, 4);
    CHECK(lost < leave3 && leave3 < leave4 && leave4 < enter4 && enter4 < r.num_ev);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_RING_LEAVE), 2);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_RING_ENTER), 1);
    CHECK_EQ(ring_mon_count_type(&r, ev0, MON_EV_DUPLICATE_TOKEN), 0);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_NO_ANSWER, 3), 1); /* 2's GAP asks it */
    CHECK_EQ(st(11)->dp_state, MON_DP_WAIT_PRM); /* its watchdog */
    CHECK_EQ(st(10)->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(st(12)->dp_state, MON_DP_DATA_EXCH);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

/* 3d: master 3 also lists card 10, which master 2 owns: the card stays with 2, in the monitor's
 * view as on the bus. (A Set_Prm the card refuses to another master: test_mon_rig_frames.c.) */
static void test_second_master(void)
{
    int failed0 = check_failed_;
    const uint8_t two[] = {10, 11};
    const uint8_t three[] = {12, 10};
    const uint8_t own[] = {2, 2, 3};
    const uint8_t own_first[] = {2, 2, 0};
    ring_mon_init(&r, BAUD, cards, 3);
    (void)ring_rig_add_master(&r.rr, 2, NULL, two, 2, 100);
    CHECK(ring_rig_settle(&r.rr, own_first, 3000000u));
    size_t ev0 = r.num_ev;
    (void)ring_rig_add_master(&r.rr, 3, NULL, three, 2, 100);
    CHECK(ring_rig_settle(&r.rr, own, 3000000u));
    ring_mon_run_ms(&r, 500);
    CHECK_EQ(dp_slave_master(&r.rr.rig.cards[0].cs.card.dp), 2);
    const mon_station_t *s = st(10);
    CHECK_EQ(s->master, 2);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_DX_LEAVE, 10), 0);
    CHECK_EQ(ring_mon_count(&r, ev0, MON_EV_MASTER_CHANGE, 10), 0);
    /* 3 asked for its diagnosis, which names 2 as the owner: it never sent Set_Prm */
    CHECK(r.req[3][10] > 0u);
    CHECK_EQ(r.set_prm[3][10], 0);
    CHECK_EQ(r.set_prm[2][10], 1);
    CHECK_EQ(s->rs, 0);
    CHECK_EQ(st(12)->master, 3);
    CHECK_EQ(st(12)->dp_state, MON_DP_DATA_EXCH);
    if (check_failed_ > failed0) {
        ring_mon_dump_events(&r, ev0);
    }
}

int main(void)
{
    RUN_TEST(test_ring_settled);
    RUN_TEST(test_switched_off);
    RUN_TEST(test_holder_dies);
    RUN_TEST(test_second_master);
    return check_report();
}
