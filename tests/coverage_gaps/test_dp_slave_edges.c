/* The generic DP slave (dp_slave) where the unit tests do not go: a slave without any device
 * hooks, DPV1_Status_1 reserved bits, Sync/Freeze requested from a slave without them, the
 * diagnosis cut to a short buffer, inputs longer than 244 octets, Stat_Diag, the state names.
 * Same rig as tests/unit (unit_rig.h): station 4, ident 0x6003, master 2, 1.5 Mbit/s. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "unit_rig.h"

#define SLAVE 4u
#define IDENT 0x6003u
#define BAUD 1500000u

static const uint8_t CFG_F3F2[] = {0xF3, 0xF2};

typedef struct rig {
    dp_slave_t s;
    fake_uart_t u;
    line_t l;
    tmaster_t m2;
    uint8_t f[FDL_FRAME_MAX];
} rig_t;

static rig_t R;

static void rx_dp(void *st, uint8_t b, uint8_t flags, hal_time_us_t t)
{
    dp_slave_rx_char(st, b, flags, t);
}

/* A slave with no device behind it: no hooks at all. */
static void rig_init(bool sync_freeze)
{
    memset(&R, 0, sizeof R);
    line_init(&R.l, BAUD, rx_dp, &R.s, &R.u);
    dp_slave_cfg_t cfg = {
        .address = SLAVE,
        .ident = IDENT,
        .fixed_baud = BAUD,
        .strict_timing = true,
        .sync_supported = sync_freeze,
        .freeze_supported = sync_freeze,
        .default_cfg = CFG_F3F2,
        .default_cfg_len = sizeof CFG_F3F2,
        .uart = fake_uart_hal(&R.u),
    };
    dp_slave_init(&R.s, &cfg, line_now_us(&R.l));
    R.m2.addr = 2;
}

#define LAST_IS(...) CHECK_BYTES(R.u.last, R.u.last_len, __VA_ARGS__)

static bool sap(uint8_t dsap, const uint8_t *d, size_t n)
{
    size_t len = mk_sap_req(R.f, SLAVE, R.m2.addr, tm_fc(&R.m2, FDL_REQ_SRD_HIGH), dsap, d, n);
    return line_request(&R.l, R.f, len);
}

static bool set_prm(uint8_t status, const uint8_t *tail, size_t tail_len)
{
    uint8_t p[DP_MAX_PRM_LEN];
    size_t n = mk_prm(p, status, 1, 100, 0, IDENT, 0, tail, tail_len);
    return sap(DP_SAP_SET_PRM, p, n);
}

#define DIAG_IS(...)                                                                           \
    do {                                                                                       \
        CHECK(sap(DP_SAP_SLAVE_DIAG, NULL, 0));                                                \
        size_t dn_;                                                                            \
        fdl_msg_t dm_;                                                                         \
        const uint8_t *dd_ = reply_du(&R.u, &dn_, &dm_);                                       \
        CHECK(dd_ != NULL);                                                                    \
        if (dd_ != NULL) {                                                                     \
            CHECK_BYTES(dd_, dn_, __VA_ARGS__);                                                \
        }                                                                                      \
    } while (0)

/* DPV1_Status_1 bits 4-3 are reserved (protocol.md §A3.2): Prm_Fault, stay in Wait_Prm. */
static void test_dpv1_status_reserved_bits(void)
{
    static const uint8_t reserved[] = {0x08, 0x10, 0x18, 0x98};
    for (size_t i = 0; i < sizeof reserved; i++) {
        rig_init(true);
        const uint8_t tail[3] = {reserved[i], 0x00, 0x00};
        CHECK(set_prm(0x88, tail, sizeof tail));
        LAST_IS(0xE5);
        CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
        DIAG_IS(0x42, 0x05, 0x00, 0xFF, 0x60, 0x03);
    }
    /* Every other DPV1_Status_1 bit is accepted. */
    rig_init(true);
    const uint8_t tail[3] = {0xE7, 0x00, 0x00};
    CHECK(set_prm(0x88, tail, sizeof tail));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    CHECK(dp_slave_dpv1_mode(&R.s));
}

/* Sync_Req / Freeze_Req to a slave that has neither: Not_Supported and Prm_Fault. */
static void test_sync_freeze_unsupported(void)
{
    static const uint8_t status[] = {0xA8, 0x98, 0xB8};
    for (size_t i = 0; i < sizeof status; i++) {
        rig_init(false);
        CHECK(set_prm(status[i], NULL, 0));
        LAST_IS(0xE5);
        CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_PRM);
        DIAG_IS(0x52, 0x05, 0x00, 0xFF, 0x60, 0x03);
    }
    /* Without the requests the same slave is parameterised, and Not_Supported goes away. */
    CHECK(set_prm(0x88, NULL, 0));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    DIAG_IS(0x02, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

/* No hooks: Set_Prm and Chk_Cfg are accepted as they are (no device to ask), with no I/O. */
static void test_no_hooks(void)
{
    rig_init(true);
    CHECK(set_prm(0x88, NULL, 0));
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_WAIT_CFG);
    CHECK(sap(DP_SAP_CHK_CFG, CFG_F3F2, sizeof CFG_F3F2));
    LAST_IS(0xE5);
    CHECK_EQ(dp_slave_state(&R.s), DP_STATE_DATA_EXCH);
    DIAG_IS(0x00, 0x0C, 0x00, 0x02, 0x60, 0x03);
}

static void test_diag_buffer_and_stat_diag(void)
{
    rig_init(true);
    const uint8_t ext[10] = {0x0A, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    dp_slave_set_ext_diag(&R.s, ext, sizeof ext);
    dp_slave_set_stat_diag(&R.s, true);
    dp_slave_set_stat_diag(&R.s, true); /* no change */
    uint8_t out[16];
    memset(out, 0xEE, sizeof out);
    CHECK_EQ(dp_slave_build_diag(&R.s, out, 5), 0); /* not even the 6 standard octets */
    CHECK_EQ(out[0], 0xEE);
    CHECK_EQ(dp_slave_build_diag(&R.s, out, 8), 8); /* standard octets + what fits */
    CHECK_BYTES(out, 9, 0x0A, 0x07, 0x00, 0xFF, 0x60, 0x03, 0x0A, 0x01, 0xEE);
    CHECK_EQ(dp_slave_build_diag(&R.s, out, sizeof out), 16);
    CHECK_BYTES(out, 16, 0x0A, 0x07, 0x00, 0xFF, 0x60, 0x03, 0x0A, 1, 2, 3, 4, 5, 6, 7, 8, 9);
    dp_slave_set_stat_diag(&R.s, false);
    dp_slave_set_ext_diag(&R.s, NULL, 0);
    CHECK_EQ(dp_slave_build_diag(&R.s, out, sizeof out), 6);
    CHECK_BYTES(out, 6, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03);
}

/* More than 244 input octets: the first 244 are taken, the rest is not read past the image. */
static void test_inputs_longer_than_244(void)
{
    rig_init(true);
    static uint8_t big[300];
    for (size_t i = 0; i < sizeof big; i++) {
        big[i] = (uint8_t)i;
    }
    dp_slave_set_inputs(&R.s, big, sizeof big);
    CHECK_EQ(R.s.inputs[0], 0);
    CHECK_EQ(R.s.inputs[DP_MAX_IO_LEN - 1u], (DP_MAX_IO_LEN - 1u) & 0xFFu);
}

static void test_names(void)
{
    CHECK_STR(dp_state_name(DP_STATE_WAIT_PRM), "Wait_Prm");
    CHECK_STR(dp_state_name(DP_STATE_WAIT_CFG), "Wait_Cfg");
    CHECK_STR(dp_state_name(DP_STATE_DATA_EXCH), "Data_Exch");
    CHECK_STR(dp_state_name((dp_state_t)99), "?");
    CHECK(strcmp(dp_baud_state_name(DP_BAUD_SEARCH), dp_baud_state_name(DP_BAUD_CONTROL)) != 0);
    CHECK(strcmp(dp_baud_state_name(DP_BAUD_CONTROL), dp_baud_state_name(DP_BAUD_FIXED)) != 0);
    CHECK_STR(dp_baud_state_name((dp_baud_state_t)99), "?");
}

int main(void)
{
    RUN_TEST(test_dpv1_status_reserved_bits);
    RUN_TEST(test_sync_freeze_unsupported);
    RUN_TEST(test_no_hooks);
    RUN_TEST(test_diag_buffer_and_stat_diag);
    RUN_TEST(test_inputs_longer_than_244);
    RUN_TEST(test_names);
    return check_report();
}
