/* The monitor's decoding (mon_decode.h): Slave_Diag lines for real diagnosis octets (the
 * DFP21B's start-up, parameterisation and inverter fault, a modular slave's identifier and
 * channel blocks, DP-V1 alarm and status blocks, damaged blocks) and the DFP21B's view of a
 * real Data_Exchange of a "Param + 3 PD" configuration
 * (tests/replay/golden/param_channel.pcap). */
#include <string.h>

#include "check.h"
#include "monitor/mon_decode.h"

static const char *diag(const uint8_t *d, size_t len, bool dpv1)
{
    static char out[512];
    size_t n = mon_decode_diag(d, len, dpv1, out, sizeof out);
    CHECK_EQ(n, strlen(out));
    return out;
}

#define DIAG(dpv1, ...)                                                                        \
    diag((const uint8_t[]){__VA_ARGS__}, sizeof((uint8_t[]){__VA_ARGS__}), dpv1)

static void test_standard_octets(void)
{
    /* the card after power-up: not ready, asks for parameters, no master yet */
    CHECK_STR(DIAG(false, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03),
              "Station_Not_Ready Prm_Req | no master, ident 0x6003");
    /* parameterised, waiting for its configuration: Stat_Diag keeps the master reading */
    CHECK_STR(DIAG(false, 0x02, 0x0F, 0x00, 0x02, 0x60, 0x03),
              "Station_Not_Ready Prm_Req Stat_Diag WD_On | Master_Add 2, ident 0x6003");
    /* every bit of octets 1 and 2, and the overflow of octet 3 */
    CHECK_STR(DIAG(false, 0xFF, 0xBF, 0x80, 0x07, 0x12, 0x34),
              "Station_Non_Existent Station_Not_Ready Cfg_Fault Ext_Diag Not_Supported "
              "Invalid_Slave_Response Prm_Fault Master_Lock Prm_Req Stat_Diag WD_On "
              "Freeze_Mode Sync_Mode Deactivated Ext_Diag_Overflow | Master_Add 7, "
              "ident 0x1234");
    CHECK_STR(DIAG(false, 0x02, 0x05, 0x00), "(short diagnosis, 3 octets)");
}

static void test_extended_blocks(void)
{
    /* the DFP21B in DP-V0 with diagnostic alarms on: inverter fault 28 */
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x1C),
              "Ext_Diag WD_On | Master_Add 2, ident 0x6003, ext: device-related: 1C");
    /* a modular slave: module 2 has diagnosis, its input channel 3 (a word) a line break */
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x80, 0xE0, 0x42, 0x04, 0x82, 0x43, 0xA6),
              "Ext_Diag WD_On | Master_Add 2, ident 0x80E0, ext: identifier-related: modules "
              "2; channel: module 2 channel 3 input word, line break (6)");
    /* modules 0 and 9 over two octets; an output bit channel with a manufacturer error */
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x80, 0xE0, 0x43, 0x01, 0x02, 0x80, 0x80,
                   0x31),
              "Ext_Diag WD_On | Master_Add 2, ident 0x80E0, ext: identifier-related: modules "
              "0, 9; channel: module 0 channel 0 output bit, manufacturer error 17");
    /* DP-V1: a device-related block is an alarm or a status */
    const uint8_t alarm[] = {0x08, 0x0C, 0x00, 0x02, 0x80, 0xE0, 0x08, 0x01,
                             0x02, 0x0D, 0x01, 0x02, 0x03, 0x04};
    CHECK_STR(diag(alarm, sizeof alarm, true),
              "Ext_Diag WD_On | Master_Add 2, ident 0x80E0, ext: diagnosis alarm (1), slot 2, "
              "seq 1, appears, Add_Ack: 01 02 03 04");
    CHECK_STR(diag(alarm, sizeof alarm, false),
              "Ext_Diag WD_On | Master_Add 2, ident 0x80E0, ext: device-related: 01 02 0D 01 "
              "02 03 04");
    CHECK_STR(DIAG(true, 0x08, 0x0C, 0x00, 0x02, 0x80, 0xE0, 0x05, 0x81, 0x00, 0x02, 0xAA),
              "Ext_Diag WD_On | Master_Add 2, ident 0x80E0, ext: Status_Message (0x81), slot "
              "0, disappears: AA");
    /* a header whose length runs past the end, and a reserved type: the rest in hex */
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x02, 0x1C, 0x05, 0x01),
              "Ext_Diag WD_On | Master_Add 2, ident 0x6003, ext: device-related: 1C; bad "
              "block: 05 01");
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0xC2, 0x00),
              "Ext_Diag WD_On | Master_Add 2, ident 0x6003, ext: bad block: C2 00");
    CHECK_STR(DIAG(false, 0x08, 0x0C, 0x00, 0x02, 0x60, 0x03, 0x00),
              "Ext_Diag WD_On | Master_Add 2, ident 0x6003, ext: bad block: 00");
}

static void test_cut_output(void)
{
    const uint8_t d[] = {0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0x02, 0x1C};
    char out[12];
    size_t n = mon_decode_diag(d, sizeof d, false, out, sizeof out);
    CHECK_STR(out, "Station_Not");
    CHECK_EQ(n, 11u);
    CHECK_EQ(mon_decode_diag(d, sizeof d, false, out, 0u), 0u);
}

static void test_prm_dpv1(void)
{
    const uint8_t v1[10] = {0x88, 0x01, 0x0A, 0x0B, 0x60, 0x03, 0x00, 0x80, 0x00, 0x00};
    const uint8_t v0[10] = {0x88, 0x01, 0x0A, 0x0B, 0x60, 0x03, 0x00, 0x04, 0x00, 0x00};
    CHECK(mon_prm_dpv1(v1, sizeof v1));
    CHECK(!mon_prm_dpv1(v0, sizeof v0));
    CHECK(!mon_prm_dpv1(v1, 7u));
}

/* Data_Exchange 2 -> 4 and its answer from param_channel.pcap: Chk_Cfg F3 F2. */
static void test_dfp21b_param_3pd(void)
{
    const uint8_t cfg[] = {0xF3, 0xF2};
    const uint8_t out[] = {0x71, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00,
                           0x00, 0x06, 0x05, 0xDC, 0x00, 0x00};
    const uint8_t in[] = {0x71, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89,
                          0x02, 0x02, 0x00, 0x00, 0x00, 0x00};
    mon_dfp21b_t r;
    mon_decode_dfp21b(cfg, sizeof cfg, out, sizeof out, in, sizeof in, &r);
    CHECK(r.cfg_valid);
    CHECK(r.param_channel);
    CHECK_EQ(r.pd_words, 3u);
    CHECK_STR(r.pd_config, "3PD + PARAM");
    CHECK(r.has_control);
    CHECK_EQ(r.control_word, 0x0006u);
    CHECK_STR(r.control_text, "enable, no rapid stop, no stop");
    CHECK(r.has_status);
    CHECK_EQ(r.status_word, 0x0202u);
    CHECK_STR(r.status_text,
              "output stage inhibited, ready, PO data disabled, unit status 2 (no enable)");
    /* P076 firmware 823 947 9.13: the value as the drive answered it */
    CHECK_STR(r.param_request, "read P076 firmware basic unit (8300)");
    CHECK_STR(r.param_answer, "read P076 firmware basic unit (8300) = 823947913");
}

static void test_dfp21b_other_configs(void)
{
    mon_dfp21b_t r;
    /* 3 PD without the channel (an empty slot first): PO1 is the first word */
    const uint8_t cfg[] = {0x00, 0xF2};
    const uint8_t out[] = {0x00, 0x46, 0x05, 0xDC, 0x00, 0x00};
    mon_decode_dfp21b(cfg, sizeof cfg, out, sizeof out, NULL, 0u, &r);
    CHECK(r.cfg_valid);
    CHECK(!r.param_channel);
    CHECK_STR(r.pd_config, "3PD");
    CHECK_EQ(r.control_word, 0x0046u);
    CHECK(!r.has_status);
    CHECK_STR(r.param_request, "");
    /* the channel alone carries no service: no request named */
    const uint8_t cfg_p1[] = {0xF3, 0xF0};
    const uint8_t idle[] = {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x06};
    mon_decode_dfp21b(cfg_p1, sizeof cfg_p1, idle, sizeof idle, idle, 8u, &r);
    CHECK_STR(r.pd_config, "1PD + PARAM");
    CHECK_STR(r.param_request, "");
    CHECK_STR(r.param_answer, "");
    CHECK(r.has_control);
    CHECK(!r.has_status); /* 8 octets of inputs: the channel only */
    /* a configuration the card refuses: not consistent */
    const uint8_t bad[] = {0x72};
    mon_decode_dfp21b(bad, sizeof bad, out, sizeof out, NULL, 0u, &r);
    CHECK(!r.cfg_valid);
    CHECK_STR(r.pd_config, "0PD");
    CHECK_EQ(r.pd_words, 0u);
    CHECK(!r.has_control);
}

static void test_is_dfp21b(void)
{
    mon_station_t st;
    memset(&st, 0, sizeof st);
    st.dp = true;
    st.ident = 0x6003u;
    CHECK(!mon_is_dfp21b(&st)); /* ident not known yet */
    st.ident_known = true;
    CHECK(mon_is_dfp21b(&st));
    st.ident = 0x80E0u;
    CHECK(!mon_is_dfp21b(&st));
}

int main(void)
{
    RUN_TEST(test_standard_octets);
    RUN_TEST(test_extended_blocks);
    RUN_TEST(test_cut_output);
    RUN_TEST(test_prm_dpv1);
    RUN_TEST(test_dfp21b_param_3pd);
    RUN_TEST(test_dfp21b_other_configs);
    RUN_TEST(test_is_dfp21b);
    return check_report();
}
