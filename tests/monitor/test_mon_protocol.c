/* The monitor's reading of a DP slave against the project's own slave (dp_slave.c), telegram
 * by telegram: what the line shows must lead to the state the slave is in.
 * - Set_Prm's Lock_Req/Unlock_Req pair (IEC 61158-6-3; dp_slave.c svc_set_prm): Unlock (01 and
 *   11) releases the slave to Wait_Prm with no master; 00 changes only the min TSDR and leaves
 *   the slave, its master and its parameters as they were.
 * - Stat_Diag in a diagnosis without Station_Not_Ready: the slave stays in Data_Exch (the bit
 *   asks the master to read diagnosis; it is no state of the slave's machine).
 * - A token the monitor heard damaged (noise on its stub, a reflection) tells it nothing: the
 *   next pass is no duplicate token and no master left the ring for it.
 * - RDL/RDH (response data, the request's data not taken for want of a resource) is an answer
 *   with data, no refusal: the slave stays in data exchange.
 * - An illegal SD2 telegram names its source address, as an SD1 one does.
 * And capture files: one whose times go back (merged or hand-made captures): the monitor's
 * times never do, so no span, rotation or load comes out of an unsigned wrap; a text line with
 * no octets in it is garbled, not nothing. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "monitor/mon_live.h"
#include "monitor/monitor.h"

#define BAUD 1500000u
#define BIT_NS 667u /* at 1.5 Mbit/s, rounded */

static mon_t mon; /* large: keep it off the stack */
static uint64_t now_ns;

static void init(void)
{
    mon_cfg_t cfg = {.baud = BAUD, .timing = true};
    mon_init(&mon, &cfg);
    now_ns = 1000000u;
}

/* One telegram on the line, then 30 bit times of idle. */
static void line(const uint8_t *f, size_t len)
{
    uint64_t end = now_ns + len * 11u * BIT_NS;
    mon_telegram(&mon, f, len, now_ns, end);
    now_ns = end + 30u * BIT_NS;
}

static void req(uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap, const uint8_t *du,
                size_t n)
{
    uint8_t f[FDL_FRAME_MAX];
    line(f, fdl_encode(f, da, sa, fc, saps, dsap, DP_SAP_MASTER, du, n));
}

static void rsp(uint8_t da, uint8_t sa, uint8_t fc, bool saps, const uint8_t *du, size_t n)
{
    uint8_t f[FDL_FRAME_MAX];
    line(f, fdl_encode(f, da, sa, fc, saps, DP_SAP_MASTER, 0u, du, n));
}

static void sc(void)
{
    const uint8_t f[] = {FDL_SC};
    line(f, sizeof f);
}

#define SRD_HIGH (FDL_FC_REQUEST | FDL_REQ_SRD_HIGH)
#define FCV FDL_FC_FCV
#define FCB FDL_FC_FCB

static const uint8_t prm[] = {DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 10, 11, 0x60, 0x03, 0};
static const uint8_t cfg[] = {0xF3, 0xF2};
static const uint8_t diag_ready[] = {0x00, DP_DIAG2_ALWAYS_ONE | DP_DIAG2_WD_ON, 0x00, 2,
                                     0x60, 0x03};
static const uint8_t io[14] = {0};

/* Master 2 takes slave 10 into data exchange: Set_Prm, Chk_Cfg, Slave_Diag, Data_Exchange. */
static void master_2_owns_10(void)
{
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, prm, sizeof prm);
    sc();
    req(10, 2, SRD_HIGH | FCV, true, DP_SAP_CHK_CFG, cfg, sizeof cfg);
    sc();
    req(10, 2, SRD_HIGH | FCV | FCB, true, DP_SAP_SLAVE_DIAG, NULL, 0);
    rsp(2, 10, FDL_RSP_DL, true, diag_ready, sizeof diag_ready);
    req(10, 2, SRD_HIGH | FCV, false, 0, io, sizeof io);
    rsp(2, 10, FDL_RSP_DL, false, io, sizeof io);
}

/* Unlock_Req, with Lock_Req (11) or without (01): dp_slave.c releases the slave to Wait_Prm
 * with no master. */
static void test_unlock(uint8_t status)
{
    init();
    master_2_owns_10();
    CHECK_EQ(mon.st[10].dp_state, MON_DP_DATA_EXCH);
    uint64_t ev0 = mon.events_total;
    const uint8_t unlock[] = {status, 1, 10, 11, 0x60, 0x03, 0};
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, unlock, sizeof unlock);
    sc();
    const mon_station_t *s = &mon.st[10];
    CHECK_EQ(s->dp_state, MON_DP_WAIT_PRM);
    CHECK_EQ(s->master, MON_NO_MASTER);
    CHECK_EQ(s->owner, 2);
    CHECK_EQ(mon.events_total, ev0 + 1u);
    const mon_event_t *e = mon_event(&mon, ev0);
    CHECK(e != NULL && e->type == MON_EV_DX_LEAVE && e->station == 10);
    /* a class-2 master may now parameterise it: a new owner, no refusal */
    req(10, 1, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, prm, sizeof prm);
    sc();
    CHECK_EQ(s->dp_state, MON_DP_WAIT_CFG);
    CHECK_EQ(s->master, 1);
}

static void test_unlock_01(void)
{
    test_unlock(DP_PRM_UNLOCK_REQ);
}

static void test_unlock_11(void)
{
    test_unlock(DP_PRM_LOCK_REQ | DP_PRM_UNLOCK_REQ);
}

/* Lock_Req 0, Unlock_Req 0: only the min TSDR is taken (dp_slave.c: "the rest of the telegram
 * is not adopted"); the slave goes on exchanging data with its master. */
static void test_min_tsdr_only(void)
{
    init();
    master_2_owns_10();
    uint64_t ev0 = mon.events_total;
    const uint8_t only_tsdr[] = {0x00, 0, 0, 40, 0x12, 0x34, 0};
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, only_tsdr, sizeof only_tsdr);
    sc();
    const mon_station_t *s = &mon.st[10];
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, 2);
    CHECK_EQ(s->ident, 0x6003);
    CHECK_EQ(s->watchdog_ms, 100);
    CHECK_EQ(s->min_tsdr_bits, 40);
    CHECK_EQ(s->prm_len, sizeof prm);
    CHECK_EQ(memcmp(s->prm, prm, sizeof prm), 0);
    CHECK_EQ(mon.events_total, ev0);
    req(10, 2, SRD_HIGH | FCV, false, 0, io, sizeof io);
    rsp(2, 10, FDL_RSP_DL, false, io, sizeof io);
    CHECK_EQ(s->dx_count, 2);
    CHECK_EQ(mon.events_total, ev0);
}

/* A min TSDR of 0 keeps the one the slave has; below the default 11 bit times it is 11
 * (dp_slave.c adopt_min_tsdr). */
static void test_min_tsdr_rules(void)
{
    init();
    master_2_owns_10();
    const uint8_t twenty[] = {DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 10, 20, 0x60, 0x03, 0};
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, twenty, sizeof twenty);
    sc();
    CHECK_EQ(mon.st[10].min_tsdr_bits, 20);
    const uint8_t zero[] = {DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 10, 0, 0x60, 0x03, 0};
    req(10, 2, SRD_HIGH | FCV, true, DP_SAP_SET_PRM, zero, sizeof zero);
    sc();
    CHECK_EQ(mon.st[10].min_tsdr_bits, 20);
    const uint8_t five[] = {DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 10, 5, 0x60, 0x03, 0};
    req(10, 2, SRD_HIGH | FCV | FCB, true, DP_SAP_SET_PRM, five, sizeof five);
    sc();
    CHECK_EQ(mon.st[10].min_tsdr_bits, 11);
}

/* A slave in data exchange that sets Stat_Diag stays there: no dx_leave, and nothing says
 * Station_Not_Ready, which its diagnosis does not. */
static void test_stat_diag_in_data_exchange(void)
{
    init();
    master_2_owns_10();
    uint64_t ev0 = mon.events_total;
    const uint8_t stat[] = {DP_DIAG1_EXT_DIAG,
                            DP_DIAG2_ALWAYS_ONE | DP_DIAG2_WD_ON | DP_DIAG2_STAT_DIAG, 0x00, 2,
                            0x60, 0x03, 0x02, 0x1C};
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SLAVE_DIAG, NULL, 0);
    rsp(2, 10, FDL_RSP_DL, true, stat, sizeof stat);
    const mon_station_t *s = &mon.st[10];
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->stat_diag, 1);
    unsigned leaves = 0;
    unsigned stats = 0;
    for (uint64_t k = ev0; k < mon.events_total; k++) {
        const mon_event_t *e = mon_event(&mon, k);
        leaves += e->type == MON_EV_DX_LEAVE;
        stats += e->type == MON_EV_STAT_DIAG;
        CHECK(strstr(e->text, "Station_Not_Ready") == NULL);
    }
    CHECK_EQ(leaves, 0);
    CHECK_EQ(stats, 1);
}

static void token(uint8_t da, uint8_t sa)
{
    const uint8_t f[] = {FDL_SD4, da, sa};
    line(f, sizeof f);
    now_ns += 100000u; /* the holder's turn: 100 us */
}

static unsigned count_events(uint64_t from, mon_event_type_t type)
{
    unsigned n = 0;
    for (uint64_t k = from; k < mon.events_total; k++) {
        n += mon_event(&mon, k)->type == type;
    }
    return n;
}

/* Ring 1 -> 2 -> 3 -> 1; one of 2's tokens reaches the monitor damaged (octets that are no
 * telegram), while 3 took it as usual. */
static void test_garbled_token(void)
{
    init();
    for (int r = 0; r < 3; r++) {
        token(2, 1);
        token(3, 2);
        token(1, 3);
    }
    uint64_t ev0 = mon.events_total;
    CHECK(mon.st[1].in_ring && mon.st[2].in_ring && mon.st[3].in_ring);
    token(2, 1);
    const uint8_t damaged[] = {FDL_SD4, 0x83, 0x02};
    mon_garbled(&mon, damaged, sizeof damaged, now_ns);
    now_ns += 100000u;
    token(1, 3);
    for (int r = 0; r < 3; r++) {
        token(2, 1);
        token(3, 2);
        token(1, 3);
    }
    CHECK_EQ(count_events(ev0, MON_EV_DUPLICATE_TOKEN), 0);
    CHECK_EQ(count_events(ev0, MON_EV_RING_LEAVE), 0);
    CHECK_EQ(count_events(ev0, MON_EV_RING_ENTER), 0);
    CHECK_EQ(mon.events_total, ev0);
    CHECK(mon.st[1].in_ring && mon.st[2].in_ring && mon.st[3].in_ring);
}

static void test_rdl_answer(void)
{
    init();
    master_2_owns_10();
    uint64_t ev0 = mon.events_total;
    req(10, 2, SRD_HIGH | FCB, false, 0, io, sizeof io);
    rsp(2, 10, FDL_RSP_RDL, false, io, sizeof io);
    CHECK_EQ(mon.st[10].dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(mon.events_total, ev0);
}

static void test_illegal_sd2_source(void)
{
    init();
    uint8_t f[FDL_FRAME_MAX];
    /* a request with the reserved function code 1 and 14 octets of data: an SD2 telegram */
    size_t n = fdl_encode(f, 10, 33, FDL_FC_REQUEST | 0x1u, false, 0, 0, io, sizeof io);
    CHECK_EQ(f[0], FDL_SD2);
    line(f, n);
    CHECK_EQ(mon.line.illegal, 1);
    const mon_event_t *e = mon_event(&mon, 0);
    CHECK(e != NULL && e->type == MON_EV_ILLEGAL);
    CHECK_EQ(e != NULL ? e->station : 0, 33);
}

static void put32(FILE *f, uint32_t v)
{
    const uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    (void)fwrite(b, 1, sizeof b, f);
}

/* Tokens 2 -> 3 -> 2 ... in a pcap (link type 257) at 10.000, 10.001, ... s, then three more
 * at 5.000 s and after: the clock of the capture went back five seconds. */
static void test_file_times_back(void)
{
    char path[] = "/tmp/test_mon_protocol_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0);
    FILE *f = fd >= 0 ? fdopen(fd, "wb") : NULL;
    if (f == NULL) {
        return;
    }
    put32(f, 0xA1B2C3D4u);
    put32(f, 2u | (4u << 16)); /* version 2.4 */
    put32(f, 0);
    put32(f, 0);
    put32(f, 65535u);
    put32(f, 257u);
    const uint32_t us[] = {0, 1000, 2000, 3000, 0, 1000, 2000};
    const uint32_t s[] = {10, 10, 10, 10, 5, 5, 5};
    for (size_t i = 0; i < sizeof us / sizeof us[0]; i++) {
        uint8_t tok[3] = {FDL_SD4, (i % 2u) == 0u ? 3u : 2u, (i % 2u) == 0u ? 2u : 3u};
        put32(f, s[i]);
        put32(f, us[i]);
        put32(f, sizeof tok);
        put32(f, sizeof tok);
        (void)fwrite(tok, 1, sizeof tok, f);
    }
    CHECK_EQ(fclose(f), 0);
    mon_cfg_t mc = {.baud = BAUD, .timing = true, .ttr_bits = 30000u};
    mon_init(&mon, &mc);
    char err[200];
    CHECK_EQ(mon_file_run(&mon, path, BAUD, NULL, err, sizeof err), 7);
    (void)unlink(path);
    for (uint8_t a = 2; a <= 3; a++) {
        const mon_station_t *st = &mon.st[a];
        CHECK(st->rotation.n >= 1u);
        CHECK(st->rotation.max_ns <= 2000000u);
        CHECK_EQ(st->rotations_over_ttr, 0);
    }
    CHECK(mon.line.last_ns >= mon.line.first_ns);
    CHECK(mon.line.last_ns - mon.line.first_ns >= 3000000u);
}

static void test_file_line_without_octets(void)
{
    char path[] = "/tmp/test_mon_protocol_XXXXXX";
    int fd = mkstemp(path);
    CHECK(fd >= 0);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (f == NULL) {
        return;
    }
    (void)fputs("68 05 05 68 84 82 6D 3C 3E ED 16\nroot:x:0:0:root:/root:/bin/bash\n", f);
    CHECK_EQ(fclose(f), 0);
    init();
    char err[200];
    CHECK_EQ(mon_file_run(&mon, path, BAUD, NULL, err, sizeof err), 2);
    (void)unlink(path);
    CHECK_EQ(mon.line.telegrams, 1);
    CHECK_EQ(mon.line.garbled, 1);
}

int main(void)
{
    RUN_TEST(test_unlock_01);
    RUN_TEST(test_unlock_11);
    RUN_TEST(test_min_tsdr_only);
    RUN_TEST(test_min_tsdr_rules);
    RUN_TEST(test_stat_diag_in_data_exchange);
    RUN_TEST(test_garbled_token);
    RUN_TEST(test_rdl_answer);
    RUN_TEST(test_illegal_sd2_source);
    RUN_TEST(test_file_times_back);
    RUN_TEST(test_file_line_without_octets);
    return check_report();
}
