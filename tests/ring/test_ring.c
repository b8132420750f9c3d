/* The token ring on the in-memory bus: rings of 1, 2 and 5 masters with their cards (GAP
 * maintenance and the rotation time: test_ring_gap.c; faults: test_ring_faults.c). Every
 * expectation comes from the token procedure (IEC 61158-4-3 as fdl_active.h states it):
 * telegram bytes, who holds the token, idle times in bit times. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/fdl_wire.h"
#include "ring_rig.h"

static ring_rig_t rr; /* large: keep it off the stack */

static const uint32_t rates[] = {1500000u, 12000000u};

static void setup(uint32_t baud, unsigned masters, const fdl_bus_params_t *bus)
{
    uint8_t cards[RING_MAX_MASTERS];
    for (unsigned i = 0; i < masters; i++) {
        cards[i] = (uint8_t)(10u + i);
    }
    ring_rig_init(&rr, baud, cards, masters);
    for (unsigned i = 0; i < masters; i++) {
        (void)ring_rig_add_master(&rr, (uint8_t)(2u + i), bus, &cards[i], 1, 100);
    }
}

/* bits at the ring's rate, in ns */
static uint64_t bits_ns(uint64_t bits)
{
    return bits * 1000000000u / rr.rig.cfg.baud;
}

static const fdl_active_t *mac(unsigned i)
{
    return dp_master_ring(rr.m[i]);
}

/* The trace from its start, one telegram per entry: each line starts with the text given. */
static unsigned trace_differs(const char *const *expected, size_t n)
{
    unsigned bad = 0;
    for (size_t i = 0; i < n; i++) {
        char line[128] = "";
        (void)ring_rig_trace_text(&rr, i, 1, line, sizeof line);
        if (strncmp(line, expected[i], strlen(expected[i])) != 0) {
            fprintf(stderr, "    telegram %zu: %s    expected %s\n", i, line, expected[i]);
            bad++;
        }
    }
    return bad;
}

/* ---- 1: a lone master ---------------------------------------------------------------------- */

/* The claim (two tokens to itself), which starts a GAP sweep, then per visit: the slave's next
 * start-up telegram and its answer, one GAP address (3, 4, ...: nobody answers), the token to
 * itself. The Slave_Diag after
 * Chk_Cfg names master 2; Data_Exchange toggles FCB. */
static const char *const ring1_start[] = {
    "DC 02 02", "DC 02 02",
    "10 0A 02 49 55 16", "10 02 0A 00 0C 16", "10 03 02 49 4E 16", "DC 02 02",
    "68 05 05 68 8A 82 6D 3C 3E", "68 0B 0B 68 82 8A 08 3E 3C", "10 04 02 49 4F 16", "DC 02 02",
    "68 15 15 68 8A 82 5D 3D 3E", "E5", "10 05 02 49 50 16", "DC 02 02",
    "68 07 07 68 8A 82 7D 3E 3E F3 F2", "E5", "10 06 02 49 51 16", "DC 02 02",
    "68 05 05 68 8A 82 5D 3C 3E", "68 0B 0B 68 82 8A 08 3E 3C 00 0C 00 02",
    "10 07 02 49 52 16", "DC 02 02",
    "68 11 11 68 0A 02 7D", "68 11 11 68 02 0A 08", "10 08 02 49 53 16", "DC 02 02",
    "68 11 11 68 0A 02 5D", "68 11 11 68 02 0A 08", "10 09 02 49 54 16", "DC 02 02",
    "68 11 11 68 0A 02 7D", "68 11 11 68 02 0A 08", "10 0A 02 49 55 16", "10 02 0A 00 0C 16",
    "DC 02 02",
};

static void ring_of_one_at(uint32_t baud)
{
    int failed0 = check_failed_;
    setup(baud, 1, NULL);
    uint64_t start_ns = rr.rig.bus.now_ns;
    const fdl_bus_params_t *bp = &mac(0)->cfg.bus;
    /* long enough for the start-up and one GAP sweep of 124 addresses, one per visit */
    ring_rig_run_us(&rr, 200u * (uint64_t)fdl_bus_us(bp, 2000u) + 20000u);
    size_t n = sizeof ring1_start / sizeof ring1_start[0];
    CHECK(rr.trace_len > n);
    CHECK_EQ(trace_differs(ring1_start, n), 0);
    /* the bus was idle from the start: the claim comes TTO = 6 TSL + 2 TS TSL after it */
    uint64_t tto_ns = bits_ns((6u + 2u * 2u) * (uint64_t)bp->tsl_bits);
    int64_t late = (int64_t)(rr.trace[0].t_ns - start_ns - tto_ns);
    CHECK(late >= 0 && late <= (int64_t)bits_ns(1) + 1000);
    CHECK_EQ(rr.rig.cards[0].cs.card.dp.state, DP_STATE_DATA_EXCH);
    CHECK_EQ(dp_slave_master(&rr.rig.cards[0].cs.card.dp), 2);
    CHECK_EQ(mac(0)->stats.claims, 1);
    for (unsigned a = 0; a <= FDL_ACTIVE_HSA_MAX; a++) {
        if (a != 2u) {
            CHECK_EQ(fdl_active_station(mac(0), (uint8_t)a),
                     a == 10u ? FDL_STATION_PASSIVE : FDL_STATION_NONE);
        }
    }
    /* steady state: exactly one Data_Exchange per visit */
    size_t from = ring_rig_find_token(&rr, n, 2, 2);
    unsigned visits = 0;
    unsigned wrong = 0;
    unsigned dx = 0;
    for (size_t i = from + 1u; i < rr.trace_len; i++) {
        dx += ring_frame_is_data_exch(&rr.trace[i], 10, 2);
        if (ring_frame_is_token(&rr.trace[i], 2, 2)) {
            visits++;
            wrong += dx != 1u;
            dx = 0;
        }
    }
    CHECK(visits > 20u);
    CHECK_EQ(wrong, 0);
    CHECK_EQ(ring_rig_foreign_senders(&rr, 0), 0);
    CHECK_EQ(rr.rig.bus.collisions, 0);
    if (check_failed_ > failed0) {
        ring_rig_dump(&rr, 0, n + 4u);
    }
}

static void test_ring_of_one(void)
{
    ring_of_one_at(1500000u);
    ring_of_one_at(12000000u);
    ring_of_one_at(19200u);
}

/* ---- 2: rings of 2 and 5 ------------------------------------------------------------------- */

static void ring_of_at(unsigned masters, uint32_t baud)
{
    int failed0 = check_failed_;
    setup(baud, masters, NULL);
    uint8_t owner[RING_MAX_MASTERS];
    for (unsigned i = 0; i < masters; i++) {
        owner[i] = (uint8_t)(2u + i);
    }
    CHECK(ring_rig_settle(&rr, owner, 3000000u));
    uint32_t tokens0[RING_MAX_MASTERS];
    for (unsigned i = 0; i < masters; i++) {
        tokens0[i] = mac(i)->stats.tokens_received;
    }
    uint32_t retries0 = 0;
    for (unsigned i = 0; i < masters; i++) {
        retries0 += mac(i)->stats.token_retries + mac(i)->stats.stations_skipped;
    }
    rr.trace_len = 0;
    ring_rig_run_us(&rr, 1000000u);
    /* the tokens go 2 -> 3 -> ... -> last -> 2 and nowhere else */
    size_t i0 = ring_rig_find_token(&rr, 0, 2, (uint8_t)(masters + 1u));
    unsigned out_of_order = 0;
    unsigned tokens = 0;
    uint8_t expect_sa = (uint8_t)(masters + 1u);
    for (size_t i = i0; i < rr.trace_len; i++) {
        if (rr.trace[i].b[0] != FDL_SD4) {
            continue;
        }
        uint8_t da = expect_sa == masters + 1u ? 2u : (uint8_t)(expect_sa + 1u);
        out_of_order += !ring_frame_is_token(&rr.trace[i], da, expect_sa);
        expect_sa = rr.trace[i].b[1];
        tokens++;
    }
    CHECK(tokens > 100u);
    CHECK_EQ(out_of_order, 0);
    uint32_t retries = 0;
    for (unsigned i = 0; i < masters; i++) {
        const fdl_active_t *a = mac(i);
        retries += a->stats.token_retries + a->stats.stations_skipped;
        CHECK(a->in_ring);
        CHECK_EQ(a->stats.late_tokens, 0);
        /* one rotation, one token each: the counts differ by at most the rotation under way */
        int32_t d = (int32_t)(a->stats.tokens_received - tokens0[i]) -
                    (int32_t)(mac(0)->stats.tokens_received - tokens0[0]);
        CHECK(d >= -1 && d <= 1);
        for (unsigned k = 0; k < masters; k++) {
            CHECK(fdl_active_in_las(a, (uint8_t)(2u + k)));
        }
        const dp_slave_t *s = &rr.rig.cards[i].cs.card.dp;
        CHECK_EQ(dp_slave_state(s), DP_STATE_DATA_EXCH);
        CHECK_EQ(dp_slave_master(s), 2u + i);
    }
    CHECK_EQ(retries, retries0);
    CHECK_EQ(ring_rig_foreign_senders(&rr, 0), 0);
    CHECK_EQ(rr.rig.bus.collisions, 0);
    if (check_failed_ > failed0) {
        ring_rig_dump(&rr, 0, 60);
    }
}

static void test_rings_of_two_and_five(void)
{
    for (size_t r = 0; r < sizeof rates / sizeof rates[0]; r++) {
        ring_of_at(2, rates[r]);
        ring_of_at(5, rates[r]);
    }
}

int main(void)
{
    RUN_TEST(test_ring_of_one);
    RUN_TEST(test_rings_of_two_and_five);
    return check_report();
}
