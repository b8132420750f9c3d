/* Faults of the token ring on the in-memory bus: a master switched off and on again, the token
 * holder dying, a second master with an address already in the ring (IEC 61158-4-3 token
 * procedure as fdl_active.h states it: token-pass retries and skip, lost token and claim after
 * TTO, duplicate address). No two stations ever transmit at once. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/fdl_wire.h"
#include "ring_rig.h"

static ring_rig_t rr; /* large: keep it off the stack */

static const uint32_t rates[] = {1500000u, 12000000u};
static const uint8_t cards[] = {10, 11, 12};
static const uint8_t owners[] = {2, 3, 4};

static uint64_t bits_ns(uint64_t bits)
{
    return bits * 1000000000u / rr.rig.cfg.baud;
}

static const fdl_active_t *mac(unsigned i)
{
    return dp_master_ring(rr.m[i]);
}

static hal_time_us_t now_us(void)
{
    return rig_now_us(&rr.rig);
}

/* Masters 2, 3, 4 with cards 10, 11, 12, settled. */
static void ring_of_three(uint32_t baud)
{
    ring_rig_init(&rr, baud, cards, 3);
    for (unsigned i = 0; i < 3u; i++) {
        (void)ring_rig_add_master(&rr, owners[i], NULL, &cards[i], 1, 100);
    }
    CHECK(ring_rig_settle(&rr, owners, 3000000u));
}

/* The number of tokens from sa to da in a row from trace index from (other tokens end it). */
static unsigned tokens_in_a_row(size_t from, uint8_t da, uint8_t sa, size_t *next)
{
    unsigned n = 0;
    size_t i = ring_rig_find_token(&rr, from, da, sa);
    for (; i < rr.trace_len; i++) {
        if (rr.trace[i].b[0] != FDL_SD4) {
            continue;
        }
        if (!ring_frame_is_token(&rr.trace[i], da, sa)) {
            break;
        }
        n++;
    }
    *next = i;
    return n;
}

/* ---- 5: a master switched off and on ------------------------------------------------------- */

static void switched_off_at(uint32_t baud)
{
    int failed0 = check_failed_;
    ring_of_three(baud);
    /* master 2 holds the token: 3 is idle */
    for (unsigned k = 0; k < 100000u && !fdl_active_holds_token(mac(0)); k++) {
        ring_rig_run_us(&rr, 1);
    }
    CHECK_EQ(mac(1)->state, FDL_MAC_ACTIVE_IDLE);
    uint32_t retries0 = mac(0)->stats.token_retries;
    unsigned failed_ev0 = rr.ring_events[FDL_EV_PASS_FAILED];
    rr.trace_len = 0;
    dp_master_stop(rr.m[1]);
    ring_rig_run_us(&rr, 300000u); /* past the card's watchdog of 100 ms */
    /* 2 passes to 3 and repeats it twice (FDL_TOKEN_PASS_REPEATS, whatever the message retry
     * limit), then skips it: 4 is its NS */
    size_t next = 0;
    const unsigned repeats = FDL_TOKEN_PASS_REPEATS;
    CHECK_EQ(tokens_in_a_row(0, 3, 2, &next), 1u + repeats);
    CHECK(next < rr.trace_len && ring_frame_is_token(&rr.trace[next], 4, 2));
    size_t first = ring_rig_find_token(&rr, 0, 3, 2);
    CHECK(first + 1u < rr.trace_len &&
          (int64_t)(rr.trace[first + 1u].t_ns - ring_frame_end_ns(&rr, &rr.trace[first])) >=
              (int64_t)bits_ns(mac(0)->cfg.bus.tsl_bits));
    CHECK_EQ(rr.ring_events[FDL_EV_PASS_FAILED] - failed_ev0, 1);
    CHECK_EQ(ring_rig_count(&rr, (const uint8_t[]){FDL_SD4, 3, 2}, 3), 1u + repeats);
    /* 4 had 3 as its PS: the first token from 2 is refused, the repeat taken */
    CHECK_EQ(mac(0)->stats.token_retries - retries0, repeats + 1u);
    CHECK(!fdl_active_in_las(mac(0), 3));
    CHECK(!fdl_active_in_las(mac(2), 3));
    CHECK_EQ(mac(0)->ns, 4);
    CHECK_EQ(mac(2)->ns, 2);
    CHECK_EQ(fdl_active_station(mac(0), 3), FDL_STATION_NONE);
    /* the ring goes on: the last tokens are 2 -> 4 -> 2 */
    size_t last = rr.trace_len;
    unsigned seen = 0;
    for (size_t i = rr.trace_len; i-- > 0 && seen < 10u;) {
        if (rr.trace[i].b[0] == FDL_SD4) {
            seen++;
            CHECK(ring_frame_is_token(&rr.trace[i], 4, 2) ||
                  ring_frame_is_token(&rr.trace[i], 2, 4));
            last = i;
        }
    }
    CHECK(last < rr.trace_len);
    CHECK_EQ(dp_slave_state(&rr.rig.cards[1].cs.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_slave_state(&rr.rig.cards[0].cs.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(dp_slave_state(&rr.rig.cards[2].cs.card.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(ring_rig_foreign_senders(&rr, 0), 0);
    /* on again: it listens, 2's GAP finds it ready and it is back in the ring with its card */
    rr.trace_len = 0;
    dp_master_start(rr.m[1], now_us());
    membus_wake(rr.port[1]);
    CHECK_EQ(mac(1)->state, FDL_MAC_LISTEN_TOKEN);
    CHECK(ring_rig_settle(&rr, owners, 3000000u));
    size_t ready = ring_rig_count(&rr, (const uint8_t[]){0x10, 0x02, 0x03, 0x20, 0x25}, 5);
    CHECK_EQ(ready, 1);
    CHECK(ring_rig_find_token(&rr, 0, 3, 2) < rr.trace_len);
    CHECK_EQ(ring_rig_foreign_senders(&rr, 0), 0);
    CHECK_EQ(rr.rig.bus.collisions, 0);
    if (check_failed_ > failed0) {
        ring_rig_dump(&rr, 0, 40);
    }
}

static void test_switched_off(void)
{
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++) {
        switched_off_at(rates[r]);
    }
}

/* ---- 6: the token holder dies -------------------------------------------------------------- */

/* Master 3 stops after its first request of a visit: 2 saw the token taken, the bus goes silent
 * after the card's answer, and 2 (the lowest address, the shortest TTO = 6 TSL + 2 x 2 TSL)
 * claims; the ring is rebuilt with 4. */
static void holder_dies_at(uint32_t baud)
{
    int failed0 = check_failed_;
    ring_of_three(baud);
    size_t from = 0;
    for (unsigned k = 0; k < 400000u; k++) {
        ring_rig_run_us(&rr, 1);
        if (rr.trace_len > RING_TRACE_MAX / 2u) {
            rr.trace_len = 0;
        }
        const ring_frame_t *f = rr.trace_len > 0u ? &rr.trace[rr.trace_len - 1u] : NULL;
        uint8_t da;
        uint8_t sa;
        uint8_t fc;
        if (fdl_active_holds_token(mac(1)) && f != NULL && ring_frame_addr(f, &da, &sa, &fc) &&
            sa == 3u && (fc & FDL_FC_REQUEST) != 0u) {
            from = rr.trace_len - 1u;
            break;
        }
    }
    CHECK(fdl_active_holds_token(mac(1)));
    dp_master_stop(rr.m[1]);
    uint32_t claims2 = mac(0)->stats.claims;
    uint32_t claims4 = mac(2)->stats.claims;
    ring_rig_run_us(&rr, 50000u);
    /* the request, the card's answer, then silence until 2's claim */
    size_t claim = ring_rig_find_token(&rr, from, 2, 2);
    CHECK_EQ(claim, from + 2u);
    CHECK(claim < rr.trace_len && claim > 0u);
    if (claim < rr.trace_len && claim > 0u) {
        uint64_t silent = rr.trace[claim].t_ns - ring_frame_end_ns(&rr, &rr.trace[claim - 1u]);
        uint64_t tto = bits_ns((6u + 2u * 2u) * (uint64_t)mac(0)->cfg.bus.tsl_bits);
        /* a few bit times, and the stations' microsecond clock: the end of the last telegram
         * and TTO each rounded to a microsecond */
        CHECK(silent >= tto && silent <= tto + bits_ns(4) + 2000u);
        CHECK(ring_frame_is_token(&rr.trace[claim + 1u], 2, 2));
    }
    CHECK_EQ(mac(0)->stats.claims - claims2, 1);
    CHECK_EQ(mac(2)->stats.claims - claims4, 0);
    const uint8_t left[] = {2, 0, 4};
    CHECK(ring_rig_settle(&rr, left, 3000000u));
    CHECK(fdl_active_in_las(mac(0), 4));
    CHECK(fdl_active_in_las(mac(2), 2));
    CHECK_EQ(mac(0)->ns, 4);
    CHECK_EQ(mac(2)->ns, 2);
    CHECK_EQ(ring_rig_foreign_senders(&rr, claim), 0);
    CHECK_EQ(rr.rig.bus.collisions, 0);
    if (check_failed_ > failed0) {
        ring_rig_dump(&rr, from > 4u ? from - 4u : 0u, 40);
    }
}

static void test_holder_dies(void)
{
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++) {
        holder_dies_at(rates[r]);
    }
}

/* ---- 7: duplicate address ------------------------------------------------------------------ */

/* A second master 3 comes up while the ring 2, 3, 4 runs: it hears a token or a request from
 * its own address and goes off the bus; the ring keeps its three masters. */
static void duplicate_at(uint32_t baud)
{
    int failed0 = check_failed_;
    ring_of_three(baud);
    unsigned dup0 = rr.ring_events[FDL_EV_DUPLICATE_ADDRESS];
    rr.trace_len = 0;
    dp_master_t *twin = ring_rig_add_master(&rr, 3, NULL, NULL, 0, 100);
    CHECK(twin != NULL);
    ring_rig_run_us(&rr, 200000u);
    CHECK(twin != NULL && dp_master_ring(twin)->state == FDL_MAC_OFFLINE);
    CHECK_EQ(rr.ring_events[FDL_EV_DUPLICATE_ADDRESS] - dup0, 1);
    for (unsigned i = 0; i < 3u; i++) {
        CHECK(mac(i)->in_ring);
        CHECK(mac(i)->state != FDL_MAC_OFFLINE);
    }
    CHECK(ring_rig_settle(&rr, owners, 1000000u));
    CHECK_EQ(ring_rig_foreign_senders(&rr, 0), 0);
    CHECK_EQ(rr.rig.bus.collisions, 0);
    if (check_failed_ > failed0) {
        ring_rig_dump(&rr, 0, 40);
    }
}

static void test_duplicate_address(void)
{
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++) {
        duplicate_at(rates[r]);
    }
}

int main(void)
{
    RUN_TEST(test_switched_off);
    RUN_TEST(test_holder_dies);
    RUN_TEST(test_duplicate_address);
    return check_report();
}
