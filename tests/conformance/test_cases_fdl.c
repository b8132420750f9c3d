/* The helpers of the GSD and FDL groups of the conformance suite (cf_cases_fdl.h) that need no
 * slave: the FC octets of built requests, the Set_Prm and configuration of one module of a GSD,
 * the diagnosis that shows Data_Exch, the positive acknowledgement and the hex text of reasons.
 * The cases themselves run against the card in the suite's own tests. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "conformance/cf_cases_fdl.h"

static cf_t cf;
static gsd_t g;

/* A modular slave whose global user parameters are 2 octets (a Const and a Ref's default) and
 * whose second module has 2 parameter octets of its own. */
static const char text[] =
    "#Profibus_DP\n"
    "GSD_Revision = 3\n"
    "Vendor_Name = \"V\"\nModel_Name = \"M\"\nRevision = \"R\"\n"
    "Ident_Number = 0x1234\nProtocol_Ident = 0\nStation_Type = 0\n"
    "Hardware_Release = \"H\"\nSoftware_Release = \"S\"\n"
    "Min_Slave_Intervall = 1\nMax_Diag_Data_Len = 6\n"
    "19.2_supp = 1\nMaxTsdr_19.2 = 60\n"
    "Modular_Station = 1\nMax_Module = 1\n"
    "Max_Input_Len = 8\nMax_Output_Len = 8\nMax_Data_Len = 16\n"
    "User_Prm_Data_Len = 2\n"
    "Ext_User_Prm_Data_Const(0) = 0xA1\n"
    "ExtUserPrmData = 7 \"P\"\nUnsigned8 5 0-9\nEndExtUserPrmData\n"
    "Ext_User_Prm_Data_Ref(1) = 7\n"
    "Module = \"2 in\" 0x11\nEndModule\n"
    "Module = \"4 out 2 prm\" 0x23\n"
    "Ext_Module_Prm_Data_Len = 2\n"
    "Ext_User_Prm_Data_Const(0) = 0xB1,0xB2\n"
    "EndModule\n";

static void load(void)
{
    char err[GSD_ERR_LEN];
    if (gsd_parse_text(text, strlen(text), &g, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        CHECK(false);
        return;
    }
    memset(&cf, 0, sizeof cf);
    cf.gsd = &g;
    cf.opt.address = 4;
    cf.opt.master = 1;
    /* what a master sends for module 0: 7 standard octets, the 2 global ones, none of its own */
    static const uint8_t prm[] = {0x88, 0x01, 0x14, 0x0B, 0x12, 0x34, 0x00, 0xA1, 0x05};
    memcpy(cf.prm, prm, sizeof prm);
    cf.prm_len = sizeof prm;
    cf.cfg[0] = 0x11;
    cf.cfg_len = 1;
    cf.in_len = 2;
}

static void test_fc_octets(void)
{
    cf_gf_fcb_t seq = {false, false};
    CHECK_EQ(cf_gf_next_fc(&seq, 0xD), 0x6D); /* FCV 0, FCB 1: the first */
    CHECK_EQ(cf_gf_next_fc(&seq, 0xD), 0x5D); /* FCV 1, FCB 0 */
    CHECK_EQ(cf_gf_next_fc(&seq, 0xD), 0x7D);
    CHECK_EQ(cf_gf_next_fc(&seq, 0xC), 0x5C);
    CHECK_EQ(cf_gf_fc(0x9, false, false), 0x49); /* Request FDL Status */
    CHECK_EQ(cf_gf_fc(0x6, false, false), 0x46); /* SDN high */
    CHECK_EQ(cf_gf_fc(0x18, true, true), 0x78);  /* only the code's 4 bits */
}

static void test_setup_default(void)
{
    cf_gf_setup_t s;
    cf_gf_setup_default(&cf, &s);
    CHECK_BYTES(s.prm, s.prm_len, 0x88, 0x01, 0x14, 0x0B, 0x12, 0x34, 0x00, 0xA1, 0x05);
    CHECK_BYTES(s.cfg, s.cfg_len, 0x11);
    CHECK_EQ(s.in_len, 2);
    CHECK_EQ(s.out_len, 0);
}

static void test_setup_module(void)
{
    cf_gf_setup_t s;
    char why[CF_TEXT_MAX] = "";
    CHECK(cf_gf_setup_module(&cf, 1, &s, why, sizeof why));
    /* the run's standard and global octets, then the module's own two */
    CHECK_BYTES(s.prm, s.prm_len, 0x88, 0x01, 0x14, 0x0B, 0x12, 0x34, 0x00, 0xA1, 0x05, 0xB1,
                0xB2);
    CHECK_BYTES(s.cfg, s.cfg_len, 0x23);
    CHECK_EQ(s.in_len, 0);
    CHECK_EQ(s.out_len, 4);
    CHECK_STR(s.name, "module \"4 out 2 prm\"");
    CHECK(cf_gf_setup_module(&cf, 0, &s, why, sizeof why));
    CHECK_EQ(s.prm_len, 9);
    CHECK_EQ(s.in_len, 2);
    /* a run whose Set_Prm is shorter than the standard and global octets cannot be cut */
    cf.prm_len = 8;
    CHECK(!cf_gf_setup_module(&cf, 1, &s, why, sizeof why));
    CHECK_STR(why, "module \"4 out 2 prm\": its Set_Prm does not fit into 244 octets");
    cf.prm_len = 9;
}

static void test_in_data_exch(void)
{
    static const uint8_t ready[] = {0x00, 0x0C, 0x00, 0x01, 0x12, 0x34};
    static const uint8_t wait_prm[] = {0x02, 0x05, 0x00, 0xFF, 0x12, 0x34};
    static const uint8_t cfg_fault[] = {0x04, 0x0C, 0x00, 0x01, 0x12, 0x34};
    static const uint8_t prm_fault[] = {0x40, 0x0C, 0x00, 0x01, 0x12, 0x34};
    CHECK(cf_gf_in_data_exch(ready, sizeof ready));
    CHECK(!cf_gf_in_data_exch(ready, 5));
    CHECK(!cf_gf_in_data_exch(wait_prm, sizeof wait_prm));
    CHECK(!cf_gf_in_data_exch(cfg_fault, sizeof cfg_fault));
    CHECK(!cf_gf_in_data_exch(prm_fault, sizeof prm_fault));
}

static void test_ack(void)
{
    cf_reply_t r;
    memset(&r, 0, sizeof r);
    r.octets[0] = 0xE5;
    r.len = 1;
    CHECK(cf_gf_ack(&r));
    static const uint8_t nr[] = {0x10, 0x01, 0x04, 0x09, 0x0E, 0x16};
    static const uint8_t rs[] = {0x10, 0x01, 0x04, 0x03, 0x08, 0x16};
    memcpy(r.octets, nr, sizeof nr);
    r.len = sizeof nr;
    CHECK(cf_gf_ack(&r));
    memcpy(r.octets, rs, sizeof rs);
    CHECK(!cf_gf_ack(&r));
    r.len = 0;
    CHECK(!cf_gf_ack(&r));
}

static void test_hex(void)
{
    static const uint8_t o[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x81, 0x6D};
    char buf[64];
    CHECK_STR(cf_gf_hex(o, sizeof o, buf, sizeof buf), "68 05 05 68 84 81 6D");
    CHECK_STR(cf_gf_hex(o, sizeof o, buf, 16), "68 05 05 68 ...");
    CHECK_STR(cf_gf_hex(o, 0, buf, sizeof buf), "");
}

int main(void)
{
    load();
    RUN_TEST(test_fc_octets);
    RUN_TEST(test_setup_default);
    RUN_TEST(test_setup_module);
    RUN_TEST(test_in_data_exch);
    RUN_TEST(test_ack);
    RUN_TEST(test_hex);
    return check_report();
}
