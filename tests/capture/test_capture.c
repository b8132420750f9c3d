/* Capture files through the reader and writer of capture.h: what dfp-sim writes reads back
 * exactly (time to the written resolution, octets, baud, positions), files of other tools
 * (big-endian pcap) read, and damaged files end with an error that names the position. */
#define _POSIX_C_SOURCE 200809L // NOLINT(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "capture/capture.h"
#include "check.h"

static const char *dir;

static const uint8_t fdl_status[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t sc[] = {0xE5};
static const uint8_t token[] = {0xDC, 0x02, 0x01};
static const uint8_t dx[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x02, 0x7D, 0x12, 0x34, 0x49, 0x16};

static void path_of(char *out, size_t max, const char *name)
{
    snprintf(out, max, "%s/%s", dir, name);
}

static void write_file(const char *path, const uint8_t *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (f != NULL) {
        fwrite(p, 1, n, f);
        fclose(f);
    }
}

static size_t read_file(const char *path, uint8_t *buf, size_t max)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return 0;
    }
    size_t n = fread(buf, 1, max, f);
    fclose(f);
    return n;
}

static void write_sample(const char *path, cap_format_t fmt, uint32_t linktype, bool ns,
                         uint32_t baud)
{
    cap_writer_t w;
    char err[256];
    cap_writer_options_t opt = {.format = fmt, .linktype = linktype, .nanosecond = ns,
                                .baud = baud};
    CHECK_EQ(cap_writer_open(&w, path, &opt, 1700000000ull * 1000000000ull, err, sizeof err),
             0);
    CHECK_EQ(cap_writer_frame(&w, 1234567891ull, fdl_status, sizeof fdl_status, CAP_DIR_TX), 0);
    CHECK_EQ(cap_writer_frame(&w, 1234600000ull, sc, sizeof sc, CAP_DIR_RX), 0);
    CHECK_EQ(cap_writer_frame(&w, 2000000001ull, dx, sizeof dx, CAP_DIR_UNKNOWN), 0);
    CHECK_EQ(cap_writer_frame(&w, 2000100000ull, token, sizeof token, CAP_DIR_TX), 0);
    CHECK_EQ(w.records, 4);
    CHECK_EQ(cap_writer_close(&w), 0);
}

/* Reads the sample back; us: times were stored in microseconds. */
static void read_sample(const char *path, cap_format_t expect_fmt, uint32_t linktype, bool us,
                        uint32_t baud, const uint64_t *positions)
{
    cap_reader_t r;
    char err[256];
    CHECK_EQ(cap_reader_open(&r, path, CAP_FORMAT_AUTO, err, sizeof err), 0);
    CHECK_EQ(r.format, expect_fmt);
    CHECK_EQ(r.linktype, linktype);
    const uint8_t *frames[] = {fdl_status, sc, dx, token};
    const size_t lens[] = {sizeof fdl_status, sizeof sc, sizeof dx, sizeof token};
    const uint64_t base = 1700000000ull * 1000000000ull;
    const uint64_t times[] = {1234567891ull, 1234600000ull, 2000000001ull, 2000100000ull};
    static cap_record_t rec;
    for (size_t i = 0; i < 4; i++) {
        CHECK_EQ(cap_reader_next(&r, &rec), 1);
        CHECK_EQ(rec.index, i + 1);
        CHECK(rec.has_time);
        uint64_t t = base + times[i];
        CHECK_EQ(rec.t_ns, us ? t / 1000u * 1000u : t);
        CHECK_EQ(rec.baud, baud);
        CHECK_EQ(rec.len, lens[i]);
        CHECK_EQ(rec.orig_len, lens[i]);
        CHECK(memcmp(rec.data, frames[i], lens[i]) == 0);
        CHECK_STR(rec.problem, "");
        if (positions != NULL) {
            CHECK_EQ(rec.position, positions[i]);
        }
    }
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    CHECK_EQ(cap_reader_next(&r, &rec), 0); /* end stays end */
    CHECK_EQ(r.records, 4);
    cap_reader_close(&r);
}

static void test_pcap_round_trip(void)
{
    char p[600];
    path_of(p, sizeof p, "us.pcap");
    write_sample(p, CAP_FORMAT_AUTO, 0, false, 0);
    /* 24-octet file header, then 16-octet record headers. */
    const uint64_t pos[] = {24, 24 + 16 + 6, 24 + 16 + 6 + 16 + 1, 24 + 16 + 6 + 16 + 1 + 16 + 11};
    read_sample(p, CAP_FORMAT_PCAP, 257, true, 0, pos);

    path_of(p, sizeof p, "ns_user0.pcap");
    write_sample(p, CAP_FORMAT_PCAP, 147, true, 0);
    read_sample(p, CAP_FORMAT_PCAP, 147, false, 0, pos);
}

static void test_pcapng_bytes_and_round_trip(void)
{
    char p[600];
    path_of(p, sizeof p, "sample.pcapng");
    write_sample(p, CAP_FORMAT_AUTO, 0, true, 1500000);
    uint8_t buf[512];
    size_t n = read_file(p, buf, sizeof buf);
    /* Section header block, little-endian, version 1.0, section length unknown. */
    CHECK_BYTES(buf, 28, 0x0A, 0x0D, 0x0D, 0x0A, 28, 0, 0, 0, 0x4D, 0x3C, 0x2B, 0x1A, 1, 0, 0, 0,
                0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 28, 0, 0, 0);
    /* Interface description: link type 257, snaplen 65535, if_tsresol 9, if_speed 1.5M. */
    CHECK_BYTES(&buf[28], 44, 1, 0, 0, 0, 44, 0, 0, 0, 0x01, 0x01, 0, 0, 0xFF, 0xFF, 0, 0,
                9, 0, 1, 0, 9, 0, 0, 0, 8, 0, 8, 0, 0x60, 0xE3, 0x16, 0, 0, 0, 0, 0,
                0, 0, 0, 0, 44, 0, 0, 0);
    /* First enhanced packet block: ns timestamp split high/low, epb_flags outbound. */
    uint64_t ts = 1700000000ull * 1000000000ull + 1234567891ull;
    CHECK_BYTES(&buf[72], 28, 6, 0, 0, 0, 52, 0, 0, 0, 0, 0, 0, 0,
                (uint8_t)(ts >> 32), (uint8_t)(ts >> 40), (uint8_t)(ts >> 48),
                (uint8_t)(ts >> 56), (uint8_t)ts, (uint8_t)(ts >> 8), (uint8_t)(ts >> 16),
                (uint8_t)(ts >> 24), 6, 0, 0, 0, 6, 0, 0, 0);
    CHECK_BYTES(&buf[100], 24, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16, 0, 0, 2, 0, 4, 0, 2, 0, 0,
                0, 0, 0, 0, 0, 52, 0, 0, 0);
    CHECK(n > 128);
    read_sample(p, CAP_FORMAT_PCAPNG, 257, false, 1500000, NULL);

    path_of(p, sizeof p, "us.pcapng");
    write_sample(p, CAP_FORMAT_PCAPNG, 147, false, 0);
    read_sample(p, CAP_FORMAT_PCAPNG, 147, true, 0, NULL);

    /* An if_speed that is no PROFIBUS rate (another tool's interface speed, damage) says
     * nothing about the bus: baud 0, as if absent. */
    path_of(p, sizeof p, "serial-speed.pcapng");
    write_sample(p, CAP_FORMAT_PCAPNG, 257, false, 115200);
    read_sample(p, CAP_FORMAT_PCAPNG, 257, true, 0, NULL);
    CHECK_EQ(cap_profibus_rate(12000000u), 12000000u);
    CHECK_EQ(cap_profibus_rate(45450u), 45450u);
    CHECK_EQ(cap_profibus_rate(1u), 0u);
    CHECK_EQ(cap_profibus_rate(0x100000000ull + 1500000u), 0u);
}

/* A big-endian microsecond pcap as another tool on another machine would write it. */
static void test_big_endian_pcap_from_another_tool(void)
{
    const uint8_t file[] = {0xA1, 0xB2, 0xC3, 0xD4, 0, 2, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0,
                            0, 0, 0xFF, 0xFF, 0, 0, 0x01, 0x01,
                            0, 0, 0, 10, 0, 0, 0, 7, 0, 0, 0, 1, 0, 0, 0, 1, 0xE5};
    char p[600];
    path_of(p, sizeof p, "be.pcap");
    write_file(p, file, sizeof file);
    cap_reader_t r;
    char err[256];
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    static cap_record_t rec;
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.t_ns, 10000007000ull);
    CHECK_EQ(rec.len, 1);
    CHECK_EQ(rec.data[0], 0xE5);
    CHECK_EQ(rec.position, 24);
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    cap_reader_close(&r);
}

static void expect_open_error(const char *name, const uint8_t *content, size_t n,
                              cap_format_t fmt, const char *needle)
{
    char p[600];
    path_of(p, sizeof p, name);
    write_file(p, content, n);
    cap_reader_t r;
    char err[256] = "";
    CHECK_EQ(cap_reader_open(&r, p, fmt, err, sizeof err), -1);
    if (strstr(err, needle) == NULL) {
        fprintf(stderr, "  %s: error \"%s\" lacks \"%s\"\n", name, err, needle);
        CHECK(false);
    }
}

static void test_unreadable_files_refused_at_open(void)
{
    const uint8_t ethernet[] = {0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                0xFF, 0xFF, 0, 0, 1, 0, 0, 0};
    expect_open_error("eth.pcap", ethernet, sizeof ethernet, CAP_FORMAT_AUTO,
                      "link type 1 (EN10MB) is not PROFIBUS");
    const uint8_t binary[] = {0x7F, 'E', 'L', 'F', 2, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    expect_open_error("a.out", binary, sizeof binary, CAP_FORMAT_AUTO, "unknown format");
    expect_open_error("empty.pcap", binary, 0, CAP_FORMAT_AUTO, "empty file");
    const uint8_t short_header[] = {0xD4, 0xC3, 0xB2, 0xA1, 2, 0};
    expect_open_error("short.pcap", short_header, sizeof short_header, CAP_FORMAT_AUTO,
                      "not a readable pcap file");
    /* Forcing a format the file is not. */
    const uint8_t text[] = "68 05 05 68\n";
    expect_open_error("text.pcap", text, sizeof text - 1, CAP_FORMAT_PCAP,
                      "not a readable pcap file");

    cap_reader_t r;
    char err[256] = "";
    char p[600];
    path_of(p, sizeof p, "does-not-exist.pcap");
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), -1);
    CHECK(strstr(err, "No such file") != NULL);
    CHECK_EQ(cap_reader_open(&r, dir, CAP_FORMAT_AUTO, err, sizeof err), -1);
    CHECK(strstr(err, "not a regular file") != NULL || strstr(err, "Is a directory") != NULL);
}

/* Reads until the end or an error; returns the records read, err gets the error. */
static uint64_t read_until_error(const char *p, int *last, char *err, size_t max)
{
    cap_reader_t r;
    char oerr[256];
    if (cap_reader_open(&r, p, CAP_FORMAT_AUTO, oerr, sizeof oerr) != 0) {
        snprintf(err, max, "open: %s", oerr);
        *last = -2;
        return 0;
    }
    static cap_record_t rec;
    uint64_t n = 0;
    int rc;
    for (int guard = 0; guard < 1000 && (rc = cap_reader_next(&r, &rec)) == 1; guard++) {
        n++;
    }
    *last = rc;
    snprintf(err, max, "%s", r.error);
    cap_reader_close(&r);
    return n;
}

static void test_damaged_pcap_reports_position(void)
{
    char p[600];
    path_of(p, sizeof p, "whole.pcap");
    write_sample(p, CAP_FORMAT_PCAP, 0, false, 0);
    uint8_t buf[256];
    size_t n = read_file(p, buf, sizeof buf);
    CHECK_EQ(n, 24 + 4 * 16 + 6 + 1 + 11 + 3);

    /* Cut inside the third record's data: two records, then an error at byte 87. */
    char bad[600];
    path_of(bad, sizeof bad, "truncated.pcap");
    write_file(bad, buf, 24 + 16 + 6 + 16 + 1 + 16 + 5);
    int last;
    char err[1024];
    CHECK_EQ(read_until_error(bad, &last, err, sizeof err), 2);
    CHECK_EQ(last, -1);
    CHECK(strstr(err, "record 3 at byte 63") != NULL);
    CHECK(strstr(err, "truncated") != NULL);

    /* Garbage where the second record header should be: a huge captured length. */
    uint8_t garbage[256];
    memcpy(garbage, buf, n);
    memset(&garbage[24 + 16 + 6], 0xEE, 16);
    path_of(bad, sizeof bad, "garbage.pcap");
    write_file(bad, garbage, n);
    CHECK_EQ(read_until_error(bad, &last, err, sizeof err), 1);
    CHECK_EQ(last, -1);
    CHECK(strstr(err, "record 2 at byte 46") != NULL);

    /* A file header alone is a valid empty capture. */
    path_of(bad, sizeof bad, "header-only.pcap");
    write_file(bad, buf, 24);
    CHECK_EQ(read_until_error(bad, &last, err, sizeof err), 0);
    CHECK_EQ(last, 0);
}

static void test_long_record_is_cut_and_marked(void)
{
    char p[600];
    path_of(p, sizeof p, "long.pcap");
    cap_writer_t w;
    char err[256];
    cap_writer_options_t opt = {.format = CAP_FORMAT_PCAP};
    CHECK_EQ(cap_writer_open(&w, p, &opt, 0, err, sizeof err), 0);
    static uint8_t big[1000];
    memset(big, 0x5A, sizeof big);
    CHECK_EQ(cap_writer_frame(&w, 0, big, sizeof big, CAP_DIR_UNKNOWN), 0);
    CHECK_EQ(cap_writer_close(&w), 0);
    cap_reader_t r;
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    static cap_record_t rec;
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.len, CAP_MAX_RECORD);
    CHECK_EQ(rec.orig_len, 1000);
    CHECK_STR(rec.problem, "1000 octets, longer than any telegram");
    cap_reader_close(&r);
}

/* Records are read a chunk (CAP_PCAP_CHUNK octets) at a time: a record that straddles two
 * chunks, and one longer than a chunk, come out whole and in place, and the records after them
 * too; a file cut inside a record header names that record and its byte. */
static void test_pcap_records_across_chunks(void)
{
    char p[600];
    path_of(p, sizeof p, "chunks.pcap");
    cap_writer_t w;
    char err[256];
    cap_writer_options_t opt = {.format = CAP_FORMAT_PCAP, .nanosecond = true};
    CHECK_EQ(cap_writer_open(&w, p, &opt, 0, err, sizeof err), 0);
    enum { BEFORE = 1500, AFTER = 1500, HUGE = 3 * CAP_PCAP_CHUNK / 2 };
    static uint8_t huge[HUGE];
    memset(huge, 0xA5, sizeof huge);
    for (uint32_t i = 0; i < BEFORE + 1 + AFTER; i++) {
        bool is_huge = i == BEFORE;
        CHECK_EQ(cap_writer_frame(&w, 1000ull * i + 7u, is_huge ? huge : dx,
                                  is_huge ? sizeof huge : sizeof dx, CAP_DIR_UNKNOWN), 0);
    }
    CHECK_EQ(cap_writer_close(&w), 0);
    cap_reader_t r;
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    static cap_record_t rec;
    uint64_t at = 24;
    for (uint32_t i = 0; i < BEFORE + 1 + AFTER; i++) {
        CHECK_EQ(cap_reader_next(&r, &rec), 1);
        CHECK_EQ(rec.index, i + 1u);
        CHECK_EQ(rec.position, at);
        CHECK_EQ(rec.t_ns, 1000ull * i + 7u);
        if (i == BEFORE) {
            CHECK_EQ(rec.orig_len, HUGE);
            CHECK_EQ(rec.len, CAP_MAX_RECORD);
            CHECK_EQ(rec.data[CAP_MAX_RECORD - 1u], 0xA5);
            at += 16u + HUGE;
        } else {
            CHECK_EQ(rec.len, sizeof dx);
            CHECK(memcmp(rec.data, dx, sizeof dx) == 0);
            CHECK_STR(rec.problem, "");
            at += 16u + sizeof dx;
        }
    }
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    cap_reader_close(&r);

    /* The same file cut 7 octets into the header of record 1 502. */
    static uint8_t buf[24 + (BEFORE + AFTER) * (16 + sizeof dx) + 16 + HUGE];
    size_t n = read_file(p, buf, sizeof buf);
    CHECK_EQ(n, sizeof buf);
    size_t cut = 24u + BEFORE * (16u + sizeof dx) + 16u + HUGE + 7u;
    char bad[600];
    path_of(bad, sizeof bad, "chunks-cut.pcap");
    write_file(bad, buf, cut);
    int last;
    char rerr[1024];
    uint64_t records = 0;
    CHECK_EQ(cap_reader_open(&r, bad, CAP_FORMAT_AUTO, err, sizeof err), 0);
    while ((last = cap_reader_next(&r, &rec)) == 1) {
        records++;
    }
    snprintf(rerr, sizeof rerr, "%s", r.error);
    cap_reader_close(&r);
    CHECK_EQ(records, BEFORE + 1u);
    CHECK_EQ(last, -1);
    char want[200];
    snprintf(want, sizeof want, "record %u at byte %zu: truncated record header: 7 of 16 octets",
             BEFORE + 2u, cut - 7u);
    if (strstr(rerr, want) == NULL) {
        fprintf(stderr, "  error \"%s\" lacks \"%s\"\n", rerr, want);
        CHECK(false);
    }
}

static void test_writer_refusals(void)
{
    cap_writer_t w;
    char err[256] = "";
    char p[600];
    path_of(p, sizeof p, "x.pcap");
    cap_writer_options_t opt = {.format = CAP_FORMAT_PCAP, .linktype = 1};
    CHECK_EQ(cap_writer_open(&w, p, &opt, 0, err, sizeof err), -1);
    CHECK(strstr(err, "link type 1") != NULL);
    opt.linktype = 0;
    opt.format = CAP_FORMAT_LCM;
    CHECK_EQ(cap_writer_open(&w, p, &opt, 0, err, sizeof err), -1);
    opt.format = CAP_FORMAT_AUTO;
    CHECK_EQ(cap_writer_open(&w, "/nonexistent-dir/x.pcap", &opt, 0, err, sizeof err), -1);
    CHECK(strstr(err, "/nonexistent-dir/x.pcap") != NULL);
}

/* A symbolic link at the name (put there by another user in a shared directory, after the
 * command line was checked) is refused by every writer; its target keeps its bytes. */
static void test_writer_refuses_a_link(void)
{
    char victim[600];
    path_of(victim, sizeof victim, "victim.txt");
    static const uint8_t secret[] = "the victim's bytes\n";
    write_file(victim, secret, sizeof secret - 1u);
    static const char *const names[] = {"planted.pcap", "planted.pcapng", "planted.txt"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char p[600];
        path_of(p, sizeof p, names[i]);
        (void)unlink(p);
        CHECK_EQ(symlink(victim, p), 0);
        cap_writer_t w;
        char err[700] = "";
        cap_writer_options_t opt = {.format = CAP_FORMAT_AUTO};
        CHECK_EQ(cap_writer_open(&w, p, &opt, 0, err, sizeof err), -1);
        char want[800];
        snprintf(want, sizeof want, "cannot write capture file %s: a symbolic link: refused "
                 "(dfp-sim writes no file through a link)", p);
        CHECK_STR(err, want);
        (void)unlink(p);
    }
    uint8_t got[64];
    CHECK_EQ(read_file(victim, got, sizeof got), sizeof secret - 1u);
    CHECK(memcmp(got, secret, sizeof secret - 1u) == 0);
}

static void test_text_round_trip_and_bad_lines(void)
{
    char p[600];
    path_of(p, sizeof p, "sample.txt");
    write_sample(p, CAP_FORMAT_AUTO, 0, false, 0);
    cap_reader_t r;
    char err[256];
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    CHECK_EQ(r.format, CAP_FORMAT_TEXT);
    static cap_record_t rec;
    const cap_dir_t dirs[] = {CAP_DIR_TX, CAP_DIR_RX, CAP_DIR_UNKNOWN, CAP_DIR_TX};
    for (uint64_t i = 1; i <= 4; i++) {
        CHECK_EQ(cap_reader_next(&r, &rec), 1);
        CHECK_EQ(rec.position, i); /* line number */
        CHECK_EQ(rec.dir, dirs[i - 1]);
        CHECK_STR(rec.problem, "");
    }
    CHECK_EQ(rec.t_ns, 1700000000ull * 1000000000ull + 2000100000ull);
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    cap_reader_close(&r);

    /* Comments and blank lines skipped; a bad line, an overlong line and a bad FCS are records
     * with a problem and their line number; the line after the long one is read whole. */
    path_of(p, sizeof p, "bad.txt");
    FILE *f = fopen(p, "w");
    CHECK(f != NULL);
    if (f == NULL) {
        return;
    }
    fputs("# a dump\n\n10 04 02 49 4F 16\nhello world\n", f);
    for (int i = 0; i < 5000; i++) {
        fputc('A', f);
    }
    fputs("\r\n0.5 RX E5\n10 04 02 49 4E 16\n", f);
    fclose(f);
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.position, 3);
    CHECK_EQ(rec.len, 6);
    CHECK_STR(rec.problem, "");
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.position, 4);
    CHECK_EQ(rec.len, 0);
    CHECK(rec.problem[0] != '\0');
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.position, 5);
    CHECK_EQ(rec.len, 0);
    CHECK(strstr(rec.problem, "longer than 4096") != NULL);
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.position, 6);
    CHECK_EQ(rec.t_ns, 500000000ull);
    CHECK_EQ(rec.dir, CAP_DIR_RX);
    CHECK_EQ(rec.data[0], 0xE5);
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.position, 7);
    CHECK_STR(rec.problem, "bad FCS (0x4E, computed 0x4F)");
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    CHECK_EQ(r.records, 5);
    cap_reader_close(&r);
}

static void test_format_names(void)
{
    cap_format_t f = CAP_FORMAT_AUTO;
    CHECK(cap_format_parse("pcapng", &f));
    CHECK_EQ(f, CAP_FORMAT_PCAPNG);
    CHECK(cap_format_parse("text", &f));
    CHECK_EQ(f, CAP_FORMAT_TEXT);
    CHECK(!cap_format_parse("PCAP", &f));
    CHECK(!cap_format_parse("", &f));
    CHECK_STR(cap_format_name(CAP_FORMAT_LCM), "lcm");
}

int main(int argc, char **argv)
{
    dir = argc > 1 ? argv[1] : ".";
    RUN_TEST(test_pcap_round_trip);
    RUN_TEST(test_pcapng_bytes_and_round_trip);
    RUN_TEST(test_big_endian_pcap_from_another_tool);
    RUN_TEST(test_unreadable_files_refused_at_open);
    RUN_TEST(test_damaged_pcap_reports_position);
    RUN_TEST(test_long_record_is_cut_and_marked);
    RUN_TEST(test_pcap_records_across_chunks);
    RUN_TEST(test_writer_refusals);
    RUN_TEST(test_writer_refuses_a_link);
    RUN_TEST(test_text_round_trip_and_bad_lines);
    RUN_TEST(test_format_names);
    return check_report();
}
