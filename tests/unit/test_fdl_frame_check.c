/* fdl_check and fdl_parse_damaged: finished records (captures, logs) checked against
 * protocol.md §A1.2 without the receiver. Every result is produced once from the worked
 * telegrams of §A1.6 (master 2, slave 4), spoiled one octet at a time. */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "spec_frames.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

static fdl_check_info_t info;
static fdl_msg_t msg;

#define CHECK_RECORD(expected, ...)                                                            \
    do {                                                                                       \
        const uint8_t r_[] = {__VA_ARGS__};                                                    \
        CHECK_EQ(fdl_check(r_, sizeof r_, &info, &msg), expected);                             \
    } while (0)

static bool same_msg(const fdl_msg_t *a, const fdl_msg_t *b)
{
    return a->sd == b->sd && a->da == b->da && a->sa == b->sa && a->fc == b->fc &&
           a->has_dsap == b->has_dsap && a->has_ssap == b->has_ssap && a->dsap == b->dsap &&
           a->ssap == b->ssap && a->data == b->data && a->data_len == b->data_len;
}

static void test_ok_matches_parse(void)
{
    static const struct {
        const uint8_t *f;
        size_t n;
    } frames[] = {
        {F_FDL_REQ, sizeof F_FDL_REQ},   {F_DIAG_REQ, sizeof F_DIAG_REQ},
        {F_SET_PRM, sizeof F_SET_PRM},   {F_CHK_CFG, sizeof F_CHK_CFG},
        {F_GC_SYNC, sizeof F_GC_SYNC},   {F_DX14_REQ, sizeof F_DX14_REQ},
        {F_DX8_REQ, sizeof F_DX8_REQ},
    };
    for (size_t i = 0; i < sizeof frames / sizeof frames[0]; i++) {
        fdl_msg_t parsed;
        CHECK_EQ(fdl_parse(frames[i].f, frames[i].n, &parsed), FDL_PARSE_OK);
        CHECK_EQ(fdl_check(frames[i].f, frames[i].n, &info, &msg), FDL_CHECK_OK);
        CHECK_EQ(info.parse, FDL_PARSE_OK);
        CHECK_EQ(info.frame_len, frames[i].n);
        CHECK(same_msg(&msg, &parsed));
        /* An intact record reads the same through the lenient reader. */
        CHECK(fdl_parse_damaged(frames[i].f, frames[i].n, &msg));
        CHECK(same_msg(&msg, &parsed));
    }
    /* The values, not only agreement: FDL status request 2 -> 4, Slave_Diag SAPs 62 -> 60. */
    CHECK_EQ(fdl_check(F_FDL_REQ, sizeof F_FDL_REQ, &info, &msg), FDL_CHECK_OK);
    CHECK_EQ(msg.sd, 0x10);
    CHECK_EQ(msg.da, 4);
    CHECK_EQ(msg.sa, 2);
    CHECK_EQ(msg.fc, 0x49);
    CHECK(!msg.has_dsap && !msg.has_ssap);
    CHECK_EQ(msg.data_len, 0);
    CHECK_EQ(fdl_check(F_DIAG_REQ, sizeof F_DIAG_REQ, &info, &msg), FDL_CHECK_OK);
    CHECK(msg.has_dsap && msg.has_ssap);
    CHECK_EQ(msg.dsap, 60);
    CHECK_EQ(msg.ssap, 62);
    CHECK_EQ(msg.data_len, 0);
    CHECK_EQ(fdl_check(F_DX8_REQ, sizeof F_DX8_REQ, &info, &msg), FDL_CHECK_OK);
    CHECK_BYTES(msg.data, msg.data_len, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88);
    /* Token and short acknowledgement: framing fine, no data. */
    CHECK_RECORD(FDL_CHECK_OK, 0xDC, 0x04, 0x02);
    CHECK_EQ(info.parse, FDL_PARSE_NOT_DATA);
    CHECK_EQ(info.frame_len, 3);
    CHECK_RECORD(FDL_CHECK_OK, 0xE5);
    CHECK_EQ(info.parse, FDL_PARSE_NOT_DATA);
    CHECK_EQ(msg.sd, 0xE5);
    /* info and msg are optional. */
    CHECK_EQ(fdl_check(F_FDL_REQ, sizeof F_FDL_REQ, NULL, NULL), FDL_CHECK_OK);
}

static void test_ok_framing_bad_addressing(void)
{
    /* SD1 with DA bit 7: a DAE is announced but SD1 has no DU. */
    CHECK_RECORD(FDL_CHECK_OK, 0x10, 0x84, 0x02, 0x49, 0xCF, 0x16);
    CHECK_EQ(info.parse, FDL_PARSE_SHORT);
    CHECK(!msg.has_dsap);
    /* Slave_Diag request with the segment bit in the DAE (0x7C): the SAP bits still show. */
    CHECK_RECORD(FDL_CHECK_OK, 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x7C, 0x3E, 0x2D, 0x16);
    CHECK_EQ(info.parse, FDL_PARSE_SEGMENT);
    CHECK(msg.has_dsap && msg.has_ssap);
    CHECK_EQ(msg.dsap, 60);
    CHECK_EQ(msg.ssap, 62);
}

static void test_every_rule(void)
{
    CHECK_EQ(fdl_check(NULL, 0, &info, &msg), FDL_CHECK_EMPTY);
    CHECK_EQ(fdl_check(F_FDL_REQ, 0, &info, &msg), FDL_CHECK_EMPTY);
    CHECK_RECORD(FDL_CHECK_UNKNOWN_SD, 0x55, 0x10);

    CHECK_RECORD(FDL_CHECK_SHORT, 0x10, 0x04, 0x02);
    CHECK_EQ(info.frame_len, 6);
    CHECK(!info.frame_len_min);
    CHECK_RECORD(FDL_CHECK_SHORT, 0x68, 0x05);
    CHECK_EQ(info.frame_len, 10);
    CHECK(info.frame_len_min);
    CHECK_RECORD(FDL_CHECK_SHORT, 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D);
    CHECK_EQ(info.frame_len, 11);
    CHECK(!info.frame_len_min);
    CHECK_RECORD(FDL_CHECK_SHORT, 0xA2, 0x04, 0x02, 0x5D, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66,
                 0x77, 0x88, 0xC7);
    CHECK_EQ(info.frame_len, 14);
    CHECK_RECORD(FDL_CHECK_SHORT, 0xDC, 0x04);
    CHECK_EQ(info.frame_len, 3);

    CHECK_RECORD(FDL_CHECK_LE_MISMATCH, 0x68, 0x05, 0x06, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                 0xED, 0x16);
    CHECK_EQ(info.found, 0x06);
    CHECK_EQ(info.expected, 0x05);
    CHECK_RECORD(FDL_CHECK_LE_RANGE, 0x68, 0x03, 0x03, 0x68, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_EQ(info.found, 3);
    CHECK_RECORD(FDL_CHECK_LE_RANGE, 0x68, 0xFA, 0xFA, 0x68);
    CHECK_EQ(info.found, FDL_LE_MAX + 1u);
    CHECK_RECORD(FDL_CHECK_SD2_REPEAT, 0x68, 0x05, 0x05, 0x69, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                 0xED, 0x16);
    CHECK_EQ(info.found, 0x69);
    CHECK_EQ(info.expected, 0x68);

    CHECK_RECORD(FDL_CHECK_ED, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x17);
    CHECK_EQ(info.found, 0x17);
    CHECK_EQ(info.expected, 0x16);
    CHECK_RECORD(FDL_CHECK_FCS, 0x10, 0x04, 0x02, 0x49, 0x12, 0x16);
    CHECK_EQ(info.found, 0x12);
    CHECK_EQ(info.expected, 0x4F);
    CHECK_RECORD(FDL_CHECK_FCS, 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xEE,
                 0x16);
    CHECK_EQ(info.expected, 0xED);
    CHECK_EQ(msg.sd, 0); /* only an OK record is decoded */

    CHECK_RECORD(FDL_CHECK_LONG, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16, 0xE5);
    CHECK_EQ(info.frame_len, 6);
    CHECK_RECORD(FDL_CHECK_LONG, 0xE5, 0xE5);
    CHECK_EQ(info.frame_len, 1);

    /* The longest SD2 (LE 249) passes. */
    uint8_t big[FDL_FRAME_MAX] = {0x68, 249, 249, 0x68, 0x04, 0x02, 0x5D};
    big[253] = fdl_fcs(&big[4], 249);
    big[254] = 0x16;
    CHECK_EQ(fdl_check(big, sizeof big, &info, &msg), FDL_CHECK_OK);
    CHECK_EQ(msg.data_len, 246);
}

static void test_parse_damaged(void)
{
    /* Data_Exchange reply 4 -> 2 cut after FC: the header is there, no DU. */
    static const uint8_t dx_rep[] = {0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x01};
    CHECK(fdl_parse_damaged(dx_rep, 7, &msg));
    CHECK_EQ(msg.sd, 0x68);
    CHECK_EQ(msg.da, 2);
    CHECK_EQ(msg.sa, 4);
    CHECK_EQ(msg.fc, 0x08);
    CHECK_EQ(msg.data_len, 0);
    CHECK(!fdl_parse_damaged(dx_rep, 6, &msg));
    CHECK(!fdl_parse_damaged(dx_rep, 3, &msg));
    /* 8 octets: too short to hold FCS and ED behind FC, so the last octet is DU. */
    CHECK(fdl_parse_damaged(dx_rep, 8, &msg));
    CHECK_BYTES(msg.data, msg.data_len, 0x01);
    /* Slave_Diag request with a bad FCS: SAPs read as usual. */
    static const uint8_t diag_bad_fcs[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82,
                                           0x6D, 0x3C, 0x3E, 0xEE, 0x16};
    CHECK(fdl_parse_damaged(diag_bad_fcs, sizeof diag_bad_fcs, &msg));
    CHECK(msg.has_dsap && msg.has_ssap);
    CHECK_EQ(msg.dsap, 60);
    CHECK_EQ(msg.ssap, 62);
    /* The same cut to 9 octets: the last two are taken for FCS and ED, so no SAP octets. */
    CHECK(fdl_parse_damaged(diag_bad_fcs, 9, &msg));
    CHECK(!msg.has_dsap && !msg.has_ssap);
    /* Octets after the end do not lengthen the DU: LE bounds it. */
    uint8_t prm_long[sizeof F_SET_PRM + 2];
    memcpy(prm_long, F_SET_PRM, sizeof F_SET_PRM);
    prm_long[sizeof F_SET_PRM] = 0xE5;
    prm_long[sizeof F_SET_PRM + 1u] = 0xE5;
    CHECK(fdl_parse_damaged(prm_long, sizeof prm_long, &msg));
    CHECK_EQ(msg.dsap, 61);
    CHECK_EQ(msg.data_len, 16);
    CHECK_EQ(msg.data[0], 0x88);
    /* SD3 cut after 10 octets: 4 DU octets before the presumed FCS and ED. */
    CHECK(fdl_parse_damaged(F_DX8_REQ, 10, &msg));
    CHECK_BYTES(msg.data, msg.data_len, 0x11, 0x22, 0x33, 0x44);
    /* SD1 never has a DU, whatever follows. */
    CHECK(fdl_parse_damaged(F_FDL_REQ, 5, &msg));
    CHECK_EQ(msg.fc, 0x49);
    CHECK_EQ(msg.data_len, 0);
    /* Token, SC, unknown. */
    CHECK(fdl_parse_damaged(F_DX8_REQ, 0, &msg) == false);
    CHECK(fdl_parse_damaged((const uint8_t[]){0xDC, 0x04, 0x02}, 3, &msg));
    CHECK_EQ(msg.da, 4);
    CHECK_EQ(msg.sa, 2);
    CHECK(!fdl_parse_damaged((const uint8_t[]){0xDC, 0x04}, 2, &msg));
    CHECK(!fdl_parse_damaged((const uint8_t[]){0xE5}, 1, &msg));
    CHECK_EQ(msg.sd, 0xE5);
    CHECK(!fdl_parse_damaged((const uint8_t[]){0x55, 0x04, 0x02, 0x49}, 4, &msg));
}

int main(void)
{
    RUN_TEST(test_ok_matches_parse);
    RUN_TEST(test_ok_framing_bad_addressing);
    RUN_TEST(test_every_rule);
    RUN_TEST(test_parse_damaged);
    return check_report();
}
