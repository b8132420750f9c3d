/* movidrive_names.h: finding parameters by P-number, index and name; value texts and parsing;
 * fault, unit status, control and status word texts; and that the name table agrees with the
 * emulation's parameter table (one row per index, the same indices). */
#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "movidrive/movidrive_names.h"
#include "movidrive/movidrive.h"

static char err[256];

static const char *find_p(const char *text)
{
    const movidrive_param_info_t *p = movidrive_param_find(text, err, sizeof err);
    return p != NULL ? p->p_number : NULL;
}

static void test_find(void)
{
    const movidrive_param_info_t *p = movidrive_param_find("P100", err, sizeof err);
    CHECK(p != NULL);
    CHECK_EQ(p->index, 8461);
    CHECK_STR(p->name, "setpoint source");
    CHECK_STR(p->unit, "");
    CHECK_EQ(p->scale_exp, 0);
    CHECK_EQ(p->num_enums, 11);
    CHECK(!p->read_only && p->non_volatile && p->inhibit_required);
    CHECK(movidrive_param_info(8461) == p);
    CHECK_STR(find_p("p100"), "P100");
    CHECK_STR(find_p(" 8461 "), "P100");
    CHECK_STR(find_p("0x210D"), "P100");
    CHECK_STR(find_p("setpoint source"), "P100");
    CHECK_STR(find_p("SETPOINT SOURCE"), "P100");
    /* an alias P-number resolves to its index's row */
    CHECK_STR(find_p("P600"), "P031");
    CHECK_STR(find_p("P080.speed"), "P080.Speed");
    /* exact name wins over substrings ("speed" is in many names) */
    CHECK_STR(find_p("speed"), "P000");
    CHECK_STR(find_p("fieldbus timeout delay"), "P819");
    CHECK(movidrive_param_find("fieldbus timeout", err, sizeof err) == NULL); /* P819 and P831 */
    CHECK_STR(err, "'fieldbus timeout' matches 2 parameters: P819 fieldbus timeout delay, "
                   "P831 response FIELDBUS TIMEOUT");
    /* a unique substring */
    CHECK_STR(find_p("baud rate (kbaud"), "P816");
    CHECK_STR(find_p("firmware basic"), "P076");
    p = movidrive_param_find("ramp t11 up cw", err, sizeof err);
    CHECK(p != NULL && p->index == 8470);
    CHECK_STR(p->unit, "ms");
    CHECK_EQ(p->scale_exp, 0);
    p = movidrive_param_info(8318);
    CHECK_STR(p->p_number, "P000");
    CHECK_STR(p->unit, "rpm");
    CHECK_EQ(p->scale_exp, -3);
    CHECK(p->read_only);
}

static void test_find_errors(void)
{
    CHECK(movidrive_param_find("P999", err, sizeof err) == NULL);
    CHECK_STR(err, "no parameter 'P999'");
    CHECK(movidrive_param_find("1", err, sizeof err) == NULL);
    CHECK_STR(err, "no parameter with index 1");
    CHECK(movidrive_param_find("70000", err, sizeof err) == NULL);
    CHECK_STR(err, "index 70000 is out of 0..65535");
    CHECK(movidrive_param_find("frobnicator", err, sizeof err) == NULL);
    CHECK_STR(err, "no parameter 'frobnicator'");
    CHECK(movidrive_param_find("", err, sizeof err) == NULL);
    CHECK_STR(err, "no parameter given (P-number, index or name)");
    CHECK(movidrive_param_find(NULL, NULL, 0) == NULL);
    CHECK(movidrive_param_find("H12", err, sizeof err) == NULL);
    CHECK_STR(err, "'H12' is IPOS variable H12 (index 11012), not a table parameter");
    CHECK(movidrive_param_info(11012) == NULL);
    /* ambiguous: at most five listed, in P-number order */
    CHECK(movidrive_param_find("internal setpoint", err, sizeof err) == NULL);
    CHECK_STR(err, "'internal setpoint' matches 6 parameters: P160 internal setpoint n11, "
                   "P161 internal setpoint n12, P162 internal setpoint n13, P170 internal "
                   "setpoint n22, P171 internal setpoint n22, ...");
    CHECK(movidrive_param_find("delay time", err, sizeof err) == NULL);
    CHECK(strncmp(err, "'delay time' matches 5 parameters: P402 delay time, P412 delay time",
                  66) == 0);
    /* a short buffer is cut, never overrun */
    char small[12];
    memset(small, 'x', sizeof small);
    CHECK(movidrive_param_find("P999", small, sizeof small) == NULL);
    CHECK_STR(small, "no paramete");
}

static void test_value_text(void)
{
    char out[64];
    const movidrive_param_info_t *p100 = movidrive_param_info(8461);
    CHECK_EQ(movidrive_value_text(p100, 3, out, sizeof out), 12);
    CHECK_STR(out, "3 (FIELDBUS)");
    CHECK_STR(movidrive_enum_text(p100, 3), "FIELDBUS");
    CHECK(movidrive_enum_text(p100, 11) == NULL);
    movidrive_value_text(p100, 11, out, sizeof out);
    CHECK_STR(out, "11 (unknown value)");
    movidrive_value_text(movidrive_param_info(8318), 300000, out, sizeof out);
    CHECK_STR(out, "300.000 rpm");
    movidrive_value_text(movidrive_param_info(8318), -1500, out, sizeof out);
    CHECK_STR(out, "-1.500 rpm");
    movidrive_value_text(movidrive_param_info(8470), 2000, out, sizeof out);
    CHECK_STR(out, "2000 ms");
    movidrive_value_text(movidrive_param_info(8454), 12, out, sizeof out);
    CHECK_STR(out, "12"); /* P093 fieldbus address */
    movidrive_value_text(movidrive_param_info(8300), 823947913, out, sizeof out);
    CHECK_STR(out, "823947913");
    /* P092 is compared unsigned by the drive: shown unsigned */
    movidrive_value_text(movidrive_param_info(8453), -1, out, sizeof out);
    CHECK_STR(out, "4294967.295 kBaud");
    movidrive_value_text(movidrive_param_info(8330), 3, out, sizeof out);
    CHECK_STR(out, "300000 Ws"); /* P017 1 digit = 10^5 Ws */
    movidrive_value_text(movidrive_param_info(8327), 35, out, sizeof out);
    CHECK_STR(out, "35 \302\260C");
    movidrive_value_text(NULL, -7, out, sizeof out);
    CHECK_STR(out, "-7");
    /* P830..P836: value 6 is named (the list printed 7 twice) */
    CHECK_STR(movidrive_enum_text(movidrive_param_info(8610), 6), "EMERG. STOP/WARNG");
    CHECK_STR(movidrive_enum_text(movidrive_param_info(8610), 7), "RAPID STOP/WARNG");
    /* snprintf-like: the length it would have, output cut */
    char small[6];
    CHECK_EQ(movidrive_value_text(movidrive_param_info(8318), 300000, small, sizeof small), 11);
    CHECK_STR(small, "300.0");
    CHECK_EQ(movidrive_value_text(movidrive_param_info(8318), 300000, NULL, 0), 11);
}

static void test_value_parse(void)
{
    int32_t raw = 0;
    const movidrive_param_info_t *p100 = movidrive_param_info(8461);
    CHECK(movidrive_value_parse(p100, "FIELDBUS", &raw, err, sizeof err));
    CHECK_EQ(raw, 3);
    CHECK(movidrive_value_parse(p100, "fieldbus", &raw, err, sizeof err));
    CHECK_EQ(raw, 3);
    CHECK(movidrive_value_parse(p100, "10", &raw, err, sizeof err));
    CHECK_EQ(raw, 10);
    CHECK(movidrive_value_parse(p100, "0x10", &raw, err, sizeof err));
    CHECK_EQ(raw, 16);
    CHECK(!movidrive_value_parse(p100, "BUS", &raw, err, sizeof err));
    CHECK_STR(err, "'BUS' is not a value of P100 setpoint source: BIPOL./FIX.SETPT, "
                   "UNIPOL/FIX.SETPT, RS-485, FIELDBUS, MOTOR POT, ... or a number");
    const movidrive_param_info_t *p000 = movidrive_param_info(8318);
    CHECK(movidrive_value_parse(p000, "300.5", &raw, err, sizeof err));
    CHECK_EQ(raw, 300500);
    CHECK(movidrive_value_parse(p000, "-0.25", &raw, err, sizeof err));
    CHECK_EQ(raw, -250);
    CHECK(movidrive_value_parse(p000, "300 rpm", &raw, err, sizeof err));
    CHECK_EQ(raw, 300000);
    CHECK(movidrive_value_parse(p000, "300", &raw, err, sizeof err)); /* integers are raw */
    CHECK_EQ(raw, 300);
    CHECK(movidrive_value_parse(p000, "-5", &raw, err, sizeof err));
    CHECK_EQ(raw, -5);
    /* trailing zeros are fine */
    CHECK(movidrive_value_parse(p000, "1.2340", &raw, err, sizeof err));
    CHECK_EQ(raw, 1234);
    CHECK(!movidrive_value_parse(p000, "1.2345", &raw, err, sizeof err));
    CHECK_STR(err, "'1.2345' has more than 3 decimals for rpm");
    CHECK(!movidrive_value_parse(p000, "fast", &raw, err, sizeof err));
    CHECK_STR(err, "'fast' is not a number for P000 speed (raw integer, or rpm with up to 3 "
                   "decimals)");
    CHECK(!movidrive_value_parse(p000, "300 ms", &raw, err, sizeof err));
    CHECK(!movidrive_value_parse(p000, "3000000.000", &raw, err, sizeof err));
    CHECK_STR(err, "'3000000.000' is out of the 32-bit range");
    CHECK(!movidrive_value_parse(p000, "99999999999", &raw, err, sizeof err));
    CHECK_STR(err, "'99999999999' is out of the 32-bit range");
    CHECK(!movidrive_value_parse(p000, "", &raw, err, sizeof err));
    CHECK_STR(err, "no value given");
    const movidrive_param_info_t *p130 = movidrive_param_info(8470);
    CHECK(movidrive_value_parse(p130, "2000 ms", &raw, err, sizeof err));
    CHECK_EQ(raw, 2000);
    CHECK(!movidrive_value_parse(p130, "1.5", &raw, err, sizeof err));
    CHECK_STR(err, "'1.5' has more than 0 decimals for ms");
    CHECK(!movidrive_value_parse(movidrive_param_info(8454), "12abc", &raw, err, sizeof err));
    CHECK_STR(err, "'12abc' is not a number for P093 fieldbus address (decimal, -N or 0xHEX)");
    /* raw integers up to 2^32 - 1 keep their bit pattern (unsigned parameters) */
    CHECK(movidrive_value_parse(movidrive_param_info(8453), "4294967295", &raw, err, sizeof err));
    CHECK_EQ(raw, -1);
    CHECK(movidrive_value_parse(NULL, "0x1234", &raw, err, sizeof err));
    CHECK_EQ(raw, 0x1234);
    CHECK(!movidrive_value_parse(NULL, "x12", &raw, err, sizeof err));
    CHECK_STR(err, "'x12' is not a number (decimal, -N or 0xHEX)");
}

static void test_words(void)
{
    char out[160];
    CHECK_STR(movidrive_fault_name(28), "fieldbus timeout");
    CHECK_STR(movidrive_fault_name(0), "no fault");
    CHECK(movidrive_fault_name(200) == NULL);
    CHECK_STR(movidrive_unit_status_name(MOVIDRIVE_UNIT_ENABLED), "enabled");
    CHECK_STR(movidrive_unit_status_name(MOVIDRIVE_UNIT_WAITING_FOR_DATA), "waiting for data");
    CHECK(movidrive_unit_status_name(99) == NULL);
    CHECK_EQ(movidrive_control_word_text(0x0006, out, sizeof out), 37);
    CHECK_STR(out, "0006 = enable, no rapid stop, no stop");
    movidrive_control_word_text(0x0000, out, sizeof out);
    CHECK_STR(out, "0000 = enable, rapid stop, stop");
    movidrive_control_word_text(0x0041, out, sizeof out);
    CHECK_STR(out, "0041 = controller inhibit, rapid stop, stop, fault reset");
    movidrive_control_word_text(0x1016, out, sizeof out);
    CHECK_STR(out, "1016 = enable, no rapid stop, no stop, ramp set 2, high byte 0x10");
    movidrive_status_word_text(0x0407, out, sizeof out);
    CHECK_STR(out, "0407 = output stage enabled, ready, PO data enabled, unit status 4 (enabled)");
    movidrive_status_word_text(0x0000, out, sizeof out);
    CHECK_STR(out, "0000 = output stage inhibited, not ready, PO data disabled, unit status 0 "
                   "(24 V operation)");
    movidrive_status_word_text(0x1C24, out, sizeof out);
    CHECK_STR(out, "1C24 = output stage inhibited, not ready, PO data enabled, fault 28 "
                   "(fieldbus timeout)");
    movidrive_status_word_text(0x6326, out, sizeof out);
    CHECK_STR(out, "6326 = output stage inhibited, ready, PO data enabled, fault 99 (unknown)");
    movidrive_status_word_text(0x0905, out, sizeof out);
    CHECK_STR(out, "0905 = output stage enabled, not ready, PO data enabled, unit status 9 "
                   "(unknown)");
    char small[8];
    CHECK_EQ(movidrive_status_word_text(0x0407, small, sizeof small), 76);
    CHECK_STR(small, "0407 = ");
}

/* Every entry of the emulation's table has exactly one name row, sorted by P-number. */
static void test_table(void)
{
    movidrive_t md;
    movidrive_cfg_t cfg = {.eeprom = {0}, .sbus_address = 0, .terminal_enable = true};
    CHECK_EQ(movidrive_init(&md, &cfg, err, sizeof err), 0);
    CHECK_EQ(movidrive_param_count(), md.num_defs);
    CHECK_EQ(movidrive_param_count(), 353);
    size_t found = 0;
    for (size_t k = 0; k < md.num_defs; k++) {
        const movidrive_param_info_t *p = movidrive_param_info(md.defs[k].index);
        found += p != NULL && p->index == md.defs[k].index ? 1u : 0u;
        if (p != NULL) {
            CHECK_EQ(p->read_only, (md.defs[k].flags & MOVIDRIVE_PF_READ_ONLY) != 0u);
        }
    }
    CHECK_EQ(found, md.num_defs);
    CHECK_STR(movidrive_param_at(0)->p_number, "P000");
    CHECK(movidrive_param_at(movidrive_param_count()) == NULL);
    for (size_t i = 1; i < movidrive_param_count(); i++) {
        if (strncmp(movidrive_param_at(i - 1)->p_number, movidrive_param_at(i)->p_number, 4) > 0) {
            CHECK(!"movidrive_param_at is not sorted by P-number");
        }
    }
}

int main(void)
{
    RUN_TEST(test_find);
    RUN_TEST(test_find_errors);
    RUN_TEST(test_value_text);
    RUN_TEST(test_value_parse);
    RUN_TEST(test_words);
    RUN_TEST(test_table);
    return check_report();
}
