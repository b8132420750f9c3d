/* The generic DP-V0 slave (dp_slave), driven character by character with exact timestamps:
 * replies byte for byte, DP states, diagnosis octets, events, timers and the baud search, held
 * against protocol.md §A1-§A3. The device behind it is a simple hooks struct that records
 * what it is given. Station 4, ident 0x6003 (so the §A1.6 frames apply), masters 2 and 3. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "spec_frames.h"
#include "unit_rig.h"

#define SLAVE 4u
#define IDENT 0x6003u
#define BAUD 1500000u

static const uint8_t DEFAULT_CFG[] = {0xF3, 0xF2};
static const uint8_t CFG_P3PD[] = {0xF3, 0xF2};
/* DP-V1 status octets + DFP21B user parameters, as in the §A1.6 Set_Prm. */
static const uint8_t PRM_TAIL[] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};

/* §A1.6 frames, literally. */
static const uint8_t DX14[] = {0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
                               0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34};
static const uint8_t DX8[] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};

/* ---- the device: records everything ------------------------------------------------------- */

typedef struct app {
    ev_log_t log;
    unsigned outputs_calls;
    uint8_t out[DP_MAX_IO_LEN];
    size_t out_len;
    dp_outputs_reason_t out_reason;
    unsigned prm_calls;
    bool prm_refuse;
    uint8_t prm[DP_MAX_PRM_LEN];
    size_t prm_len;
    unsigned cfg_calls;
    bool cfg_refuse;
    const unsigned *tx_count;   /* the UART's, to see what was sent when a hook ran */
    unsigned tx_at_outputs;     /* replies sent when the outputs hook last ran */
    unsigned tx_at_cfg_check;   /* replies sent when the Chk_Cfg hook last ran */
} app_t;

static bool h_prm(void *ctx, const uint8_t *prm, size_t len)
{
    app_t *a = ctx;
    a->prm_calls++;
    a->prm_len = len;
    if (len > 0u) {
        memcpy(a->prm, prm, len);
    }
    return !a->prm_refuse;
}

/* General identifiers only; lengths summed per direction. */
static bool h_cfg(void *ctx, const uint8_t *cfg, size_t len, uint8_t *out_len, uint8_t *in_len)
{
    app_t *a = ctx;
    a->cfg_calls++;
    a->tx_at_cfg_check = *a->tx_count;
    if (a->cfg_refuse) {
        return false;
    }
    unsigned out = 0;
    unsigned in = 0;
    for (size_t i = 0; i < len; i++) {
        uint8_t dir = (uint8_t)(cfg[i] & DP_CFG_DIR_MASK);
        if (dir == DP_CFG_DIR_SPECIAL) {
            return false;
        }
        unsigned n = (cfg[i] & DP_CFG_LEN_MASK) + 1u;
        if ((cfg[i] & DP_CFG_WORDS) != 0u) {
            n *= 2u;
        }
        if ((dir & DP_CFG_DIR_OUT) != 0u) out += n;
        if ((dir & DP_CFG_DIR_IN) != 0u) in += n;
    }
    *out_len = (uint8_t)out;
    *in_len = (uint8_t)in;
    return true;
}

static void h_out(void *ctx, const uint8_t *out, size_t len, dp_outputs_reason_t why)
{
    app_t *a = ctx;
    a->outputs_calls++;
    a->tx_at_outputs = *a->tx_count;
    a->out_len = len;
    memcpy(a->out, out, len);
    a->out_reason = why;
}

static void h_ev(void *ctx, const dp_event_t *ev)
{
    app_t *a = ctx;
    ev_log_add(&a->log, ev);
}

/* ---- rig ---------------------------------------------------------------------------------- */

typedef struct rig {
    dp_slave_t s;
    fake_uart_t u;
    app_t a;
    line_t l;
    tmaster_t m2;
    tmaster_t m3;
    uint8_t f[FDL_FRAME_MAX];
    uint8_t saved[FDL_FRAME_MAX];
    size_t saved_len;
} rig_t;

static rig_t R; /* large: off the stack */

static void rx_dp(void *st, uint8_t b, uint8_t flags, hal_time_us_t t)
{
    dp_slave_rx_char(st, b, flags, t);
}

/* uart_max_baud: the fastest rate the fake UART makes (0: every rate). */
static void rig_init_uart(uint32_t fixed_baud, uint32_t baud_control_ms, uint32_t uart_max_baud)
{
    memset(&R, 0, sizeof R);
    R.u.max_baud = uart_max_baud;
    R.a.tx_count = &R.u.tx_count;
    line_init(&R.l, fixed_baud != 0u ? fixed_baud : 12000000u, rx_dp, &R.s, &R.u);
    dp_slave_cfg_t cfg = {
        .address = SLAVE,
        .ident = IDENT,
        .fixed_baud = fixed_baud,
        .strict_timing = true,
        .baud_control_ms = baud_control_ms,
        .sync_supported = true,
        .freeze_supported = true,
        .default_cfg = DEFAULT_CFG,
        .default_cfg_len = sizeof DEFAULT_CFG,
        .uart = fake_uart_hal(&R.u),
        .hooks = {.ctx = &R.a, .prm_check = h_prm, .cfg_check = h_cfg, .outputs = h_out,
                  .event = h_ev},
    };
    dp_slave_init(&R.s, &cfg, line_now_us(&R.l));
    R.m2.addr = 2;
    R.m3.addr = 3;
}

static void rig_init(uint32_t fixed_baud, uint32_t baud_control_ms)
{
    rig_init_uart(fixed_baud, baud_control_ms, 0u);
}

static bool req(const uint8_t *f, size_t n) { return line_request(&R.l, f, n); }

#define REQ(arr) req((arr), sizeof(arr))
#define LAST_IS(...) CHECK_BYTES(R.u.last, R.u.last_len, __VA_ARGS__)

static void save_reply(void)
{
    R.saved_len = R.u.last_len;
    memcpy(R.saved, R.u.last, R.u.last_len);
}

/* SRD high to one of the slave's SAPs. */
static bool sap(tmaster_t *m, uint8_t dsap, const uint8_t *d, size_t n)
{
    size_t len = mk_sap_req(R.f, SLAVE, m->addr, tm_fc(m, FDL_REQ_SRD_HIGH), dsap, d, n);
    return req(R.f, len);
}

static bool dx(tmaster_t *m, const uint8_t *d, size_t n)
{
    size_t len = mk_dx_req(R.f, SLAVE, m->addr, tm_fc(m, FDL_REQ_SRD_HIGH), d, n);
    return req(R.f, len);
}

/* Global_Control as SDN to 127 (no FCB). */
static bool gc(tmaster_t *m, uint8_t cmd, uint8_t group)
{
    const uint8_t d[2] = {cmd, group};
    size_t len = mk_sap_req(R.f, FDL_ADDR_BROADCAST, m->addr,
                            FDL_FC_REQUEST | FDL_REQ_SDN_HIGH, DP_SAP_GLOBAL_CONTROL, d, 2);
    return req(R.f, len);
}

/* Reads the diagnosis; returns its DU (valid until the next reply). */
static const uint8_t *diag(tmaster_t *m, size_t *n)
{
    *n = 0;
    if (!sap(m, DP_SAP_SLAVE_DIAG, NULL, 0)) {
        return NULL;
    }
    fdl_msg_t msg;
    const uint8_t *du = reply_du(&R.u, n, &msg);
    CHECK_EQ(msg.fc, FDL_RSP_DL);
    CHECK_EQ(msg.dsap, DP_SAP_MASTER);
    CHECK_EQ(msg.ssap, DP_SAP_SLAVE_DIAG);
    return du;
}

#define DIAG_IS(m, ...)                                                                        \
    do {                                                                                       \
        size_t dn_;                                                                            \
        const uint8_t *dd_ = diag((m), &dn_);                                                  \
        CHECK(dd_ != NULL);                                                                    \
        CHECK_BYTES(dd_ != NULL ? dd_ : (const uint8_t *)"", dn_, __VA_ARGS__);                \
    } while (0)

static bool set_prm(tmaster_t *m, uint8_t status, uint8_t f1, uint8_t f2, uint8_t tsdr,
                    uint16_t ident, uint8_t group, const uint8_t *tail, size_t tail_len)
{
    uint8_t p[DP_MAX_PRM_LEN];
    size_t n = mk_prm(p, status, f1, f2, tsdr, ident, group, tail, tail_len);
    return sap(m, DP_SAP_SET_PRM, p, n);
}

static bool chk_cfg(tmaster_t *m, const uint8_t *cfg, size_t n)
{
    return sap(m, DP_SAP_CHK_CFG, cfg, n);
}

/* Slave_Diag, Set_Prm, Chk_Cfg by master 2; ends in Data_Exch with counters reset. */
static void bring_up(uint8_t status, uint8_t f1, uint8_t f2, uint8_t group, const uint8_t *cfg,
                     size_t cfg_len)
{
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, status, f1, f2, 0, IDENT, group, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    CHECK(chk_cfg(&R.m2, cfg, cfg_len));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    R.a.outputs_calls = 0;
    R.a.log.n = 0;
}

/* ---- FDL level ---------------------------------------------------------------------------- */

/* Source address 127 is the global address, never a station: such a telegram (damaged in a way
 * the FCS missed, or forged) is not served, so it neither locks the slave to "master 127" nor
 * draws a reply sent to everyone. */
static void test_source_address_127_not_served(void)
{
    rig_init(BAUD, 0);
    uint8_t p[16];
    size_t n = mk_prm(p, 0x80, 0, 0, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, SLAVE, FDL_ADDR_BROADCAST, 0x6D, DP_SAP_SET_PRM, p, n);
    CHECK(!req(R.f, n));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_slave_master(&R.s), 0xFF);
    n = mk_sap_req(R.f, SLAVE, FDL_ADDR_BROADCAST, 0x6D, DP_SAP_SLAVE_DIAG, NULL, 0);
    CHECK(!req(R.f, n));
    CHECK_EQ(R.u.tx_count, 0u);
    CHECK(set_prm(&R.m2, 0x80, 0, 0, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_master(&R.s), 2);
}

static void test_fdl_status(void)
{
    rig_init(BAUD, 0);
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(R.u.tx_count, 1u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 1u);
    CHECK_EQ(ev_last(&R.a.log, DP_EV_ADDRESSED)->master, 2);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    /* Also with FCB/FCV bits set: FDL status is answered without FCB evaluation. */
    uint8_t f69[] = {0x10, 0x04, 0x02, 0x69, 0x6F, 0x16};
    CHECK(REQ(f69));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK(REQ(f69));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_FCB_REPEAT), 0u);
}

static void test_wrong_da_ignored(void)
{
    rig_init(BAUD, 0);
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    CHECK(!REQ(fdl5));
    size_t n = mk_sap_req(R.f, 5, 2, 0x6D, DP_SAP_SLAVE_DIAG, NULL, 0);
    CHECK(!req(R.f, n));
    uint8_t prm[16];
    n = mk_prm(prm, 0x88, 1, 100, 11, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, 3, 2, 0x6D, DP_SAP_SET_PRM, prm, n);
    CHECK(!req(R.f, n));
    n = mk_dx_req(R.f, 0, 2, 0x6D, DX8, sizeof DX8);
    CHECK(!req(R.f, n));
    /* A response (FC bit 6 = 0) addressed to this station is not a request. */
    uint8_t resp[] = {0x10, 0x04, 0x02, 0x00, 0x06, 0x16};
    CHECK(!REQ(resp));
    uint8_t sc[] = {0xE5};
    CHECK(!REQ(sc));
    uint8_t token[] = {0xDC, 0x04, 0x02};
    CHECK(!REQ(token));
    CHECK_EQ(R.u.tx_count, 0u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 0u);
    CHECK_EQ(R.a.prm_calls, 0u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_slave_master(&R.s), 0xFF);
}

static void test_broadcast_srd_not_answered(void)
{
    rig_init(BAUD, 0);
    uint8_t fdl127[] = {0x10, 0x7F, 0x02, 0x49, 0xCA, 0x16};
    CHECK(!REQ(fdl127));
    size_t n = mk_sap_req(R.f, 127, 2, 0x6D, DP_SAP_SLAVE_DIAG, NULL, 0);
    CHECK(!req(R.f, n));
    uint8_t prm[16];
    n = mk_prm(prm, 0x88, 1, 100, 11, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, 127, 2, 0x5D, DP_SAP_SET_PRM, prm, n);
    CHECK(!req(R.f, n));
    n = mk_dx_req(R.f, 127, 2, 0x7D, DX8, sizeof DX8);
    CHECK(!req(R.f, n));
    CHECK_EQ(R.u.tx_count, 0u);
    /* A request with reply cannot be executed for everybody: no parameterisation happened. */
    CHECK_EQ(R.a.prm_calls, 0u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    /* Still answers its own address. */
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
}

static void test_unsupported_sap(void)
{
    rig_init(BAUD, 0);
    static const uint8_t saps[] = {0, 20, 48, 49, 50, 51, 52, 53, 54, 63};
    for (size_t i = 0; i < sizeof saps; i++) {
        unsigned before = R.u.tx_count;
        CHECK(sap(&R.m2, saps[i], NULL, 0));
        CHECK_EQ(R.u.tx_count, before + 1u);
        LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    }
    /* DSAP without SSAP. */
    uint8_t nossap[] = {0x68, 0x04, 0x04, 0x68, 0x84, 0x02, 0x4D, 0x3C, 0x0F, 0x16};
    CHECK(REQ(nossap));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    /* An FDL service a DP slave does not offer (SDA high). */
    uint8_t sda[] = {0x68, 0x05, 0x05, 0x68, 0x04, 0x02, 0x45, 0x01, 0x02, 0x4E, 0x16};
    CHECK(REQ(sda));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    /* Rd_Inp / Rd_Outp before Data_Exch. */
    CHECK(sap(&R.m2, DP_SAP_RD_INP, NULL, 0));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    CHECK(sap(&R.m2, DP_SAP_RD_OUTP, NULL, 0));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
}

static void test_set_slave_add(void)
{
    rig_init(BAUD, 0);
    const uint8_t ssa[] = {0x05, 0x60, 0x03, 0x00};
    CHECK(sap(&R.m2, DP_SAP_SET_SLAVE_ADD, ssa, sizeof ssa));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    CHECK(!REQ(fdl5));
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
}

/* ---- DP start-up -------------------------------------------------------------------------- */

static void test_diag_wait_prm(void)
{
    rig_init(BAUD, 0);
    CHECK(REQ(F_DIAG_REQ));
    /* 02 05 00 FF + ident: a DU of 8 octets, sent as SD2 (§A1.6). */
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60,
            0x03, 0xF1, 0x16);
    size_t n;
    uint8_t d[64];
    n = dp_slave_build_diag(&R.s, d, sizeof d);
    CHECK_BYTES(d, n, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    CHECK_EQ(dp_slave_build_diag(&R.s, d, 5), 0u);
}

static void test_get_cfg_default(void)
{
    rig_init(BAUD, 0);
    uint8_t getcfg[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3B, 0x3E, 0xEC, 0x16};
    CHECK(REQ(getcfg));
    LAST_IS(0x68, 0x07, 0x07, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3B, 0xF3, 0xF2, 0x6C, 0x16);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
}

static void test_set_prm_ok(void)
{
    rig_init(BAUD, 0);
    CHECK_EQ(tm_fc(&R.m2, FDL_REQ_SRD_HIGH), 0x6D);
    CHECK(REQ(F_DIAG_REQ));
    CHECK_EQ(tm_fc(&R.m2, FDL_REQ_SRD_HIGH), 0x5D);
    CHECK(REQ(F_SET_PRM));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    CHECK_EQ(dp_slave_master(&R.s), 2);
    CHECK_EQ(dp_slave_wd_time_ms(&R.s), 1000u); /* 10 ms x 1 x 100 */
    CHECK_EQ(R.a.prm_calls, 1u);
    CHECK_BYTES(R.a.prm, R.a.prm_len, 0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_PRM_OK);
    CHECK(ev != NULL);
    if (ev != NULL) {
        CHECK_EQ(ev->value, 1000u);
        CHECK_EQ(ev->master, 2);
    }
    ev = ev_last(&R.a.log, DP_EV_STATE);
    CHECK(ev != NULL);
    if (ev != NULL) {
        CHECK_EQ(ev->old_state, DP_STATE_WAIT_PRM);
        CHECK_EQ(ev->new_state, DP_STATE_WAIT_CFG);
    }
    /* Wait_Cfg: Station_Not_Ready, WD_On, Master_Add 2. */
    DIAG_IS(&R.m2, 0x02, 0x0C, 0x00, 0x02, 0x60, 0x03);
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xFB, 0x16);
}

static void test_set_prm_wrong_ident(void)
{
    rig_init(BAUD, 0);
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, 0x6004, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(R.a.prm_calls, 0u);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_PRM_FAULT);
    CHECK(ev != NULL);
    if (ev != NULL) {
        CHECK_EQ(ev->value, DP_PRM_FAULT_IDENT);
    }
    DIAG_IS(&R.m2, 0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x42, 0x05, 0x00, 0xFF, 0x60,
            0x03, 0x31, 0x16);
    /* A correct Set_Prm clears Prm_Fault. */
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    DIAG_IS(&R.m2, 0x02, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

static void test_set_prm_watchdog_factors(void)
{
    static const uint8_t bad[][2] = {{0, 100}, {100, 0}, {0, 0}, {1, 1}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        rig_init(BAUD, 0);
        size_t n;
        (void)diag(&R.m2, &n);
        CHECK(set_prm(&R.m2, 0x88, bad[i][0], bad[i][1], 0, IDENT, 0, PRM_TAIL,
                      sizeof PRM_TAIL));
        LAST_IS(0xE5);
        CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
        const dp_event_t *ev = ev_last(&R.a.log, DP_EV_PRM_FAULT);
        CHECK(ev != NULL && ev->value == DP_PRM_FAULT_WATCHDOG);
        DIAG_IS(&R.m2, 0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    }
}

static void test_set_prm_other_faults(void)
{
    size_t n;
    /* Too short (6 octets). */
    rig_init(BAUD, 0);
    (void)diag(&R.m2, &n);
    const uint8_t short_prm[] = {0x88, 0x01, 0x64, 0x0B, 0x60, 0x03};
    CHECK(sap(&R.m2, DP_SAP_SET_PRM, short_prm, sizeof short_prm));
    LAST_IS(0xE5);
    CHECK(ev_last(&R.a.log, DP_EV_PRM_FAULT) != NULL &&
          ev_last(&R.a.log, DP_EV_PRM_FAULT)->value == DP_PRM_FAULT_LENGTH);
    DIAG_IS(&R.m2, 0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    /* Reserved station-status bits. */
    rig_init(BAUD, 0);
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x89, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK(ev_last(&R.a.log, DP_EV_PRM_FAULT) != NULL &&
          ev_last(&R.a.log, DP_EV_PRM_FAULT)->value == DP_PRM_FAULT_RESERVED_BITS);
    DIAG_IS(&R.m2, 0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    /* Refused by the device. */
    rig_init(BAUD, 0);
    R.a.prm_refuse = true;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK_EQ(R.a.prm_calls, 1u);
    CHECK(ev_last(&R.a.log, DP_EV_PRM_FAULT) != NULL &&
          ev_last(&R.a.log, DP_EV_PRM_FAULT)->value == DP_PRM_FAULT_USER);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    DIAG_IS(&R.m2, 0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

static void test_chk_cfg_ok(void)
{
    rig_init(BAUD, 0);
    CHECK(REQ(F_DIAG_REQ));
    CHECK(REQ(F_SET_PRM));
    CHECK(REQ(F_CHK_CFG));
    R.m2 = (tmaster_t){.addr = 2, .started = true, .fcb = 1};
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_CFG_OK);
    CHECK(ev != NULL && ev->value == ((14u << 8) | 14u));
    /* The outputs start cleared. */
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK_EQ(R.a.out_len, 14u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    static const uint8_t zero[14];
    CHECK(memcmp(R.a.out, zero, 14) == 0);
    DIAG_IS(&R.m2, 0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xF9, 0x16);

    /* Get_Cfg answers the accepted configuration. */
    rig_init(BAUD, 0);
    const uint8_t f1[] = {0xF1};
    bring_up(0x88, 1, 100, 0, f1, sizeof f1);
    CHECK(sap(&R.m2, DP_SAP_GET_CFG, NULL, 0));
    LAST_IS(0x68, 0x06, 0x06, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3B, 0xF1, 0x78, 0x16);
}

static void test_chk_cfg_refused(void)
{
    rig_init(BAUD, 0);
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    const uint8_t special[] = {0x00};
    CHECK(chk_cfg(&R.m2, special, sizeof special));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_CFG_FAULT), 1u);
    DIAG_IS(&R.m2, 0x06, 0x05, 0x00, 0xFF, 0x60, 0x03);
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x06, 0x05, 0x00, 0xFF, 0x60,
            0x03, 0xF5, 0x16);
    /* Get_Cfg still answers the default configuration. */
    CHECK(sap(&R.m2, DP_SAP_GET_CFG, NULL, 0));
    LAST_IS(0x68, 0x07, 0x07, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3B, 0xF3, 0xF2, 0x6C, 0x16);
    /* Refused by the device hook. */
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    DIAG_IS(&R.m2, 0x02, 0x0C, 0x00, 0x02, 0x60, 0x03); /* new Set_Prm cleared Cfg_Fault */
    R.a.cfg_refuse = true;
    CHECK(chk_cfg(&R.m2, CFG_P3PD, sizeof CFG_P3PD));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    DIAG_IS(&R.m2, 0x06, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

/* ---- Data_Exchange ------------------------------------------------------------------------ */

static void test_dx_outside_data_exch(void)
{
    rig_init(BAUD, 0);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    CHECK(dx(&R.m2, NULL, 0));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    CHECK_EQ(R.a.outputs_calls, 0u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
}

/* The request's end is a microsecond timestamp: the card waits that microsecond on top. */
#define TS_US FDL_TIMESTAMP_RESOLUTION_US

static void test_dx_data_exch(void)
{
    rig_init(BAUD, 0);
    CHECK(REQ(F_DIAG_REQ));
    CHECK(REQ(F_SET_PRM));
    CHECK(REQ(F_CHK_CFG));
    R.a.outputs_calls = 0;
    dp_slave_set_inputs(&R.s, DX14, sizeof DX14);
    CHECK(REQ(F_DX14_REQ));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34, 0xC8, 0x16);
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_DATA);
    CHECK(R.a.out_len == sizeof DX14 && memcmp(R.a.out, DX14, sizeof DX14) == 0);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 8u + TS_US);
    /* Rd_Inp / Rd_Outp read the images. */
    R.m2 = (tmaster_t){.addr = 2, .started = true, .fcb = 0};
    CHECK(sap(&R.m2, DP_SAP_RD_OUTP, NULL, 0));
    LAST_IS(0x68, 0x13, 0x13, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x39, 0x01, 0x00, 0x20, 0x6C, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34, 0x3F, 0x16);
}

/* An SD3 request (8 output octets) is taken; the 8 input octets go back as SD2. */
static void test_dx_sd3(void)
{
    rig_init(BAUD, 0);
    const uint8_t cfg8[] = {0xF3}; /* 4 words in/out = 8 octets each way */
    bring_up(0x88, 1, 100, 0, cfg8, sizeof cfg8);
    const uint8_t in8[] = {0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7, 0xA8};
    dp_slave_set_inputs(&R.s, in8, sizeof in8);
    /* The request builder makes the SD3 of §A1.2 for 8 output octets. */
    uint8_t fc = tm_fc(&R.m2, FDL_REQ_SRD_HIGH);
    CHECK_EQ(fc, 0x5D);
    size_t n = mk_dx_req(R.f, SLAVE, 2, fc, DX8, sizeof DX8);
    CHECK(n == sizeof F_DX8_REQ && memcmp(R.f, F_DX8_REQ, n) == 0);
    CHECK(REQ(F_DX8_REQ));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x02, 0x04, 0x08, 0xA1, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7,
            0xA8, 0x32, 0x16);
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK(R.a.out_len == 8u && memcmp(R.a.out, DX8, 8) == 0);
}

static void test_fcb_retry(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    const uint8_t in1[14] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14};
    const uint8_t in2[14] = {0x21, 0x22, 0x23};
    uint8_t outB[14];
    memcpy(outB, DX14, sizeof outB);
    outB[13] = 0x99;
    dp_slave_set_inputs(&R.s, in1, sizeof in1);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    save_reply();
    CHECK_EQ(R.a.outputs_calls, 1u);
    /* Retry: same FCB, FCV=1. Inputs changed meanwhile; different output bytes to prove that
     * nothing is executed. The held reply goes out again. */
    dp_slave_set_inputs(&R.s, in2, sizeof in2);
    uint8_t fc = tm_fc_retry(&R.m2, FDL_REQ_SRD_HIGH);
    size_t n = mk_dx_req(R.f, SLAVE, 2, fc, outB, sizeof outB);
    CHECK(req(R.f, n));
    CHECK(R.u.last_len == R.saved_len && memcmp(R.u.last, R.saved, R.saved_len) == 0);
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK(memcmp(R.a.out, DX14, sizeof DX14) == 0);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_FCB_REPEAT), 1u);
    /* Toggled FCB: executed. */
    CHECK(dx(&R.m2, outB, sizeof outB));
    CHECK_EQ(R.a.outputs_calls, 2u);
    CHECK(memcmp(R.a.out, outB, sizeof outB) == 0);
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x21, 0x22, 0x23, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x74, 0x16);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_FCB_REPEAT), 1u);

    /* Set_Prm retry: acknowledged again, not executed again. */
    rig_init(BAUD, 0);
    size_t dn;
    (void)diag(&R.m2, &dn);
    CHECK(set_prm(&R.m2, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK_EQ(R.a.prm_calls, 1u);
    unsigned states = ev_count(&R.a.log, DP_EV_STATE);
    uint8_t prm[16];
    n = mk_prm(prm, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, SLAVE, 2, tm_fc_retry(&R.m2, FDL_REQ_SRD_HIGH), DP_SAP_SET_PRM, prm, n);
    CHECK(req(R.f, n));
    LAST_IS(0xE5);
    CHECK_EQ(R.a.prm_calls, 1u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_STATE), states);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_FCB_REPEAT), 1u);

    /* FCV=0 (first frame after start) is never a retry: executed each time. */
    rig_init(BAUD, 0);
    n = mk_prm(prm, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, SLAVE, 2, 0x6D, DP_SAP_SET_PRM, prm, n);
    CHECK(req(R.f, n));
    CHECK(req(R.f, n));
    CHECK_EQ(R.a.prm_calls, 2u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_FCB_REPEAT), 0u);
}

/* ---- multi-master lock -------------------------------------------------------------------- */

static void test_locked_by_other_master(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    unsigned outputs = R.a.outputs_calls;
    unsigned prm_calls = R.a.prm_calls;
    unsigned cfg_calls = R.a.cfg_calls;

    CHECK(set_prm(&R.m3, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0x10, 0x03, 0x04, 0x03, 0x0A, 0x16);
    CHECK(chk_cfg(&R.m3, CFG_P3PD, sizeof CFG_P3PD));
    LAST_IS(0x10, 0x03, 0x04, 0x03, 0x0A, 0x16);
    CHECK(dx(&R.m3, DX14, sizeof DX14));
    LAST_IS(0x10, 0x03, 0x04, 0x03, 0x0A, 0x16);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_LOCKED_OUT), 3u);
    CHECK_EQ(ev_last(&R.a.log, DP_EV_LOCKED_OUT)->master, 3);
    /* Global_Control of the other master is ignored. */
    CHECK(!gc(&R.m3, DP_GC_CLEAR_DATA, 0));
    CHECK_EQ(R.a.outputs_calls, outputs);
    CHECK_EQ(R.a.prm_calls, prm_calls);
    CHECK_EQ(R.a.cfg_calls, cfg_calls);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK_EQ(dp_slave_master(&R.s), 2);

    /* Diagnosis and Get_Cfg stay readable for the other master; Master_Add shows 2. */
    CHECK(sap(&R.m3, DP_SAP_SLAVE_DIAG, NULL, 0));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x83, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xFA, 0x16);
    CHECK(sap(&R.m3, DP_SAP_GET_CFG, NULL, 0));
    LAST_IS(0x68, 0x07, 0x07, 0x68, 0x83, 0x84, 0x08, 0x3E, 0x3B, 0xF3, 0xF2, 0x6D, 0x16);
    /* Master 2 goes on. */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(R.a.outputs_calls, outputs + 1u);
}

/* ---- watchdog ----------------------------------------------------------------------------- */

static void check_expiry(uint32_t wd_ms, uint32_t prev_outputs)
{
    hal_time_us_t end = R.l.req_end_us;
    hal_time_us_t next = dp_slave_poll(&R.s, end + wd_ms * 1000u - 1000u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    /* The deadline the poll reports is the expiry instant (±1 ms). */
    CHECK(hal_time_diff(next, end + wd_ms * 1000u) >= -1000 &&
          hal_time_diff(next, end + wd_ms * 1000u) <= 1000);
    CHECK_EQ(R.a.outputs_calls, prev_outputs);
    hal_time_us_t late = end + wd_ms * 1000u + 1000u;
    (void)dp_slave_poll(&R.s, late);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_slave_master(&R.s), 0xFF);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_WD_EXPIRED);
    CHECK(ev != NULL);
    if (ev != NULL) {
        CHECK_EQ(ev->t, late);
        CHECK_EQ(ev->value, wd_ms);
        CHECK_EQ(ev->master, 2);
    }
    /* Outputs to the safe state: zeros. */
    CHECK_EQ(R.a.outputs_calls, prev_outputs + 1u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_SAFE_STATE);
    static const uint8_t zero[DP_MAX_IO_LEN];
    CHECK(R.a.out_len == 14u && memcmp(R.a.out, zero, 14) == 0);
    CHECK_EQ(dp_slave_wd_time_ms(&R.s), 0u);
    /* The diagnosis is framed by the poll that changed it, so the first request after the
     * expiry only addresses it (Prm_Req, no master). */
    CHECK(R.s.diag_framed);
    const dp_diag_buffer_t *d = &R.s.diag[R.s.diag_current];
    CHECK_BYTES(&d->buf[FDL_TX_HEADROOM], 4u, 0x02, 0x05, 0x00, 0xFF);
}

static void test_watchdog_10ms_base(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 2, 5, 0, CFG_P3PD, sizeof CFG_P3PD); /* 10 ms x 2 x 5 = 100 ms */
    CHECK_EQ(dp_slave_wd_time_ms(&R.s), 100u);
    DIAG_IS(&R.m2, 0x00, 0x0C, 0x00, 0x02, 0x60, 0x03); /* WD_On */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    unsigned outputs = R.a.outputs_calls;
    /* A telegram of the master 60 ms later retriggers it ... */
    hal_time_us_t first = R.l.req_end_us;
    R.l.now_ns = (uint64_t)(first + 60000u) * 1000u;
    (void)dp_slave_poll(&R.s, line_now_us(&R.l));
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    outputs = R.a.outputs_calls;
    (void)dp_slave_poll(&R.s, first + 101000u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    /* ... one of another master does not. */
    hal_time_us_t own = R.l.req_end_us;
    R.l.now_ns = (uint64_t)(own + 50000u) * 1000u;
    CHECK(sap(&R.m3, DP_SAP_SLAVE_DIAG, NULL, 0));
    R.l.req_end_us = own;
    check_expiry(100u, outputs);
    DIAG_IS(&R.m2, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    /* Data_Exchange is refused now. */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
}

/* DP_EV_ADDRESSED: once, for the first telegram to this station since start-up, the rate's
 * loss or the watchdog's expiry; not one per telegram. */
static void test_addressed_once_per_loss(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 2, 5, 0, CFG_P3PD, sizeof CFG_P3PD); /* 100 ms watchdog */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 0u); /* reported during the start-up */
    unsigned outputs = R.a.outputs_calls;
    check_expiry(100u, outputs);
    uint32_t counted = R.s.telegrams_for_me;
    DIAG_IS(&R.m2, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 1u);
    CHECK_EQ(ev_last(&R.a.log, DP_EV_ADDRESSED)->master, 2);
    DIAG_IS(&R.m2, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 1u);
    CHECK_EQ(R.s.telegrams_for_me, counted + 2u); /* every telegram is still counted */
}

/* The ASIC's order: a reply that the service's remaining work cannot change goes out first.
 * Chk_Cfg is SC whatever the check finds; Data_Exchange carries inputs framed ahead. */
static void test_reply_before_the_work(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    unsigned before = R.u.tx_count;
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.tx_count, before + 1u);
    CHECK_EQ(R.a.tx_at_outputs, before + 1u); /* the reply was out when the outputs were given */
    CHECK(memcmp(R.a.out, DX14, sizeof DX14) == 0);
    before = R.u.tx_count;
    CHECK(chk_cfg(&R.m2, CFG_P3PD, sizeof CFG_P3PD));
    LAST_IS(0xE5);
    CHECK_EQ(R.a.tx_at_cfg_check, before + 1u);
    CHECK_EQ(R.u.tx_count, before + 1u); /* once: the SRD path does not send it again */
}

static void test_watchdog_1ms_base(void)
{
    rig_init(BAUD, 0);
    size_t n;
    (void)diag(&R.m2, &n);
    /* DPV1_Status_1 = DPV1_Enable | WD_Base_1ms: 1 ms x 5 x 4 = 20 ms. */
    const uint8_t tail[] = {0x84, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
    CHECK(set_prm(&R.m2, 0x88, 5, 4, 0, IDENT, 0, tail, sizeof tail));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_wd_time_ms(&R.s), 20u);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_PRM_OK);
    CHECK(ev != NULL && ev->value == 20u);
    CHECK(chk_cfg(&R.m2, CFG_P3PD, sizeof CFG_P3PD));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    check_expiry(20u, R.a.outputs_calls);
}

static void test_watchdog_in_wait_cfg(void)
{
    rig_init(BAUD, 0);
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK(set_prm(&R.m2, 0x88, 2, 5, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    hal_time_us_t end = R.l.req_end_us;
    (void)dp_slave_poll(&R.s, end + 99000u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    (void)dp_slave_poll(&R.s, end + 101000u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_WD_EXPIRED), 1u);
}

static void test_no_watchdog(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK_EQ(dp_slave_wd_time_ms(&R.s), 0u);
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    (void)dp_slave_poll(&R.s, R.l.req_end_us + 700000000u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_WD_EXPIRED), 0u);
}

/* ---- Global_Control ----------------------------------------------------------------------- */

static void test_gc_clear_data(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.outputs_calls, 1u);
    unsigned tx = R.u.tx_count;
    CHECK(!gc(&R.m2, DP_GC_CLEAR_DATA, 0));
    CHECK_EQ(R.u.tx_count, tx); /* SDN: no reply */
    CHECK_EQ(R.a.outputs_calls, 2u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    static const uint8_t zero[14];
    CHECK(R.a.out_len == 14u && memcmp(R.a.out, zero, 14) == 0);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_GLOBAL_CONTROL);
    CHECK(ev != NULL && ev->value == DP_GC_CLEAR_DATA);
    CHECK(sap(&R.m2, DP_SAP_RD_OUTP, NULL, 0));
    LAST_IS(0x68, 0x13, 0x13, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x39, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x85, 0x16);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.outputs_calls, 3u);
    CHECK(memcmp(R.a.out, DX14, 14) == 0);
    /* Addressed directly (DA 4) instead of 127 works too. */
    const uint8_t d[2] = {DP_GC_CLEAR_DATA, 0};
    size_t n = mk_sap_req(R.f, SLAVE, 2, 0x46, DP_SAP_GLOBAL_CONTROL, d, 2);
    CHECK(!req(R.f, n));
    CHECK_EQ(R.a.outputs_calls, 4u);
    CHECK(memcmp(R.a.out, zero, 14) == 0);
}

/* A master in Clear sends full-length outputs (zeros for a slave without Fail_Safe) until a
 * Global_Control without Clear_Data says it is back in Operate: they are handed over as sent
 * but marked CLEAR, so a device does not take them for its application's data. */
static void test_gc_clear_mode(void)
{
    rig_init(BAUD, 0);
    bring_up(0xB0, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD); /* Lock | Sync_Req | Freeze_Req */
    static const uint8_t zero[14];
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_DATA);
    CHECK(!gc(&R.m2, DP_GC_CLEAR_DATA, 0));
    CHECK(dx(&R.m2, zero, sizeof zero));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(R.a.outputs_calls, 3u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    CHECK(R.a.out_len == 14u && memcmp(R.a.out, zero, 14) == 0);
    /* Still Clear: Sync with Clear_Data latches nothing, the telegram counts at once. */
    CHECK(!gc(&R.m2, DP_GC_CLEAR_DATA | DP_GC_SYNC, 0));
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.outputs_calls, 5u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    CHECK(memcmp(R.a.out, DX14, 14) == 0);
    /* A Global_Control for another group says nothing about this slave. */
    CHECK(!gc(&R.m2, 0x00, 0x02));
    CHECK(dx(&R.m2, zero, sizeof zero));
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    /* Operate (Unsync too): the next telegram is data again. */
    CHECK(!gc(&R.m2, DP_GC_UNSYNC, 0));
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_DATA);
    CHECK(memcmp(R.a.out, DX14, 14) == 0);
    /* Clear ends with Data_Exch too: after the watchdog or a new parameterisation the master
     * starts over in whatever mode its next Global_Control says. */
    CHECK(!gc(&R.m2, DP_GC_CLEAR_DATA, 0));
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_DATA);
}

static void test_gc_sync(void)
{
    rig_init(BAUD, 0);
    bring_up(0xB0, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD); /* Lock | Sync_Req | Freeze_Req */
    uint8_t o[5][14];
    for (unsigned i = 0; i < 5; i++) {
        memset(o[i], (int)(0xA0u + i), 14);
    }
    CHECK(dx(&R.m2, o[0], 14));
    CHECK_EQ(R.a.outputs_calls, 1u);
    /* The §A1.6 Sync frame. */
    CHECK(!REQ(F_GC_SYNC));
    CHECK_EQ(R.a.outputs_calls, 1u);
    DIAG_IS(&R.m2, 0x00, 0x24, 0x00, 0x02, 0x60, 0x03); /* Sync_Mode */
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x24, 0x00, 0x02, 0x60,
            0x03, 0x11, 0x16);
    /* Outputs are held ... */
    CHECK(dx(&R.m2, o[1], 14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK(dx(&R.m2, o[2], 14));
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK(memcmp(R.a.out, o[0], 14) == 0);
    /* ... until the next Sync, which applies the latest. */
    CHECK(!gc(&R.m2, DP_GC_SYNC, 0));
    CHECK_EQ(R.a.outputs_calls, 2u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_DATA);
    CHECK(memcmp(R.a.out, o[2], 14) == 0);
    DIAG_IS(&R.m2, 0x00, 0x24, 0x00, 0x02, 0x60, 0x03);
    CHECK(dx(&R.m2, o[3], 14));
    CHECK_EQ(R.a.outputs_calls, 2u);
    /* Unsync releases the held outputs and ends Sync_Mode. */
    CHECK(!gc(&R.m2, DP_GC_UNSYNC, 0));
    CHECK_EQ(R.a.outputs_calls, 3u);
    CHECK(memcmp(R.a.out, o[3], 14) == 0);
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    CHECK(dx(&R.m2, o[4], 14));
    CHECK_EQ(R.a.outputs_calls, 4u);
    CHECK(memcmp(R.a.out, o[4], 14) == 0);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_GLOBAL_CONTROL);
    CHECK(ev != NULL && ev->value == DP_GC_UNSYNC);
}

static void test_gc_freeze(void)
{
    rig_init(BAUD, 0);
    const uint8_t cfg8[] = {0xF3};
    bring_up(0x90, 0, 0, 0, cfg8, sizeof cfg8); /* Lock | Freeze_Req */
    uint8_t in[3][8];
    for (unsigned i = 0; i < 3; i++) {
        memset(in[i], (int)(0x10u * (i + 1u)), 8);
    }
    const size_t in_at = FDL_SD2_HEADER_LEN + FDL_ADDR_FC_LEN; /* 68 LE LEr 68 DA SA FC */
    dp_slave_set_inputs(&R.s, in[0], 8);
    CHECK(dx(&R.m2, DX8, 8));
    CHECK_BYTES(&R.u.last[in_at], 8, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10);
    CHECK(!gc(&R.m2, DP_GC_FREEZE, 0));
    DIAG_IS(&R.m2, 0x00, 0x14, 0x00, 0x02, 0x60, 0x03); /* Freeze_Mode */
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x14, 0x00, 0x02, 0x60,
            0x03, 0x01, 0x16);
    dp_slave_set_inputs(&R.s, in[1], 8);
    CHECK(dx(&R.m2, DX8, 8));
    CHECK_BYTES(&R.u.last[in_at], 8, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10);
    CHECK(sap(&R.m2, DP_SAP_RD_INP, NULL, 0)); /* Rd_Inp shows the frozen image too */
    LAST_IS(0x68, 0x0D, 0x0D, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x38, 0x10, 0x10, 0x10, 0x10, 0x10,
            0x10, 0x10, 0x10, 0x04, 0x16);
    /* A second Freeze takes a new snapshot. */
    CHECK(!gc(&R.m2, DP_GC_FREEZE, 0));
    dp_slave_set_inputs(&R.s, in[2], 8);
    CHECK(dx(&R.m2, DX8, 8));
    CHECK_BYTES(&R.u.last[in_at], 8, 0x20, 0x20, 0x20, 0x20, 0x20, 0x20, 0x20, 0x20);
    /* Unfreeze: live inputs again. */
    CHECK(!gc(&R.m2, DP_GC_UNFREEZE, 0));
    CHECK(dx(&R.m2, DX8, 8));
    CHECK_BYTES(&R.u.last[in_at], 8, 0x30, 0x30, 0x30, 0x30, 0x30, 0x30, 0x30, 0x30);
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
}

static void test_gc_group_select(void)
{
    rig_init(BAUD, 0);
    bring_up(0xB0, 0, 0, 0x02, CFG_P3PD, sizeof CFG_P3PD); /* member of group 2 */
    CHECK(!gc(&R.m2, DP_GC_SYNC, 0x04)); /* group 3 only: not me */
    CHECK_EQ(ev_count(&R.a.log, DP_EV_GLOBAL_CONTROL), 0u);
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    CHECK(!gc(&R.m2, DP_GC_SYNC, 0x06)); /* groups 2 and 3 */
    CHECK_EQ(ev_count(&R.a.log, DP_EV_GLOBAL_CONTROL), 1u);
    DIAG_IS(&R.m2, 0x00, 0x24, 0x00, 0x02, 0x60, 0x03);
    CHECK(!gc(&R.m2, DP_GC_UNSYNC, 0x01)); /* group 1: not me */
    DIAG_IS(&R.m2, 0x00, 0x24, 0x00, 0x02, 0x60, 0x03);
    CHECK(!gc(&R.m2, DP_GC_UNSYNC, 0x00)); /* 0 = all */
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    CHECK(!gc(&R.m2, DP_GC_CLEAR_DATA, 0x80));
    CHECK_EQ(R.a.outputs_calls, 0u);
}

static void test_gc_reserved_bits(void)
{
    rig_init(BAUD, 0);
    bring_up(0xB0, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    unsigned outputs = R.a.outputs_calls;
    static const uint8_t cmds[] = {0x21, 0x60, 0xA0, 0x03, 0x82, 0x01, 0x40, 0x80};
    for (size_t i = 0; i < sizeof cmds; i++) {
        CHECK(!gc(&R.m2, cmds[i], 0));
    }
    CHECK_EQ(ev_count(&R.a.log, DP_EV_GLOBAL_CONTROL), 0u);
    CHECK_EQ(R.a.outputs_calls, outputs);
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    /* Wrong length (3 octets) is ignored as well. */
    const uint8_t d3[3] = {DP_GC_CLEAR_DATA, 0, 0};
    size_t n = mk_sap_req(R.f, 127, 2, 0x46, DP_SAP_GLOBAL_CONTROL, d3, 3);
    CHECK(!req(R.f, n));
    CHECK_EQ(R.a.outputs_calls, outputs);
}

/* protocol.md §A3.5: "Freeze/Sync must be enabled via Set_Prm Freeze_Req/Sync_Req (and
 * supported)". Without the request bits a Sync|Freeze command changes nothing (before the fix
 * the diagnosis read 00 34 00 02 60 03 and the outputs were held). */
static void test_gc_sync_freeze_not_requested(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD); /* Lock only */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK(!gc(&R.m2, DP_GC_SYNC | DP_GC_FREEZE, 0));
    DIAG_IS(&R.m2, 0x00, 0x04, 0x00, 0x02, 0x60, 0x03);
    uint8_t o2[14];
    memset(o2, 0x5A, sizeof o2);
    unsigned outputs = R.a.outputs_calls;
    CHECK(dx(&R.m2, o2, sizeof o2));
    CHECK_EQ(R.a.outputs_calls, outputs + 1u); /* applied at once, not held */
    CHECK(memcmp(R.a.out, o2, 14) == 0);
}

static void test_set_prm_sync_unsupported(void)
{
    /* A slave without Sync support refuses Sync_Req: Prm_Fault + Not_Supported. */
    memset(&R, 0, sizeof R);
    line_init(&R.l, BAUD, rx_dp, &R.s, &R.u);
    dp_slave_cfg_t cfg = {
        .address = SLAVE, .ident = IDENT, .fixed_baud = BAUD, .strict_timing = true,
        .sync_supported = false, .freeze_supported = true,
        .uart = fake_uart_hal(&R.u),
        .hooks = {.ctx = &R.a, .prm_check = h_prm, .cfg_check = h_cfg, .outputs = h_out,
                  .event = h_ev},
    };
    dp_slave_init(&R.s, &cfg, line_now_us(&R.l));
    R.m2.addr = 2;
    CHECK(set_prm(&R.m2, 0xA0, 0, 0, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_PRM_FAULT);
    CHECK(ev != NULL && ev->value == DP_PRM_FAULT_UNSUPPORTED);
    DIAG_IS(&R.m2, 0x52, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

/* ---- extended diagnosis ------------------------------------------------------------------- */

static void test_ext_diag_dh(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    dp_slave_set_inputs(&R.s, DX14, sizeof DX14);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    const uint8_t ext[] = {0x02, 0x11};
    dp_slave_set_ext_diag(&R.s, ext, sizeof ext);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x0A, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34, 0xCA, 0x16);
    /* Still DH until the master reads the diagnosis. */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DH);
    CHECK(sap(&R.m2, DP_SAP_SLAVE_DIAG, NULL, 0));
    LAST_IS(0x68, 0x0D, 0x0D, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x08, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0x02, 0x11, 0x14, 0x16);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34, 0xC8, 0x16);
    /* Same content again: nothing new, stays DL. */
    dp_slave_set_ext_diag(&R.s, ext, sizeof ext);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    /* Cleared: DH once more, then the six standard octets without Ext_Diag. */
    dp_slave_set_ext_diag(&R.s, ext, 0);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DH);
    DIAG_IS(&R.m2, 0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    /* Stat_Diag also makes the master look. */
    dp_slave_set_stat_diag(&R.s, true);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DH);
    DIAG_IS(&R.m2, 0x00, 0x0E, 0x00, 0x02, 0x60, 0x03);
}

/* The diagnosis is framed once, ahead, and addressed on the reply path: each requester gets its
 * own DA, DSAP and check octet, and a retry of one master after another master's request is
 * never answered with the frame addressed to the other. */
static void test_diag_addressed_per_requester(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(sap(&R.m3, DP_SAP_SLAVE_DIAG, NULL, 0));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x83, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xFA, 0x16);
    save_reply();
    CHECK(sap(&R.m2, DP_SAP_SLAVE_DIAG, NULL, 0));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xF9, 0x16);
    /* Master 3 did not hear its reply and repeats (same FCB): its own frame again. */
    size_t n = mk_sap_req(R.f, SLAVE, 3, tm_fc_retry(&R.m3, FDL_REQ_SRD_HIGH), DP_SAP_SLAVE_DIAG,
                          NULL, 0);
    CHECK(req(R.f, n));
    CHECK(R.u.last_len == R.saved_len && memcmp(R.u.last, R.saved, R.saved_len) == 0);
    /* A class-2 master's own SSAP comes back as DSAP, counted in the check octet. */
    n = fdl_encode(R.f, SLAVE, 3, tm_fc(&R.m3, FDL_REQ_SRD_HIGH), true, DP_SAP_SLAVE_DIAG, 50,
                   NULL, 0);
    CHECK(req(R.f, n));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x83, 0x84, 0x08, 0x32, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xEE, 0x16);
}

/* ---- timing ------------------------------------------------------------------------------- */

static void test_tsyn_violation(void)
{
    rig_init(BAUD, 0);
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    CHECK(!REQ(fdl5));
    /* 20 bit times after the previous telegram: no TSYN, dropped. */
    CHECK(!line_request_idle(&R.l, F_FDL_REQ, sizeof F_FDL_REQ, 20u));
    CHECK_EQ(R.u.tx_count, 0u);
    CHECK_EQ(R.s.rx.error_count[FDL_RX_ERR_TSYN], 1u);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_RX_ERROR);
    CHECK(ev != NULL && ev->value == FDL_RX_ERR_TSYN && ev->master == 2);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_ADDRESSED), 0u);
    /* A dropped Set_Prm is not executed. */
    CHECK(!REQ(fdl5));
    uint8_t prm[16];
    size_t n = mk_prm(prm, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, SLAVE, 2, 0x6D, DP_SAP_SET_PRM, prm, n);
    CHECK(!line_request_idle(&R.l, R.f, n, 10u));
    CHECK_EQ(R.a.prm_calls, 0u);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    /* Exactly 33 bit times: answered. */
    CHECK(!REQ(fdl5));
    CHECK(line_request_idle(&R.l, F_FDL_REQ, sizeof F_FDL_REQ, 33u));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
}

static void test_min_tsdr(void)
{
    rig_init(BAUD, 0);
    /* Default 11 bit times at 1.5 Mbit/s = 7.3 µs, rounded up to 8. */
    CHECK(REQ(F_FDL_REQ));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 8u + TS_US);
    size_t n;
    (void)diag(&R.m2, &n);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 8u + TS_US);
    /* Set_Prm min TSDR 100: 66.7 µs -> 67. */
    CHECK(set_prm(&R.m2, 0x80, 0, 0, 100, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    (void)diag(&R.m2, &n);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 67u + TS_US);
    CHECK(REQ(F_FDL_REQ));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 67u + TS_US);
    /* 0 = unchanged. */
    CHECK(set_prm(&R.m2, 0x80, 0, 0, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    (void)diag(&R.m2, &n);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 67u + TS_US);
    /* 255 bit times: 170 µs. */
    CHECK(set_prm(&R.m2, 0x80, 0, 0, 255, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    CHECK(chk_cfg(&R.m2, CFG_P3PD, sizeof CFG_P3PD));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 170u + TS_US);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 170u + TS_US);
    /* Lock_Req = Unlock_Req = 0: only min TSDR is taken over (200 -> 133.3 -> 134 µs). */
    CHECK(set_prm(&R.m2, 0x00, 0, 0, 200, 0x1234, 0, NULL, 0));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK_EQ(dp_slave_master(&R.s), 2);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 134u + TS_US);
}

static void test_min_tsdr_12m(void)
{
    rig_init(12000000u, 0);
    CHECK(REQ(F_FDL_REQ));
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 1u + TS_US); /* 11 bits = 0.92 µs */
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(R.u.baud_count, 1u);
    CHECK_EQ(R.u.bauds[0], 12000000u);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_FIXED);
}

/* ---- baud search -------------------------------------------------------------------------- */

/* Walks the search from 12 Mbit/s down to hal_uart_bauds[idx] by polling at each deadline;
 * returns the instant of the last step. */
static hal_time_us_t search_to(unsigned idx, hal_time_us_t t0)
{
    hal_time_us_t t = t0;
    for (unsigned k = 1; k <= idx; k++) {
        t += dp_baud_search_dwell_us(hal_uart_bauds[k - 1u]);
        (void)dp_slave_poll(&R.s, t);
    }
    return t;
}

static void test_baud_search_steps(void)
{
    rig_init(0, 0);
    hal_time_us_t t = line_now_us(&R.l);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
    CHECK_EQ(dp_slave_baud(&R.s), 12000000u);
    CHECK_EQ(R.u.baud_count, 1u);
    CHECK_EQ(R.u.bauds[0], 12000000u);
    CHECK(ev_last(&R.a.log, DP_EV_BAUD_SET) != NULL &&
          ev_last(&R.a.log, DP_EV_BAUD_SET)->value == 12000000u);
    for (unsigned k = 1; k <= HAL_UART_NUM_BAUDS; k++) {
        uint32_t cur = hal_uart_bauds[k - 1u];
        uint32_t dwell = dp_baud_search_dwell_us(cur);
        /* Dwell covers two longest telegrams at that rate. */
        CHECK((uint64_t)(dwell + 1u) * cur >= 2ull * 255u * 11u * 1000000ull);
        hal_time_us_t next = dp_slave_poll(&R.s, t + dwell - 1u);
        CHECK_EQ(next, t + dwell);
        CHECK_EQ(dp_slave_baud(&R.s), cur);
        t += dwell;
        (void)dp_slave_poll(&R.s, t);
        uint32_t expect = hal_uart_bauds[k % HAL_UART_NUM_BAUDS];
        CHECK_EQ(dp_slave_baud(&R.s), expect);
        CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
        CHECK_EQ(R.u.baud_count, k + 1u);
        CHECK_EQ(R.u.bauds[k], expect);
        const dp_event_t *ev = ev_last(&R.a.log, DP_EV_BAUD_SET);
        CHECK(ev != NULL && ev->value == expect && ev->t == t);
    }
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_SET), HAL_UART_NUM_BAUDS + 1u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_FOUND), 0u);
}

/* A UART that cannot make 12 Mbit/s (the reference MCU's USART tops out at 10.5 Mbit/s): the
 * search passes over the rate instead of believing it while the UART still listens at the old
 * one, so a telegram heard at power-up or after the search wrapped is taken at its real rate. */
static void test_baud_search_skips_refused_rate(void)
{
    rig_init_uart(0, 0, 10500000u);
    hal_time_us_t t = line_now_us(&R.l);
    CHECK_EQ(dp_slave_baud(&R.s), 6000000u);
    CHECK_EQ(R.u.refused, 1u);
    CHECK_EQ(R.u.baud_count, 1u);
    CHECK(ev_last(&R.a.log, DP_EV_BAUD_SET) != NULL &&
          ev_last(&R.a.log, DP_EV_BAUD_SET)->value == 6000000u);
    for (unsigned k = 1; k < HAL_UART_NUM_BAUDS; k++) {
        t += dp_baud_search_dwell_us(hal_uart_bauds[k]);
        (void)dp_slave_poll(&R.s, t);
    }
    /* From 9.6 kbit/s the search wraps to 6 Mbit/s, past 12 Mbit/s again. */
    CHECK_EQ(dp_slave_baud(&R.s), 6000000u);
    CHECK_EQ(R.u.refused, 2u);
    CHECK_EQ(R.u.baud_count, (unsigned)HAL_UART_NUM_BAUDS);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_SET), (unsigned)HAL_UART_NUM_BAUDS);
    R.l.baud = 6000000u;
    R.l.now_ns = (uint64_t)t * 1000u;
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    CHECK_EQ(dp_slave_baud(&R.s), 6000000u);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + hal_uart_bits_us(6000000u, 11u) + TS_US);
}

static void test_baud_found(void)
{
    rig_init(0, 0);
    hal_time_us_t t = search_to(3, line_now_us(&R.l)); /* 1.5 Mbit/s */
    CHECK_EQ(dp_slave_baud(&R.s), 1500000u);
    R.l.baud = 1500000u;
    R.l.now_ns = (uint64_t)t * 1000u;
    /* Characters at a wrong rate arrive with framing errors: no hit. */
    uint8_t flags[sizeof F_SET_PRM];
    memset(flags, HAL_UART_RX_FRAMING_ERR, sizeof flags);
    line_put(&R.l, F_SET_PRM, sizeof F_SET_PRM, flags, 100u);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
    /* A telegram with a bad FCS: no hit either. */
    uint8_t bad[] = {0x10, 0x05, 0x02, 0x49, 0x51, 0x16};
    CHECK(!REQ(bad));
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
    /* Token frames do not count (only SD1/SD2/SD3). */
    uint8_t token[] = {0xDC, 0x05, 0x02};
    CHECK(!REQ(token));
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_FOUND), 0u);
    /* A correct telegram, even to another station, stops the search. */
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    CHECK(!REQ(fdl5));
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    CHECK_EQ(dp_slave_baud(&R.s), 1500000u);
    const dp_event_t *ev = ev_last(&R.a.log, DP_EV_BAUD_FOUND);
    CHECK(ev != NULL && ev->value == 1500000u);
    unsigned sets = R.u.baud_count;
    /* The search deadline no longer applies. */
    (void)dp_slave_poll(&R.s, t + dp_baud_search_dwell_us(1500000u) + 1u);
    CHECK_EQ(dp_slave_baud(&R.s), 1500000u);
    CHECK_EQ(R.u.baud_count, sets);
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
}

static void test_baud_control_expiry(void)
{
    rig_init(0, 100); /* baud control 100 ms */
    hal_time_us_t t = search_to(3, line_now_us(&R.l));
    R.l.baud = 1500000u;
    R.l.now_ns = (uint64_t)t * 1000u;
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD); /* no DP watchdog */
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    /* Telegrams to this station retrigger baud control. */
    hal_time_us_t own = R.l.req_end_us;
    R.l.now_ns = (uint64_t)(own + 60000u) * 1000u;
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    own = R.l.req_end_us;
    (void)dp_slave_poll(&R.s, own + 50000u);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    /* Telegrams to others do not. */
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    R.l.now_ns = (uint64_t)(own + 70000u) * 1000u;
    CHECK(!REQ(fdl5));
    hal_time_us_t next = dp_slave_poll(&R.s, own + 100000u - 1u);
    CHECK_EQ(next, own + 100000u);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    unsigned states = ev_count(&R.a.log, DP_EV_STATE);
    unsigned outputs = R.a.outputs_calls;
    (void)dp_slave_poll(&R.s, own + 100000u);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_SEARCH);
    CHECK_EQ(dp_slave_baud(&R.s), 12000000u);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_LOST), 1u);
    /* The DP state machine is not touched. */
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_STATE), states);
    CHECK_EQ(R.a.outputs_calls, outputs);
    CHECK_EQ(dp_slave_master(&R.s), 2);
    /* Found again at 1.5 Mbit/s: still in Data_Exch. */
    t = search_to(3, own + 100000u);
    R.l.now_ns = (uint64_t)t * 1000u;
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(dp_slave_baud_state(&R.s), DP_BAUD_CONTROL);
    CHECK_EQ(ev_count(&R.a.log, DP_EV_BAUD_FOUND), 1u); /* log was reset by bring_up */
}


static void test_unlock_releases(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    /* Unlock_Req: the master releases the slave. */
    CHECK(set_prm(&R.m2, 0x40, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_slave_master(&R.s), 0xFF);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_SAFE_STATE);
    static const uint8_t zero[14];
    CHECK(memcmp(R.a.out, zero, 14) == 0);
    DIAG_IS(&R.m2, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
    /* Now master 3 may parameterise it. */
    CHECK(set_prm(&R.m3, 0x88, 1, 100, 0, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    CHECK_EQ(dp_slave_master(&R.s), 3);
}

static void test_ext_diag_overflow(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD);
    uint8_t big[DP_MAX_EXT_DIAG_LEN + 8u];
    for (size_t i = 0; i < sizeof big; i++) {
        big[i] = (uint8_t)(0x40u + i);
    }
    dp_slave_set_ext_diag(&R.s, big, sizeof big);
    size_t n;
    const uint8_t *d = diag(&R.m2, &n);
    CHECK_EQ(n, 6u + DP_MAX_EXT_DIAG_LEN);
    if (d != NULL && n >= 6u) {
        CHECK_BYTES(d, 6, 0x08, 0x04, 0x80, 0x02, 0x60, 0x03); /* Ext_Diag, Ext_Diag_Overflow */
        CHECK(memcmp(&d[6], big, n - 6u) == 0);
    }
}

static void test_dx_without_inputs(void)
{
    rig_init(BAUD, 0);
    const uint8_t out_only[] = {0xE1}; /* 2 output words, no inputs */
    bring_up(0x80, 0, 0, 0, out_only, sizeof out_only);
    const uint8_t o[4] = {0x0A, 0x0B, 0x0C, 0x0D};
    CHECK(dx(&R.m2, o, sizeof o));
    LAST_IS(0xE5); /* SC: no input data */
    CHECK_EQ(R.a.outputs_calls, 1u);
    CHECK(R.a.out_len == 4u && memcmp(R.a.out, o, 4) == 0);
    /* Diagnosis pending: SD1 with DH instead. */
    const uint8_t ext[] = {0x02, 0x33};
    dp_slave_set_ext_diag(&R.s, ext, sizeof ext);
    CHECK(dx(&R.m2, o, sizeof o));
    LAST_IS(0x10, 0x02, 0x04, 0x0A, 0x10, 0x16);

    /* Inputs only: Data_Exchange without output octets. */
    rig_init(BAUD, 0);
    const uint8_t in_only[] = {0xD1};
    bring_up(0x80, 0, 0, 0, in_only, sizeof in_only);
    const uint8_t in[4] = {0x42, 0x43, 0x44, 0x45};
    dp_slave_set_inputs(&R.s, in, sizeof in);
    CHECK(dx(&R.m2, NULL, 0));
    LAST_IS(0x68, 0x07, 0x07, 0x68, 0x02, 0x04, 0x08, 0x42, 0x43, 0x44, 0x45, 0x1C, 0x16);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
}

static void test_time_wrap(void)
{
    /* The µs counter wraps during start-up and during the watchdog time. */
    rig_init(BAUD, 0);
    R.l.now_ns = (0x100000000ull - 30000u) * 1000ull; /* 30 ms before the wrap */
    dp_slave_cfg_t cfg = R.s.cfg; /* dp_slave_init clears the slave first: pass a copy */
    dp_slave_init(&R.s, &cfg, line_now_us(&R.l));
    bring_up(0x88, 2, 5, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    hal_time_us_t end = R.l.req_end_us;
    (void)dp_slave_poll(&R.s, end + 40000u); /* past the wrap */
    R.l.now_ns = (0x100000000ull + 40000u) * 1000ull;
    CHECK(line_now_us(&R.l) < 100000u);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(R.u.last_not_before, R.l.req_end_us + 8u + TS_US);
    check_expiry(100u, R.a.outputs_calls);
}

/* A card at a fixed rate without watchdog has no deadline of its own, yet after 40 min of bus
 * silence (more than half the 32-bit µs clock) the first request must be answered, not taken
 * for one that came without TSYN idle: dp_slave_poll asks to be called 1 s after the last
 * character and forgets it then. */
static void test_long_silence(void)
{
    rig_init(BAUD, 0);
    bring_up(0x80, 0, 0, 0, CFG_P3PD, sizeof CFG_P3PD); /* no watchdog */
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    hal_time_us_t end = line_now_us(&R.l);
    hal_time_us_t next = dp_slave_poll(&R.s, end);
    CHECK(hal_time_diff(next, end) > 0 && hal_time_diff(next, end) <= (int32_t)FDL_RX_FORGET_US);
    R.l.now_ns += (uint64_t)hal_time_diff(next, end) * 1000u;
    next = dp_slave_poll(&R.s, line_now_us(&R.l));
    CHECK_EQ(next, line_now_us(&R.l) + HAL_TIME_NO_DEADLINE_US);
    R.l.now_ns += 2400ull * 1000000000ull;
    (void)dp_slave_poll(&R.s, line_now_us(&R.l));
    uint32_t tsyn = R.s.rx.error_count[FDL_RX_ERR_TSYN];
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(R.s.rx.error_count[FDL_RX_ERR_TSYN], tsyn);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
}

static void test_dx_output_length(void)
{
    rig_init(BAUD, 0);
    bring_up(0x88, 1, 100, 0, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(dx(&R.m2, DX14, sizeof DX14));
    CHECK_EQ(R.a.outputs_calls, 1u);
    /* No output octets: the fail-safe Clear telegram, outputs cleared, normal reply. */
    CHECK(dx(&R.m2, NULL, 0));
    CHECK_EQ(R.u.last[6], FDL_RSP_DL);
    CHECK_EQ(R.a.outputs_calls, 2u);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_CLEAR);
    static const uint8_t zero[14];
    CHECK(R.a.out_len == 14u && memcmp(R.a.out, zero, 14) == 0);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    /* 13 octets where 14 are configured: RS, the slave leaves Data_Exch. */
    CHECK(dx(&R.m2, DX14, 13));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
    CHECK_EQ(R.a.out_reason, DP_OUTPUTS_SAFE_STATE);
    DIAG_IS(&R.m2, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

static void test_srd_low(void)
{
    /* Masters that send the DP-V0 services as SRD low (FC 0x4C/0x6C/0x7C, profirust). */
    rig_init(BAUD, 0);
    size_t n = mk_sap_req(R.f, SLAVE, 2, 0x6C, DP_SAP_SLAVE_DIAG, NULL, 0);
    CHECK(req(R.f, n));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60,
            0x03, 0xF1, 0x16);
    uint8_t prm[16];
    size_t pn = mk_prm(prm, 0x88, 1, 100, 11, IDENT, 0, PRM_TAIL, sizeof PRM_TAIL);
    n = mk_sap_req(R.f, SLAVE, 2, 0x5C, DP_SAP_SET_PRM, prm, pn);
    CHECK(req(R.f, n));
    LAST_IS(0xE5);
    n = mk_sap_req(R.f, SLAVE, 2, 0x7C, DP_SAP_CHK_CFG, CFG_P3PD, sizeof CFG_P3PD);
    CHECK(req(R.f, n));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
}

int main(void)
{
    RUN_TEST(test_fdl_status);
    RUN_TEST(test_source_address_127_not_served);
    RUN_TEST(test_wrong_da_ignored);
    RUN_TEST(test_broadcast_srd_not_answered);
    RUN_TEST(test_unsupported_sap);
    RUN_TEST(test_set_slave_add);
    RUN_TEST(test_diag_wait_prm);
    RUN_TEST(test_get_cfg_default);
    RUN_TEST(test_set_prm_ok);
    RUN_TEST(test_set_prm_wrong_ident);
    RUN_TEST(test_set_prm_watchdog_factors);
    RUN_TEST(test_set_prm_other_faults);
    RUN_TEST(test_chk_cfg_ok);
    RUN_TEST(test_chk_cfg_refused);
    RUN_TEST(test_dx_outside_data_exch);
    RUN_TEST(test_dx_data_exch);
    RUN_TEST(test_dx_sd3);
    RUN_TEST(test_fcb_retry);
    RUN_TEST(test_locked_by_other_master);
    RUN_TEST(test_watchdog_10ms_base);
    RUN_TEST(test_addressed_once_per_loss);
    RUN_TEST(test_reply_before_the_work);
    RUN_TEST(test_watchdog_1ms_base);
    RUN_TEST(test_watchdog_in_wait_cfg);
    RUN_TEST(test_no_watchdog);
    RUN_TEST(test_gc_clear_data);
    RUN_TEST(test_gc_clear_mode);
    RUN_TEST(test_gc_sync);
    RUN_TEST(test_gc_freeze);
    RUN_TEST(test_gc_group_select);
    RUN_TEST(test_gc_reserved_bits);
    RUN_TEST(test_gc_sync_freeze_not_requested);
    RUN_TEST(test_set_prm_sync_unsupported);
    RUN_TEST(test_ext_diag_dh);
    RUN_TEST(test_diag_addressed_per_requester);
    RUN_TEST(test_tsyn_violation);
    RUN_TEST(test_min_tsdr);
    RUN_TEST(test_min_tsdr_12m);
    RUN_TEST(test_baud_search_steps);
    RUN_TEST(test_baud_search_skips_refused_rate);
    RUN_TEST(test_baud_found);
    RUN_TEST(test_baud_control_expiry);
    RUN_TEST(test_unlock_releases);
    RUN_TEST(test_ext_diag_overflow);
    RUN_TEST(test_dx_without_inputs);
    RUN_TEST(test_time_wrap);
    RUN_TEST(test_long_silence);
    RUN_TEST(test_dx_output_length);
    RUN_TEST(test_srd_low);
    return check_report();
}
