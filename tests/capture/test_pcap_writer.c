/* The pcap writer produces exactly the bytes of the libpcap format for link type 257. */
#include <stdlib.h>

#include "capture/pcap_writer.h"
#include "check.h"

static const char *dir;

static size_t read_all(const char *path, uint8_t *buf, size_t max)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return 0;
    }
    size_t n = fread(buf, 1, max, f);
    fclose(f);
    return n;
}

static void test_microsecond_file_bytes(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/us.pcap", dir);
    pcap_writer_t w;
    char err[256];
    CHECK_EQ(pcap_writer_open(&w, path, PCAP_LINKTYPE_PROFIBUS_DL, false, 0, err, sizeof err), 0);
    const uint8_t fdl_status[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
    const uint8_t sc[] = {0xE5};
    CHECK_EQ(pcap_writer_frame(&w, 1500000123ull, fdl_status, sizeof fdl_status), 0);
    CHECK_EQ(pcap_writer_frame(&w, 2000000000ull, sc, sizeof sc), 0);
    CHECK_EQ(pcap_writer_close(&w), 0);
    uint8_t buf[128];
    size_t n = read_all(path, buf, sizeof buf);
    CHECK_BYTES(buf, n,
                0xD4, 0xC3, 0xB2, 0xA1, 0x02, 0x00, 0x04, 0x00, 0, 0, 0, 0, 0, 0, 0, 0,
                0xFF, 0xFF, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, /* snaplen, linktype 257 */
                0x01, 0, 0, 0, 0x20, 0xA1, 0x07, 0x00, 6, 0, 0, 0, 6, 0, 0, 0, /* 1 s 500000 us */
                0x10, 0x04, 0x02, 0x49, 0x4F, 0x16,
                0x02, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0xE5);
}

static void test_nanosecond_magic_and_fraction(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/ns.pcap", dir);
    pcap_writer_t w;
    char err[256];
    CHECK_EQ(pcap_writer_open(&w, path, PCAP_LINKTYPE_USER0, true, 1000000000ull, err,
                              sizeof err), 0);
    const uint8_t sc[] = {0xE5};
    CHECK_EQ(pcap_writer_frame(&w, 123ull, sc, 1), 0);
    CHECK_EQ(pcap_writer_close(&w), 0);
    uint8_t buf[64];
    size_t n = read_all(path, buf, sizeof buf);
    CHECK_EQ(n, 24 + 16 + 1);
    CHECK_BYTES(buf, 4, 0x4D, 0x3C, 0xB2, 0xA1);
    CHECK_BYTES(&buf[20], 4, 147, 0, 0, 0);
    CHECK_BYTES(&buf[24], 8, 1, 0, 0, 0, 123, 0, 0, 0);
}

static void test_unwritable_path_reports_reason(void)
{
    pcap_writer_t w;
    char err[256] = "";
    CHECK_EQ(pcap_writer_open(&w, "/nonexistent-dir/x.pcap", PCAP_LINKTYPE_PROFIBUS_DL, false, 0,
                              err, sizeof err),
             -1);
    CHECK(strstr(err, "/nonexistent-dir/x.pcap") != NULL);
    CHECK(strstr(err, "No such file") != NULL);
}

int main(int argc, char **argv)
{
    dir = argc > 1 ? argv[1] : ".";
    RUN_TEST(test_microsecond_file_bytes);
    RUN_TEST(test_nanosecond_magic_and_fraction);
    RUN_TEST(test_unwritable_path_reports_reason);
    return check_report();
}
