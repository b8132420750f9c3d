/* The card's DP-V1 (docs/dpv1.md is the contract), byte for byte on the wire: a card_station with
 * the emulated MOVIDRIVE behind it (CARD_INVERTER_SIM) is fed request telegrams character by
 * character at exact times (1.5 Mbit/s fixed, strict timing, 100 bit idle before each request);
 * a recording UART keeps every frame it transmits; the station's poll (the card's main loop) runs
 * only where a test calls it, so "before the main loop ran" is exact. Station 4, class-1 master
 * 2 (so the frames of protocol.md §A1.6 apply literally), class-2 masters 3, 5 and 6 with SSAP
 * 50.
 *
 * Covered: the SC/poll convention, the manual's data set 47 examples (protocol.md §B7), 0xB5
 * polling with a slow inverter, DP-V1 error codes and the MOVILINK/PROFIdrive error mapping,
 * MSAC1 availability, MSAC2 resource manager (and the contract's "smaller decisions"),
 * connections, supervision, Idle and Abort, C1 + two C2 + Data_Exchange interleaved, I&M with
 * its per-connection selection and its persistence in the card's file-backed NVM.
 *
 * Two tests (..._while_service_runs) guard a fixed bug: a connection closed while its MOVILINK
 * service ran let that service's late answer complete the next request on the same channel. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "dp_slave/dp_wire.h"
#include "dpv1/dpv1_wire.h"
#include "sim_stations/stations.h"
#include "spec_frames.h"
#include "unit_rig.h"

#define BAUD 1500000u
#define SLAVE 4u
#define M1 2u        /* the class-1 master (locks the card with Set_Prm) */
#define SSAP_C2 50u  /* class-2 masters' SSAP */
#define C1 51u       /* MSAC1: DSAP = SSAP = 51 */
#define LOG_MAX 16u

/* ---- a UART that records every frame ------------------------------------------------------ */

typedef struct rec_uart {
    fake_uart_t u; /* the line follows this one (count, last frame, not_before) */
    unsigned frames;
    bool in_main_loop;
    unsigned tx_from_main_loop; /* the card must never transmit outside a reply */
    size_t len[LOG_MAX];
    uint8_t f[LOG_MAX][FDL_FRAME_MAX + 1u];
} rec_uart_t;

static int rec_set_baud(void *ctx, uint32_t baud)
{
    return fake_uart_set_baud(&((rec_uart_t *)ctx)->u, baud);
}

static int rec_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    rec_uart_t *r = ctx;
    size_t i = r->frames % LOG_MAX;
    r->len[i] = len <= sizeof r->f[i] ? len : sizeof r->f[i];
    memcpy(r->f[i], frame, r->len[i]);
    r->frames++;
    if (r->in_main_loop) {
        r->tx_from_main_loop++;
    }
    return fake_uart_transmit(&r->u, frame, len, not_before);
}

static const hal_uart_ops_t rec_ops = {.set_baud = rec_set_baud, .transmit = rec_transmit};

/* ---- rig ---------------------------------------------------------------------------------- */

typedef struct rig {
    card_station_t cs;
    sim_station_t st;
    rec_uart_t ru;
    line_t l;
    tmaster_t m[128]; /* FCB per master address */
    unsigned tx_before;
    unsigned requests; /* every one is an SRD: exactly one reply each */
    uint8_t f[FDL_FRAME_MAX];
    uint8_t e[FDL_FRAME_MAX];
    uint8_t pdu[DPV1_MAX_PDU];
} rig_t;

static rig_t R; /* large: off the stack */

typedef struct opts {
    uint32_t delay_us;
    const char *eeprom;
    const char *card_nvm;
} opts_t;

static void station_init(const opts_t *o)
{
    card_options_t co = {.address = SLAVE, .fixed_baud = BAUD, .strict_timing = true,
                         .inverter = CARD_INVERTER_SIM, .inverter_delay_us = o->delay_us,
                         .eeprom_path = o->eeprom, .card_nvm_path = o->card_nvm};
    char err[256];
    hal_uart_t uart = {.ops = &rec_ops, .ctx = &R.ru};
    int rc = card_station_init(&R.cs, &co, uart, line_now_us(&R.l), err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "card_station_init: %s\n", err);
    }
    CHECK_EQ(rc, 0);
    for (unsigned i = 0; i < 128u; i++) {
        R.m[i] = (tmaster_t){.addr = (uint8_t)i};
    }
}

static void setup_opts(const opts_t *o)
{
    memset(&R, 0, sizeof R);
    R.st = card_station(&R.cs);
    line_init(&R.l, BAUD, R.st.rx_char, R.st.ctx, &R.ru.u);
    station_init(o);
}

static void setup(uint32_t delay_us)
{
    opts_t o = {.delay_us = delay_us};
    setup_opts(&o);
}

/* The card's main loop, a few rounds at the current time (delivers due inverter answers, works
 * the mailboxes, starts the next MOVILINK service). */
static void main_loop(void)
{
    R.ru.in_main_loop = true;
    for (int i = 0; i < 4; i++) {
        (void)R.st.poll(R.st.ctx, line_now_us(&R.l));
    }
    R.ru.in_main_loop = false;
}

/* Time passes with the main loop running every step_us. */
static void run_us(uint64_t us, uint64_t step_us)
{
    for (uint64_t t = 0; t < us; t += step_us) {
        line_wait_us(&R.l, step_us < us - t ? step_us : us - t);
        main_loop();
    }
}

/* ---- sending ------------------------------------------------------------------------------ */

static bool send_frame(const uint8_t *f, size_t n)
{
    R.requests++;
    R.tx_before = R.ru.u.tx_count;
    return line_request(&R.l, f, n);
}

static void send_sap_fc(uint8_t ma, uint8_t fc, uint8_t dsap, uint8_t ssap, const uint8_t *d,
                        size_t n)
{
    size_t len = fdl_encode(R.f, SLAVE, ma, fc, true, dsap, ssap, d, n);
    CHECK(len > 0u);
    (void)send_frame(R.f, len);
}

static void send_sap(uint8_t ma, uint8_t dsap, uint8_t ssap, const uint8_t *d, size_t n)
{
    send_sap_fc(ma, tm_fc(&R.m[ma], FDL_REQ_SRD_HIGH), dsap, ssap, d, n);
}

/* A telegram printed in protocol.md §A1.6, sent as printed: its FC must be the one the FCB
 * tracker of its master gives next. */
static void send_literal(int line, const uint8_t *f, size_t n)
{
    uint8_t sa = (uint8_t)((f[0] == FDL_SD2 ? f[5] : f[2]) & FDL_ADDR_MASK);
    uint8_t fc = f[0] == FDL_SD2 ? f[6] : f[3];
    uint8_t want = tm_fc(&R.m[sa], FDL_REQ_SRD_HIGH);
    if (fc != want) {
        fprintf(stderr, "line %d: literal FC %02X, tracker says %02X\n", line, fc, want);
    }
    CHECK_EQ(fc, want);
    (void)send_frame(f, n);
}

static void send_dx(uint8_t ma, const uint8_t *out, size_t n)
{
    size_t len = fdl_encode(R.f, SLAVE, ma, tm_fc(&R.m[ma], FDL_REQ_SRD_HIGH), false, 0, 0, out, n);
    (void)send_frame(R.f, len);
}

/* ---- expectations ------------------------------------------------------------------------- */

/* The last request got exactly one reply, and it is this frame. */
static void expect_frame(int line, const uint8_t *e, size_t n)
{
    bool one = R.ru.u.tx_count == R.tx_before + 1u;
    if (one && R.ru.u.last_len == n && memcmp(R.ru.u.last, e, n) == 0) {
        check_passed_++;
        return;
    }
    check_failed_++;
    fprintf(stderr, "%s:%d: [%s] reply differs (%u replies to the request)\n", __FILE__, line,
            check_test_name_, R.ru.u.tx_count - R.tx_before);
    check_hex_("actual  ", R.ru.u.last, R.ru.u.tx_count == R.tx_before ? 0u : R.ru.u.last_len);
    check_hex_("expected", e, n);
}

/* A DP-V1 answer: DL from the slave, SAPs of the request swapped. */
static void expect_du(int line, uint8_t ma, uint8_t req_dsap, uint8_t req_ssap, const uint8_t *du,
                      size_t n)
{
    size_t len = fdl_encode_reply(R.e, ma, SLAVE, FDL_RSP_DL, true, req_ssap, req_dsap, du, n);
    expect_frame(line, R.e, len);
}

static void expect_rs(int line, uint8_t ma)
{
    size_t len = fdl_encode_reply(R.e, ma, SLAVE, FDL_RSP_RS, false, 0, 0, NULL, 0);
    expect_frame(line, R.e, len);
}

static const uint8_t SC[] = {0xE5};

#define EXPECT_SC() expect_frame(__LINE__, SC, 1)
#define EXPECT_RS(ma) expect_rs(__LINE__, (ma))
#define EXPECT_FRAME(...)                                                                      \
    do {                                                                                       \
        const uint8_t ef_[] = {__VA_ARGS__};                                                   \
        expect_frame(__LINE__, ef_, sizeof ef_);                                               \
    } while (0)
#define EXPECT_DU(ma, dsap, ssap, ...)                                                         \
    do {                                                                                       \
        const uint8_t ed_[] = {__VA_ARGS__};                                                   \
        expect_du(__LINE__, (ma), (dsap), (ssap), ed_, sizeof ed_);                            \
    } while (0)

/* Octets of a request: B(1, 2, 3) is a literal, BN(p, n) points at n octets. */
typedef struct bytes {
    const uint8_t *p;
    size_t n;
} bytes_t;
#define B(...) ((bytes_t){(const uint8_t[]){__VA_ARGS__}, sizeof((const uint8_t[]){__VA_ARGS__})})
#define BN(ptr, len) ((bytes_t){(ptr), (len)})

static void send_b(uint8_t ma, uint8_t dsap, uint8_t ssap, bytes_t b)
{
    send_sap(ma, dsap, ssap, b.p, b.n);
}

/* ---- DP-V1 transactions ------------------------------------------------------------------- */

/* Request PDU -> SC; main loop; poll -> the response PDU rsp. */
static void transact(int line, uint8_t ma, uint8_t dsap, uint8_t ssap, bytes_t req,
                     const uint8_t *rsp, size_t rn)
{
    send_b(ma, dsap, ssap, req);
    expect_frame(line, SC, 1);
    main_loop();
    send_sap(ma, dsap, ssap, NULL, 0);
    expect_du(line, ma, dsap, ssap, rsp, rn);
}

#define TRANSACT(ma, dsap, ssap, req, ...)                                                     \
    do {                                                                                       \
        const uint8_t tr_[] = {__VA_ARGS__};                                                   \
        transact(__LINE__, (ma), (dsap), (ssap), (req), tr_, sizeof tr_);                        \
    } while (0)

/* MSAC1 shorthand. */
#define C1_TRANSACT(req, ...) TRANSACT(M1, C1, C1, req, __VA_ARGS__)

static size_t mk_write(uint8_t *pdu, uint8_t index, const uint8_t *data, size_t n)
{
    pdu[0] = DPV1_FN_WRITE;
    pdu[1] = 0;
    pdu[2] = index;
    pdu[3] = (uint8_t)n;
    memcpy(&pdu[4], data, n);
    return 4u + n;
}

/* Data set 47 on one connection: Write.req -> Write.res, then Read.req until it is not B5; the
 * answer must be exactly `rsp`. Returns the number of B5 answers. */
static unsigned ds47(int line, uint8_t ma, uint8_t dsap, uint8_t ssap, bytes_t req,
                     const uint8_t *rsp, size_t rn)
{
    uint8_t pdu[DPV1_MAX_PDU];
    size_t pn = mk_write(pdu, DPV1_INDEX_DS47, req.p, req.n);
    transact(line, ma, dsap, ssap, BN(pdu, pn), pdu, 4);
    unsigned b5 = 0;
    for (int i = 0; i < 400; i++) {
        send_b(ma, dsap, ssap, B(0x5E, 0x00, 0x2F, 0xF0));
        expect_frame(line, SC, 1);
        main_loop();
        send_sap(ma, dsap, ssap, NULL, 0);
        fdl_msg_t m;
        size_t dl;
        const uint8_t *du = reply_du(&R.ru.u, &dl, &m);
        if (du != NULL && dl == 4u && du[0] == 0xDE && du[2] == DPV1_ERR_STATE_CONFLICT) {
            b5++;
            run_us(1000, 1000);
            continue;
        }
        break;
    }
    uint8_t want[DPV1_MAX_PDU] = {0x5E, 0x00, 0x2F, (uint8_t)rn};
    memcpy(&want[4], rsp, rn);
    expect_du(line, ma, dsap, ssap, want, 4u + rn);
    return b5;
}

#define DS47(ma, dsap, ssap, req, ...)                                                         \
    do {                                                                                       \
        const uint8_t d_[] = {__VA_ARGS__};                                                    \
        (void)ds47(__LINE__, (ma), (dsap), (ssap), (req), d_, sizeof d_);                      \
    } while (0)
#define DS47_C1(req, ...) DS47(M1, C1, C1, req, __VA_ARGS__)

/* ---- start-up ----------------------------------------------------------------------------- */

static const uint8_t USER_DPV1[9] = {0x80, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
static const uint8_t USER_DPV0[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
static const uint8_t CFG_P3PD[] = {0xF3, 0xF2};
static const uint8_t OUT_ZERO[14] = {0};

static void set_prm(uint8_t ma, const uint8_t user[9])
{
    uint8_t p[DP_MAX_PRM_LEN];
    size_t n = mk_prm(p, DP_PRM_LOCK_REQ | DP_PRM_WD_ON, 1, 100, 11, DFP21B_IDENT, 0, user, 9);
    send_sap(ma, DP_SAP_SET_PRM, DP_SAP_MASTER, p, n);
    EXPECT_SC();
}

static void chk_cfg(uint8_t ma)
{
    send_sap(ma, DP_SAP_CHK_CFG, DP_SAP_MASTER, CFG_P3PD, sizeof CFG_P3PD);
    EXPECT_SC();
}

/* Slave_Diag, Set_Prm (watchdog 1 s) with the given user parameters, Chk_Cfg Param + 3 PD, one
 * Data_Exchange with zero outputs, the main loop. Master 2's FCs were 6D 5D 7D 5D, as in §A1.6:
 * the next is 7D, the one of §A1.6's C1 Write. */
static void startup(const uint8_t user[9])
{
    send_sap(M1, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, NULL, 0);
    EXPECT_DU(M1, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    set_prm(M1, user);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_WAIT_CFG);
    chk_cfg(M1);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_DATA_EXCH);
    send_dx(M1, OUT_ZERO, sizeof OUT_ZERO);
    main_loop();
}

/* The card's current inputs: parameter channel idle (8 x 00), PI1 status word 0x0202 (ready,
 * unit status 2 "no enable"), PI2 speed 0, PI3 0. */
static void expect_inputs(int line)
{
    const uint8_t in[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x02, 0x02, 0x00, 0x00, 0x00, 0x00};
    size_t len = fdl_encode_reply(R.e, M1, SLAVE, FDL_RSP_DL, false, 0, 0, in, sizeof in);
    expect_frame(line, R.e, len);
}

/* ---- the request/poll convention ---------------------------------------------------------- */

/* §A1.6: C1 Write DS47 (MOVILINK read of 8300) from master 2 to slave 4, FC 7D. */
static const uint8_t F_C1_WRITE[] = {0x68, 0x13, 0x13, 0x68, 0x84, 0x82, 0x7D, 0x33, 0x33,
                                     0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x10,
                                     0x00, 0x20, 0x6C, 0x00, 0x00, 0x5F, 0x16};
/* §A1.6: C1 Read DS47, FC 5D. */
static const uint8_t F_C1_READ[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x82, 0x5D,
                                    0x33, 0x33, 0x5E, 0x00, 0x2F, 0xF0, 0x46, 0x16};
/* §A1.6: the negative Read response B5, and RS. */
#define F_C1_READ_B5                                                                           \
    0x68, 0x09, 0x09, 0x68, 0x82, 0x84, 0x08, 0x33, 0x33, 0xDE, 0x80, 0xB5, 0x00, 0x87, 0x16
#define F_RS_2 0x10, 0x02, 0x04, 0x03, 0x09, 0x16

static void test_startup_inputs(void)
{
    setup(0);
    startup(USER_DPV1);
    CHECK(dp_slave_dpv1_mode(&R.cs.card.dp));
    CHECK(R.cs.card.dpv1.c1.open);
    CHECK_EQ(R.cs.card.dpv1.c1.master, M1);
    send_dx(M1, OUT_ZERO, sizeof OUT_ZERO);
    expect_inputs(__LINE__);
}

static void test_sc_poll_convention(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Write.req: taken with SC, nothing worked on the reply path. */
    send_literal(__LINE__, F_C1_WRITE, sizeof F_C1_WRITE);
    EXPECT_SC();
    CHECK_EQ(R.cs.card.dpv1.c1.mailbox, DPV1_MB_REQUEST);
    /* A poll before the main loop ran: SC. */
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
    main_loop();
    CHECK_EQ(R.cs.card.dpv1.c1.mailbox, DPV1_MB_RESPONSE);
    /* The next poll fetches Write.res. */
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0x5F, 0x00, 0x2F, 0x0A);
    unsigned first = (R.ru.frames - 1u) % LOG_MAX;
    /* The same poll again (FCB unchanged, a retry): the cached frame. */
    send_sap_fc(M1, tm_fc_retry(&R.m[M1], FDL_REQ_SRD_HIGH), C1, C1, NULL, 0);
    expect_frame(__LINE__, R.ru.f[first], R.ru.len[first]);
    /* A new poll after the response was fetched: SC, and again after the main loop. */
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
    /* The data set 47 answer is there for a Read. */
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0x5E, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01,
                0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
}

/* A retried request (FCB unchanged) gets the cached SC and is not taken again; a new request
 * replaces an unfetched response. */
static void test_request_retry_and_replacement(void)
{
    setup(0);
    startup(USER_DPV1);
    const uint8_t read48[] = {0x5E, 0x00, 0x30, 0xF0}; /* index 48: B0 */
    send_sap(M1, C1, C1, read48, sizeof read48);
    EXPECT_SC();
    main_loop(); /* the response (B0) is ready, not fetched */
    send_sap_fc(M1, tm_fc_retry(&R.m[M1], FDL_REQ_SRD_HIGH), C1, C1, read48, sizeof read48);
    EXPECT_SC();
    CHECK_EQ(R.cs.card.dpv1.c1.mailbox, DPV1_MB_RESPONSE); /* not taken as a new request */
    /* A different request replaces the unfetched answer. */
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x31, 0xF0)); /* index 49 */
    EXPECT_SC();
    CHECK_EQ(R.cs.card.dpv1.c1.mailbox, DPV1_MB_REQUEST);
    CHECK_EQ(dpv1_pdu(&R.cs.card.dpv1.c1)[2], 0x31); /* the response is written over the request */
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0xDE, 0x80, 0xB0, 0x00);
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
}

/* ---- data set 47: the manual's examples (protocol.md §B7) ------------------------------------ */

static void test_manual_examples(void)
{
    char dir[] = "/tmp/dpv1_ee_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char ee[64];
    snprintf(ee, sizeof ee, "%s/eeprom", dir);
    opts_t o = {.eeprom = ee};
    setup_opts(&o);
    startup(USER_DPV1);
    uint32_t ee0 = R.cs.md.eeprom_writes;

    /* MOVILINK read of 8300 (firmware version). */
    DS47_C1(B(0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* MOVILINK write volatile of H0 (11000) = 3000: RAM only. */
    DS47_C1(B(0x01, 0x40, 0x00, 0x01, 0x30, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x0B, 0xB8),
            0x01, 0x40, 0x00, 0x01);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 3000);
    CHECK_EQ(R.cs.md.eeprom_writes - ee0, 0);
    DS47_C1(B(0x02, 0x40, 0x00, 0x01, 0x10, 0x00, 0x2A, 0xF8, 0x00, 0x00),
            0x02, 0x40, 0x00, 0x01, 0x43, 0x01, 0x00, 0x00, 0x0B, 0xB8);
    /* PROFIdrive request parameter 8300. */
    DS47_C1(B(0x01, 0x01, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x01, 0x01, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* PROFIdrive change parameter P160 n11 (8489 = 0x2129, axis 0) to 300000 (0x000493E0):
     * non-volatile, one EEPROM write. */
    DS47_C1(B(0x05, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00),
            0x05, 0x01, 0x00, 0x01, 0x43, 0x01, 0x00, 0x02, 0x49, 0xF0); /* 150000 before */
    DS47_C1(B(0x06, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x04, 0x93, 0xE0),
            0x06, 0x02, 0x00, 0x01);
    CHECK_EQ(R.cs.md.eeprom_writes - ee0, 1);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_P160_N11, &v));
    CHECK_EQ(v, 300000);
    DS47_C1(B(0x07, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00),
            0x07, 0x01, 0x00, 0x01, 0x43, 0x01, 0x00, 0x04, 0x93, 0xE0);
    /* Negative MOVILINK response: illegal index 1 -> 0x0810; as PROFIdrive: 0x00. */
    DS47_C1(B(0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x00, 0x01, 0x00, 0x00),
            0x01, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x10);
    DS47_C1(B(0x01, 0x01, 0x00, 0x01, 0x10, 0x00, 0x00, 0x01, 0x00, 0x00),
            0x01, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x00);
    /* Value too high (P302 8517 > max): MOVILINK 0x0815, PROFIdrive "limit exceeded" 0x02. */
    DS47_C1(B(0x08, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x45, 0x00, 0x00, 0x43, 0x01, 0x05,
              0xE6, 0xA4, 0xC0),
            0x08, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x15);
    DS47_C1(B(0x09, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x45, 0x00, 0x00, 0x43, 0x01, 0x05,
              0xE6, 0xA4, 0xC0),
            0x09, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x02);
    /* The slot is not evaluated (protocol.md §B1): slot 5 works and is echoed. */
    TRANSACT(M1, C1, C1,
             B(0x5F, 0x05, 0x2F, 0x0A, 0x0A, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
               0x00),
             0x5F, 0x05, 0x2F, 0x0A);
    TRANSACT(M1, C1, C1, B(0x5E, 0x05, 0x2F, 0xF0), 0x5E, 0x05, 0x2F, 0x0A, 0x0A, 0x40, 0x00,
             0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    unlink(ee);
    char bak[80];
    snprintf(bak, sizeof bak, "%s.bak", ee);
    unlink(bak);
    rmdir(dir);
}

/* ---- 0xB5 polling ------------------------------------------------------------------------- */

static void test_b5_polling(void)
{
    setup(20000); /* every MOVILINK service takes 20 ms */
    startup(USER_DPV1);
    send_literal(__LINE__, F_C1_WRITE, sizeof F_C1_WRITE);
    EXPECT_SC();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_SC();
    main_loop();
    hal_time_us_t due = line_now_us(&R.l) + 20000u; /* the service started in this round */
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0x5F, 0x00, 0x2F, 0x0A);
    /* Read right after the Write: B5, the frame of §A1.6. */
    send_literal(__LINE__, F_C1_READ, sizeof F_C1_READ);
    EXPECT_SC();
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_FRAME(F_C1_READ_B5);
    /* Repeated Reads: B5 while the main loop runs before the answer is due, then Read.res. */
    unsigned b5 = 1;
    bool answered = false;
    for (int i = 0; i < 40 && !answered; i++) {
        run_us(2000, 500);
        send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
        EXPECT_SC();
        bool before_due = !hal_time_reached(line_now_us(&R.l), due);
        main_loop();
        send_sap(M1, C1, C1, NULL, 0);
        if (before_due) {
            EXPECT_FRAME(F_C1_READ_B5);
            b5++;
        } else {
            EXPECT_DU(M1, C1, C1, 0x5E, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x43, 0x01,
                      0x31, 0x1C, 0x72, 0x89);
            answered = true;
        }
    }
    CHECK(answered);
    CHECK(b5 >= 5u);
    /* A Read with nothing pending: B5. */
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_FRAME(F_C1_READ_B5);

    /* A second Write while the first runs: DF 80 B5 00; the first goes on and is answered. */
    TRANSACT(M1, C1, C1,
             B(0x5F, 0x00, 0x2F, 0x0A, 0x21, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00,
               0x00),
             0x5F, 0x00, 0x2F, 0x0A);
    TRANSACT(M1, C1, C1, BN(F_C1_WRITE + 9, 14), 0xDF, 0x80, 0xB5, 0x00);
    CHECK_EQ(R.ru.u.last_len, 15);
    CHECK_EQ(R.ru.u.last[13], 0x88); /* FCS of 82 84 08 33 33 DF 80 B5 00 */
    run_us(25000, 1000);
    TRANSACT(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0), 0x5E, 0x00, 0x2F, 0x0A, 0x21, 0x01, 0x00,
             0x01, 0x43, 0x01, 0x00, 0x02, 0x49, 0xF0);
}

/* ---- errors ------------------------------------------------------------------------------- */

static void test_index_and_length_errors(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Index 48: B0 for Read and Write. */
    C1_TRANSACT(B(0x5E, 0x00, 0x30, 0xF0), 0xDE, 0x80, 0xB0, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0x30, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB0, 0x00);
    /* Write length field != data: B1 (11 announced, 10 sent; 9 announced, 10 sent; 0). */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0B, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB1, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x09, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB1, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x00), 0xDF, 0x80, 0xB1, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0x2F), 0xDF, 0x80, 0xB1, 0x00);
    /* Read length 0 and > 240: B7. */
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0x00), 0xDE, 0x80, 0xB7, 0x00);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF1), 0xDE, 0x80, 0xB7, 0x00);
    /* An unknown function on SAP 51: A9. */
    C1_TRANSACT(B(0x51, 0x00, 0x2F, 0x00), 0xD1, 0x80, 0xA9, 0x00);
    /* None of these left anything to read. */
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
}

static void test_header_errors_b7(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Request ID 0x03. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x03, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* Number of parameters 0. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x04, 0x01, 0x40, 0x00, 0x00), 0xDF, 0x80, 0xB7, 0x00);
    /* Number of parameters 20, with 20 address blocks. */
    uint8_t req[4 + 20 * 6] = {0x01, 0x40, 0x00, 20};
    for (unsigned i = 0; i < 20u; i++) {
        const uint8_t a[6] = {0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
        memcpy(&req[4 + 6 * i], a, 6);
    }
    size_t n = mk_write(R.pdu, DPV1_INDEX_DS47, req, sizeof req);
    TRANSACT(M1, C1, C1, BN(R.pdu, n), 0xDF, 0x80, 0xB7, 0x00);
    /* Truncated: 2 parameters announced, 1 address block. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x02, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* Truncated: write without its value block. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x30, 0x00, 0x2A, 0xF8, 0x00,
                  0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* Trailing octets after a complete request. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0C, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00, 0x00, 0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* Request Reference 0: the range is 0x01..0xFF. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0A, 0x00, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00,
                  0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* Only a request header of 3 octets. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x03, 0x01, 0x40, 0x00), 0xDF, 0x80, 0xB7, 0x00);
    /* Nothing was accepted. */
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
}

static void test_parameter_errors(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Axis 1: negative, 44 01 00 19 for every parameter (MOVILINK and PROFIdrive). */
    DS47_C1(B(0x11, 0x40, 0x01, 0x02, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x30, 0x00, 0x2A,
              0xF8, 0x00, 0x00, 0x43, 0x01, 0x00, 0x00, 0x00, 0x01),
            0x11, 0xC0, 0x01, 0x02, 0x44, 0x01, 0x00, 0x19, 0x44, 0x01, 0x00, 0x19);
    DS47_C1(B(0x12, 0x01, 0x01, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x12, 0x81, 0x01, 0x01, 0x44, 0x01, 0x00, 0x19);
    int32_t v = -1;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 0); /* the axis-1 write was not executed */
    /* The card has no description (0x09), no text (0x0F); another attribute is an address the
     * card does not have (0x16), manual §6.3. */
    DS47_C1(B(0x13, 0x01, 0x00, 0x01, 0x20, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x13, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x09);
    DS47_C1(B(0x13, 0x01, 0x00, 0x01, 0x30, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x13, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x0F);
    DS47_C1(B(0x13, 0x01, 0x00, 0x01, 0x50, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x13, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x16);
    /* Values of another format are found by their size (a zero octet after an odd count), so
     * the parameter is refused with 0x17 and the one after it still runs: U32 (4 octets), U8
     * (1 + pad). Write H0 in U32, then read 8300. */
    DS47_C1(B(0x18, 0x02, 0x00, 0x02, 0x10, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x10, 0x00, 0x2A,
              0xF9, 0x00, 0x00, 0x07, 0x01, 0x00, 0x00, 0x00, 0x05, 0x05, 0x01, 0x07, 0x00),
            0x18, 0x82, 0x00, 0x02, 0x44, 0x01, 0x00, 0x17, 0x44, 0x01, 0x00, 0x17);
    /* Format 0x09 VisibleString of 3 octets + pad, then a DWord that is taken: H1 := 7. */
    DS47_C1(B(0x19, 0x02, 0x00, 0x02, 0x10, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x10, 0x00, 0x2A,
              0xF9, 0x00, 0x00, 0x09, 0x03, 0x41, 0x42, 0x43, 0x00, 0x43, 0x01, 0x00, 0x00,
              0x00, 0x07),
            0x19, 0x82, 0x00, 0x02, 0x44, 0x01, 0x00, 0x17, 0x40, 0x00);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0 + 1u, &v));
    CHECK_EQ(v, 7);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 0);
    /* A format whose size is unknown hides where the request goes on: a header error. */
    C1_TRANSACT(B(0x5F, 0x00, 0x2F, 0x0E, 0x1A, 0x02, 0x00, 0x01, 0x10, 0x00, 0x2A, 0xF8, 0x00,
                  0x00, 0x0B, 0x01, 0x00, 0x00),
                0xDF, 0x80, 0xB7, 0x00);
    /* PROFIdrive subindex 1: 0x03; elements 2: 0x04; format 0x42: 0x17; two values: 0x18. */
    DS47_C1(B(0x14, 0x01, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x01),
            0x14, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x03);
    DS47_C1(B(0x15, 0x01, 0x00, 0x01, 0x10, 0x02, 0x20, 0x6C, 0x00, 0x00),
            0x15, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x04);
    DS47_C1(B(0x16, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x42, 0x01, 0x00,
              0x01),
            0x16, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x17);
    DS47_C1(B(0x17, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x02, 0x00,
              0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02),
            0x17, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x18);
    /* MOVILINK (id 0x40) refused before any service: subindex 1, elements 2, format 0x42, two
     * values: 0x0810 (decision). */
    DS47_C1(B(0x19, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x01),
            0x19, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x10);
    DS47_C1(B(0x1A, 0x40, 0x00, 0x01, 0x10, 0x02, 0x20, 0x6C, 0x00, 0x00),
            0x1A, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x10);
    DS47_C1(B(0x1B, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x29, 0x00, 0x00, 0x42, 0x01, 0x00,
              0x01),
            0x1B, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x10);
    DS47_C1(B(0x1C, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x02, 0x00,
              0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02),
            0x1C, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x10);
    /* MOVILINK reserved service (attribute 0x40): 0x0505. */
    DS47_C1(B(0x18, 0x40, 0x00, 0x01, 0x40, 0x00, 0x20, 0x6C, 0x00, 0x00),
            0x18, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x05, 0x05);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_P160_N11, &v));
    CHECK_EQ(v, 150000); /* none of the refused writes reached the inverter */
}

/* Data set 47 requests on IPOS H0..H18: a write of 100 + i to each, and a read of all with the
 * response that write leads to. */
static void nineteen_h(uint8_t wr[4 + 19 * 12], uint8_t rd[4 + 19 * 6], uint8_t rr[4 + 19 * 6])
{
    const uint8_t wh[4] = {0x32, 0x02, 0x00, 19}, rh[4] = {0x33, 0x01, 0x00, 19};
    memcpy(wr, wh, 4);
    memcpy(rd, rh, 4);
    memcpy(rr, rh, 4);
    for (unsigned i = 0; i < 19u; i++) {
        uint16_t idx = (uint16_t)(MOVIDRIVE_IDX_IPOS_H0 + i);
        const uint8_t a[6] = {0x10, 0x00, (uint8_t)(idx >> 8), (uint8_t)idx, 0x00, 0x00};
        const uint8_t val[6] = {0x43, 0x01, 0x00, 0x00, 0x00, (uint8_t)(100 + i)};
        memcpy(&wr[4 + 6 * i], a, 6);
        memcpy(&wr[4 + 19 * 6 + 6 * i], val, 6);
        memcpy(&rd[4 + 6 * i], a, 6);
        memcpy(&rr[4 + 6 * i], val, 6);
    }
}

static void test_19_parameters_and_mixed_results(void)
{
    setup(0);
    startup(USER_DPV1);
    /* 19 MOVILINK reads of 8300: 19 values, 118 octets. */
    uint8_t req[4 + 19 * 6] = {0x31, 0x40, 0x00, 19};
    uint8_t rsp[4 + 19 * 6] = {0x31, 0x40, 0x00, 19};
    for (unsigned i = 0; i < 19u; i++) {
        const uint8_t a[6] = {0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
        const uint8_t r[6] = {0x43, 0x01, 0x31, 0x1C, 0x72, 0x89};
        memcpy(&req[4 + 6 * i], a, 6);
        memcpy(&rsp[4 + 6 * i], r, 6);
    }
    (void)ds47(__LINE__, M1, C1, C1, BN(req, sizeof req), rsp, sizeof rsp);
    /* 19 PROFIdrive reads of different parameters: H0..H18 after writing H0..H18 = 100 + i. */
    uint8_t wr[4 + 19 * 12], rd[4 + 19 * 6], rr[4 + 19 * 6];
    nineteen_h(wr, rd, rr);
    const uint8_t wres[4] = {0x32, 0x02, 0x00, 19};
    (void)ds47(__LINE__, M1, C1, C1, BN(wr, sizeof wr), wres, sizeof wres);
    (void)ds47(__LINE__, M1, C1, C1, BN(rd, sizeof rd), rr, sizeof rr);
    /* Mixed MOVILINK: write volatile H0 = 7 ok, read 8300 ok, write volatile index 1 fails. */
    DS47_C1(B(0x41, 0x40, 0x00, 0x03, 0x30, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x10, 0x00, 0x20,
              0x6C, 0x00, 0x00, 0x30, 0x00, 0x00, 0x01, 0x00, 0x00, 0x43, 0x01, 0x00, 0x00,
              0x00, 0x07, 0x43, 0x01, 0x00, 0x00, 0x00, 0x08),
            0x41, 0xC0, 0x00, 0x03, 0x40, 0x00, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89, 0x44, 0x01,
            0x08, 0x10);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 7);
    /* Mixed PROFIdrive change: P160 = 200000 ok, index 1 fails (0x00). */
    DS47_C1(B(0x42, 0x02, 0x00, 0x02, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x10, 0x00, 0x00,
              0x01, 0x00, 0x00, 0x43, 0x01, 0x00, 0x03, 0x0D, 0x40, 0x43, 0x01, 0x00, 0x00,
              0x00, 0x01),
            0x42, 0x82, 0x00, 0x02, 0x40, 0x00, 0x44, 0x01, 0x00, 0x00);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_P160_N11, &v));
    CHECK_EQ(v, 200000);
}

/* The main loop's long DP-V1 work runs in steps with dpv1's preempt hook between them, where
 * the card serves telegrams (PendSV on the MCU). These tests deliver a telegram from that hook. */
typedef struct preempt_inject {
    unsigned calls;
    unsigned at;  /* deliver on this call */
    bytes_t pdu;  /* on C1 */
} preempt_inject_t;

static preempt_inject_t PI;

static void inject_on_preempt(void *ctx)
{
    (void)ctx;
    if (++PI.calls == PI.at) {
        R.ru.in_main_loop = false; /* the card's reply path, not its main loop, answers this */
        send_b(M1, C1, C1, PI.pdu);
        expect_frame(__LINE__, SC, 1);
        R.ru.in_main_loop = true;
    }
}

/* A Read 47 whose response is being written (DS47_BUILD_STEP entries per step) is replaced by a
 * Read of I&M0 between two steps: the first is dropped unanswered, the I&M read is answered, and
 * the data set 47 response stays unread for the next Read 47, which gets all of it, once. */
static void test_ds47_read_replaced_between_steps(void)
{
    setup(0);
    startup(USER_DPV1);
    uint8_t wr[4 + 19 * 12], rd[4 + 19 * 6], rr[4 + 19 * 6];
    nineteen_h(wr, rd, rr);
    const uint8_t wres[4] = {0x32, 0x02, 0x00, 19};
    (void)ds47(__LINE__, M1, C1, C1, BN(wr, sizeof wr), wres, sizeof wres);
    uint8_t pdu[DPV1_MAX_PDU];
    size_t pn = mk_write(pdu, DPV1_INDEX_DS47, rd, sizeof rd);
    transact(__LINE__, M1, C1, C1, BN(pdu, pn), pdu, 4);
    run_us(20000, 1000); /* 19 services done: the response is ready, not yet written anywhere */
    CHECK_EQ(R.cs.card.dpv1.c1.ds47.state, DS47_DONE);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    PI = (preempt_inject_t){.at = 1, .pdu = B(0x5E, 0x00, 0xFF, 0xF0)};
    R.cs.card.dpv1.preempt = inject_on_preempt;
    main_loop();
    R.cs.card.dpv1.preempt = NULL;
    CHECK_EQ(PI.calls >= 1u, 1);
    send_sap(M1, C1, C1, NULL, 0);
    fdl_msg_t m;
    size_t dl = 0;
    const uint8_t *du = reply_du(&R.ru.u, &dl, &m);
    CHECK(du != NULL && dl == 4u + 4u + IM_RECORD_LEN);
    if (du != NULL && dl >= 4u) {
        CHECK_EQ(du[0], 0x5E);
        CHECK_EQ(du[2], DPV1_INDEX_IM);
        CHECK_EQ(du[3], 4u + IM_RECORD_LEN);
    }
    CHECK_EQ(R.cs.card.dpv1.c1.ds47.state, DS47_DONE);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    main_loop();
    uint8_t want[DPV1_MAX_PDU] = {0x5E, 0x00, 0x2F, (uint8_t)sizeof rr};
    memcpy(&want[4], rr, sizeof rr);
    send_sap(M1, C1, C1, NULL, 0);
    expect_du(__LINE__, M1, C1, C1, want, 4u + sizeof rr);
    /* read once: the next Read has nothing to answer */
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0xDE, 0x80, 0xB5, 0x00);
}

/* A Write 47 being checked in steps (DS47_PARSE_STEP parameters each) is replaced by another
 * Write between two steps: the first is dropped (no service of it runs), the second runs. */
static void test_ds47_write_replaced_between_steps(void)
{
    setup(0);
    startup(USER_DPV1);
    uint8_t wr[4 + 19 * 12], rd[4 + 19 * 6], rr[4 + 19 * 6];
    nineteen_h(wr, rd, rr);
    int32_t h0_before = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &h0_before));
    uint8_t first[DPV1_MAX_PDU], second[DPV1_MAX_PDU];
    size_t fn = mk_write(first, DPV1_INDEX_DS47, wr, sizeof wr);
    /* the second: one MOVILINK read of 8300 */
    const uint8_t one[] = {0x34, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
    size_t sn = mk_write(second, DPV1_INDEX_DS47, one, sizeof one);
    send_b(M1, C1, C1, BN(first, fn));
    EXPECT_SC();
    PI = (preempt_inject_t){.at = 1, .pdu = BN(second, sn)};
    R.cs.card.dpv1.preempt = inject_on_preempt;
    main_loop();
    R.cs.card.dpv1.preempt = NULL;
    CHECK_EQ(PI.calls >= 1u, 1);
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0x5F, 0x00, 0x2F, 0x0A); /* the second Write's response */
    run_us(20000, 1000);
    int32_t h0 = -1;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &h0));
    CHECK_EQ(h0, h0_before); /* the dropped Write's services never ran */
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_DU(M1, C1, C1, 0x5E, 0x00, 0x2F, 0x0A, 0x34, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31,
              0x1C, 0x72, 0x89);
}

/* MOVILINK error values and their PROFIdrive numbers (docs/dpv1.md "Error values"). */
static void test_error_mapping(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Read only (P076 8300): 0x0812 / PROFIdrive 0x01. */
    DS47_C1(B(0x51, 0x40, 0x00, 0x01, 0x30, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x51, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x12);
    DS47_C1(B(0x52, 0x02, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x52, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x01);
    /* Too low (P130 8470 = -1): 0x0816 / 0x02. */
    DS47_C1(B(0x53, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x16, 0x00, 0x00, 0x43, 0x01, 0xFF,
              0xFF, 0xFF, 0xFF),
            0x53, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x16);
    DS47_C1(B(0x54, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x16, 0x00, 0x00, 0x43, 0x01, 0xFF,
              0xFF, 0xFF, 0xFF),
            0x54, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x02);
    /* Value not permitted (P873 8307 = 10, a reserved enumeration value): 0x081D / 0x14. */
    DS47_C1(B(0x55, 0x40, 0x00, 0x01, 0x30, 0x00, 0x20, 0x73, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x0A),
            0x55, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x1D);
    DS47_C1(B(0x56, 0x02, 0x00, 0x01, 0x10, 0x00, 0x20, 0x73, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x0A),
            0x56, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x14);
    /* Parameter lock (P803 8595 = 1): 0x0813 / 0x11; unlocked, the write goes through. */
    DS47_C1(B(0x57, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x93, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x57, 0x40, 0x00, 0x01);
    DS47_C1(B(0x58, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x58, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x13);
    DS47_C1(B(0x59, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x59, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x11);
    DS47_C1(B(0x5A, 0x40, 0x00, 0x01, 0x30, 0x00, 0x21, 0x93, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x00),
            0x5A, 0x40, 0x00, 0x01);
    DS47_C1(B(0x5B, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x00, 0x00, 0x01),
            0x5B, 0x02, 0x00, 0x01);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_P160_N11, &v));
    CHECK_EQ(v, 1);
}

/* The inverter does not answer within the card's 200 ms: 0x0602. */
static void test_inverter_timeout_0602(void)
{
    setup(500000);
    startup(USER_DPV1);
    unsigned b5 = ds47(__LINE__, M1, C1, C1,
                       B(0x61, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
                       (const uint8_t[]){0x61, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x06, 0x02}, 8);
    CHECK(b5 >= 100u); /* about 200 ms of B5 at one Read every ~1.2 ms */
    CHECK_EQ(R.cs.card.ml.timeouts, 1);
    /* The late answer arrives and changes nothing; as PROFIdrive the fault is 0x0082 (0x0080 +
     * the low octet of 0x0602, the value the master's texts use). */
    run_us(400000, 1000);
    CHECK_EQ(R.cs.card.ml.stale_responses, 1);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
    b5 = ds47(__LINE__, M1, C1, C1, B(0x62, 0x01, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
              (const uint8_t[]){0x62, 0x81, 0x00, 0x01, 0x44, 0x01, 0x00, 0x82}, 8);
    CHECK(b5 >= 100u);
    CHECK_EQ(R.cs.card.ml.timeouts, 2);
}

/* ---- MSAC1 availability ------------------------------------------------------------------- */

static void test_msac1_closed_without_dpv1_enable(void)
{
    setup(0);
    /* Before any parameterisation: RS. */
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_FRAME(F_RS_2);
    /* §A1.6 start-up literally (user prm 00 00 00 ...: no DPV1_Enable). */
    send_literal(__LINE__, F_SET_PRM, sizeof F_SET_PRM);
    EXPECT_SC();
    send_literal(__LINE__, F_CHK_CFG, sizeof F_CHK_CFG);
    EXPECT_SC();
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_DATA_EXCH);
    CHECK(!dp_slave_dpv1_mode(&R.cs.card.dp));
    main_loop();
    send_literal(__LINE__, F_C1_READ, sizeof F_C1_READ);
    EXPECT_FRAME(F_RS_2);
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_FRAME(F_RS_2);
    CHECK(!R.cs.card.dpv1.c1.open);
}

static void test_msac1_other_master_watchdog_new_prm(void)
{
    setup(0);
    startup(USER_DPV1);
    /* Another master: RS (and MSAC1 of master 2 is untouched). */
    send_b(3, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_RS(3);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
    /* A new Set_Prm: RS until Chk_Cfg is accepted. */
    set_prm(M1, USER_DPV1);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_WAIT_CFG);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_FRAME(F_RS_2);
    main_loop();
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_FRAME(F_RS_2);
    chk_cfg(M1);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
    /* A new Set_Prm without DPV1_Enable + Chk_Cfg: MSAC1 stays closed. */
    set_prm(M1, USER_DPV0);
    chk_cfg(M1);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_DATA_EXCH);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_FRAME(F_RS_2);
    /* DP-V1 again, then the watchdog (1 s) expires: Wait_Prm, RS. */
    set_prm(M1, USER_DPV1);
    chk_cfg(M1);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
    run_us(1000000, 10000);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_WAIT_PRM);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_FRAME(F_RS_2);
    send_sap(M1, C1, C1, NULL, 0);
    EXPECT_FRAME(F_RS_2);
    /* The master comes back: MSAC1 again after Set_Prm + Chk_Cfg. */
    set_prm(M1, USER_DPV1);
    chk_cfg(M1);
    C1_TRANSACT(B(0x5E, 0x00, 0x2F, 0xF0), 0xDE, 0x80, 0xB5, 0x00);
}

/* ---- MSAC2 -------------------------------------------------------------------------------- */

/* Initiate.req: Send_Timeout, Features 01 00, Profile features 12 34, Profile ident 3A 00,
 * S_Type 0 S_Len 2, D_Type 0 D_Len 2, S_Addr API 0 SCL 0, D_Addr API 0 SCL 0: 20 octets. */
static size_t mk_initiate(uint8_t *p, uint16_t send_timeout_10ms)
{
    const uint8_t t[20] = {0x57, 0x00, 0x00, 0x00, (uint8_t)(send_timeout_10ms >> 8),
                           (uint8_t)send_timeout_10ms, 0x01, 0x00, 0x12, 0x34, 0x3A, 0x00,
                           0x00, 0x02, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00};
    memcpy(p, t, sizeof t);
    return sizeof t;
}

/* Initiate from master ma (SSAP 50) to the RM: 56 sap 00 00; then the Initiate.res from the
 * connection SAP (SC before the main loop ran). */
static void c2_open(int line, uint8_t ma, uint8_t sap)
{
    uint8_t p[20];
    size_t n = mk_initiate(p, 0x0064); /* 1 s */
    send_sap(ma, DPV1_SAP_RM, SSAP_C2, p, n);
    const uint8_t rm[4] = {0x56, sap, 0x00, 0x00};
    expect_du(line, ma, DPV1_SAP_RM, SSAP_C2, rm, sizeof rm);
    send_sap(ma, sap, SSAP_C2, NULL, 0);
    expect_frame(line, SC, 1);
    main_loop();
    send_sap(ma, sap, SSAP_C2, NULL, 0);
    /* 57, Max_Len_Data_Unit F0, Features 01 00; the requested profile 3A 00 (features 12 34)
     * is not the card's (profile ident 0): 00 00 00 00, then 4 x 00 */
    const uint8_t res[12] = {0x57, 0xF0, 0x01, 0x00, 0x00, 0x00,
                             0x00, 0x00, 0x00, 0x00, 0x00, 0x00};
    expect_du(line, ma, sap, SSAP_C2, res, sizeof res);
    send_sap(ma, sap, SSAP_C2, NULL, 0);
    expect_frame(line, SC, 1);
}

static void test_msac2_connections(void)
{
    setup(0); /* no Set_Prm at all: the card stays in Wait_Prm */
    c2_open(__LINE__, 3, 0);
    CHECK(R.cs.card.dpv1.c2[0].open);
    CHECK_EQ(R.cs.card.dpv1.c2[0].master, 3);
    CHECK_EQ(R.cs.card.dpv1.c2[0].ssap, SSAP_C2);
    CHECK_EQ(R.cs.card.dpv1.c2[0].send_timeout_us, 1000000);
    /* Data set 47 over the connection. */
    DS47(3, 0, SSAP_C2, B(0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
         0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* A second master gets SAP 1, a third is refused. */
    c2_open(__LINE__, 5, 1);
    uint8_t p[20];
    size_t n = mk_initiate(p, 0x0064);
    send_sap(6, DPV1_SAP_RM, SSAP_C2, p, n);
    EXPECT_DU(6, DPV1_SAP_RM, SSAP_C2, 0x58, 0x00, 0x1F, 0x00);
    CHECK_EQ(R.cs.card.dpv1.c2_refused, 1);
    /* The connections are bound to their master and SSAP. */
    send_sap(5, 0, SSAP_C2, NULL, 0);
    EXPECT_RS(5);
    send_sap(3, 1, SSAP_C2, NULL, 0);
    EXPECT_RS(3);
    send_b(3, 0, 51, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_RS(3);
    send_b(6, 0, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_RS(6);
    /* No third connection SAP, no alarm SAP. */
    send_b(3, 2, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_RS(3);
    send_b(3, 50, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_RS(3);
    /* Both connections work, each with its own data set 47. */
    DS47(5, 1, SSAP_C2, B(0x02, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00),
         0x02, 0x01, 0x00, 0x01, 0x43, 0x01, 0x00, 0x02, 0x49, 0xF0);
    DS47(3, 0, SSAP_C2, B(0x03, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
         0x03, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* An unknown function on a connection: A9. */
    TRANSACT(5, 1, SSAP_C2, B(0x5C, 0x00, 0x00, 0x00), 0xDC, 0x80, 0xA9, 0x00);
    /* C2 never needed a parameterisation; MSAC1 is closed. */
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_WAIT_PRM);
    send_b(M1, C1, C1, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_FRAME(F_RS_2);
}

/* docs/dpv1.md "Smaller decisions" about the resource manager and Initiate. */
static void test_msac2_rm_decisions(void)
{
    setup(0);
    uint8_t p[24];
    size_t n = mk_initiate(p, 0x0064);
    /* SAP 49: a 19-octet Initiate, a Read, an Idle: Abort FE (58 00 12 00), no connection. */
    send_sap(3, DPV1_SAP_RM, SSAP_C2, p, 19);
    EXPECT_DU(3, DPV1_SAP_RM, SSAP_C2, 0x58, 0x00, 0x12, 0x00);
    send_b(3, DPV1_SAP_RM, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_DU(3, DPV1_SAP_RM, SSAP_C2, 0x58, 0x00, 0x12, 0x00);
    send_b(3, DPV1_SAP_RM, SSAP_C2, B(0x48, 0x00, 0x00, 0x00));
    EXPECT_DU(3, DPV1_SAP_RM, SSAP_C2, 0x58, 0x00, 0x12, 0x00);
    CHECK(!R.cs.card.dpv1.c2[0].open && !R.cs.card.dpv1.c2[1].open);
    /* An Initiate longer than 20 octets (addresses with 4 octets each) is fine. */
    p[13] = 4;
    p[15] = 4;
    memset(&p[16], 0, 8);
    send_sap(3, DPV1_SAP_RM, SSAP_C2, p, 24);
    EXPECT_DU(3, DPV1_SAP_RM, SSAP_C2, 0x56, 0x00, 0x00, 0x00);
    main_loop();
    send_sap(3, 0, SSAP_C2, NULL, 0);
    EXPECT_DU(3, 0, SSAP_C2, 0x57, 0xF0, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
              0x00);
    /* Master 5 takes SAP 1; master 3 initiates again (a restart): its connection is replaced,
     * SAP 0 again, master 5's stays. A request with its old state finds a fresh mailbox. */
    c2_open(__LINE__, 5, 1);
    send_b(3, 0, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0));
    EXPECT_SC();
    c2_open(__LINE__, 3, 0);
    CHECK(R.cs.card.dpv1.c2[1].open);
    CHECK_EQ(R.cs.card.dpv1.c2_refused, 0);
    /* The same master with another SSAP is another requester: refused now (both taken). */
    send_sap(3, DPV1_SAP_RM, 40, p, n);
    EXPECT_DU(3, DPV1_SAP_RM, 40, 0x58, 0x00, 0x1F, 0x00);
    /* Send_Timeout 0 is 10 ms. */
    send_b(5, 1, SSAP_C2, B(0x58, 0x00, 0x20, 0x00));
    EXPECT_SC();
    n = mk_initiate(p, 0x0000);
    send_sap(6, DPV1_SAP_RM, SSAP_C2, p, n);
    EXPECT_DU(6, DPV1_SAP_RM, SSAP_C2, 0x56, 0x01, 0x00, 0x00);
    CHECK_EQ(R.cs.card.dpv1.c2[1].send_timeout_us, 10000);
    hal_time_us_t t6 = R.l.req_end_us;
    run_us((uint64_t)(t6 + 9999u - line_now_us(&R.l)), 100);
    CHECK(R.cs.card.dpv1.c2[1].open);
    run_us(1, 1);
    CHECK(!R.cs.card.dpv1.c2[1].open);
    send_sap(6, 1, SSAP_C2, NULL, 0);
    EXPECT_RS(6);
}

/* The FCB cache points at a fetched response in its connection's buffer; once that buffer holds
 * another master's PDU, the old master's retry must not get those octets as its answer. */
static void test_msac2_retry_after_buffer_reused(void)
{
    setup(0);
    c2_open(__LINE__, 3, 0);
    send_b(3, 0, SSAP_C2, B(0x5E, 0x00, 0x2F, 0xF0)); /* Read 47: nothing to read, B5 */
    EXPECT_SC();
    main_loop();
    send_sap(3, 0, SSAP_C2, NULL, 0);
    EXPECT_DU(3, 0, SSAP_C2, 0xDE, 0x80, 0xB5, 0x00);
    unsigned fetched = (R.ru.frames - 1u) % LOG_MAX;
    /* A retry while the buffer still holds it: the same frame, nothing executed. */
    send_sap_fc(3, tm_fc_retry(&R.m[3], FDL_REQ_SRD_HIGH), 0, SSAP_C2, NULL, 0);
    expect_frame(__LINE__, R.ru.f[fetched], R.ru.len[fetched]);
    /* Master 3 falls silent past its Send_Timeout (1 s): closed. Master 5 opens SAP 0, its
     * Initiate PDU now in that buffer. */
    run_us(1100000, 1000);
    CHECK(!R.cs.card.dpv1.c2[0].open);
    c2_open(__LINE__, 5, 0);
    /* Master 3 repeats its old poll: not answered from the buffer, refused as a new request. */
    send_sap_fc(3, tm_fc_retry(&R.m[3], FDL_REQ_SRD_HIGH), 0, SSAP_C2, NULL, 0);
    EXPECT_RS(3);
}

static void test_msac2_supervision_idle_abort(void)
{
    setup(0);
    c2_open(__LINE__, 3, 0);
    hal_time_us_t last3 = R.l.req_end_us; /* master 3's last telegram */
    c2_open(__LINE__, 5, 1);
    /* Master 5 sends Idle every 300 ms (echoed); master 3 is silent. */
    uint64_t idle_at = 300000;
    for (int k = 0; k < 3; k++) {
        run_us(idle_at - (line_now_us(&R.l) - last3), 1000);
        send_b(5, 1, SSAP_C2, B(0x48, 0x00, 0x00, 0x00));
        EXPECT_DU(5, 1, SSAP_C2, 0x48, 0x00, 0x00, 0x00);
        idle_at += 300000;
    }
    /* An Idle of 6 octets travels as SD3 (8-octet DU with the SAPs); echoed (4 octets). */
    send_b(5, 1, SSAP_C2, B(0x48, 0x00, 0x00, 0x00, 0x00, 0x00));
    CHECK_EQ(R.f[0], FDL_SD3);
    EXPECT_DU(5, 1, SSAP_C2, 0x48, 0x00, 0x00, 0x00);
    /* 990 ms after master 3's last telegram: both connections still there (master 6 refused). */
    run_us((uint64_t)(last3 + 990000u - line_now_us(&R.l)), 1000);
    CHECK(R.cs.card.dpv1.c2[0].open);
    uint8_t p[20];
    size_t n = mk_initiate(p, 0x0064);
    send_sap(6, DPV1_SAP_RM, SSAP_C2, p, n);
    EXPECT_DU(6, DPV1_SAP_RM, SSAP_C2, 0x58, 0x00, 0x1F, 0x00);
    /* 1 s of silence: the main loop frees master 3's connection. Master 5's, opened ~1 ms
     * later, lives on its Idles: still there at 1.3 s (its last Idle was at 0.9 s). */
    run_us((uint64_t)(last3 + 999999u - line_now_us(&R.l)), 500);
    CHECK(R.cs.card.dpv1.c2[0].open);
    run_us(1, 1);
    CHECK(!R.cs.card.dpv1.c2[0].open);
    CHECK(R.cs.card.dpv1.c2[1].open);
    CHECK_EQ(R.cs.card.dpv1.c2_timeouts, 1);
    run_us((uint64_t)(last3 + 1300000u - line_now_us(&R.l)), 1000);
    CHECK(R.cs.card.dpv1.c2[1].open);
    CHECK_EQ(R.cs.card.dpv1.c2_timeouts, 1);
    send_sap(3, 0, SSAP_C2, NULL, 0);
    EXPECT_RS(3);
    c2_open(__LINE__, 6, 0);
    DS47(5, 1, SSAP_C2, B(0x04, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
         0x04, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* Master 5 aborts: SC, the connection is free, its SAP answers RS. */
    send_b(5, 1, SSAP_C2, B(0x58, 0x00, 0x20, 0x00));
    EXPECT_SC();
    CHECK(!R.cs.card.dpv1.c2[1].open);
    CHECK_EQ(R.cs.card.dpv1.c2_aborts, 1);
    send_sap(5, 1, SSAP_C2, NULL, 0);
    EXPECT_RS(5);
    main_loop();
    c2_open(__LINE__, 3, 1);
}

/* A connection dropped while its data set 47 service runs (20 ms inverter): the late inverter
 * answer of the dropped request must not complete the next request on the same channel. */
static void test_msac2_abort_while_service_runs(void)
{
    setup(20000);
    c2_open(__LINE__, 3, 0);
    DS47(3, 0, SSAP_C2, B(0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00),
         0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    const uint8_t rd8300[] = {0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
    size_t n = mk_write(R.pdu, DPV1_INDEX_DS47, rd8300, sizeof rd8300);
    transact(__LINE__, 3, 0, SSAP_C2, BN(R.pdu, n), R.pdu, 4); /* MOVILINK read of 8300 runs */
    send_b(3, 0, SSAP_C2, B(0x58, 0x00, 0x20, 0x00));
    EXPECT_SC();
    CHECK(!R.cs.card.dpv1.c2[0].open);
    main_loop();
    c2_open(__LINE__, 5, 0); /* the same SAP, the same MOVILINK channel */
    /* Not the dropped read's answer (8300 = 0x311C7289): 8489's own 150000 = 0x000249F0. */
    DS47(5, 0, SSAP_C2, B(0x02, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00),
         0x02, 0x01, 0x00, 0x01, 0x43, 0x01, 0x00, 0x02, 0x49, 0xF0);
}

/* The same on MSAC1: a new parameterisation closes MSAC1 while a read of 8300 runs; the change
 * of P160 sent after the re-opening must reach the inverter. */
static void test_msac1_reopen_while_service_runs(void)
{
    setup(20000);
    startup(USER_DPV1);
    TRANSACT(M1, C1, C1, BN(F_C1_WRITE + 9, 14), 0x5F, 0x00, 0x2F, 0x0A); /* read 8300 runs */
    set_prm(M1, USER_DPV1);
    chk_cfg(M1);
    CHECK(R.cs.card.dpv1.c1.open);
    /* Answered positively only once the write really reached the inverter. */
    DS47_C1(B(0x02, 0x02, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00,
              0x04, 0x93, 0xE0),
            0x02, 0x02, 0x00, 0x01);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_P160_N11, &v));
    CHECK_EQ(v, 300000);
}

/* ---- interleaving ------------------------------------------------------------------------- */

static void test_interleaving(void)
{
    setup(20000);
    startup(USER_DPV1);
    c2_open(__LINE__, 3, 0);
    c2_open(__LINE__, 5, 1);
    /* Three data set 47 requests go in, Data_Exchange between every DP-V1 telegram. */
    const uint8_t r1[] = {0x11, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
    const uint8_t r2[] = {0x22, 0x01, 0x00, 0x01, 0x10, 0x00, 0x21, 0x29, 0x00, 0x00};
    const uint8_t r3[] = {0x33, 0x40, 0x00, 0x02, 0x30, 0x00, 0x2A, 0xF8, 0x00, 0x00,
                          0x10, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x43, 0x01, 0x12, 0x34, 0x56, 0x78};
    const uint8_t a1[] = {0x11, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89};
    const uint8_t a2[] = {0x22, 0x01, 0x00, 0x01, 0x43, 0x01, 0x00, 0x02, 0x49, 0xF0};
    const uint8_t a3[] = {0x33, 0x40, 0x00, 0x02, 0x43, 0x01, 0x12, 0x34, 0x56, 0x78};
    struct {
        uint8_t ma, dsap, ssap;
        const uint8_t *req, *ans;
        size_t rn, an;
        bool written, done;
    } c[3] = {
        {M1, C1, C1, r1, a1, sizeof r1, sizeof a1, false, false},
        {3, 0, SSAP_C2, r2, a2, sizeof r2, sizeof a2, false, false},
        {5, 1, SSAP_C2, r3, a3, sizeof r3, sizeof a3, false, false},
    };
    unsigned dx = 0;
    unsigned b5 = 0;
    for (int round = 0; round < 100; round++) {
        for (int i = 0; i < 3; i++) {
            if (c[i].done) {
                continue;
            }
            send_dx(M1, OUT_ZERO, sizeof OUT_ZERO);
            expect_inputs(__LINE__);
            dx++;
            uint8_t pdu[DPV1_MAX_PDU];
            size_t n;
            if (!c[i].written) {
                n = mk_write(pdu, DPV1_INDEX_DS47, c[i].req, c[i].rn);
            } else {
                const uint8_t rd[4] = {0x5E, 0x00, 0x2F, 0xF0};
                memcpy(pdu, rd, 4);
                n = 4;
            }
            send_sap(c[i].ma, c[i].dsap, c[i].ssap, pdu, n);
            EXPECT_SC();
            send_dx(M1, OUT_ZERO, sizeof OUT_ZERO);
            expect_inputs(__LINE__);
            dx++;
            main_loop();
            send_sap(c[i].ma, c[i].dsap, c[i].ssap, NULL, 0);
            fdl_msg_t m;
            size_t dl;
            const uint8_t *du = reply_du(&R.ru.u, &dl, &m);
            if (!c[i].written) {
                expect_du(__LINE__, c[i].ma, c[i].dsap, c[i].ssap, pdu, 4);
                c[i].written = true;
            } else if (du != NULL && dl == 4u && du[0] == 0xDE && du[2] == 0xB5) {
                b5++;
            } else {
                uint8_t want[64] = {0x5E, 0x00, 0x2F, (uint8_t)c[i].an};
                memcpy(&want[4], c[i].ans, c[i].an);
                expect_du(__LINE__, c[i].ma, c[i].dsap, c[i].ssap, want, 4u + c[i].an);
                c[i].done = true;
            }
        }
        if (c[0].done && c[1].done && c[2].done) {
            break;
        }
        run_us(1000, 500);
    }
    CHECK(c[0].done && c[1].done && c[2].done);
    CHECK(b5 >= 10u);
    CHECK(dx >= 40u);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 0x12345678);
    CHECK_EQ(dp_slave_state(&R.cs.card.dp), DP_STATE_DATA_EXCH);
}

/* ---- I&M ---------------------------------------------------------------------------------- */

static const uint8_t IM0[64] = {
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0,                              /* header */
    0x01, 0x0A,                                                /* MANUFACTURER_ID */
    '8', '2', '4', ' ', '2', '4', '0', ' ', '2', ' ', ' ', ' ', ' ', ' ', ' ', ' ', ' ', ' ',
    ' ', ' ',                                                  /* ORDER_ID */
    'D', 'F', 'P', '-', 'S', 'I', 'M', '-', '0', '0', '4', ' ', ' ', ' ', ' ', ' ', /* SERIAL */
    0x00, 0x01,                                                /* HARDWARE_REVISION */
    'V', 0x00, 0x04, 0x00,                                     /* SOFTWARE_REVISION */
    0x00, 0x00,                                                /* REV_COUNTER */
    0x00, 0x00,                                                /* PROFILE_ID */
    0x00, 0x00,                                                /* PROFILE_SPECIFIC_TYPE */
    0x01, 0x01,                                                /* IM_VERSION */
    0x00, 0x1E,                                                /* IM_SUPPORTED */
};

static void im_record(uint8_t rec[64], uint8_t seed)
{
    for (unsigned i = 0; i < 64u; i++) {
        rec[i] = (uint8_t)(seed + 7u * i);
    }
}

/* Write index 255 (call header + optional record) -> Write.res. */
static void im_call_write(int line, uint8_t ma, uint8_t dsap, uint8_t ssap, uint16_t fi,
                     const uint8_t *rec)
{
    uint8_t data[68] = {0x08, 0x00, (uint8_t)(fi >> 8), (uint8_t)fi};
    size_t n = 4;
    if (rec != NULL) {
        memcpy(&data[4], rec, 64);
        n = 68;
    }
    size_t pn = mk_write(R.pdu, DPV1_INDEX_IM, data, n);
    transact(line, ma, dsap, ssap, BN(R.pdu, pn), R.pdu, 4);
}

/* Read index 255 -> 08 00 FI + record. */
static void im_call_read(int line, uint8_t ma, uint8_t dsap, uint8_t ssap, uint16_t fi,
                    const uint8_t rec[64])
{
    uint8_t want[4 + 68] = {0x5E, 0x00, 0xFF, 68, 0x08, 0x00, (uint8_t)(fi >> 8), (uint8_t)fi};
    memcpy(&want[8], rec, 64);
    const uint8_t rd[4] = {0x5E, 0x00, 0xFF, 0xF0};
    transact(line, ma, dsap, ssap, BN(rd, sizeof rd), want, sizeof want);
}

static void test_im(void)
{
    setup(0);
    startup(USER_DPV1);
    /* I&M0: select, read. */
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x04, 0x08, 0x00, 0xFD, 0xE8), 0x5F, 0x00, 0xFF, 0x04);
    im_call_read(__LINE__, M1, C1, C1, 65000, IM0);
    /* I&M1 written (68 octets) and read back; selecting it again reads the same. */
    uint8_t rec1[64];
    im_record(rec1, 0x11);
    im_call_write(__LINE__, M1, C1, C1, 65001, rec1);
    im_call_read(__LINE__, M1, C1, C1, 65001, rec1);
    im_call_write(__LINE__, M1, C1, C1, 65000, NULL);
    im_call_read(__LINE__, M1, C1, C1, 65000, IM0);
    im_call_write(__LINE__, M1, C1, C1, 65001, NULL);
    im_call_read(__LINE__, M1, C1, C1, 65001, rec1);
    /* An I&M record never written reads blank (zeros). */
    const uint8_t blank[64] = {0};
    im_call_write(__LINE__, M1, C1, C1, 65004, NULL);
    im_call_read(__LINE__, M1, C1, C1, 65004, blank);
    /* Writing I&M0: B6 access denied; FI_Index 65005 and 64999: B0. */
    uint8_t data[68] = {0x08, 0x00, 0xFD, 0xE8};
    size_t n = mk_write(R.pdu, DPV1_INDEX_IM, data, sizeof data);
    TRANSACT(M1, C1, C1, BN(R.pdu, n), 0xDF, 0x80, 0xB6, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x04, 0x08, 0x00, 0xFD, 0xED), 0xDF, 0x80, 0xB0, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x04, 0x08, 0x00, 0xFD, 0xE7), 0xDF, 0x80, 0xB0, 0x00);
    data[3] = 0xED;
    n = mk_write(R.pdu, DPV1_INDEX_IM, data, sizeof data);
    TRANSACT(M1, C1, C1, BN(R.pdu, n), 0xDF, 0x80, 0xB0, 0x00);
    /* I&M0 is unchanged, and I&M over a C2 connection reads the same. */
    im_call_write(__LINE__, M1, C1, C1, 65000, NULL);
    im_call_read(__LINE__, M1, C1, C1, 65000, IM0);
    c2_open(__LINE__, 3, 0);
    im_call_write(__LINE__, 3, 0, SSAP_C2, 65001, NULL);
    im_call_read(__LINE__, 3, 0, SSAP_C2, 65001, rec1);
    /* Two requesters, each with its own Write/Read call pair, interleaved. */
    im_call_write(__LINE__, M1, C1, C1, 65000, NULL);
    im_call_write(__LINE__, 3, 0, SSAP_C2, 65001, NULL);
    im_call_read(__LINE__, M1, C1, C1, 65000, IM0);
    im_call_read(__LINE__, 3, 0, SSAP_C2, 65001, rec1);
    /* Read of index 255 shorter than call header + record: B7; a call header other than 08 00
     * (or shorter than 4 octets): B7. */
    C1_TRANSACT(B(0x5E, 0x00, 0xFF, 0x43), 0xDE, 0x80, 0xB7, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x04, 0x09, 0x00, 0xFD, 0xE8), 0xDF, 0x80, 0xB7, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x04, 0x08, 0x01, 0xFD, 0xE8), 0xDF, 0x80, 0xB7, 0x00);
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x03, 0x08, 0x00, 0xFD), 0xDF, 0x80, 0xB7, 0x00);
    /* A record of the wrong length: B1. */
    C1_TRANSACT(B(0x5F, 0x00, 0xFF, 0x05, 0x08, 0x00, 0xFD, 0xE9, 0x00), 0xDF, 0x80, 0xB1, 0x00);
    im_call_read(__LINE__, M1, C1, C1, 65000, IM0); /* the selection stayed */
    /* A new connection starts with I&M0 selected. */
    send_b(3, 0, SSAP_C2, B(0x58, 0x00, 0x20, 0x00));
    EXPECT_SC();
    c2_open(__LINE__, 3, 0);
    im_call_read(__LINE__, 3, 0, SSAP_C2, 65000, IM0);
}

static void test_im_persistence(void)
{
    char dir[] = "/tmp/dpv1_im_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[64];
    snprintf(path, sizeof path, "%s/card.nvm", dir);
    opts_t o = {.card_nvm = path};
    setup_opts(&o);
    c2_open(__LINE__, 3, 0); /* I&M over C2: no parameterisation needed */
    uint8_t rec[4][64];
    for (unsigned i = 0; i < 4u; i++) {
        im_record(rec[i], (uint8_t)(0x40 + 0x21 * i));
        im_call_write(__LINE__, 3, 0, SSAP_C2, (uint16_t)(65001 + i), rec[i]);
    }
    CHECK_EQ(R.cs.card_nvm.writes, 4);
    /* Power cycle: a new card from the same file (the old one's end gives up its lock). */
    card_station_close(&R.cs);
    memset(&R.cs, 0, sizeof R.cs);
    line_wait_us(&R.l, 100000);
    station_init(&o);
    R.st = card_station(&R.cs);
    c2_open(__LINE__, 3, 0);
    im_call_read(__LINE__, 3, 0, SSAP_C2, 65000, IM0);
    for (unsigned i = 0; i < 4u; i++) {
        im_call_write(__LINE__, 3, 0, SSAP_C2, (uint16_t)(65001 + i), NULL);
        im_call_read(__LINE__, 3, 0, SSAP_C2, (uint16_t)(65001 + i), rec[i]);
    }
    /* Without the file, a new card has blank records. */
    card_station_close(&R.cs);
    memset(&R.cs, 0, sizeof R.cs);
    opts_t none = {0};
    station_init(&none);
    R.st = card_station(&R.cs);
    c2_open(__LINE__, 3, 0);
    im_call_write(__LINE__, 3, 0, SSAP_C2, 65002, NULL);
    const uint8_t blank[64] = {0};
    im_call_read(__LINE__, 3, 0, SSAP_C2, 65002, blank);
    char p2[80];
    unlink(path);
    snprintf(p2, sizeof p2, "%s.bak", path);
    unlink(p2);
    snprintf(p2, sizeof p2, "%s.tmp", path);
    unlink(p2);
    rmdir(dir);
}

/* After every test: one reply per request, none from the main loop. */
static void finish(void)
{
    CHECK_EQ(R.ru.frames, R.requests);
    CHECK_EQ(R.ru.tx_from_main_loop, 0);
}

#define RUN(fn)                                                                                \
    do {                                                                                       \
        RUN_TEST(fn);                                                                          \
        finish();                                                                              \
    } while (0)

/* ---- The cyclic channel while the master is in Clear --------------------------------------
 * A master in Clear (PLC stopped, Auto_Clear) goes on sending this card, which has no
 * Fail_Safe, 14 octets of zeros. They are not a parameter request with handshake 0: taken as
 * one, the next service with handshake 0 would never run (and be answered "done" with zeros),
 * and the unchanged last request would run a second time back in Operate. */

static void send_gc(uint8_t ma, uint8_t cmd)
{
    const uint8_t d[2] = {cmd, 0};
    size_t len = mk_sap_req(R.f, FDL_ADDR_BROADCAST, ma, FDL_FC_REQUEST | FDL_REQ_SDN_HIGH,
                            DP_SAP_GLOBAL_CONTROL, d, 2);
    (void)line_request(&R.l, R.f, len); /* SDN: no reply */
}

/* The 8 octets of the parameter channel, PO1..PO3 = 0; three cycles, the main loop after each. */
static void dx_param_cycles(const uint8_t p[8])
{
    uint8_t out[14] = {0};
    memcpy(out, p, 8);
    for (int i = 0; i < 3; i++) {
        send_dx(M1, out, sizeof out);
        main_loop();
    }
}

static const uint8_t PARAM_ZERO[8] = {0};

static void test_clear_zeros_are_no_request(void)
{
    setup(0);
    startup(USER_DPV1);
    const uint8_t read_8300[8] = {0x41, 0x00, 0x20, 0x6C, 0, 0, 0, 0}; /* handshake 1 */
    dx_param_cycles(read_8300);
    CHECK_EQ(R.cs.card.param.services, 1);
    uint8_t before[8];
    memcpy(before, ml_channel_reply(&R.cs.card.param), 8);
    CHECK_EQ(before[0], 0x41);
    send_gc(M1, DP_GC_CLEAR_DATA);
    main_loop();
    dx_param_cycles(PARAM_ZERO);
    CHECK_EQ(R.cs.card.param.services, 1);
    CHECK(memcmp(ml_channel_reply(&R.cs.card.param), before, 8) == 0);
    /* Operate again; the PLC had toggled to its next job, read 8301 with handshake 0. */
    send_gc(M1, 0x00);
    const uint8_t read_8301[8] = {0x01, 0x00, 0x20, 0x6D, 0, 0, 0, 0};
    dx_param_cycles(read_8301);
    CHECK_EQ(R.cs.card.param.services, 2);
    const uint8_t *rsp = ml_channel_reply(&R.cs.card.param);
    CHECK_EQ(rsp[0], 0x01);
    CHECK_EQ(rsp[2], 0x20);
    CHECK_EQ(rsp[3], 0x6D);
}

static void test_clear_does_not_repeat_the_last_write(void)
{
    setup(0);
    startup(USER_DPV1);
    const uint8_t write_h0_5[8] = {0x73, 0x00, 0x2A, 0xF8, 0, 0, 0, 5}; /* volatile, handshake 1 */
    dx_param_cycles(write_h0_5);
    int32_t v = 0;
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 5);
    /* A class-2 tool sets H0 := 7 meanwhile. */
    c2_open(__LINE__, 3, 0);
    DS47(3, 0, SSAP_C2, B(0x01, 0x40, 0x00, 0x01, 0x30, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x43,
                          0x01, 0x00, 0x00, 0x00, 0x07),
         0x01, 0x40, 0x00, 0x01);
    send_gc(M1, DP_GC_CLEAR_DATA);
    dx_param_cycles(PARAM_ZERO);
    send_gc(M1, 0x00);
    dx_param_cycles(write_h0_5); /* the PLC's output image, unchanged */
    CHECK_EQ(R.cs.card.param.services, 1);
    CHECK(movidrive_read_value(&R.cs.md, MOVIDRIVE_IDX_IPOS_H0, &v));
    CHECK_EQ(v, 7);
}

int main(void)
{
    RUN(test_startup_inputs);
    RUN(test_sc_poll_convention);
    RUN(test_request_retry_and_replacement);
    RUN(test_manual_examples);
    RUN(test_b5_polling);
    RUN(test_index_and_length_errors);
    RUN(test_header_errors_b7);
    RUN(test_parameter_errors);
    RUN(test_19_parameters_and_mixed_results);
    RUN(test_ds47_read_replaced_between_steps);
    RUN(test_ds47_write_replaced_between_steps);
    RUN(test_error_mapping);
    RUN(test_inverter_timeout_0602);
    RUN(test_msac1_closed_without_dpv1_enable);
    RUN(test_msac1_other_master_watchdog_new_prm);
    RUN(test_msac2_connections);
    RUN(test_msac2_rm_decisions);
    RUN(test_msac2_retry_after_buffer_reused);
    RUN(test_msac2_supervision_idle_abort);
    RUN(test_msac2_abort_while_service_runs);
    RUN(test_msac1_reopen_while_service_runs);
    RUN(test_interleaving);
    RUN(test_im);
    RUN(test_im_persistence);
    RUN(test_clear_zeros_are_no_request);
    RUN(test_clear_does_not_repeat_the_last_write);
    return check_report();
}
