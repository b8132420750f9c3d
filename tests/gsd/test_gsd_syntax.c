/* The GSD syntax (sim_host/gsd/README.md): keywords in any case, comments (not inside quotes),
 * continuation lines, numbers, modules with their parameters and reference numbers, PrmText,
 * ExtUserPrmData with Bit / BitArea / Unsigned16 and the default octets they give, keywords
 * ignored; and every kind of bad file with its exact error and line, limits included.
 *
 * usage: test_gsd_syntax BAD_DIR (tests/gsd/bad: the same errors read from files) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gsd/gsd.h"
#include "gsd_base.h"

static gsd_t g;
static char err[GSD_ERR_LEN + 512];
static const char *bad_dir;

static int parse_str(const char *text)
{
    return gsd_parse_text(text, strlen(text), &g, err, sizeof err);
}

/* base followed by extra. */
static int parse_base(const char *extra)
{
    static char text[1 << 16];
    (void)snprintf(text, sizeof text, "%s%s", base, extra);
    return parse_str(text);
}

static void test_case_comments_continuation(void)
{
    const char *text =
        "; a comment before the header\n"
        "#PROFIBUS_DP\r\n"
        "gsd_revision = 3\r\n"
        "VENDOR_NAME = \"ACME; Inc\"   ; a ';' in quotes is no comment\n"
        "Ident_Number=0X00ab\n"
        "ident_NUMBER = 0x00AB ; repeated: noted, the later value kept\n"
        "9.6_SUPP = 1\n"
        "maxtsdr_9.6 = 60\n"
        "Module = \"long\" 0x10, \\\n"
        "  0x20,\\\n"
        "  0x30\n"
        "ENDMODULE\n"
        "Info_Text = \"not kept\"\n"
        "\t\n";
    CHECK_EQ(parse_str(text), 0);
    uint32_t v = 0;
    CHECK(gsd_key(&g, GSD_K_IDENT_NUMBER, &v) && v == 0xABu);
    CHECK_EQ(g.key_line[GSD_K_IDENT_NUMBER], 6);
    CHECK_STR(gsd_text(&g, GSD_S_VENDOR_NAME), "ACME; Inc");
    CHECK_EQ(gsd_max_tsdr_bits(&g, 9600), 60);
    CHECK_EQ(g.header_line, 2);
    CHECK_EQ(g.n_modules, 1);
    CHECK_BYTES(gsd_module_cfg(&g, 0), g.modules[0].cfg_len, 0x10, 0x20, 0x30);
    CHECK_EQ(g.modules[0].line, 9);
    CHECK_EQ(g.modules[0].end_line, 12);
    CHECK_EQ(g.n_notes, 2);
    CHECK_EQ(g.notes[0].kind, GSD_NOTE_REPEATED);
    CHECK_EQ(g.notes[0].line, 6);
    CHECK_EQ(g.notes[0].first_line, 5);
    CHECK_EQ(g.notes[1].kind, GSD_NOTE_IGNORED);
    CHECK_EQ(g.notes[1].line, 13);
    CHECK_STR(g.notes[1].keyword, "Info_Text");
    CHECK_EQ(g.lines, 14);
}

/* A UTF-8 byte order mark before the first line is no text before the header. */
static void test_byte_order_mark(void)
{
    CHECK_EQ(parse_str("\xEF\xBB\xBF#Profibus_DP\nIdent_Number = 7\n"), 0);
    CHECK_EQ(g.key[GSD_K_IDENT_NUMBER], 7);
    CHECK_EQ(parse_str("#Profibus_DP\n\xEF\xBB\xBFIdent_Number = 7\n"), -1);
    CHECK_STR(err, "line 2: expected a keyword, found '\xEF\xBB\xBFIdent_Number = 7'");
}

/* Anything after another #section is not DP's and is not read. */
static void test_other_section(void)
{
    CHECK_EQ(parse_base("#Profibus_PA\nIdent_Number = 0x99999\nModule = \"x\"\n"), 0);
    CHECK_EQ(g.key[GSD_K_IDENT_NUMBER], 0x1234);
    CHECK_EQ(g.n_modules, 1);
}

static const char prm_text[] =
    "User_Prm_Data_Len = 5\n"              /* 22 */
    "Ext_User_Prm_Data_Const(0) = 0x11, \\\n"
    "    0x22\n"
    "Ext_User_Prm_Data_Ref(2) = 10\n"      /* 25 */
    "Ext_User_Prm_Data_Ref(2) = 11\n"
    "Ext_User_Prm_Data_Ref(3) = 12\n"
    "PrmText = 7\n"                        /* 28 */
    "Text(0) = \"off\"\n"
    "Text(3) = \"fast\"\n"
    "EndPrmText\n"
    "ExtUserPrmData = 10 \"low bit\"\n"    /* 32 */
    "Bit(0) 1 0-1\n"
    "EndExtUserPrmData\n"
    "ExtUserPrmData = 11 \"area\"\n"       /* 35 */
    "BitArea(4-6) 3 0,1,3,5\n"
    "Prm_Text_Ref = 7\n"
    "Changeable = 0\n"
    "EndExtUserPrmData\n"
    "ExtUserPrmData = 12 \"word\"\n"       /* 40 */
    "unsigned16 0x1234 0-40000\n"
    "EndExtUserPrmData\n"
    "ExtUserPrmData = 13 \"signed\"\n"     /* 43 */
    "Signed8 -2 -5--1\n"
    "EndExtUserPrmData\n"
    "Module = \"with prm\" 0x20\n"         /* 46 */
    "7\n"
    "Ext_Module_Prm_Data_Len = 3\n"
    "Ext_User_Prm_Data_Const(0) = 0xAA\n"
    "Ext_User_Prm_Data_Ref(1) = 10\n"
    "Ext_User_Prm_Data_Ref(2) = 13\n"
    "Preset = 1\n"
    "EndModule\n";

static void test_user_prm(void)
{
    CHECK_EQ(parse_base(prm_text), 0);
    CHECK_EQ(g.n_defs, 4);
    const gsd_prm_def_t *d = gsd_find_def(&g, 11);
    CHECK(d != NULL);
    if (d == NULL) return;
    CHECK_EQ(d->type, GSD_T_BIT_AREA);
    CHECK_EQ(d->bit_first, 4);
    CHECK_EQ(d->bit_last, 6);
    CHECK_EQ(d->def, 3);
    CHECK_EQ(d->value_count, 4);
    CHECK_EQ(g.values[d->value_first + 3], 5);
    CHECK_EQ(d->min, 0);
    CHECK_EQ(d->max, 5);
    CHECK_EQ(d->text_ref, 7);
    CHECK(!d->changeable);
    CHECK(d->visible);
    CHECK_EQ(d->line, 35);
    CHECK_EQ(d->type_line, 36);
    CHECK_STR(gsd_prm_text(&g, 7, 3), "fast");
    d = gsd_find_def(&g, 13);
    CHECK(d != NULL && d->min == -5 && d->max == -1 && d->def == -2);
    const gsd_module_t *m = &g.modules[1];
    CHECK(m->has_reference && m->reference == 7u);
    CHECK(m->preset);
    CHECK_EQ(m->ext_prm_len, 3);
    uint8_t prm[GSD_MAX_USER_PRM];
    /* 11 22, then bit 0 = 1 and bits 4-6 = 3 in octet 2, then 0x1234 big-endian */
    int len = gsd_default_prm(&g, NULL, 0, prm, sizeof prm);
    CHECK_BYTES(prm, len, 0x11, 0x22, 0x31, 0x12, 0x34);
    /* the module's part follows: AA, its bit 0, then -2 as Signed8 */
    const size_t mods[] = {1, 0, 1};
    len = gsd_default_prm(&g, mods, 3, prm, sizeof prm);
    CHECK_BYTES(prm, len, 0x11, 0x22, 0x31, 0x12, 0x34, 0xAA, 0x01, 0xFE, 0xAA, 0x01, 0xFE);
    gsd_problem_t p[4];
    CHECK_EQ(gsd_check(&g, p, 4), 0);
}

static void test_prm_put(void)
{
    gsd_prm_def_t d = {.type = GSD_T_BIT_AREA, .bit_first = 2, .bit_last = 4};
    uint8_t image[4] = {0xFF, 0x00, 0x00, 0x00};
    CHECK(gsd_prm_put(&d, 0x5, image, sizeof image, 0)); /* 101 into bits 2-4 of 0xFF */
    CHECK_EQ(image[0], 0xF7);
    d.type = GSD_T_UNSIGNED32;
    CHECK(gsd_prm_put(&d, 0x01020304, image, sizeof image, 0));
    CHECK_BYTES(image, 4, 0x01, 0x02, 0x03, 0x04);
    CHECK(!gsd_prm_put(&d, 1, image, sizeof image, 1)); /* does not fit */
    d.type = GSD_T_SIGNED16;
    CHECK(gsd_prm_put(&d, -2, image, sizeof image, 2));
    CHECK_BYTES(image, 4, 0x01, 0x02, 0xFF, 0xFE);
}

typedef struct bad_case {
    const char *extra; /* after base */
    const char *error;
} bad_case_t;

static const bad_case_t bad_cases[] = {
    {"Module = \"open\" 0x10\n", "line 22: Module without EndModule"},
    {"Module = \"a\" 0x10\nModule = \"b\" 0x10\nEndModule\n",
     "line 23: Module inside the Module of line 22 (no EndModule before it)"},
    {"EndModule\n", "line 22: EndModule without Module"},
    {"Ext_User_Prm_Data_Const(0) = 0x01,\\\n", "line 22: a continuation line ('\\') at the end "
                                               "of the file"},
    {"Max_Diag_Data_Len = 256\n", "line 22: Max_Diag_Data_Len: 256 is out of range 0..255"},
    {"MaxTsdr_12M = 70000\n", "line 22: MaxTsdr_12M: 70000 is out of range 0..65535"},
    {"Fail_Safe = 2\n", "line 22: Fail_Safe: 2 is out of range 0..1"},
    {"Ident_Number = 99999999999999999999\n",
     "line 22: Ident_Number: 1099511627776 is out of range 0..65535"},
    {"Ident_Number = 12ab\n", "line 22: Ident_Number: expected a number, found '12ab'"},
    {"Ident_Number 5\n", "line 22: Ident_Number needs '= value'"},
    {"Module = \"x\" 0x10,0x100\nEndModule\n", "line 22: Module: 256 is out of range 0..255"},
    {"Module = \"x\"\nEndModule\n", "line 22: Module: expected a number, found ''"},
    {"Module = x 0x10\n", "line 22: Module: expected a \"string\", found 'x 0x10'"},
    {"Vendor_Name = \"open\n", "line 22: Vendor_Name: a string without its closing '\"'"},
    {"Vendor_Name = \"V\" 5\n", "line 22: Vendor_Name: unexpected '5' after the value"},
    {"= 5\n", "line 22: expected a keyword, found '= 5'"},
    {"5\n", "line 22: a number where a keyword belongs ('5')"},
    {"#Profibus_DP\n", "line 22: a second #Profibus_DP (the first is on line 1)"},
    {"ExtUserPrmData = 1 \"x\"\nEndExtUserPrmData\n",
     "line 22: ExtUserPrmData 1 has no data type line (Bit, BitArea, Unsigned8 ...)"},
    {"ExtUserPrmData = 1 \"x\"\nBit(8) 0 0-1\nEndExtUserPrmData\n",
     "line 23: Bit: 8 is out of range 0..7"},
    {"ExtUserPrmData = 1 \"x\"\nBitArea(5-3) 0 0-1\nEndExtUserPrmData\n",
     "line 23: BitArea(5-3): not first-last with first <= last <= 7"},
    {"ExtUserPrmData = 1 \"x\"\nBitArea(0-2) 9 0-7\nEndExtUserPrmData\n",
     "line 23: BitArea: 9 is out of range 0..7"},
    {"ExtUserPrmData = 1 \"x\"\nUnsigned8 300 0-255\nEndExtUserPrmData\n",
     "line 23: Unsigned8: 300 is out of range 0..255"},
    {"ExtUserPrmData = 1 \"x\"\nUnsigned8 3\nEndExtUserPrmData\n",
     "line 23: Unsigned8: a default needs its allowed values after it"},
    {"ExtUserPrmData = 1 \"x\"\nUnsigned8 1 0-1\nUnsigned8 1 0-1\n",
     "line 24: a second data type in the ExtUserPrmData of line 22"},
    {"ExtUserPrmData = 1 \"x\"\nUnsigned8 1 0-1\n",
     "line 22: ExtUserPrmData without EndExtUserPrmData"},
    {"PrmText = 1\nText(0) = \"a\"\nModule = \"m\" 0x10\n",
     "line 24: Module inside the PrmText of line 22 (no EndPrmText before it)"},
    {"Ext_User_Prm_Data_Const(237) = 0x00\n",
     "line 22: Ext_User_Prm_Data_Const: 237 is out of range 0..236"},
    {"Ext_User_Prm_Data_Const(230) = 0,0,0,0,0,0,0,0\n",
     "line 22: Ext_User_Prm_Data_Const(230) reaches past the 237 octets of the user "
     "parameters"},
    {"Ext_User_Prm_Data_Ref = 3\n", "line 22: Ext_User_Prm_Data_Ref needs '(number)'"},
    {"Ext_User_Prm_Data_Ref(1 2) = 3\n",
     "line 22: Ext_User_Prm_Data_Ref: '(1 2)' is not one number"},
    {"Module = \"m\" 0x10\n1\n2\nEndModule\n",
     "line 24: a second module reference in the Module of line 22"},
};

static void test_bad_texts(void)
{
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        CHECK_EQ(parse_base(bad_cases[i].extra), -1);
        CHECK_STR(err, bad_cases[i].error);
    }
    CHECK_EQ(parse_str("GSD_Revision = 1\n#Profibus_DP\n"), -1);
    CHECK_STR(err, "line 1: 'GSD_Revision = 1' before the #Profibus_DP line");
    CHECK_EQ(parse_str("; only a comment\n"), -1);
    CHECK_STR(err, "no #Profibus_DP line");
    static const char nul[] = "#Profibus_DP\nA = \"\0\"\n";
    CHECK_EQ(gsd_parse_text(nul, sizeof nul - 1u, &g, err, sizeof err), -1);
    CHECK_STR(err, "line 2: a NUL character: not a text file");
    /* a short error buffer gets the start of the message, NUL-terminated */
    char small[8];
    CHECK_EQ(gsd_parse_text("x\n", 2, &g, small, sizeof small), -1);
    CHECK_STR(small, "line 1:");
}

/* Each limit of gsd.h is an error on the line that goes past it, not a crash. */
static void test_limits(void)
{
    static char text[1 << 20];
    size_t n = (size_t)snprintf(text, sizeof text, "%s", base); /* has one module */
    for (unsigned i = 1; i < GSD_MAX_MODULES; i++) {
        n += (size_t)snprintf(text + n, sizeof text - n, "Module = \"m%u\" 0x10\nEndModule\n", i);
    }
    CHECK_EQ(parse_str(text), 0);
    CHECK_EQ(g.n_modules, GSD_MAX_MODULES);
    (void)snprintf(text + n, sizeof text - n, "Module = \"one too many\" 0x10\nEndModule\n");
    CHECK_EQ(parse_str(text), -1);
    CHECK_STR(err, "line 532: more than 256 modules (GSD_MAX_MODULES)");

    char s[GSD_MAX_STRING + 40];
    memset(s, 'x', sizeof s);
    (void)snprintf(s, sizeof s, "Vendor_Name = \"%0*d\"\n", GSD_MAX_STRING + 1, 0);
    CHECK_EQ(parse_base(s), -1);
    CHECK_STR(err, "line 22: a string longer than 255 characters");

    n = (size_t)snprintf(text, sizeof text, "%sA = ", base);
    memset(text + n, '1', GSD_MAX_LINE);
    text[n + GSD_MAX_LINE] = '\0';
    CHECK_EQ(parse_str(text), -1);
    CHECK_STR(err, "line 22: longer than 4096 characters");

    n = (size_t)snprintf(text, sizeof text, "%s", base);
    for (unsigned i = 0; i < 3000; i++) {
        n += (size_t)snprintf(text + n, sizeof text - n, "X = 1,\\\n");
    }
    (void)snprintf(text + n, sizeof text - n, "1\n");
    CHECK_EQ(parse_str(text), -1);
    CHECK_STR(err, "line 22: longer than 4096 characters (with its continuation lines)");

    n = (size_t)snprintf(text, sizeof text, "%sPrmText = 1\n", base);
    for (unsigned i = 0; i <= GSD_MAX_TEXTS; i++) {
        n += (size_t)snprintf(text + n, sizeof text - n, "Text(%u) = \"t\"\n", i);
    }
    CHECK_EQ(parse_str(text), -1);
    CHECK_STR(err, "line 4119: more than 4096 Text lines (GSD_MAX_TEXTS)");
}

static void test_files(void)
{
    static const struct {
        const char *file;
        const char *error; /* after "DIR/file:" */
    } cases[] = {
        {"unterminated_module.gsd", "6: Module inside the Module of line 5 (no EndModule "
                                    "before it)"},
        {"continuation_eof.gsd", "4: a continuation line ('\\') at the end of the file"},
        {"out_of_range.gsd", "3: Ident_Number: 65536 is out of range 0..65535"},
        {"no_such_file.gsd", " No such file or directory"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[512], want[1024];
        (void)snprintf(path, sizeof path, "%s/%s", bad_dir, cases[i].file);
        (void)snprintf(want, sizeof want, "%s:%s", path, cases[i].error);
        CHECK_EQ(gsd_parse_file(path, &g, err, sizeof err), -1);
        CHECK_STR(err, want);
    }
    char want[1024];
    (void)snprintf(want, sizeof want, "%s: cannot read: Is a directory", bad_dir);
    CHECK_EQ(gsd_parse_file(bad_dir, &g, err, sizeof err), -1);
    CHECK_STR(err, want);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_gsd_syntax BAD_DIR\n");
        return 2;
    }
    bad_dir = argv[1];
    RUN_TEST(test_case_comments_continuation);
    RUN_TEST(test_byte_order_mark);
    RUN_TEST(test_other_section);
    RUN_TEST(test_user_prm);
    RUN_TEST(test_prm_put);
    RUN_TEST(test_bad_texts);
    RUN_TEST(test_limits);
    RUN_TEST(test_files);
    return check_report();
}
