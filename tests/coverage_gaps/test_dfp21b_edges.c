/* The DFP21B's own Chk_Cfg and Set_Prm rules (protocol.md §B3, §B4) through the public checks,
 * every refusal the card tests do not reach: universal modules with separate output and input
 * identifiers, wrong directions and lengths, DPV1_Status bits the card does not support, the
 * structured block and its flag; and the P090 text cut to short buffers. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "dfp21b/dfp21b.h"

static dfp21b_pd_cfg_t pd;

static bool cfg(const uint8_t *c, size_t n)
{
    memset(&pd, 0xEE, sizeof pd);
    return dfp21b_check_cfg(c, n, &pd);
}

#define CFG_OK(words, param, ...)                                                              \
    do {                                                                                       \
        const uint8_t c_[] = {__VA_ARGS__};                                                    \
        CHECK(cfg(c_, sizeof c_));                                                             \
        CHECK(pd.valid);                                                                       \
        CHECK_EQ(pd.pd_words, words);                                                          \
        CHECK_EQ(pd.param_channel, param);                                                     \
    } while (0)

#define CFG_REFUSED(...)                                                                       \
    do {                                                                                       \
        const uint8_t c_[] = {__VA_ARGS__};                                                    \
        CHECK(!cfg(c_, sizeof c_));                                                            \
        CHECK(!pd.valid);                                                                      \
    } while (0)

static void test_cfg_predefined(void)
{
    CFG_OK(1, false, 0xF0);
    CFG_OK(2, false, 0xF1);
    CFG_OK(3, false, 0xF2);
    CFG_OK(6, false, 0x00, 0xF5);
    CFG_OK(10, false, 0x00, 0xF9);
    CFG_OK(1, true, 0xF3, 0xF0);
    CFG_OK(2, true, 0xF3, 0xF1);
    CFG_OK(3, true, 0xF3, 0xF2);
    CFG_OK(6, true, 0xF3, 0xF5);
    CFG_OK(10, true, 0xF3, 0xF9);
}

static void test_cfg_universal(void)
{
    /* 4, 5, 7, 8, 9 words besides the predefined ones. */
    CFG_OK(4, true, 0xF3, 0xF3);
    CFG_OK(5, false, 0x00, 0xF4);
    CFG_OK(7, true, 0xF3, 0xF6);
    CFG_OK(8, false, 0x00, 0xF7);
    CFG_OK(9, true, 0xF3, 0xF8);
    /* Process data as an output and an input identifier (either order). */
    CFG_OK(3, false, 0xE2, 0xD2);
    CFG_OK(3, false, 0xD2, 0xE2);
    CFG_OK(3, true, 0xF3, 0xE2, 0xD2);
    CFG_OK(10, false, 0x00, 0xE9, 0xD9);
    /* Byte units: 6 bytes = 3 words; the parameter channel as 8 consistent bytes. */
    CFG_OK(3, false, 0xB5);
    CFG_OK(3, true, 0xB7, 0xF2);
    CFG_OK(2, true, 0xB7, 0xA3, 0x93);
}

static void test_cfg_refused(void)
{
    CHECK(!cfg(NULL, 0));
    CHECK(!cfg(NULL, 2));
    const uint8_t f2 = 0xF2;
    CHECK(!cfg(&f2, 0));
    CFG_REFUSED(0xF3, 0xE2, 0xD2, 0x00);   /* four identifiers */
    CFG_REFUSED(0xE2, 0xD2, 0x00);         /* three without module 0 */
    CFG_REFUSED(0x00);                     /* no process data */
    CFG_REFUSED(0xF3, 0x00);
    CFG_REFUSED(0xE2, 0xE2);               /* two outputs */
    CFG_REFUSED(0xD2, 0xD2);               /* two inputs */
    CFG_REFUSED(0xF2, 0xD2);               /* in+out next to another identifier */
    CFG_REFUSED(0xE2);                     /* outputs only */
    CFG_REFUSED(0xD2);                     /* inputs only */
    CFG_REFUSED(0xE2, 0xD1);               /* unequal lengths: "0PD" */
    CFG_REFUSED(0x72);                     /* not consistent over the whole length */
    CFG_REFUSED(0xF3, 0x62, 0x52);
    CFG_REFUSED(0xB2);                     /* 3 bytes: not whole words */
    CFG_REFUSED(0xF3, 0xFA);               /* 11 words */
    CFG_REFUSED(0xFF);                     /* 16 words */
    CFG_REFUSED(0x40, 0xC1);               /* special identifier format */
    CFG_REFUSED(0xC0, 0xC2, 0xC2);
}

static bool alarm;

static bool prm(const uint8_t *p, size_t n)
{
    alarm = false;
    return dfp21b_check_user_prm(p, n, &alarm);
}

#define PRM_OK(diag_alarm, ...)                                                                \
    do {                                                                                       \
        const uint8_t p_[] = {__VA_ARGS__};                                                    \
        CHECK(prm(p_, sizeof p_));                                                             \
        CHECK_EQ(alarm, diag_alarm);                                                           \
    } while (0)

#define PRM_REFUSED(...)                                                                       \
    do {                                                                                       \
        const uint8_t p_[] = {__VA_ARGS__};                                                    \
        CHECK(!prm(p_, sizeof p_));                                                            \
    } while (0)

static void test_user_prm(void)
{
    PRM_OK(false, 0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01); /* factory */
    PRM_OK(true, 0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00);  /* alarm on */
    /* DPV1_Status_1: DPV1_Enable, WD_Base_1ms, Dis_Stop/Start_Control are fine ... */
    PRM_OK(false, 0x80, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_OK(false, 0x87, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    /* ... Fail_Safe, Publisher_Enable and the reserved bits are not. */
    PRM_REFUSED(0xC0, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0xA0, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x88, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    /* DPV1_Status_2: no alarm type may be enabled, no user Check_Cfg mode. */
    PRM_REFUSED(0x80, 0x20, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x80, 0x04, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x80, 0x01, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    /* DPV1_Status_3: Prm_Structure and Alarm_Mode pass, PrmCmd and IsoM_Req do not. */
    PRM_OK(false, 0x80, 0x00, 0x0F, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x80, 0x00, 0x80, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x80, 0x00, 0x10, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01);
    /* The structured block and its flag. */
    PRM_REFUSED(0x00, 0x00, 0x00, 0x05, 0x81, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x82, 0x00, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x01, 0x00, 0x01, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x01, 0x01, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x02, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x02);
    /* Length: exactly 9 octets. */
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01);
    PRM_REFUSED(0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01, 0x00);
    CHECK(!prm(NULL, 0));
}

static void test_p090_text(void)
{
    char out[32];
    dfp21b_pd_cfg_t p = {.valid = true, .param_channel = true, .pd_words = 3};
    CHECK_EQ(dfp21b_p090_text(&p, out, sizeof out), 11);
    CHECK_STR(out, "3PD + PARAM");
    p = (dfp21b_pd_cfg_t){.valid = true, .param_channel = false, .pd_words = 10};
    CHECK_EQ(dfp21b_p090_text(&p, out, sizeof out), 4);
    CHECK_STR(out, "10PD");
    p = (dfp21b_pd_cfg_t){.valid = false};
    CHECK_EQ(dfp21b_p090_text(&p, out, sizeof out), 3);
    CHECK_STR(out, "0PD");
    /* Cut to the buffer, always terminated; nothing written without room. */
    p = (dfp21b_pd_cfg_t){.valid = true, .param_channel = true, .pd_words = 6};
    CHECK_EQ(dfp21b_p090_text(&p, out, 4), 3);
    CHECK_STR(out, "6PD");
    CHECK_EQ(dfp21b_p090_text(&p, out, 1), 0);
    CHECK_STR(out, "");
    out[0] = 'x';
    CHECK_EQ(dfp21b_p090_text(&p, out, 0), 0);
    CHECK_EQ(out[0], 'x');
}

int main(void)
{
    RUN_TEST(test_cfg_predefined);
    RUN_TEST(test_cfg_universal);
    RUN_TEST(test_cfg_refused);
    RUN_TEST(test_user_prm);
    RUN_TEST(test_p090_text);
    return check_report();
}
