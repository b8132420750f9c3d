/* The monitor fed telegram by telegram, where the rig's masters never go: a second master whose
 * Set_Prm and Data_Exchange a locked slave refuses with RS (dp_slave.c, DP_LOCK_OWNER_OR_RS), and
 * telegrams no station may send (source address 127, a token to or from 127, a request with a
 * reserved function code), which are counted as illegal with an event and make no station. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
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

/* One telegram on the line, then 30 bit times of idle (a TSDR within the DP profile's). */
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

static const uint8_t prm[] = {DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 10, 11, 0x60, 0x03, 0};
static const uint8_t cfg[] = {0xF3, 0xF2};
static const uint8_t diag_ready[] = {0x00, DP_DIAG2_ALWAYS_ONE | DP_DIAG2_WD_ON, 0x00, 2,
                                     0x60, 0x03};
static const uint8_t io[14] = {0};

#define SRD_HIGH (FDL_FC_REQUEST | FDL_REQ_SRD_HIGH)
#define FCV FDL_FC_FCV
#define FCB FDL_FC_FCB

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

static void test_locked_out(void)
{
    init();
    master_2_owns_10();
    const mon_station_t *s = &mon.st[10];
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, 2);
    CHECK_EQ(s->watchdog_ms, 100);
    CHECK_EQ(s->min_tsdr_bits, 11);
    uint64_t ev0 = mon.events_total;
    /* master 3 asks for it: the slave, locked by 2, answers RS to each */
    req(10, 3, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, prm, sizeof prm);
    rsp(3, 10, FDL_RSP_RS, false, NULL, 0);
    req(10, 3, SRD_HIGH | FCV, true, DP_SAP_CHK_CFG, cfg, sizeof cfg);
    rsp(3, 10, FDL_RSP_RS, false, NULL, 0);
    req(10, 3, SRD_HIGH | FCV | FCB, false, 0, io, sizeof io);
    rsp(3, 10, FDL_RSP_RS, false, NULL, 0);
    CHECK_EQ(s->rs, 3);
    CHECK_EQ(s->dp_state, MON_DP_DATA_EXCH);
    CHECK_EQ(s->master, 2);
    CHECK_EQ(s->prm_len, sizeof prm);
    CHECK_EQ(s->dx_count, 1);
    /* 2 goes on with it */
    req(10, 2, SRD_HIGH | FCV | FCB, false, 0, io, sizeof io);
    rsp(2, 10, FDL_RSP_DL, false, io, sizeof io);
    CHECK_EQ(s->dx_count, 2);
    CHECK_EQ(s->missing + s->repeats_received, 0);
    CHECK_EQ(mon.st[3].role, MON_ROLE_ACTIVE);
    CHECK_EQ(mon.events_total, ev0 + 1u); /* only: master 3 heard */
    const mon_event_t *e = mon_event(&mon, ev0);
    CHECK(e != NULL && e->type == MON_EV_NEW_STATION && e->station == 3);
}

/* The owner's own Set_Prm refused (its parameters do not fit): the slave waits for others. */
static void test_refused_by_owner(void)
{
    init();
    master_2_owns_10();
    uint64_t ev0 = mon.events_total;
    req(10, 2, SRD_HIGH | FCB, true, DP_SAP_SET_PRM, prm, sizeof prm);
    rsp(2, 10, FDL_RSP_RS, false, NULL, 0);
    CHECK_EQ(mon.st[10].dp_state, MON_DP_WAIT_PRM);
    const mon_event_t *e = mon_event(&mon, ev0);
    CHECK(e != NULL && e->type == MON_EV_DX_LEAVE && e->station == 10 && e->other == 2);
    CHECK_EQ(mon.events_total, ev0 + 1u);
}

static size_t live(void)
{
    size_t n = 0;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        n += mon.st[a].seen || mon.st[a].role != MON_ROLE_UNKNOWN;
    }
    return n;
}

/* 5: telegrams no station may send. */
static void test_illegal(void)
{
    init();
    uint8_t f[FDL_FRAME_MAX];
    /* an SRD from source address 127 */
    line(f, fdl_encode(f, 10, 127, SRD_HIGH, false, 0, 0, NULL, 0));
    /* tokens to and from 127 */
    const uint8_t to_127[] = {FDL_SD4, 127, 2};
    const uint8_t from_127[] = {FDL_SD4, 2, 127};
    line(to_127, sizeof to_127);
    line(from_127, sizeof from_127);
    /* requests with the reserved function codes 1, 2, 8, 10, 11 */
    const uint8_t reserved[] = {0x1, 0x2, 0x8, 0xA, 0xB};
    for (size_t i = 0; i < sizeof reserved; i++) {
        line(f, fdl_encode(f, 10, 2, (uint8_t)(FDL_FC_REQUEST | reserved[i]), false, 0, 0, NULL,
                           0));
    }
    CHECK_EQ(mon.line.illegal, 8);
    CHECK_EQ(mon.line.telegrams, 8);
    CHECK_EQ(mon.line.garbled, 0);
    CHECK_EQ(mon.line.requests + mon.line.tokens + mon.line.answers, 0);
    CHECK_EQ(live(), 0);
    CHECK(!mon.st[10].addressed);
    CHECK_EQ(mon.events_total, 8);
    for (uint64_t k = 0; k < mon.events_total; k++) {
        const mon_event_t *e = mon_event(&mon, k);
        CHECK(e != NULL && e->type == MON_EV_ILLEGAL && e->level == MON_LEVEL_WARN);
    }
    CHECK_EQ(strncmp(mon_event(&mon, 0)->text, "source address 127", 18), 0);
    CHECK_EQ(strncmp(mon_event(&mon, 1)->text, "token with address 127", 22), 0);
    CHECK_EQ(strncmp(mon_event(&mon, 2)->text, "token with address 127", 22), 0);
    CHECK_EQ(strncmp(mon_event(&mon, 3)->text, "request with a reserved function code", 37), 0);
    /* a broadcast (SDN to 127) is legal: no answer expected, nobody missing */
    line(f, fdl_encode(f, 127, 2, FDL_FC_REQUEST | FDL_REQ_SDN_HIGH, true, DP_SAP_GLOBAL_CONTROL,
                       DP_SAP_MASTER, (const uint8_t[]){0x00, 0x00}, 2));
    mon_idle(&mon, now_ns + 1000000u);
    CHECK_EQ(mon.line.illegal, 8);
    CHECK_EQ(mon.line.broadcasts, 1);
    CHECK_EQ(mon.line.unanswered, 0);
    CHECK(mon.st[2].seen);
    CHECK(!mon.st[127].seen);
}

int main(void)
{
    RUN_TEST(test_locked_out);
    RUN_TEST(test_refused_by_owner);
    RUN_TEST(test_illegal);
    return check_report();
}
