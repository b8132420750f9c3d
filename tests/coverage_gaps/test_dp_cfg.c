/* dp_cfg_io_lengths (dp_slave/dp_cfg.h): the I/O lengths of a Chk_Cfg configuration in the
 * general and the special identifier format (protocol.md §A3.3). The card's own Chk_Cfg tests
 * only use the general format; masters size Data_Exchange with this function for any slave.
 *
 * General identifier: b7 consistency, b6 word units, b5-4 01 in / 10 out / 11 in+out,
 * b3-0 length-1. Special identifier (b5-4 = 00): b7-6 00 free place, 01 one input-length octet
 * follows, 10 one output-length octet, 11 output- then input-length octet; b3-0 manufacturer
 * octets after the length octets (0 none, 1..14, 15 none). Length octet: b7 consistency, b6 word
 * units, b5-0 length-1 (1..64 units). At most 244 octets each way. */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "check.h"
#include "dp_slave/dp_cfg.h"

static uint16_t out_len;
static uint16_t in_len;


static bool lengths(const uint8_t *cfg, size_t len)
{
    out_len = 0xEEEEu;
    in_len = 0xEEEEu;
    return dp_cfg_io_lengths(cfg, len, &out_len, &in_len);
}

#define CFG_OK(out, in, ...)                                                                   \
    do {                                                                                       \
        const uint8_t c_[] = {__VA_ARGS__};                                                    \
        CHECK(lengths(c_, sizeof c_));                                                         \
        CHECK_EQ(out_len, out);                                                                \
        CHECK_EQ(in_len, in);                                                                  \
    } while (0)

#define CFG_REFUSED(...)                                                                       \
    do {                                                                                       \
        const uint8_t c_[] = {__VA_ARGS__};                                                    \
        CHECK(!lengths(c_, sizeof c_));                                                        \
        CHECK_EQ(out_len, 0xEEEEu);                                                            \
        CHECK_EQ(in_len, 0xEEEEu);                                                             \
    } while (0)

static void test_general_format(void)
{
    CHECK(lengths(NULL, 0));
    CHECK_EQ(out_len, 0);
    CHECK_EQ(in_len, 0);
    CFG_OK(1, 0, 0x20);             /* 1 output byte */
    CFG_OK(0, 1, 0x10);             /* 1 input byte */
    CFG_OK(0, 2, 0x50);             /* 1 input word */
    CFG_OK(16, 16, 0x3F);           /* 16 bytes in and out */
    CFG_OK(32, 32, 0xFF);           /* 16 words in and out, consistent */
    CFG_OK(14, 14, 0xF3, 0xF2);     /* DFP21B: parameter channel + 3 PD */
    CFG_OK(12, 12, 0x00, 0xF5);     /* DFP21B 6 PD: free place, then 6 words */
    CFG_OK(2, 5, 0x21, 0x14);       /* outputs and inputs from different modules */
}

static void test_special_format(void)
{
    CFG_OK(0, 0, 0x00);                   /* free place only */
    CFG_OK(0, 4, 0x40, 0x41);             /* input length octet: 2 words */
    CFG_OK(6, 0, 0x80, 0x05);             /* output length octet: 6 bytes */
    CFG_OK(4, 64, 0xC0, 0xC1, 0x3F);      /* output 2 words, input 64 bytes */
    CFG_OK(128, 0, 0x80, 0x7F);           /* 64 words, the largest length octet */
    CFG_OK(0, 8, 0x42, 0x07, 0xAA, 0xBB); /* two manufacturer octets are skipped */
    CFG_OK(0, 9, 0x42, 0x07, 0xAA, 0xBB, 0x10); /* ... and the next identifier follows */
    CFG_OK(0, 2, 0x4F, 0x00, 0x10);       /* 15: no manufacturer octets */
    CFG_OK(2, 0, 0x0E, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 0x20, 0x20); /* 14 octets */
    CFG_OK(3, 1, 0x80, 0x00, 0x40, 0x00, 0x80, 0x01); /* mixed special identifiers */
    CFG_OK(8, 8, 0xC0, 0xC3, 0xC3);       /* the DFP21B parameter channel in special form */
}

static void test_special_format_truncated(void)
{
    CFG_REFUSED(0x40);                   /* input length octet missing */
    CFG_REFUSED(0x80);                   /* output length octet missing */
    CFG_REFUSED(0xC0, 0x01);             /* input length octet of 11 missing */
    CFG_REFUSED(0xC0);                   /* both missing */
    CFG_REFUSED(0x03, 0xAA, 0xBB);       /* 3 manufacturer octets announced, 2 present */
    CFG_REFUSED(0x41, 0x00);             /* 1 manufacturer octet missing after the length */
    CFG_REFUSED(0x20, 0x0E, 1, 2, 3);    /* 14 announced at the end */
}

static void test_limit_244(void)
{
    CFG_OK(244, 0, 0x80, 0x7F, 0x80, 0x79);          /* 128 + 116 */
    CFG_REFUSED(0x80, 0x7F, 0x80, 0x7A);             /* 128 + 118 */
    CFG_OK(0, 244, 0x40, 0x7F, 0x40, 0x79);
    CFG_REFUSED(0x40, 0x7F, 0x40, 0x7A);
    CFG_OK(244, 244, 0xC0, 0x7F, 0x7F, 0xC0, 0x79, 0x79);
    /* General identifiers add up too: 15 x 16 words = 480 bytes. */
    uint8_t many[15];
    for (size_t i = 0; i < sizeof many; i++) {
        many[i] = 0x7F; /* 16 words in and out */
    }
    CHECK(!lengths(many, sizeof many));
    CHECK(lengths(many, 7));   /* 224 */
    CHECK_EQ(out_len, 224);
    CHECK_EQ(in_len, 224);
    CHECK(!lengths(many, 8));  /* 256 */
}

int main(void)
{
    RUN_TEST(test_general_format);
    RUN_TEST(test_special_format);
    RUN_TEST(test_special_format_truncated);
    RUN_TEST(test_limit_244);
    return check_report();
}
