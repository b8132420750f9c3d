/* The consistency check (gsd_check): each rule broken on its own in an otherwise consistent
 * file, with the problem's code, line and text; the count when the output array is short. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gsd/gsd.h"
#include "gsd_base.h"

static gsd_t g;
static gsd_problem_t p[16];
static size_t n;

static bool parse(const char *extra)
{
    static char text[1 << 14];
    char err[GSD_ERR_LEN];
    (void)snprintf(text, sizeof text, "%s%s", base, extra);
    if (gsd_parse_text(text, strlen(text), &g, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        CHECK(false);
        return false;
    }
    n = gsd_check(&g, p, 16);
    return true;
}

/* The problem (code, line, text) is among those found. */
static void has(gsd_problem_code_t code, uint32_t line, const char *text)
{
    for (size_t i = 0; i < n && i < 16u; i++) {
        if (p[i].code == code && p[i].line == line && strcmp(p[i].text, text) == 0) {
            CHECK(true);
            return;
        }
    }
    fprintf(stderr, "missing: %u line %u: %s; found:\n", (unsigned)code, (unsigned)line, text);
    for (size_t i = 0; i < n && i < 16u; i++) {
        fprintf(stderr, "  %u line %u: %s\n", (unsigned)p[i].code, (unsigned)p[i].line,
                p[i].text);
    }
    CHECK(false);
}

/* extra gives exactly this one problem. */
static void only(const char *extra, gsd_problem_code_t code, uint32_t line, const char *text)
{
    if (!parse(extra)) return;
    CHECK_EQ(n, 1);
    has(code, line, text);
}

static void test_consistent(void)
{
    if (!parse("")) return;
    CHECK_EQ(n, 0);
}

static void test_rates(void)
{
    only("1.5M_supp = 1\n", GSD_P_RATE, 22, "1.5M_supp = 1 without MaxTsdr_1.5M");
    only("9.6_supp = 1\nMaxTsdr_9.6 = 10\n", GSD_P_RATE, 23,
         "MaxTsdr_9.6 = 10 is below the least TSDR (11)");
    /* a MaxTsdr for a rate not claimed is no problem, and gives no figure */
    if (parse("3M_supp = 0\nMaxTsdr_3M = 200\n")) {
        CHECK_EQ(n, 0);
        CHECK_EQ(gsd_max_tsdr_bits(&g, 3000000), 0);
    }
}

static void test_modules(void)
{
    only("Module = \"big\" 0x1F\nEndModule\n", GSD_P_MODULE, 22,
         "module \"big\": 16 input octets, Max_Input_Len is 8");
    only("Module = \"bad\" 0x40\nEndModule\n", GSD_P_MODULE, 22,
         "module \"bad\": its identifiers are malformed (a length or manufacturer octet "
         "missing, or over 244 octets of data)");
    if (parse("Max_Data_Len = 10\nModule = \"both\" 0x35\nEndModule\n")) {
        CHECK_EQ(n, 2);
        has(GSD_P_MODULE, 23, "module \"both\": 12 data octets, Max_Data_Len is 10");
        has(GSD_P_REPEATED, 22, "Max_Data_Len repeated (first on line 19)");
    }
    if (parse("Modular_Station = 0\nModule = \"b\" 0x10\nEndModule\n")) {
        CHECK_EQ(n, 2);
        has(GSD_P_MODULES, 22, "a compact station (Modular_Station absent or 0) needs exactly "
                               "one Module, there are 2");
        has(GSD_P_REPEATED, 22, "Modular_Station repeated (first on line 15)");
    }
}

static void test_prm_lengths(void)
{
    only("User_Prm_Data_Len = 2\nExt_User_Prm_Data_Const(0) = 1,2,3\n", GSD_P_PRM_LEN, 23,
         "Ext_User_Prm_Data_Const(0) with 3 octets reaches past User_Prm_Data_Len = 2");
    /* without User_Prm_Data_Len the octets defined give the length */
    if (parse("Ext_User_Prm_Data_Const(3) = 1\n")) {
        CHECK_EQ(n, 0);
        CHECK_EQ(gsd_part_len(&g, GSD_GLOBAL), 4);
    }
    only("User_Prm_Data_Len = 1\nExt_User_Prm_Data_Ref(0) = 5\nExtUserPrmData = 5 \"w\"\n"
         "Unsigned16 0 0-9\nEndExtUserPrmData\n", GSD_P_PRM_LEN, 23,
         "Ext_User_Prm_Data_Ref(0) (2 octets) reaches past User_Prm_Data_Len = 1");
    only("User_Prm_Data_Len = 4\nMax_User_Prm_Data_Len = 3\n", GSD_P_PRM_LEN, 22,
         "User_Prm_Data_Len = 4 is more than Max_User_Prm_Data_Len = 3");
    only("Module = \"p\" 0x10\nExt_User_Prm_Data_Const(0) = 1\nEndModule\n", GSD_P_PRM_LEN, 22,
         "module \"p\" defines parameter octets without Ext_Module_Prm_Data_Len");
    only("Module = \"q\" 0x10\nExt_Module_Prm_Data_Len = 1\nExt_User_Prm_Data_Const(0) = 1,2\n"
         "EndModule\n", GSD_P_PRM_LEN, 24, "Ext_User_Prm_Data_Const(0) with 2 octets reaches "
         "past module \"q\" Ext_Module_Prm_Data_Len = 1");
}

static void test_prm_defs(void)
{
    only("User_Prm_Data_Len = 1\nExt_User_Prm_Data_Ref(0) = 5\nExtUserPrmData = 5 \"x\"\n"
         "Unsigned8 9 0-5\nEndExtUserPrmData\n", GSD_P_PRM_DEFAULT, 25,
         "ExtUserPrmData 5: default 9 is not one of its allowed values");
    only("ExtUserPrmData = 5 \"x\"\nBitArea(0-2) 4 0,1,2\nEndExtUserPrmData\n",
         GSD_P_PRM_DEFAULT, 23, "ExtUserPrmData 5: default 4 is not one of its allowed values");
    only("ExtUserPrmData = 5 \"x\"\nUnsigned8 1 5-2\nEndExtUserPrmData\n", GSD_P_PRM_DEFAULT, 23,
         "ExtUserPrmData 5: range 5-2 is empty");
    only("User_Prm_Data_Len = 1\nExt_User_Prm_Data_Ref(0) = 9\n", GSD_P_PRM_REF, 23,
         "Ext_User_Prm_Data_Ref(0) = 9: no ExtUserPrmData 9");
    only("ExtUserPrmData = 5 \"x\"\nBit(1) 0 0-1\nPrm_Text_Ref = 3\nEndExtUserPrmData\n",
         GSD_P_PRM_REF, 22, "ExtUserPrmData 5: Prm_Text_Ref = 3, no PrmText 3");
    only("ExtUserPrmData = 5 \"x\"\nBit(1) 0 0-1\nEndExtUserPrmData\n"
         "ExtUserPrmData = 5 \"y\"\nBit(2) 0 0-1\nEndExtUserPrmData\n", GSD_P_PRM_REF, 25,
         "ExtUserPrmData 5 is defined twice (first on line 22)");
    only("User_Prm_Data_Len = 1\nExt_User_Prm_Data_Ref(0) = 1\nExt_User_Prm_Data_Ref(0) = 2\n"
         "ExtUserPrmData = 1 \"a\"\nBitArea(0-3) 0 0-15\nEndExtUserPrmData\n"
         "ExtUserPrmData = 2 \"b\"\nBitArea(2-5) 0 0-15\nEndExtUserPrmData\n", GSD_P_PRM_REF, 24,
         "Ext_User_Prm_Data_Ref(0) = 2 overlaps the bits of another Ref");
    /* the same bits in two modules' parts do not overlap */
    if (parse("ExtUserPrmData = 1 \"a\"\nBit(0) 0 0-1\nEndExtUserPrmData\n"
              "Module = \"m1\" 0x10\nExt_Module_Prm_Data_Len = 1\nExt_User_Prm_Data_Ref(0) = 1\n"
              "EndModule\nModule = \"m2\" 0x10\nExt_Module_Prm_Data_Len = 1\n"
              "Ext_User_Prm_Data_Ref(0) = 1\nEndModule\n")) {
        CHECK_EQ(n, 0);
    }
}

static void test_dpv1(void)
{
    only("C1_Read_Write_supp = 1\n", GSD_P_DPV1, 22, "C1_Read_Write_supp without DPV1_Slave = 1");
    only("DPV1_Slave = 0\nWD_Base_1ms_supp = 1\n", GSD_P_DPV1, 23,
         "WD_Base_1ms_supp without DPV1_Slave = 1");
    only("DPV1_Slave = 1\n", GSD_P_PRM_LEN, 22, "DPV1_Slave = 1 needs at least 3 octets of user "
         "parameters (DPV1_Status_1..3), there are 0");
    if (parse("DPV1_Slave = 1\nUser_Prm_Data_Len = 3\nC2_Read_Write_supp = 1\n")) {
        CHECK_EQ(n, 4);
        has(GSD_P_DPV1, 24, "C2_Read_Write_supp = 1 without C2_Max_Data_Len");
        has(GSD_P_DPV1, 24, "C2_Read_Write_supp = 1 without C2_Response_Timeout");
        has(GSD_P_DPV1, 24, "C2_Read_Write_supp = 1 without C2_Max_Count_Channels");
        has(GSD_P_DPV1, 24, "C2_Read_Write_supp = 1 without Max_Initiate_PDU_Length");
    }
    if (parse("GSD_Revision = 2\nDPV1_Slave = 1\nUser_Prm_Data_Len = 3\n")) {
        CHECK_EQ(n, 2);
        has(GSD_P_DPV1, 23, "DPV1_Slave = 1 needs GSD_Revision 3 or later (it is 2)");
        has(GSD_P_REPEATED, 22, "GSD_Revision repeated (first on line 2)");
    }
}

static void test_missing_and_limits(void)
{
    if (parse("Max_Diag_Data_Len = 245\n")) {
        CHECK_EQ(n, 2);
        has(GSD_P_LIMIT, 22, "Max_Diag_Data_Len = 245 is outside 6..244");
        has(GSD_P_REPEATED, 22, "Max_Diag_Data_Len repeated (first on line 12)");
    }
    const char *text = "#Profibus_DP\nModule = \"m\" 0x10\nEndModule\n";
    char err[GSD_ERR_LEN];
    CHECK_EQ(gsd_parse_text(text, strlen(text), &g, err, sizeof err), 0);
    n = gsd_check(&g, p, 16);
    CHECK_EQ(n, 12); /* 6 keys, 5 strings, no rate */
    has(GSD_P_MISSING, 0, "Ident_Number is missing");
    has(GSD_P_MISSING, 0, "Software_Release is missing");
    has(GSD_P_RATE, 0, "no rate is supported (every <rate>_supp absent or 0)");
    /* a short array: the count stays whole */
    CHECK_EQ(gsd_check(&g, p, 2), 12);
    CHECK_EQ(gsd_check(&g, NULL, 0), 12);
}

int main(void)
{
    RUN_TEST(test_consistent);
    RUN_TEST(test_rates);
    RUN_TEST(test_modules);
    RUN_TEST(test_prm_lengths);
    RUN_TEST(test_prm_defs);
    RUN_TEST(test_dpv1);
    RUN_TEST(test_missing_and_limits);
    return check_report();
}
