/* Text captures: every accepted line shape gives exact octets, time and direction; bad lines are
 * reported with a reason naming what is wrong; dfp-sim's export reads back exactly; the telegram
 * check names each kind of damage. Lines are handed over in heap buffers of exactly their length
 * (no NUL), so a read past the end shows under ASan. */
#include <stdlib.h>

#include "capture/record.h"
#include "capture/text_import.h"
#include "check.h"

static text_import_state_t st;
static cap_record_t rec;

static text_line_result_t import_n(const char *text, size_t n)
{
    char *copy = malloc(n > 0u ? n : 1u);
    if (copy == NULL) {
        abort();
    }
    memcpy(copy, text, n);
    text_line_result_t r = text_import_line(&st, copy, n, &rec);
    free(copy);
    return r;
}

static text_line_result_t import(const char *line)
{
    return import_n(line, strlen(line));
}

/* A line that must give a valid telegram with no time and an unknown direction. */
#define CHECK_PLAIN(line, ...)                                                                 \
    do {                                                                                       \
        CHECK_EQ(import(line), TEXT_LINE_RECORD);                                              \
        CHECK_BYTES(rec.data, rec.len, __VA_ARGS__);                                           \
        CHECK_EQ(rec.orig_len, rec.len);                                                       \
        CHECK(!rec.has_time);                                                                  \
        CHECK_EQ(rec.dir, CAP_DIR_UNKNOWN);                                                    \
        CHECK_STR(rec.problem, "");                                                            \
    } while (0)

#define CHECK_BAD(line, reason)                                                                \
    do {                                                                                       \
        CHECK_EQ(import(line), TEXT_LINE_BAD);                                                 \
        CHECK_STR(rec.problem, reason);                                                        \
        CHECK_EQ(rec.len, 0);                                                                  \
    } while (0)

static void test_plain_hex_separators(void)
{
    text_import_init(&st);
    CHECK_PLAIN("68 05 05 68 84 02 5D 00 00 E3 16", 0x68, 0x05, 0x05, 0x68, 0x84, 0x02, 0x5D,
                0x00, 0x00, 0xE3, 0x16);
    CHECK_PLAIN("6805056884025D0000E316", 0x68, 0x05, 0x05, 0x68, 0x84, 0x02, 0x5D, 0x00, 0x00,
                0xE3, 0x16);
    CHECK_PLAIN("0x68,0x05,0x05,0x68,0x84,0x02,0x5D,0x00,0x00,0xE3,0x16", 0x68, 0x05, 0x05, 0x68,
                0x84, 0x02, 0x5D, 0x00, 0x00, 0xE3, 0x16);
    CHECK_PLAIN("0x68, 0x5, 0x5, 0x68, 0x84, 0x2, 0x5d, 0x0, 0x0, 0xe3, 0x16", 0x68, 0x05, 0x05,
                0x68, 0x84, 0x02, 0x5D, 0x00, 0x00, 0xE3, 0x16);
    CHECK_PLAIN("68:05:05:68:84:02:5D:00:00:E3:16", 0x68, 0x05, 0x05, 0x68, 0x84, 0x02, 0x5D,
                0x00, 0x00, 0xE3, 0x16);
    CHECK_PLAIN("  \t10 04 02\t49 4f 16  \r", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_PLAIN("10 04 02 49 4F 16   # FDL status request", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_PLAIN("10 04 02 49 4F 16 // to station 4", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_PLAIN("E5", 0xE5);
    CHECK_PLAIN("DC 02 01", 0xDC, 0x02, 0x01);
    /* Lowercase SD3 starting "a2": hex, not a ProSoft timestamp. */
    CHECK_PLAIN("a2 82 84 08 3e 3c 02 05 00 ff 60 03 f1 16", 0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16);
    /* "10:02:01" alone is three octets (a time needs something after it). */
    CHECK_EQ(import("10:02:01"), TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x02, 0x01);
    CHECK(!rec.has_time);
    CHECK_STR(rec.problem, "truncated SD1: 3 of 6 octets");
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_HEX);
    CHECK_EQ(st.line, 12);
    CHECK_EQ(rec.position, 12);
}

static void check_timed(const char *line, uint64_t t_ns, cap_dir_t dir)
{
    CHECK_EQ(import(line), TEXT_LINE_RECORD);
    CHECK(rec.has_time);
    CHECK_EQ(rec.t_ns, t_ns);
    CHECK_EQ(rec.dir, dir);
}

static void test_time_and_direction(void)
{
    text_import_init(&st);
    check_timed("0.001234 TX 10 84 02 49 CF 16", 1234000u, CAP_DIR_TX);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x84, 0x02, 0x49, 0xCF, 0x16);
    CHECK_STR(rec.problem, "");
    check_timed("[12.345678] < E5", 12345678000u, CAP_DIR_RX);
    CHECK_BYTES(rec.data, rec.len, 0xE5);
    check_timed("[    3.250000] E5", 3250000000u, CAP_DIR_UNKNOWN);
    check_timed("12:34:56.789012 RX E5", 45296789012000u, CAP_DIR_RX);
    check_timed("12:34:56 rx E5", 45296000000000u, CAP_DIR_RX);
    check_timed("23:59:59.999999999 E5", 86399999999999u, CAP_DIR_UNKNOWN);
    check_timed("1700000000.123456789 -> E5", 1700000000123456789u, CAP_DIR_TX);
    check_timed("0.5s <- E5", 500000000u, CAP_DIR_RX);
    check_timed("7s M> 10 04 02 49 4F 16", 7000000000u, CAP_DIR_TX);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    check_timed("8.0 S< E5", 8000000000u, CAP_DIR_RX);
    check_timed("9.000000001 > E5", 9000000001u, CAP_DIR_TX);
    check_timed("10.1 TX: E5", 10100000000u, CAP_DIR_TX);
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_HEX);
    CHECK(st.seen_time);
    CHECK_EQ(st.last_t_ns, 10100000000u);

    /* Direction without a time. */
    CHECK_EQ(import("TX 10 04 02 49 4F 16"), TEXT_LINE_RECORD);
    CHECK(!rec.has_time);
    CHECK_EQ(rec.dir, CAP_DIR_TX);
    CHECK_EQ(import("< E5"), TEXT_LINE_RECORD);
    CHECK_EQ(rec.dir, CAP_DIR_RX);

    /* A time earlier than the one before is kept as written. */
    check_timed("5.0 E5", 5000000000u, CAP_DIR_UNKNOWN);
    CHECK_STR(rec.problem, "");
    CHECK_EQ(st.last_t_ns, 5000000000u);
}

static void test_export_line_text_and_limits(void)
{
    const uint8_t frame[] = {0x10, 0x02, 0x01, 0x49, 0x4C, 0x16};
    char out[128];
    size_t n = text_export_line(out, sizeof out, 12000000001u, CAP_DIR_TX, frame, sizeof frame);
    CHECK_STR(out, "12.000000001 TX 10 02 01 49 4C 16");
    CHECK_EQ(n, strlen("12.000000001 TX 10 02 01 49 4C 16"));
    n = text_export_line(out, sizeof out, 5u, CAP_DIR_RX, frame, 1);
    CHECK_STR(out, "0.000000005 RX 10");
    n = text_export_line(out, sizeof out, 0u, CAP_DIR_UNKNOWN, frame, 1);
    CHECK_STR(out, "0.000000000 -- 10");
    /* Exactly fitting, one short, and nothing at all. */
    CHECK_EQ(text_export_line(out, 18, 0u, CAP_DIR_UNKNOWN, frame, 1), 17);
    CHECK_EQ(text_export_line(out, 17, 0u, CAP_DIR_UNKNOWN, frame, 1), 0);
    CHECK_STR(out, "");
    CHECK_EQ(text_export_line(out, 0, 0u, CAP_DIR_TX, frame, 1), 0);
    CHECK_EQ(text_export_line(out, sizeof out, 0u, CAP_DIR_TX, NULL, 1), 0);

    text_import_init(&st);
    check_timed("12.000000001 TX 10 02 01 49 4C 16", 12000000001u, CAP_DIR_TX);
    check_timed("0.000000000 -- 10 02 01 49 4C 16", 0u, CAP_DIR_UNKNOWN);
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_EXPORT);
}

static uint64_t prng_state = 0x9E3779B97F4A7C15u;

static uint64_t prng(void)
{
    prng_state ^= prng_state << 13;
    prng_state ^= prng_state >> 7;
    prng_state ^= prng_state << 17;
    return prng_state;
}

static void test_export_round_trip(void)
{
    text_import_init(&st);
    int exact = 0;
    const int rounds = 2000;
    for (int i = 0; i < rounds; i++) {
        uint8_t frame[CAP_MAX_RECORD];
        size_t len = 1u + (size_t)(prng() % (i % 10 == 0 ? CAP_MAX_RECORD : 256u));
        for (size_t k = 0; k < len; k++) {
            frame[k] = (uint8_t)prng();
        }
        /* Times up to 10^10 s, the import's limit; every fifth one small. */
        uint64_t t = prng() % (i % 5 == 0 ? 1000000000u : 10000000000u * 1000000000u);
        cap_dir_t dir = (cap_dir_t)(prng() % 3u);
        char line[TEXT_IMPORT_MAX_LINE];
        size_t n = text_export_line(line, sizeof line, t, dir, frame, len);
        if (n == 0u || import_n(line, n) != TEXT_LINE_RECORD) {
            continue;
        }
        if (rec.has_time && rec.t_ns == t && rec.dir == dir && rec.len == len &&
            rec.orig_len == len && memcmp(rec.data, frame, len) == 0) {
            exact++;
        }
    }
    CHECK_EQ(exact, rounds);
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_EXPORT);
    CHECK_EQ(st.line, (uint64_t)rounds);
}

static void test_pyprofibus_phy(void)
{
    text_import_init(&st);
    CHECK_EQ(import("PHY-serial: TX   10 02 01 49 4C 16"), TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x02, 0x01, 0x49, 0x4C, 0x16);
    CHECK_EQ(rec.dir, CAP_DIR_TX);
    CHECK(!rec.has_time);
    CHECK_STR(rec.problem, "");
    CHECK_EQ(import("PHY-serial: RX   E5"), TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0xE5);
    CHECK_EQ(rec.dir, CAP_DIR_RX);
    CHECK_EQ(import("PHY-fpga: RX   10 01 02 00 03 16"), TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x01, 0x02, 0x00, 0x03, 0x16);
    CHECK_EQ(import("PHY: TX   DC 02 01"), TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0xDC, 0x02, 0x01);
    /* A time in front, as `ts` or a logger adds it. */
    CHECK_EQ(import("10:00:00.5 PHY-serial: RX   E5"), TEXT_LINE_RECORD);
    CHECK(rec.has_time);
    CHECK_EQ(rec.t_ns, 36000500000000u);
    CHECK_EQ(rec.dir, CAP_DIR_RX);
    CHECK_EQ(import("PHY-serial: RX (fragment)   68 05"), TEXT_LINE_SKIP);
    CHECK_EQ(rec.len, 0);
    CHECK_BAD("PHY-serial: Warning: Baudrate 12000000 is not well supported",
              "pyprofibus message, not a telegram: 'Warning: Baudrate 12...'");
    CHECK_BAD("PHY-serial: TX   10 0", "odd number of hex digits: '0'");
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_PHY);
}

/* The lines below were printed once by pyprofibus 2020's own code (fdl.py, as installed for the
 * interop tests): FdlTelegram.fromRawData(frame) for each frame, repr() of the result, and
 * getRawData() checked to give the frame back. They are pasted here as literals. */
static void test_profisniff_repr(void)
{
    text_import_init(&st);
    CHECK_PLAIN("FdlTelegram(sd=SD1, haveLE=False, da=0x04, sa=0x02, fc=0x49, dae=Empty, "
                "sae=Empty, du=None, haveFCS=True, ed=0x16)",
                0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD1, haveLE=False, da=0x02, sa=0x04, fc=0x00, dae=Empty, "
                "sae=Empty, du=None, haveFCS=True, ed=0x16)",
                0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD2, haveLE=True, da=0x04, sa=0x02, fc=0x6D, dae=3C, sae=3E, "
                "du=Empty, haveFCS=True, ed=0x16)",
                0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD2, haveLE=True, da=0x02, sa=0x04, fc=0x08, dae=3E, sae=3C, "
                "du=02 05 00 FF 60 03, haveFCS=True, ed=0x16)",
                0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF,
                0x60, 0x03, 0xF1, 0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD3, haveLE=False, da=0x02, sa=0x04, fc=0x08, dae=3E, sae=3C, "
                "du=02 05 00 FF 60 03, haveFCS=True, ed=0x16)",
                0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1,
                0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD3, haveLE=False, da=0x04, sa=0x02, fc=0x5D, dae=Empty, "
                "sae=Empty, du=01 02 03 04 05 06 07 08, haveFCS=True, ed=0x16)",
                0xA2, 0x04, 0x02, 0x5D, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x87,
                0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD2, haveLE=True, da=0x7F, sa=0x02, fc=0x46, dae=3A, sae=3E, "
                "du=20 00, haveFCS=True, ed=0x16)",
                0x68, 0x07, 0x07, 0x68, 0xFF, 0x82, 0x46, 0x3A, 0x3E, 0x20, 0x00, 0x5F, 0x16);
    /* Two DAE octets (extension chain) */
    CHECK_PLAIN("FdlTelegram(sd=SD2, haveLE=True, da=0x04, sa=0x02, fc=0x7D, dae=BC 05, "
                "sae=Empty, du=11 22, haveFCS=True, ed=0x16)",
                0x68, 0x07, 0x07, 0x68, 0x84, 0x02, 0x7D, 0xBC, 0x05, 0x11, 0x22, 0xF7, 0x16);
    CHECK_PLAIN("FdlTelegram(sd=SD4, haveLE=False, da=0x02, sa=0x01, fc=None, dae=Empty, "
                "sae=Empty, du=None, haveFCS=False, ed=None)",
                0xDC, 0x02, 0x01);
    CHECK_PLAIN("FdlTelegram(sd=SC, haveLE=False, da=None, sa=None, fc=None, dae=Empty, "
                "sae=Empty, du=None, haveFCS=False, ed=None)",
                0xE5);
    /* pyprofibus accepts LE 3 (no DU at all); the check does not. */
    CHECK_EQ(import("FdlTelegram(sd=SD2, haveLE=True, da=0x02, sa=0x04, fc=0x08, dae=Empty, "
                    "sae=Empty, du=Empty, haveFCS=True, ed=0x16)"),
             TEXT_LINE_RECORD);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x03, 0x03, 0x68, 0x02, 0x04, 0x08, 0x0E, 0x16);
    CHECK_STR(rec.problem, "LE 3 outside 4..249");
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_PROFISNIFF);

    CHECK_BAD("FdlTelegram(sd=SD1, haveLE=False, da=0x04, sa=0x02, fc=0x0100, dae=Empty, "
              "sae=Empty, du=None, haveFCS=True, ed=0x16)",
              "fc=0x0100 is not an octet");
    CHECK_BAD("FdlTelegram(sd=SD1, haveLE=False, da=0x04, sa=0x02, fc=0x49, dae=Empty, "
              "sae=Empty, du=None, haveFCS=True)",
              "FdlTelegram without ed");
    CHECK_BAD("FdlTelegram(sd=SD1, haveLE=False, da=0x04, sa=0x02, fc=0x49, dae=Empty, "
              "sae=Empty, du=None, haveFCS=True, ed=0x16, xx=1)",
              "unknown field 'xx'");
    CHECK_BAD("FdlTelegram(sd=SD1, haveLE=Maybe, da=0x04, sa=0x02, fc=0x49, dae=Empty, "
              "sae=Empty, du=None, haveFCS=True, ed=0x16)",
              "haveLE is not True or False: 'Maybe'");
    CHECK_BAD("FdlTelegram(sd=SD2, haveLE=True, da=0x04, sa=0x02, fc=0x49, dae=Empty, "
              "sae=Empty, du=0G, haveFCS=True, ed=0x16)",
              "not hex: '0G'");
    CHECK_BAD("FdlTelegram(sd=SD1, haveLE=False", "FdlTelegram(...) without its ')'");
}

static void check_prosoft(const char *line, uint64_t t_ns)
{
    CHECK_EQ(import(line), TEXT_LINE_RECORD);
    CHECK(rec.has_time);
    CHECK_EQ(rec.t_ns, t_ns);
    CHECK_EQ(rec.dir, CAP_DIR_UNKNOWN);
}

/* Lines from the ProSoft AN-X-PB manual (AN-X-PBCAPT chapter, pages 21-30), and variants. */
static void test_prosoft(void)
{
    text_import_init(&st);
    check_prosoft("46: a 3.040,029 g 0,027 g.................. |........SD2 120<0 SRDH 8a 8a 8a "
                  "8a 8a",
                  3040029000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x08, 0x08, 0x68, 0x78, 0x00, 0x4D, 0x8A, 0x8A, 0x8A,
                0x8A, 0x8A, 0x77, 0x16);
    CHECK_STR(rec.problem, "");
    check_prosoft("2: a11.000,517 ........ 54<0 SRDH 00", 11000517000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x36, 0x00, 0x4D, 0x00, 0x83, 0x16);
    /* With ShowFcs: the written FCS equals the one rebuilt. */
    check_prosoft("3: a11.000,540 0<54 DL 00 [3e]", 11000540000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x00, 0x36, 0x08, 0x00, 0x3E, 0x16);
    CHECK_STR(rec.problem, "");
    check_prosoft("146: a11.003,277,602 SD1 107<0 RFDL ED", 11003277602u);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x6B, 0x00, 0x49, 0xB4, 0x16);
    check_prosoft("147: a11.003,291,394 SD1 0<107 OK ED", 11003291394u);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x00, 0x6B, 0x00, 0x6B, 0x16);
    check_prosoft("146: a11.003,277,602 107<0 RFDL", 11003277602u);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x6B, 0x00, 0x49, 0xB4, 0x16);
    check_prosoft("148: a11.003,313,066 SD4 0<0", 11003313066u);
    CHECK_BYTES(rec.data, rec.len, 0xDC, 0x00, 0x00);
    check_prosoft("148: a11.003,313,066 0<0", 11003313066u);
    CHECK_BYTES(rec.data, rec.len, 0xDC, 0x00, 0x00);
    check_prosoft("144: a11.003,225,638 SD2 125<0 SRDH 00 ED", 11003225638u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x7D, 0x00, 0x4D, 0x00, 0xCA, 0x16);
    check_prosoft("205: a 1.016242644 ........ 4<0 SRDH 01 7f 80 ff", 1016242644u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x07, 0x07, 0x68, 0x04, 0x00, 0x4D, 0x01, 0x7F, 0x80,
                0xFF, 0x50, 0x16);
    check_prosoft("205: a 1.016242644 ........ 4<0 SRDH 017f 80ff", 1016242644u); /* Data16 */
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x07, 0x07, 0x68, 0x04, 0x00, 0x4D, 0x01, 0x7F, 0x80,
                0xFF, 0x50, 0x16);
    /* Times in h:mm:ss and mm:ss, delta and gap values, an empty gap graph. */
    check_prosoft("7: a 0:00:01.500,000 d 0.002,975 g 0.001,054 g | 4<2 SRDH 00", 1500000000u);
    check_prosoft("8: a 1:01.000,001 d 5,666 g 2,545 4<2 SRDH 00", 61000001000u);
    check_prosoft("9: a 1:00:00.000 4<2 OK", 3600000000000u);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x04, 0x02, 0x00, 0x06, 0x16);
    /* SAPs (DSAP^ SSAP-): extension bits set, DSAP and SSAP lead the data unit. */
    check_prosoft("10: a 1.000,000 4<2 60^ 62- SRDH", 1000000000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x4D, 0x3C, 0x3E, 0xCD,
                0x16);
    /* SD3 only when the line says so, with 8 data octets. */
    check_prosoft("20: a 2.000 SD3 4<2 SRDH 01 02 03 04 05 06 07 08 ED", 2000000000u);
    CHECK_BYTES(rec.data, rec.len, 0xA2, 0x04, 0x02, 0x4D, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06,
                0x07, 0x08, 0x77, 0x16);
    check_prosoft("20: a 2.000 4<2 SRDH 01 02 03 04 05 06 07 08", 2000000000u);
    CHECK_EQ(rec.data[0], 0x68);
    CHECK_EQ(rec.len, 17);
    CHECK_STR(rec.problem, "");
    check_prosoft("21: a 2.000 SC", 2000000000u);
    CHECK_BYTES(rec.data, rec.len, 0xE5);
    check_prosoft("22: a 2.000 e5", 2000000000u);
    CHECK_BYTES(rec.data, rec.len, 0xE5);
}

/* ShowFcs, the detailed status columns and the '*' of a bad frame. */
static void test_prosoft_fcs_and_status(void)
{
    text_import_init(&st);
    /* ShowFcs restores FCB/FCV: the written FCS is 0x30 above the one with FC 0x4D. */
    check_prosoft("23: a 2.000 4<2 SRDH 00 [83]", 2000000000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x04, 0x02, 0x7D, 0x00, 0x83, 0x16);
    CHECK_STR(rec.problem, "");
    check_prosoft("24: a 2.000 SD2 4<2 SRDH 00 ED [99]", 2000000000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x04, 0x02, 0x4D, 0x00, 0x99, 0x16);
    CHECK_STR(rec.problem, "bad FCS (0x99, computed 0x53)");
    /* Bad status: the frame is rebuilt, the problem says what the analyser saw. */
    check_prosoft("366: a 0.184,865,694 .p..u...SD2 4<0 SRDH 00", 184865694u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x04, 0x00, 0x4D, 0x00, 0x51, 0x16);
    CHECK_STR(rec.problem, "analyser status: parity, underrun");
    check_prosoft("367: a 0.2 s.d....e4<0 SRDH 00", 200000000u);
    CHECK_STR(rec.problem, "analyser status: stop bit, start delimiter, end delimiter");
    check_prosoft("368: a 0.2 spdruoce4<0 SRDH 00", 200000000u); /* cut to the field, no more */
    CHECK_EQ(strlen(rec.problem), sizeof rec.problem - 1u);
    check_prosoft("6: a11.000,621 d 0.000,029 d* * 56<0 SRDH", 11000621000u);
    CHECK_BYTES(rec.data, rec.len, 0x10, 0x38, 0x00, 0x4D, 0x85, 0x16);
    CHECK_STR(rec.problem, "analyser marked the frame bad ('*')");
    /* Without reference number (NoRef) or time. */
    CHECK_EQ(import("4<2 SRDH 00"), TEXT_LINE_RECORD);
    CHECK(!rec.has_time);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x04, 0x04, 0x68, 0x04, 0x02, 0x4D, 0x00, 0x53, 0x16);
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_PROSOFT);
}

static void test_prosoft_bad_lines(void)
{
    text_import_init(&st);
    /* These two manual lines (also in the AN-X-AMX manual) have no PROFIBUS addresses. */
    CHECK_BAD("2: a 0:00:00.002,975 d 0.002,975 g 0.001,054 255< 05^ 1- 0000 0000 0000",
              "destination '255' is not a station address (0..127)");
    CHECK_BAD("357: a 0:00.748,593 *255< 05^ 55- 00 00 00 00 00",
              "destination '255' is not a station address (0..127)");
    CHECK_BAD("9289: a 0:00:19.423,410 d 5,666 g 2,545 ....FrmLen?(1)1e",
              "analyser reports a malformed frame: '....FrmLen?(1)1e'");
    CHECK_BAD("2774: a32.529,859,313 .p..u...SD2 SD2 LE?(46) 68",
              "analyser reports a malformed frame: 'LE?(46)'");
    CHECK_BAD("5: a 1.000 3<2 SRDX 00", "unknown frame control 'SRDX'");
    CHECK_BAD("146: a11.003,277,602 <0 RFDL", "no destination address (written with NoDst?)");
    CHECK_BAD("146: a11.003,277,602 107< RFDL", "no source address (written with NoSrc?)");
    CHECK_BAD("146: a11.003,277,602 RFDL",
              "frame control RFDL without addresses (written with NoDst/NoSrc?)");
    CHECK_BAD("5: a 1.000 3<2 00", "no frame control before '00'");
    CHECK_BAD("5: a 1.000 SD1 3<2 SRDH 00", "SD1 with 1 data octets");
    CHECK_BAD("5: a 1.000 SD3 3<2 SRDH 00", "SD3 with 1 data octets, not 8");
    CHECK_BAD("5: a 1.000 3<2 64^ SRDH", "SAP '64^' outside 0..63");
    CHECK_BAD("5: a 1.000 3<200 SRDH", "source '200' is not a station address (0..127)");
    /* Without the delimiter names "ED" is a data octet. */
    check_prosoft("5: a 1.000 3<2 SRDH 00 ED", 1000000000u);
    CHECK_BYTES(rec.data, rec.len, 0x68, 0x05, 0x05, 0x68, 0x03, 0x02, 0x4D, 0x00, 0xED, 0x3F,
                0x16);
    CHECK_BAD("5: a 1.000 3<2 SRDH 1 127 128 255", "odd number of hex digits: '1'");
    CHECK_BAD("5: a 99999999999.000 3<2 SRDH", "time beyond 10^10 s: '99999999999.000'");
    CHECK_BAD("5: a x", "not a time: 'x'");
}

/* head, then count times " 11", then tail: a data unit of count octets 0x11. */
static const char *line_with_octets(char *buf, size_t max, const char *head, size_t count,
                                    const char *tail)
{
    size_t n = strlen(head);
    CHECK(n + 3u * count + strlen(tail) < max);
    memcpy(buf, head, n);
    for (size_t i = 0; i < count; i++) {
        memcpy(&buf[n], " 11", 3);
        n += 3u;
    }
    memcpy(&buf[n], tail, strlen(tail) + 1u);
    return buf;
}

/* Frame 68 F9 F9 68 DA SA FC, then 246 octets 0x11, the FCS and 16. */
static void check_le_249(uint8_t da, uint8_t sa, uint8_t fc, uint8_t fcs)
{
    CHECK_EQ(rec.len, 255);
    CHECK_EQ(rec.orig_len, 255);
    CHECK_BYTES(rec.data, 7, 0x68, 0xF9, 0xF9, 0x68, da, sa, fc);
    size_t elevens = 0;
    for (size_t i = 7; i < 253; i++) {
        elevens += rec.data[i] == 0x11 ? 1u : 0u;
    }
    CHECK_EQ(elevens, 246);
    CHECK_BYTES(&rec.data[253], 2, fcs, 0x16);
    CHECK_STR(rec.problem, "");
}

/* The encoders stop where the core's FDL_LE_MAX does: LE 249 is the longest telegram rebuilt,
 * a line that would need LE 250 is a bad line. */
static void test_rebuilt_length_limit(void)
{
    char line[1024];
    text_import_init(&st);
    /* ProSoft: DA 3, SA 2, SRDH (0x4D), FCS 03 + 02 + 4D + 246 * 11 = 0xA8. */
    CHECK_EQ(import(line_with_octets(line, sizeof line, "5: a 1.000 3<2 SRDH", 246, "")),
             TEXT_LINE_RECORD);
    check_le_249(0x03, 0x02, 0x4D, 0xA8);
    CHECK_BAD(line_with_octets(line, sizeof line, "5: a 1.000 3<2 SRDH", 247, ""),
              "247 data octets, more than an SD2 holds");
    CHECK_BAD(line_with_octets(line, sizeof line, "5: a 1.000 3<2 60^ 62- SRDH", 245, ""),
              "247 data octets, more than an SD2 holds");

    /* profisniff: DA 4, SA 2, FC 0x5D, FCS 04 + 02 + 5D + 246 * 11 = 0xB9. */
    const char *head = "FdlTelegram(sd=SD2, haveLE=True, da=0x04, sa=0x02, fc=0x5D, dae=Empty, "
                       "sae=Empty, du=";
    const char *tail = ", haveFCS=True, ed=0x16)";
    CHECK_EQ(import(line_with_octets(line, sizeof line, head, 246, tail)), TEXT_LINE_RECORD);
    check_le_249(0x04, 0x02, 0x5D, 0xB9);
    CHECK_BAD(line_with_octets(line, sizeof line, head, 247, tail),
              "LE would be 250, more than 249");
    /* The extension octets count towards LE as well. */
    CHECK_BAD(line_with_octets(line, sizeof line,
                               "FdlTelegram(sd=SD2, haveLE=True, da=0x04, sa=0x02, fc=0x5D, "
                               "dae=3E, sae=3C, du=",
                               245, tail),
              "LE would be 250, more than 249");
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_PROSOFT | TEXT_SHAPE_PROFISNIFF);
}

static void test_skipped_lines(void)
{
    text_import_init(&st);
    const char *skipped[] = {"", "   ", "\t", "\r", "# dfp-sim capture", "  // note",
                             "; ini style"};
    for (size_t i = 0; i < sizeof skipped / sizeof skipped[0]; i++) {
        CHECK_EQ(import(skipped[i]), TEXT_LINE_SKIP);
        CHECK_EQ(rec.len, 0);
        CHECK_STR(rec.problem, "");
    }
    CHECK_EQ(st.line, 7);
    CHECK_EQ(st.shape_seen, 0);
    CHECK(!st.seen_time);
}

static void test_byte_order_mark_on_first_line_only(void)
{
    text_import_init(&st);
    CHECK_PLAIN("\xEF\xBB\xBF" "10 04 02 49 4F 16", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_BAD("\xEF\xBB\xBF" "10 04 02 49 4F 16", "not hex: '???10'");
}

static void test_bad_lines(void)
{
    text_import_init(&st);
    CHECK_BAD("10 zz 16", "not hex: 'zz'");
    CHECK_BAD("10 0 16", "odd number of hex digits: '0'");
    CHECK_BAD("0x100 0x02", "not one octet: '0x100'");
    CHECK_BAD("0x", "not hex: '0x'");
    CHECK_BAD("hello world", "not hex: 'hello'");
    CHECK_BAD("10 02 zzzzzzzzzzzzzzzzzzzzzzzzzzzzzz",
              "not hex: 'zzzzzzzzzzzzzzzzzzzz...'");
    CHECK_BAD("10 02 \x01\x7f", "not hex: '?" "?'"); /* split: no trigraph */
    CHECK_BAD("99999999999.5 TX E5", "time beyond 10^10 s: '99999999999.5'");
    CHECK_BAD("[99999999999.5] E5", "time beyond 10^10 s: '99999999999.5'");
    CHECK_BAD("18446744073709551616.0 E5",
              "time beyond 10^10 s: '18446744073709551616...'");
    CHECK_BAD("0.1234567891 TX E5", "more than 9 fraction digits: '0.1234567891'");
    CHECK_BAD("[12.5 E5", "no ']' after '[12.5 E5'");
    CHECK_BAD("[abc] E5", "not a time: 'abc'");
    CHECK_BAD("1.5 TX", "no octets after the direction");
    CHECK_BAD("1.5", "no octets after the time");
    CHECK_BAD("12:34:56 TX", "no octets after the direction");
    /* 10^10 s itself is accepted. */
    CHECK_EQ(import("10000000000.0 E5"), TEXT_LINE_RECORD);
    CHECK_EQ(rec.t_ns, 10000000000000000000u);

    /* Too long: rejected before anything is read. */
    size_t n = TEXT_IMPORT_MAX_LINE + 1u;
    char *long_line = malloc(n);
    if (long_line == NULL) {
        abort();
    }
    memset(long_line, 'E', n);
    CHECK_EQ(import_n(long_line, n), TEXT_LINE_BAD);
    CHECK_STR(rec.problem, "line longer than 4096 characters");
    free(long_line);

    /* The longest line gives 2048 octets: cut to CAP_MAX_RECORD, orig_len says how many. */
    char *max_line = malloc(TEXT_IMPORT_MAX_LINE);
    if (max_line == NULL) {
        abort();
    }
    memset(max_line, '5', TEXT_IMPORT_MAX_LINE);
    CHECK_EQ(import_n(max_line, TEXT_IMPORT_MAX_LINE), TEXT_LINE_RECORD);
    CHECK_EQ(rec.len, CAP_MAX_RECORD);
    CHECK_EQ(rec.orig_len, TEXT_IMPORT_MAX_LINE / 2u);
    CHECK_EQ(rec.data[CAP_MAX_RECORD - 1u], 0x55);
    CHECK_STR(rec.problem, "2048 octets, longer than any telegram (first 512 kept)");
    free(max_line);

    /* An embedded NUL is just a bad character. */
    CHECK_EQ(import_n("10 \0 16", 7), TEXT_LINE_BAD);
    CHECK_STR(rec.problem, "not hex: '?'");
    CHECK_EQ(st.shape_seen, TEXT_SHAPE_HEX);
}

/* ---- cap_check_telegram ------------------------------------------------------------------- */

static char problem[96];

static bool check_frame(const uint8_t *f, size_t n)
{
    return cap_check_telegram(f, n, problem, sizeof problem);
}

#define CHECK_TELEGRAM(expect_ok, reason, ...)                                                 \
    do {                                                                                       \
        const uint8_t f_[] = {__VA_ARGS__};                                                    \
        CHECK_EQ(check_frame(f_, sizeof f_), expect_ok);                                       \
        CHECK_STR(problem, reason);                                                            \
    } while (0)

static void test_check_valid(void)
{
    CHECK_TELEGRAM(true, "", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_TELEGRAM(true, "", 0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16);
    CHECK_TELEGRAM(true, "", 0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60,
                   0x03, 0xF1, 0x16);
    CHECK_TELEGRAM(true, "", 0xDC, 0x02, 0x01);
    CHECK_TELEGRAM(true, "", 0xE5);
    /* The longest: LE 249. */
    uint8_t big[255] = {0x68, 249, 249, 0x68};
    uint8_t fcs = 0;
    for (size_t i = 4; i < 253; i++) {
        big[i] = (uint8_t)i;
        fcs = (uint8_t)(fcs + big[i]);
    }
    big[253] = fcs;
    big[254] = 0x16;
    CHECK(check_frame(big, sizeof big));
    CHECK_STR(problem, "");
}

static void test_check_problems(void)
{
    CHECK_EQ(check_frame(NULL, 0), false);
    CHECK_STR(problem, "empty");
    CHECK_TELEGRAM(false, "unknown start delimiter 0x55", 0x55, 0x10);
    /* SD1 */
    CHECK_TELEGRAM(false, "truncated SD1: 3 of 6 octets", 0x10, 0x04, 0x02);
    CHECK_TELEGRAM(false, "end delimiter 0x17, expected 0x16", 0x10, 0x04, 0x02, 0x49, 0x4F,
                   0x17);
    CHECK_TELEGRAM(false, "bad FCS (0x12, computed 0x4F)", 0x10, 0x04, 0x02, 0x49, 0x12, 0x16);
    CHECK_TELEGRAM(false, "1 octet after the end delimiter", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16,
                   0xE5);
    CHECK_TELEGRAM(false, "9 octets after the end delimiter", 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16,
                   0x10, 0x04, 0x02, 0x49, 0x4F, 0x16, 0x10, 0x04, 0x02);
    /* SD2 */
    CHECK_TELEGRAM(false, "truncated SD2: 2 of at least 10 octets", 0x68, 0x05);
    CHECK_TELEGRAM(false, "length octets differ (LE 0x05, LEr 0x06)", 0x68, 0x05, 0x06, 0x68,
                   0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16);
    CHECK_TELEGRAM(false, "LE 3 outside 4..249", 0x68, 0x03, 0x03, 0x68, 0x02, 0x04, 0x08, 0x0E,
                   0x16);
    CHECK_TELEGRAM(false, "LE 250 outside 4..249", 0x68, 0xFA, 0xFA, 0x68);
    CHECK_TELEGRAM(false, "start delimiter repeated as 0x69, expected 0x68", 0x68, 0x05, 0x05,
                   0x69, 0x84, 0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x16);
    CHECK_TELEGRAM(false, "truncated SD2: 7 of 11 octets", 0x68, 0x05, 0x05, 0x68, 0x84, 0x82,
                   0x6D);
    CHECK_TELEGRAM(false, "bad FCS (0xEE, computed 0xED)", 0x68, 0x05, 0x05, 0x68, 0x84, 0x82,
                   0x6D, 0x3C, 0x3E, 0xEE, 0x16);
    CHECK_TELEGRAM(false, "end delimiter 0x00, expected 0x16", 0x68, 0x05, 0x05, 0x68, 0x84,
                   0x82, 0x6D, 0x3C, 0x3E, 0xED, 0x00);
    CHECK_TELEGRAM(false, "2 octets after the end delimiter", 0x68, 0x05, 0x05, 0x68, 0x84, 0x82,
                   0x6D, 0x3C, 0x3E, 0xED, 0x16, 0xDC, 0x02);
    /* SD3 */
    CHECK_TELEGRAM(false, "truncated SD3: 13 of 14 octets", 0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                   0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1);
    CHECK_TELEGRAM(false, "bad FCS (0xF2, computed 0xF1)", 0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                   0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF2, 0x16);
    /* SD4 and SC */
    CHECK_TELEGRAM(false, "truncated SD4 token: 2 of 3 octets", 0xDC, 0x02);
    CHECK_TELEGRAM(false, "1 octet after the SD4 token", 0xDC, 0x02, 0x01, 0xE5);
    CHECK_TELEGRAM(false, "2 octets after the short acknowledgement", 0xE5, 0xE5, 0xE5);

    /* A small or absent problem buffer is never overrun. */
    char small[8];
    memset(small, 'x', sizeof small);
    const uint8_t sd1_bad_fcs[] = {0x10, 0x04, 0x02, 0x49, 0x12, 0x16};
    CHECK(!cap_check_telegram(sd1_bad_fcs, sizeof sd1_bad_fcs, small, sizeof small));
    CHECK_STR(small, "bad FCS");
    CHECK(!cap_check_telegram(sd1_bad_fcs, sizeof sd1_bad_fcs, NULL, 0));
}

int main(void)
{
    RUN_TEST(test_plain_hex_separators);
    RUN_TEST(test_time_and_direction);
    RUN_TEST(test_export_line_text_and_limits);
    RUN_TEST(test_export_round_trip);
    RUN_TEST(test_pyprofibus_phy);
    RUN_TEST(test_profisniff_repr);
    RUN_TEST(test_prosoft);
    RUN_TEST(test_prosoft_fcs_and_status);
    RUN_TEST(test_prosoft_bad_lines);
    RUN_TEST(test_rebuilt_length_limit);
    RUN_TEST(test_skipped_lines);
    RUN_TEST(test_byte_order_mark_on_first_line_only);
    RUN_TEST(test_bad_lines);
    RUN_TEST(test_check_valid);
    RUN_TEST(test_check_problems);
    return check_report();
}
