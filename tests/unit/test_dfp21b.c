/* The DFP21B personality (dfp21b), driven on the wire like the generic slave: accepted and
 * refused configurations (protocol.md §B3), user parameters (§B4), DIP address and LEDs (§B1, §B2),
 * fieldbus monitor values P090/P092/P093/P819, PO -> PI loopback and the DP-V0 external
 * diagnosis for inverter faults. Station 4 (DIP), master 2, 1.5 Mbit/s unless searching. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "dfp21b/dfp21b.h"
#include "spec_frames.h"
#include "unit_rig.h"

#define BAUD 1500000u

static const uint8_t DX14[] = {0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
                               0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34};

static const uint8_t CFG_P3PD[] = {0xF3, 0xF2};
static const uint8_t USER_ALARM_OFF[] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
static const uint8_t USER_ALARM_ON[] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};

/* ---- rig ---------------------------------------------------------------------------------- */

typedef struct crig {
    dfp21b_t c;
    fake_uart_t u;
    led_log_t leds;
    ev_log_t log;
    line_t l;
    tmaster_t m2;
    uint8_t dip;
    unsigned timeouts;
    unsigned pd_calls;
    uint16_t po[DFP21B_MAX_PD];
    uint8_t pd_n;
    dp_outputs_reason_t pd_why;
    unsigned param_calls;
    uint8_t param_req[DFP21B_PARAM_LEN];
    uint8_t f[FDL_FRAME_MAX];
} crig_t;

static crig_t C; /* large: off the stack */

static uint8_t dip_read(void *ctx)
{
    return ((crig_t *)ctx)->dip;
}
static const hal_dip_ops_t dip_ops = {.read = dip_read};

static void rx_card(void *st, uint8_t b, uint8_t flags, hal_time_us_t t)
{
    dfp21b_rx_char(st, b, flags, t);
}

static void on_event(void *ctx, const dp_event_t *ev) { ev_log_add(&((crig_t *)ctx)->log, ev); }

static void on_timeout(void *ctx) { ((crig_t *)ctx)->timeouts++; }

/* An inverter that answers PI = PO xor 0xFFFF and mirrors the parameter channel request with
 * the error bit set (to see both paths in the input image). */
static void app_pd(void *ctx, const uint16_t *po, uint16_t *pi, uint8_t n, dp_outputs_reason_t why)
{
    crig_t *r = ctx;
    r->pd_calls++;
    r->pd_n = n;
    r->pd_why = why;
    memcpy(r->po, po, sizeof r->po);
    for (uint8_t i = 0; i < n; i++) {
        pi[i] = (uint16_t)(po[i] ^ 0xFFFFu);
    }
}

static void app_param(void *ctx, const uint8_t req[DFP21B_PARAM_LEN],
                      uint8_t rsp[DFP21B_PARAM_LEN])
{
    crig_t *r = ctx;
    r->param_calls++;
    memcpy(r->param_req, req, DFP21B_PARAM_LEN);
    memcpy(rsp, req, DFP21B_PARAM_LEN);
    rsp[0] = (uint8_t)(rsp[0] | 0x80u);
}

static void crig_init(uint8_t dip, uint32_t fixed_baud, bool with_app)
{
    memset(&C, 0, sizeof C);
    C.dip = dip;
    line_init(&C.l, fixed_baud != 0u ? fixed_baud : 12000000u, rx_card, &C.c, &C.u);
    dfp21b_cfg_t cfg = {
        .uart = fake_uart_hal(&C.u),
        .led = {.ops = &led_log_ops, .ctx = &C.leds},
        .dip = {.ops = &dip_ops, .ctx = &C},
        .fixed_baud = fixed_baud,
        .strict_timing = true,
        .app = {.ctx = &C, .fieldbus_timeout = on_timeout},
        .event = on_event,
        .event_ctx = &C,
    };
    if (with_app) {
        cfg.app.process_data = app_pd;
        cfg.app.param_channel = app_param;
    }
    dfp21b_init(&C.c, &cfg, line_now_us(&C.l));
    C.m2.addr = 2;
}

static bool req(const uint8_t *f, size_t n) { return line_request(&C.l, f, n); }
#define REQ(arr) req((arr), sizeof(arr))
#define LAST_IS(...) CHECK_BYTES(C.u.last, C.u.last_len, __VA_ARGS__)

static bool sap(uint8_t dsap, const uint8_t *d, size_t n)
{
    size_t len = mk_sap_req(C.f, 4, 2, tm_fc(&C.m2, FDL_REQ_SRD_HIGH), dsap, d, n);
    return req(C.f, len);
}

static bool dx(const uint8_t *d, size_t n)
{
    size_t len = mk_dx_req(C.f, 4, 2, tm_fc(&C.m2, FDL_REQ_SRD_HIGH), d, n);
    return req(C.f, len);
}

static const uint8_t *diag(size_t *n)
{
    *n = 0;
    if (!sap(DP_SAP_SLAVE_DIAG, NULL, 0)) {
        return NULL;
    }
    fdl_msg_t m;
    return reply_du(&C.u, n, &m);
}

#define DIAG_IS(...)                                                                           \
    do {                                                                                       \
        size_t dn_;                                                                            \
        const uint8_t *dd_ = diag(&dn_);                                                       \
        CHECK(dd_ != NULL);                                                                    \
        CHECK_BYTES(dd_ != NULL ? dd_ : (const uint8_t *)"", dn_, __VA_ARGS__);                \
    } while (0)

static bool set_prm(uint8_t status, uint8_t f1, uint8_t f2, const uint8_t *user, size_t n)
{
    uint8_t p[DP_MAX_PRM_LEN];
    size_t len = mk_prm(p, status, f1, f2, 11, DFP21B_IDENT, 0, user, n);
    return sap(DP_SAP_SET_PRM, p, len);
}

static bool chk_cfg(const uint8_t *cfg, size_t n) { return sap(DP_SAP_CHK_CFG, cfg, n); }

static void bring_up(const uint8_t *cfg, size_t cfg_len, const uint8_t *user)
{
    size_t n;
    (void)diag(&n);
    CHECK(set_prm(0x88, 1, 100, user, 9));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_CFG);
    CHECK(chk_cfg(cfg, cfg_len));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
}

static void p090_is(const char *expect)
{
    char txt[32];
    size_t n = dfp21b_p090_text(&C.c.pd, txt, sizeof txt);
    CHECK_STR(txt, expect);
    CHECK_EQ(n, strlen(expect));
}

/* ---- configurations (§B3) ------------------------------------------------------------------ */

typedef struct cfg_case {
    uint8_t bytes[4];
    uint8_t len;
    bool param;
    uint8_t pd_words;
    const char *p090;
} cfg_case_t;

static const cfg_case_t PREDEFINED[] = {
    {{0xF0}, 1, false, 1, "1PD"},
    {{0xF1}, 1, false, 2, "2PD"},
    {{0xF2}, 1, false, 3, "3PD"},
    {{0x00, 0xF5}, 2, false, 6, "6PD"},
    {{0x00, 0xF9}, 2, false, 10, "10PD"},
    {{0xF3, 0xF0}, 2, true, 1, "1PD + PARAM"},
    {{0xF3, 0xF1}, 2, true, 2, "2PD + PARAM"},
    {{0xF3, 0xF2}, 2, true, 3, "3PD + PARAM"},
    {{0xF3, 0xF5}, 2, true, 6, "6PD + PARAM"},
    {{0xF3, 0xF9}, 2, true, 10, "10PD + PARAM"},
};

static const cfg_case_t UNIVERSAL[] = {
    {{0xF3}, 1, false, 4, "4PD"},
    {{0xF4}, 1, false, 5, "5PD"},
    {{0xF6}, 1, false, 7, "7PD"},
    {{0xF7}, 1, false, 8, "8PD"},
    {{0xF8}, 1, false, 9, "9PD"},
    {{0x00, 0xF3}, 2, false, 4, "4PD"},
    {{0x00, 0xF4}, 2, false, 5, "5PD"},
    {{0x00, 0xF0}, 2, false, 1, "1PD"},
    {{0xF3, 0xF3}, 2, true, 4, "4PD + PARAM"},
    {{0xF3, 0xF4}, 2, true, 5, "5PD + PARAM"},
    {{0xF3, 0xF6}, 2, true, 7, "7PD + PARAM"},
    {{0xF3, 0xF7}, 2, true, 8, "8PD + PARAM"},
    {{0xF3, 0xF8}, 2, true, 9, "9PD + PARAM"},
    /* parameter channel written as 8 consistent I/O octets */
    {{0xB7, 0xF2}, 2, true, 3, "3PD + PARAM"},
    /* process data written in octets: 6 consistent I/O octets = 3 words */
    {{0xF3, 0xB5}, 2, true, 3, "3PD + PARAM"},
};

static void check_cfg_case(const cfg_case_t *k, bool live)
{
    dfp21b_pd_cfg_t pd;
    CHECK(dfp21b_check_cfg(k->bytes, k->len, &pd));
    CHECK(pd.valid);
    CHECK_EQ(pd.param_channel, k->param);
    CHECK_EQ(pd.pd_words, k->pd_words);
    char txt[32];
    (void)dfp21b_p090_text(&pd, txt, sizeof txt);
    CHECK_STR(txt, k->p090);
    if (!live) {
        return;
    }
    unsigned io = (k->param ? 8u : 0u) + 2u * k->pd_words;
    crig_init(4, BAUD, false);
    bring_up(k->bytes, k->len, USER_ALARM_OFF);
    const dp_event_t *ev = ev_last(&C.log, DP_EV_CFG_OK);
    CHECK(ev != NULL && ev->value == ((io << 8) | io));
    p090_is(k->p090);
    CHECK_EQ(C.c.pd.param_channel, k->param);
    CHECK_EQ(C.c.pd.pd_words, k->pd_words);
    /* Get_Cfg answers the configuration just accepted. */
    CHECK(sap(DP_SAP_GET_CFG, NULL, 0));
    fdl_msg_t m;
    size_t n;
    const uint8_t *du = reply_du(&C.u, &n, &m);
    CHECK(du != NULL && n == k->len && memcmp(du, k->bytes, n) == 0);
    /* Data_Exchange with exactly io output octets returns io input octets. */
    uint8_t out[28];
    for (unsigned i = 0; i < io; i++) {
        out[i] = (uint8_t)(i + 1u);
    }
    CHECK(dx(out, io));
    du = reply_du(&C.u, &n, &m);
    CHECK(du != NULL);
    CHECK_EQ(m.fc, FDL_RSP_DL);
    CHECK_EQ(n, io);
    CHECK_EQ(C.u.last[0], FDL_SD2); /* 8 input octets too */
}

static void test_cfg_predefined(void)
{
    for (size_t i = 0; i < sizeof PREDEFINED / sizeof PREDEFINED[0]; i++) {
        check_cfg_case(&PREDEFINED[i], true);
    }
}

static void test_cfg_universal(void)
{
    for (size_t i = 0; i < sizeof UNIVERSAL / sizeof UNIVERSAL[0]; i++) {
        check_cfg_case(&UNIVERSAL[i], i == 9u || i == 13u);
    }
}

static void test_cfg_refused(void)
{
    static const struct {
        uint8_t b[4];
        uint8_t len;
    } bad[] = {
        {{0xF3, 0xE2, 0xD1}, 3},       /* param + 3 PO words, 2 PI words: unequal */
        {{0x62, 0x51}, 2},             /* 3 out words, 2 in words (not consistent either) */
        {{0xE2, 0xD1}, 2},             /* unequal, consistent */
        {{0x00, 0xE4, 0xD3}, 3},       /* unequal after an empty slot */
        {{0xF3, 0xE2}, 2},             /* outputs only */
        {{0xD2}, 1},                   /* inputs only */
        {{0xC0, 0xC5, 0xC5}, 3},       /* special format with output and input length octets */
        {{0x40, 0xC5}, 2},             /* special format with an input length octet */
        {{0x80, 0xC5}, 2},             /* special format with an output length octet */
        {{0xF3, 0xC0, 0xC5, 0xC5}, 4}, /* param + special PD module */
        {{0x00}, 1},                   /* empty slot only */
        {{0xF3, 0x00}, 2},             /* param + empty slot */
        {{0xFA}, 1},                   /* 11 PD words */
        {{0xF3, 0xFA}, 2},
        {{0x00, 0xFF}, 2},             /* 16 PD words */
        {{0x72}, 1},                   /* 3 PD words without consistency */
        {{0xF3, 0xF2, 0xF0}, 3},       /* two PD modules */
        {{0xF3, 0xF3, 0xF2}, 3},       /* two parameter channels */
        {{0xF2, 0xF3}, 2},             /* modules in the wrong order is 3 PD + 4 PD */
        {{0xF3, 0xF2, 0x00, 0x00}, 4},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        dfp21b_pd_cfg_t pd = {.valid = true};
        CHECK(!dfp21b_check_cfg(bad[i].b, bad[i].len, &pd));
        CHECK(!pd.valid);
    }
    dfp21b_pd_cfg_t pd;
    CHECK(!dfp21b_check_cfg(bad[0].b, 0, &pd));

    /* On the wire: Cfg_Fault, back to Wait_Prm, P090 "0PD", BUS FAULT blinking. */
    crig_init(4, BAUD, false);
    size_t n;
    (void)diag(&n);
    CHECK(set_prm(0x88, 1, 100, USER_ALARM_OFF, 9));
    CHECK(chk_cfg(bad[0].b, bad[0].len));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(ev_count(&C.log, DP_EV_CFG_FAULT), 1u);
    DIAG_IS(0x06, 0x05, 0x00, 0xFF, 0x60, 0x03);
    p090_is("0PD");
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    CHECK(dx(DX14, 6));
    LAST_IS(0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    /* A good configuration afterwards, then a bad one again: P090 back to 0PD. */
    const uint8_t good[] = {0xF2};
    CHECK(set_prm(0x88, 1, 100, USER_ALARM_OFF, 9));
    CHECK(chk_cfg(good, sizeof good));
    p090_is("3PD");
    const uint8_t unequal[] = {0x62, 0x51};
    CHECK(chk_cfg(unequal, sizeof unequal));
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_PRM);
    p090_is("0PD");
}

/* ---- user parameters (§B4) ----------------------------------------------------------------- */

static void test_user_prm(void)
{
    bool alarm = true;
    CHECK(dfp21b_check_user_prm(USER_ALARM_OFF, 9, &alarm));
    CHECK(!alarm);
    CHECK(dfp21b_check_user_prm(USER_ALARM_ON, 9, &alarm));
    CHECK(alarm);
    const uint8_t dpv1[] = {0x80, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
    CHECK(dfp21b_check_user_prm(dpv1, 9, &alarm));
    CHECK(!alarm);
    /* DP-V1 with octet 8 = 00: accepted, but the DP-V0-only external diagnosis stays off. */
    const uint8_t dpv1_alarm[] = {0x80, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    alarm = true;
    CHECK(dfp21b_check_user_prm(dpv1_alarm, 9, &alarm));
    CHECK(!alarm);

    /* Every other value of the user block (octets 3..8) is refused, and so are other lengths. */
    static const struct {
        uint8_t pos;
        uint8_t val;
    } wrong[] = {
        {3, 0x05}, {3, 0x07}, {3, 0x00}, {4, 0x80}, {4, 0x82}, {4, 0x01}, {5, 0x01},
        {5, 0x80}, {6, 0x01}, {6, 0xFF}, {7, 0x00}, {7, 0x02}, {8, 0x02}, {8, 0xFF},
    };
    for (size_t i = 0; i < sizeof wrong / sizeof wrong[0]; i++) {
        uint8_t p[9];
        memcpy(p, USER_ALARM_OFF, 9);
        p[wrong[i].pos] = wrong[i].val;
        CHECK(!dfp21b_check_user_prm(p, 9, &alarm));
    }
    uint8_t p10[10];
    memcpy(p10, USER_ALARM_OFF, 9);
    p10[9] = 0;
    CHECK(!dfp21b_check_user_prm(p10, 10, &alarm));
    CHECK(!dfp21b_check_user_prm(USER_ALARM_OFF, 8, &alarm));
    CHECK(!dfp21b_check_user_prm(USER_ALARM_OFF, 0, &alarm));

    /* On the wire: refused user parameters are a Prm_Fault. */
    crig_init(4, BAUD, false);
    size_t n;
    (void)diag(&n);
    uint8_t p[9];
    memcpy(p, USER_ALARM_OFF, 9);
    p[7] = 0x02;
    CHECK(set_prm(0x88, 1, 100, p, 9));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_PRM);
    const dp_event_t *ev = ev_last(&C.log, DP_EV_PRM_FAULT);
    CHECK(ev != NULL && ev->value == DP_PRM_FAULT_USER);
    DIAG_IS(0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    /* Set_Prm without any user parameters (7 octets): refused too. */
    CHECK(set_prm(0x88, 1, 100, NULL, 0));
    DIAG_IS(0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    /* DP-V1 status octets 80 00 00: accepted. */
    CHECK(set_prm(0x88, 1, 100, dpv1, 9));
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_CFG);
    DIAG_IS(0x02, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

static void test_set_prm_spec_frame(void)
{
    crig_init(4, BAUD, false);
    CHECK(REQ(F_DIAG_REQ));
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60,
            0x03, 0xF1, 0x16);
    CHECK(REQ(F_SET_PRM));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_CFG);
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 1000u);
    CHECK(!C.c.diag_alarm);
    CHECK(REQ(F_CHK_CFG));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
    p090_is("3PD + PARAM");
    CHECK(REQ(F_DX14_REQ));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0E, 0x16);
}

/* ---- address and LEDs (§B1, §B2) ------------------------------------------------------------ */

static void test_dip_address(void)
{
    crig_init(4, BAUD, false);
    CHECK(C.c.on_bus);
    CHECK_EQ(dfp21b_p093_address(&C.c), 4);
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);

    static const uint8_t on_bus[] = {0, 1, 125};
    for (size_t i = 0; i < sizeof on_bus; i++) {
        crig_init(on_bus[i], BAUD, false);
        CHECK(C.c.on_bus);
        CHECK_EQ(dfp21b_p093_address(&C.c), on_bus[i]);
        uint8_t fdl[] = {0x10, on_bus[i], 0x02, 0x49, 0, 0x16};
        fdl[4] = fdl_fcs(&fdl[1], 3);
        CHECK(REQ(fdl));
        CHECK_BYTES(C.u.last, 3, 0x10, 0x02, on_bus[i]);
    }

    static const uint8_t off_bus[] = {126, 127};
    for (size_t i = 0; i < sizeof off_bus; i++) {
        crig_init(off_bus[i], 0, false);
        CHECK(!C.c.on_bus);
        CHECK_EQ(dfp21b_p093_address(&C.c), off_bus[i]);
        /* RUN blinks, BUS FAULT on. */
        CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_BLINK);
        CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
        /* Whatever is on the bus, at whatever time: never a transmission, no rate changes. */
        uint8_t fdl[] = {0x10, off_bus[i], 0x02, 0x49, 0, 0x16};
        fdl[4] = fdl_fcs(&fdl[1], 3);
        CHECK(!REQ(fdl));
        CHECK(!REQ(F_FDL_REQ));
        CHECK(!REQ(F_DIAG_REQ));
        CHECK(!REQ(F_SET_PRM));
        hal_time_us_t now = line_now_us(&C.l);
        CHECK_EQ(dfp21b_poll(&C.c, now), now + HAL_TIME_NO_DEADLINE_US);
        for (unsigned k = 0; k < 50; k++) {
            now += 100000u;
            (void)dfp21b_poll(&C.c, now);
        }
        C.l.now_ns = (uint64_t)now * 1000u;
        CHECK(!REQ(F_FDL_REQ));
        CHECK_EQ(C.u.tx_count, 0u);
        CHECK_EQ(C.u.baud_count, 0u);
        CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_BLINK);
        CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    }
}

static void test_led_sequence(void)
{
    crig_init(4, 0, false); /* automatic baud detection, starts at 12 Mbit/s */
    CHECK_EQ(C.leds.n, 2u);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON); /* searching */
    CHECK_EQ(dfp21b_p092_baud(&C.c), 0u);
    hal_time_us_t t = line_now_us(&C.l);
    (void)dfp21b_poll(&C.c, t + 1000u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);

    /* A telegram at 12 Mbit/s: baud found, not configured -> blink. */
    CHECK(REQ(F_FDL_REQ));
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(dfp21b_p092_baud(&C.c), 12000000u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    CHECK(REQ(F_DIAG_REQ));
    CHECK(REQ(F_SET_PRM));
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    CHECK(REQ(F_CHK_CFG));
    /* Data_Exch -> off. */
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    CHECK(REQ(F_DX14_REQ));
    hal_time_us_t end = C.l.req_end_us;
    (void)dfp21b_poll(&C.c, end + 999000u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    CHECK_EQ(C.timeouts, 0u);
    /* Watchdog (1 s) expires -> on, the inverter is told (P831 reaction). */
    (void)dfp21b_poll(&C.c, end + 1001000u);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    CHECK_EQ(C.timeouts, 1u);
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 1000u);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);
    /* The master comes back: blink, then off once configured again. */
    C.l.now_ns = (uint64_t)(end + 1100000u) * 1000u;
    C.m2 = (tmaster_t){.addr = 2};
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);

    static const struct {
        hal_led_id_t id;
        hal_led_mode_t mode;
    } seq[] = {
        {HAL_LED_RUN, HAL_LED_ON},         {HAL_LED_BUS_FAULT, HAL_LED_ON},
        {HAL_LED_BUS_FAULT, HAL_LED_BLINK}, {HAL_LED_BUS_FAULT, HAL_LED_OFF},
        {HAL_LED_BUS_FAULT, HAL_LED_ON},    {HAL_LED_BUS_FAULT, HAL_LED_BLINK},
        {HAL_LED_BUS_FAULT, HAL_LED_OFF},
    };
    CHECK_EQ(C.leds.n, sizeof seq / sizeof seq[0]);
    for (unsigned i = 0; i < sizeof seq / sizeof seq[0] && i < C.leds.n; i++) {
        CHECK_EQ(C.leds.id[i], seq[i].id);
        CHECK_EQ(C.leds.mode[i], seq[i].mode);
    }
}

/* protocol.md §B2: BUS FAULT on when the bus is interrupted or the master stopped, also without a
 * DP watchdog (baud control runs out), and off again once the master's telegrams return; RUN
 * stays on throughout. */
static void test_led_bus_interrupted_without_watchdog(void)
{
    crig_init(4, 0, false); /* automatic baud detection, the line at 12 Mbit/s */
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    CHECK(set_prm(0x80, 0, 0, USER_ALARM_OFF, 9)); /* watchdog off */
    CHECK(chk_cfg(CFG_P3PD, 2));
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 0u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    hal_time_us_t end = C.l.req_end_us;
    (void)dfp21b_poll(&C.c, end + 1000u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);
    /* The master goes silent: no watchdog fires, but the baud control does. */
    (void)dfp21b_poll(&C.c, end + (hal_time_us_t)DP_BAUD_CONTROL_MS_DEFAULT * 1000u + 1000u);
    CHECK_EQ(ev_count(&C.log, DP_EV_BAUD_LOST), 1u);
    CHECK_EQ(ev_count(&C.log, DP_EV_WD_EXPIRED), 0u);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);
    CHECK_EQ(C.timeouts, 0u); /* no P831 reaction without a watchdog */
    /* The master is back (the search starts at 12 Mbit/s): off again, still in Data_Exch. */
    C.l.now_ns = (uint64_t)(end + (hal_time_us_t)DP_BAUD_CONTROL_MS_DEFAULT * 1000u + 2000u) *
                 1000u;
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_OFF);
}

/* protocol.md §B1: the address is read at power-up only; moving the switches later changes
 * nothing until the next start. */
static void test_dip_read_at_power_up_only(void)
{
    crig_init(4, BAUD, false);
    C.dip = 9;
    for (unsigned k = 0; k < 10; k++) {
        (void)dfp21b_poll(&C.c, line_now_us(&C.l) + k * 100000u);
    }
    CHECK_EQ(dfp21b_p093_address(&C.c), 4);
    CHECK(REQ(F_FDL_REQ)); /* to station 4 */
    LAST_IS(0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    uint8_t fdl9[] = {0x10, 0x09, 0x02, 0x49, 0, 0x16};
    fdl9[4] = fdl_fcs(&fdl9[1], 3);
    size_t before = C.u.tx_count;
    CHECK(!REQ(fdl9));
    CHECK_EQ(C.u.tx_count, before);
    /* The next power-up takes the new setting. */
    crig_init(9, BAUD, false);
    CHECK_EQ(dfp21b_p093_address(&C.c), 9);
    CHECK(REQ(fdl9));
    CHECK_BYTES(C.u.last, 3, 0x10, 0x02, 0x09);
}

/* The Set_Prm count the inverter uses for P819 (ml_fieldbus_status_t): 0 only before the first
 * Set_Prm, then 1..255 and round again, never 0. */
static void test_prm_count_never_returns_to_zero(void)
{
    crig_init(4, BAUD, false);
    CHECK_EQ(C.c.prm_count, 0u);
    for (unsigned k = 1; k <= 256u; k++) {
        CHECK(set_prm(0x88, 1, 100, USER_ALARM_OFF, 9));
        CHECK_EQ(C.c.prm_count, k <= 255u ? k : 1u);
    }
    /* A refused Set_Prm does not count. */
    uint8_t bad[9];
    memcpy(bad, USER_ALARM_OFF, 9);
    bad[7] = 0x02;
    CHECK(set_prm(0x88, 1, 100, bad, 9));
    CHECK_EQ(C.c.prm_count, 1u);
}

static void test_led_fixed_baud(void)
{
    /* A fixed rate needs no search, but until an error-free telegram is seen there is no
     * connection to a master: BUS FAULT on. Any telegram on the line -> blink. */
    crig_init(4, BAUD, false);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    CHECK_EQ(dfp21b_p092_baud(&C.c), BAUD);
    uint8_t garbage[] = {0x10, 0x05, 0x02, 0x49, 0x00, 0x16}; /* FCS wrong */
    CHECK(!REQ(garbage));
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_ON);
    uint8_t fdl5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    CHECK(!REQ(fdl5));
    (void)dfp21b_poll(&C.c, line_now_us(&C.l)); /* LEDs follow in the main loop */
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
    CHECK_EQ(C.leds.now[HAL_LED_RUN], HAL_LED_ON);
    /* A telegram to the card itself changes them at once. */
    crig_init(4, BAUD, false);
    CHECK(REQ(F_FDL_REQ));
    CHECK_EQ(C.leds.now[HAL_LED_BUS_FAULT], HAL_LED_BLINK);
}

/* ---- monitor values ----------------------------------------------------------------------- */

static void test_monitor_values(void)
{
    crig_init(4, BAUD, false);
    p090_is("0PD");
    CHECK_EQ(dfp21b_p092_baud(&C.c), BAUD);
    CHECK_EQ(dfp21b_p093_address(&C.c), 4);
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 0u);
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    p090_is("3PD + PARAM");
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 1000u);
    /* Watchdog off: P819 0. */
    CHECK(set_prm(0x80, 0, 0, USER_ALARM_OFF, 9));
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 0u);
    /* 1 ms base (DP-V1): 1 x 5 x 40 = 200 ms. */
    const uint8_t dpv1_1ms[] = {0x84, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
    CHECK(set_prm(0x88, 5, 40, dpv1_1ms, 9));
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 200u);
    /* 10 ms x 255 x 255 = 650.25 s. */
    CHECK(set_prm(0x88, 255, 255, USER_ALARM_OFF, 9));
    CHECK_EQ(dfp21b_p819_timeout_ms(&C.c), 650250u);

    /* P090 text buffer handling. */
    dfp21b_pd_cfg_t pd = {.valid = true, .param_channel = true, .pd_words = 10};
    char small[5];
    CHECK_EQ(dfp21b_p090_text(&pd, small, sizeof small), 4u);
    CHECK_STR(small, "10PD");
    CHECK_EQ(dfp21b_p090_text(&pd, small, 0), 0u);
}

/* ---- process data ------------------------------------------------------------------------- */

static void test_pi_echo(void)
{
    crig_init(4, BAUD, false);
    CHECK(REQ(F_DIAG_REQ));
    CHECK(REQ(F_SET_PRM));
    CHECK(REQ(F_CHK_CFG));
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK(REQ(F_DX14_REQ));
    /* Before the main loop ran: the inputs are still the cleared image. */
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0E, 0x16);
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK_EQ(C.c.po[0], 0x0006);
    CHECK_EQ(C.c.po[1], 0x05DC);
    CHECK_EQ(C.c.po[2], 0x1234);
    CHECK_EQ(C.c.po[3], 0x0000);
    CHECK_BYTES(C.c.param_req, 8, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00);
    /* PI1..PI3 echo PO1..PO3; the parameter channel answers 8 zero octets. */
    CHECK(dx(DX14, sizeof DX14));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x06, 0x05, 0xDC, 0x12, 0x34, 0x3B, 0x16);

    /* 3 PD without parameter channel. */
    crig_init(4, BAUD, false);
    const uint8_t f2[] = {0xF2};
    bring_up(f2, sizeof f2, USER_ALARM_OFF);
    const uint8_t po[] = {0x00, 0x06, 0x05, 0xDC, 0xAB, 0xCD};
    CHECK(dx(po, sizeof po));
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK(dx(po, sizeof po));
    LAST_IS(0x68, 0x09, 0x09, 0x68, 0x02, 0x04, 0x08, 0x00, 0x06, 0x05, 0xDC, 0xAB, 0xCD, 0x6D,
            0x16);
}

static void test_process_data_app(void)
{
    crig_init(4, BAUD, true);
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    C.pd_calls = 0;
    C.param_calls = 0;
    CHECK(dx(DX14, sizeof DX14));
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK_EQ(C.pd_calls, 1u);
    CHECK_EQ(C.pd_n, 3);
    CHECK_EQ(C.pd_why, DP_OUTPUTS_DATA);
    CHECK_EQ(C.po[0], 0x0006);
    CHECK_EQ(C.po[1], 0x05DC);
    CHECK_EQ(C.po[2], 0x1234);
    CHECK_EQ(C.param_calls, 1u);
    CHECK_BYTES(C.param_req, 8, 0x01, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00);
    /* No new outputs: the main loop does not call the inverter again. */
    (void)dfp21b_poll(&C.c, line_now_us(&C.l));
    CHECK_EQ(C.pd_calls, 1u);
    CHECK(dx(DX14, sizeof DX14));
    LAST_IS(0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x81, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00,
            0x00, 0xFF, 0xF9, 0xFA, 0x23, 0xED, 0xCB, 0xE8, 0x16);
    /* Watchdog: the inverter gets zero PO words with the safe-state reason. */
    hal_time_us_t end = C.l.req_end_us;
    (void)dfp21b_poll(&C.c, end + 1000000u);
    CHECK_EQ(C.timeouts, 1u);
    CHECK_EQ(C.pd_why, DP_OUTPUTS_SAFE_STATE);
    CHECK_EQ(C.po[0], 0);
    CHECK_EQ(C.po[1], 0);
    CHECK_EQ(C.po[2], 0);
}

/* ---- external diagnosis ------------------------------------------------------------------- */


static void test_ext_diag_alarm_on(void)
{
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, USER_ALARM_ON);
    CHECK(C.c.diag_alarm);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DH);
    /* 6 standard octets (Ext_Diag set) + device-related block 02 <fault>: 8 in all. */
    CHECK(sap(DP_SAP_SLAVE_DIAG, NULL, 0));
    LAST_IS(0x68, 0x0D, 0x0D, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x08, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0x02, 0x11, 0x14, 0x16);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    /* The same fault again is nothing new. */
    dfp21b_set_inverter_fault(&C.c, 0x11);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    /* Another fault number. */
    dfp21b_set_inverter_fault(&C.c, 0x2B);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DH);
    DIAG_IS(0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x2B);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
}

static void test_ext_diag_fault_cleared(void)
{
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, USER_ALARM_ON);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    DIAG_IS(0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
    /* Fault gone: DH once so the master reads the diagnosis without Ext_Diag. */
    dfp21b_set_inverter_fault(&C.c, 0);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DH);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
}

static void test_ext_diag_alarm_off(void)
{
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    CHECK(!C.c.diag_alarm);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    LAST_IS(0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x00, 0x0C, 0x00, 0x02, 0x60,
            0x03, 0xF9, 0x16);
    dfp21b_set_inverter_fault(&C.c, 0);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
}

/* protocol.md §B4: with user prm octet 8 = 01 the card does not report inverter faults, with 00
 * every inverter fault is signalled; a new Set_Prm re-evaluates the fault that is active. */

/* Re-parameterised from 00 to 01 while a fault is reported: the master must not keep seeing
 * it (it read 08 0C 00 02 60 03 02 11 before the fix). */
static void test_ext_diag_alarm_switched_off(void)
{
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, USER_ALARM_ON);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    DIAG_IS(0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
    CHECK(set_prm(0x88, 1, 100, USER_ALARM_OFF, 9));
    CHECK(chk_cfg(CFG_P3PD, 2));
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
    CHECK(!C.c.diag_alarm);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

/* A fault active when the master enables diagnostic alarms must be reported. Today the
 * diagnosis stays 00 0C 00 02 60 03 until the inverter reports a different fault. */
static void test_ext_diag_alarm_switched_on(void)
{
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, USER_ALARM_OFF);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    CHECK(set_prm(0x88, 1, 100, USER_ALARM_ON, 9));
    CHECK(chk_cfg(CFG_P3PD, 2));
    CHECK_EQ(dp_slave_state(&C.c.dp), DP_STATE_DATA_EXCH);
    CHECK(C.c.diag_alarm);
    DIAG_IS(0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
}

/* protocol.md §B4: the external diagnosis is DP-V0 only. A DP-V1 master that asks for it with
 * octet 8 = 00 gets its Set_Prm accepted and a diagnosis without Ext_Diag and without the
 * 2-octet block (a DP-V1 master would parse it as a malformed alarm/status block). */
static void test_ext_diag_not_in_dpv1_mode(void)
{
    static const uint8_t dpv1_alarm_on[] = {0x80, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    crig_init(4, BAUD, false);
    bring_up(CFG_P3PD, 2, dpv1_alarm_on);
    CHECK(dp_slave_dpv1_mode(&C.c.dp));
    CHECK(!C.c.diag_alarm);
    dfp21b_set_inverter_fault(&C.c, 0x11);
    CHECK(dx(DX14, sizeof DX14));
    CHECK_EQ(C.u.last[6], FDL_RSP_DL);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
    /* The same master back in DP-V0 mode with alarms on: the active fault is reported. */
    CHECK(set_prm(0x88, 1, 100, USER_ALARM_ON, 9));
    CHECK(chk_cfg(CFG_P3PD, 2));
    CHECK(!dp_slave_dpv1_mode(&C.c.dp));
    DIAG_IS(0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x11);
}

int main(void)
{
    RUN_TEST(test_cfg_predefined);
    RUN_TEST(test_cfg_universal);
    RUN_TEST(test_cfg_refused);
    RUN_TEST(test_user_prm);
    RUN_TEST(test_set_prm_spec_frame);
    RUN_TEST(test_dip_address);
    RUN_TEST(test_led_sequence);
    RUN_TEST(test_led_fixed_baud);
    RUN_TEST(test_led_bus_interrupted_without_watchdog);
    RUN_TEST(test_dip_read_at_power_up_only);
    RUN_TEST(test_prm_count_never_returns_to_zero);
    RUN_TEST(test_monitor_values);
    RUN_TEST(test_pi_echo);
    RUN_TEST(test_process_data_app);
    RUN_TEST(test_ext_diag_alarm_on);
    RUN_TEST(test_ext_diag_fault_cleared);
    RUN_TEST(test_ext_diag_alarm_off);
    RUN_TEST(test_ext_diag_alarm_switched_off);
    RUN_TEST(test_ext_diag_alarm_switched_on);
    RUN_TEST(test_ext_diag_not_in_dpv1_mode);
    return check_report();
}
