/* The token ring where timing is against it (a review's findings, each a case that failed):
 * two masters whose lost-token time-outs end together (a claim race), a message retry limit of
 * 0 while a master joins, a newcomer whose first-heard station leaves while it listens, and bus
 * parameters whose time-outs do not fit the stations' 32-bit microsecond timers. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "ring_rig.h"

static ring_rig_t rr; /* large: keep it off the stack */

static const fdl_active_t *mac(unsigned i)
{
    return dp_master_ring(rr.m[i]);
}

/* Master 3 starts at once, master 2 delay_us later: with TTO = (6 + 2 TS) TSL both time-outs
 * end in the same microsecond when delay_us is 2 TSL. Both claim, their tokens collide; each
 * hears characters while it holds the token and no answer is due, drops it, and the staggered
 * time-outs then give the token to 2 alone, which lets 3 in. */
static void claim_race_at(uint32_t baud, uint64_t delay_us)
{
    int failed0 = check_failed_;
    const uint8_t cards[] = {100, 101};
    ring_rig_init(&rr, baud, cards, 2);
    (void)ring_rig_add_master(&rr, 3, NULL, &cards[0], 1, 100);
    ring_rig_run_us(&rr, delay_us);
    (void)ring_rig_add_master(&rr, 2, NULL, &cards[1], 1, 100);
    const uint8_t owners[] = {3, 2};
    CHECK(ring_rig_settle(&rr, owners, 2000000u));
    CHECK(mac(0)->stats.double_tokens + mac(1)->stats.double_tokens >= 1u);
    uint64_t collisions = rr.rig.bus.collisions;
    ring_rig_run_us(&rr, 200000u);
    CHECK_EQ(rr.rig.bus.collisions, collisions); /* none once the ring stands */
    CHECK(fdl_active_in_las(mac(0), 2) && fdl_active_in_las(mac(1), 3));
    if (check_failed_ != failed0) {
        fprintf(stderr, "    claim race at %u bit/s, delay %llu us\n", baud,
                (unsigned long long)delay_us);
    }
}

static void test_claim_race(void)
{
    check_test_name_ = "claim_race";
    claim_race_at(1500000u, 400u); /* 2 TSL = 600 bit at 1.5 Mbit/s */
    claim_race_at(12000000u, 166u); /* 2 TSL = 2000 bit at 12 Mbit/s */
}

/* With no message retries the ring still takes a newcomer: a station refuses a new PS's first
 * token, and token passes are repeated whatever the message retry limit. */
static void test_retry_zero_join(void)
{
    check_test_name_ = "retry_zero_join";
    const uint8_t cards[] = {10, 11, 12};
    ring_rig_init(&rr, 1500000u, cards, 3);
    fdl_bus_params_t bp;
    fdl_bus_params_default(&bp, 1500000u, FDL_BUS_PROFILE_DP);
    bp.max_retry = 0;
    bp.gap_factor = 1;
    bp.hsa = 8;
    (void)ring_rig_add_master(&rr, 2, &bp, &cards[0], 1, 100);
    (void)ring_rig_add_master(&rr, 5, &bp, &cards[1], 1, 100);
    const uint8_t two[] = {2, 5, 0};
    CHECK(ring_rig_settle(&rr, two, 3000000u));
    unsigned failed = rr.ring_events[FDL_EV_PASS_FAILED];
    (void)ring_rig_add_master(&rr, 3, &bp, &cards[2], 1, 100);
    const uint8_t three[] = {2, 5, 3};
    CHECK(ring_rig_settle(&rr, three, 3000000u));
    ring_rig_run_us(&rr, 300000u);
    CHECK_EQ(rr.ring_events[FDL_EV_PASS_FAILED], failed); /* nobody skipped */
    CHECK(mac(2)->in_ring && fdl_active_in_las(mac(0), 3) && fdl_active_in_las(mac(1), 3));
    CHECK_EQ(rr.rig.bus.collisions, 0);
}

/* A newcomer counts rotations by the tokens to a lower address, whoever passes them: the
 * station it heard first may leave while it listens. */
static void test_listen_first_station_leaves(void)
{
    check_test_name_ = "listen_first_station_leaves";
    const uint8_t cards[] = {10, 11, 12};
    ring_rig_init(&rr, 1500000u, cards, 3);
    (void)ring_rig_add_master(&rr, 2, NULL, &cards[0], 1, 100);
    (void)ring_rig_add_master(&rr, 4, NULL, &cards[1], 1, 100);
    const uint8_t two[] = {2, 4, 0};
    CHECK(ring_rig_settle(&rr, two, 3000000u));
    dp_master_t *m3 = ring_rig_add_master(&rr, 3, NULL, &cards[2], 1, 100);
    uint64_t tokens0 = rr.tokens_seen;
    for (unsigned k = 0; k < 100000u && rr.tokens_seen == tokens0; k++) {
        ring_rig_run_us(&rr, 1);
    }
    /* the token 3 heard first came from 2 or 4: that one leaves */
    bool from_two = rr.trace_len > 0 && rr.trace[rr.trace_len - 1u].b[2] == 2u;
    dp_master_stop(rr.m[from_two ? 0u : 1u]);
    ring_rig_run_us(&rr, 3000000u);
    CHECK(m3->mac.state != FDL_MAC_LISTEN_TOKEN);
    CHECK(m3->mac.in_ring);
    CHECK_EQ(rr.rig.cards[2].cs.card.dp.state, DP_STATE_DATA_EXCH);
    CHECK_EQ(rr.rig.bus.collisions, 0);
}

/* A master that leaves on its first token visit hands the token back to a PS that refuses a
 * new station's first token: the leaver repeats the pass like any, so nobody waits for the
 * lost-token time-out. */
static void test_leave_on_first_visit(void)
{
    check_test_name_ = "leave_on_first_visit";
    const uint8_t cards[] = {10, 11};
    ring_rig_init(&rr, 1500000u, cards, 2);
    fdl_bus_params_t bp;
    fdl_bus_params_default(&bp, 1500000u, FDL_BUS_PROFILE_DP);
    bp.gap_factor = 1;
    bp.hsa = 8;
    (void)ring_rig_add_master(&rr, 2, &bp, &cards[0], 1, 100);
    const uint8_t one[] = {2, 0};
    CHECK(ring_rig_settle(&rr, one, 3000000u));
    dp_master_t *m3 = ring_rig_add_master(&rr, 3, &bp, &cards[1], 1, 100);
    for (unsigned k = 0; k < 2000000u && !fdl_active_holds_token(&m3->mac); k++) {
        ring_rig_run_us(&rr, 1);
    }
    CHECK(fdl_active_holds_token(&m3->mac));
    CHECK_EQ(m3->mac.stats.tokens_received, 1);
    uint32_t claims = mac(0)->stats.claims;
    dp_master_leave(m3);
    membus_wake(rr.port[1]);
    ring_rig_run_us(&rr, 200000u);
    CHECK(dp_master_left(m3));
    CHECK_EQ(m3->mac.state, FDL_MAC_OFFLINE);
    CHECK_EQ(mac(0)->stats.claims, claims); /* the token came back: no claim */
    CHECK(mac(0)->stats.tokens_to_self > 0u && !fdl_active_in_las(mac(0), 3));
    CHECK_EQ(rr.rig.cards[0].cs.card.dp.state, DP_STATE_DATA_EXCH);
    CHECK_EQ(rr.rig.bus.collisions, 0);
}

/* Every time-out must fit the stations' timers (2^31 us): the lost-token time-out of address
 * 126 is 258 TSL. */
static void test_times_fit_the_timers(void)
{
    check_test_name_ = "times_fit_the_timers";
    fdl_bus_params_t bp;
    fdl_bus_params_default(&bp, 9600u, FDL_BUS_PROFILE_DP);
    char why[160] = "";
    bp.tsl_bits = 79000u; /* 258 x 79000 bit = 2123 s at 9600 bit/s */
    CHECK(fdl_bus_params_check(&bp, why, sizeof why));
    bp.tsl_bits = 80000u; /* 2150 s */
    CHECK(!fdl_bus_params_check(&bp, why, sizeof why));
    CHECK(strstr(why, "2147 s") != NULL);
    fdl_bus_params_default(&bp, 12000000u, FDL_BUS_PROFILE_USB);
    CHECK(fdl_bus_params_check(&bp, why, sizeof why)); /* TTR 2 s = 24e6 bit */
    bp.ttr_bits = 4000000000u; /* 333 s */
    CHECK(fdl_bus_params_check(&bp, why, sizeof why));
    fdl_bus_params_default(&bp, 9600u, FDL_BUS_PROFILE_DP);
    bp.ttr_bits = 4000000000u; /* 4.8 days */
    CHECK(!fdl_bus_params_check(&bp, why, sizeof why));
}

int main(void)
{
    test_claim_race();
    test_retry_zero_join();
    test_listen_first_station_leaves();
    test_leave_on_first_visit();
    test_times_fit_the_timers();
    return check_report();
}
