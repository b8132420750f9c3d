/* The pcapng writer of the bus monitor (capture/pcapng_writer.h): the exact blocks, records
 * read back through the capture reader (libpcap) with their octets and ns times, a file whose
 * writer was killed reads to its last flush, a failed write is told once, links are refused.
 *
 * Usage: test_pcapng_writer DIR           the tests, files in DIR
 *        test_pcapng_writer DIR sample    only writes DIR/sample257.pcapng and
 *                                         DIR/sample147.pcapng for test_pcapng_tshark.sh */
#define _POSIX_C_SOURCE 200809L // NOLINT(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro

#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "capture/capture.h"
#include "capture/pcapng_writer.h"
#include "check.h"

static const char *dir;

static const uint8_t fdl_status[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t sc[] = {0xE5};
static const uint8_t token[] = {0xDC, 0x02, 0x01};
/* An SD2 request 2 → 4 (DSAP 18, one data octet), and the same cut after DA. */
static const uint8_t dx[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x02, 0x7D, 0x12, 0x34, 0x49, 0x16};
static const uint8_t cut[] = {0x68, 0x05, 0x05, 0x68, 0x84};

static void path_of(char *out, size_t max, const char *name)
{
    snprintf(out, max, "%s/%s", dir, name);
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

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static void test_blocks_exact_bytes(void)
{
    char p[600];
    path_of(p, sizeof p, "bytes.pcapng");
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {.baud = 12000000u, .if_name = "membus"};
    CHECK_EQ(pcapng_writer_open(&w, p, &opt, err, sizeof err), 0);
    CHECK_EQ(pcapng_writer_telegram(&w, 0x100000002ull, sc, sizeof sc), 0);
    CHECK_EQ(pcapng_writer_garbled(&w, 7, cut, 2), 0);
    CHECK_EQ(w.records, 2);
    CHECK_EQ(pcapng_writer_close(&w), 0);
    uint8_t b[512];
    size_t n = read_file(p, b, sizeof b);
    CHECK_BYTES(b, n,
                /* SHB, 44 octets: byte-order magic, 1.0, length unknown, shb_userappl */
                0x0A, 0x0D, 0x0D, 0x0A, 44, 0, 0, 0, 0x4D, 0x3C, 0x2B, 0x1A, 1, 0, 0, 0,
                0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
                4, 0, 7, 0, 'd', 'f', 'p', '-', 's', 'i', 'm', 0, 0, 0, 0, 0, 44, 0, 0, 0,
                /* IDB, 56 octets: link type 257, snaplen 1024, if_name, if_speed, if_tsresol */
                1, 0, 0, 0, 56, 0, 0, 0, 0x01, 0x01, 0, 0, 0x00, 0x04, 0, 0,
                2, 0, 6, 0, 'm', 'e', 'm', 'b', 'u', 's', 0, 0,
                8, 0, 8, 0, 0x00, 0x1B, 0xB7, 0x00, 0, 0, 0, 0,
                9, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0, 56, 0, 0, 0,
                /* EPB, 36 octets: interface 0, ns high and low, 1 of 1 octet, no option */
                6, 0, 0, 0, 36, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0,
                1, 0, 0, 0, 0xE5, 0, 0, 0, 36, 0, 0, 0,
                /* EPB, 52 octets: 2 octets, opt_comment "garbled" */
                6, 0, 0, 0, 52, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 7, 0, 0, 0, 2, 0, 0, 0,
                2, 0, 0, 0, 0x68, 0x05, 0, 0, 1, 0, 7, 0, 'g', 'a', 'r', 'b', 'l', 'e', 'd', 0,
                0, 0, 0, 0, 52, 0, 0, 0);
}

/* The sample the reader and tshark read: six records, one garbled, a long run cut. */
static void write_sample(const char *p, uint32_t linktype)
{
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {.linktype = linktype, .baud = 1500000u, .if_name = "/dev/ttyUSB0",
                               .if_description = "dfp-sim monitor, 1.5 Mbit/s",
                               .base_ns = 1700000000ull * 1000000000ull};
    CHECK_EQ(pcapng_writer_open(&w, p, &opt, err, sizeof err), 0);
    uint8_t long_run[1500];
    for (size_t i = 0; i < sizeof long_run; i++) {
        long_run[i] = (uint8_t)i;
    }
    CHECK_EQ(pcapng_writer_telegram(&w, 1, token, sizeof token), 0);
    CHECK_EQ(pcapng_writer_telegram(&w, 123456789ull, fdl_status, sizeof fdl_status), 0);
    CHECK_EQ(pcapng_writer_telegram(&w, 123499999ull, sc, sizeof sc), 0);
    CHECK_EQ(pcapng_writer_garbled(&w, 2000000001ull, cut, sizeof cut), 0);
    CHECK_EQ(pcapng_writer_telegram(&w, 2000000500ull, dx, sizeof dx), 0);
    CHECK_EQ(pcapng_writer_garbled(&w, 3000000000ull, long_run, sizeof long_run), 0);
    CHECK_EQ(pcapng_writer_close(&w), 0);
}

static void expect_record(cap_reader_t *r, uint64_t t_ns, const uint8_t *f, size_t len,
                          bool valid)
{
    static cap_record_t rec;
    CHECK_EQ(cap_reader_next(r, &rec), 1);
    CHECK_EQ(rec.t_ns, 1700000000ull * 1000000000ull + t_ns);
    CHECK_EQ(rec.baud, 1500000u);
    CHECK_EQ(rec.len, len);
    CHECK(memcmp(rec.data, f, len) == 0);
    CHECK_EQ(rec.problem[0] == '\0', valid);
}

static void test_read_back_through_the_capture_reader(void)
{
    char p[600];
    path_of(p, sizeof p, "sample.pcapng");
    write_sample(p, 0);
    cap_reader_t r;
    char err[700] = "";
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    CHECK_EQ(r.format, CAP_FORMAT_PCAPNG);
    CHECK_EQ(r.linktype, PCAP_LINKTYPE_PROFIBUS_DL);
    CHECK_EQ(r.if_baud, 1500000u);
    expect_record(&r, 1, token, sizeof token, true);
    expect_record(&r, 123456789ull, fdl_status, sizeof fdl_status, true);
    expect_record(&r, 123499999ull, sc, sizeof sc, true);
    expect_record(&r, 2000000001ull, cut, sizeof cut, false);
    expect_record(&r, 2000000500ull, dx, sizeof dx, true);
    static cap_record_t rec;
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    /* Kept 1 024 of the 1 500 octets; the reader holds 512 of them. */
    CHECK_EQ(rec.orig_len, 1500);
    CHECK_EQ(rec.len, CAP_MAX_RECORD);
    CHECK_EQ(rec.data[511], 511 & 0xFF);
    CHECK_STR(rec.problem, "cut when captured: 1024 of 1500 octets");
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    cap_reader_close(&r);
}

/* A child writes, flushes, writes on and is killed: what it flushed is in the file, whole, and
 * the file ends cleanly there. */
static void killed_writer(const char *p)
{
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {.baud = 12000000u};
    if (pcapng_writer_open(&w, p, &opt, err, sizeof err) != 0) {
        _exit(3);
    }
    uint64_t t = 0;
    for (unsigned i = 0; i < 5u; i++) {
        (void)pcapng_writer_telegram(&w, t, token, sizeof token);
        t += 300000000ull; /* 0.3 s */
        (void)pcapng_writer_tick(&w, t);
    }
    /* 1.5 s: the tick at 1.2 s flushed the first four records, the fifth waits. */
    for (unsigned i = 0; i < 100u; i++) {
        (void)pcapng_writer_telegram(&w, t + i, sc, sizeof sc);
    }
    (void)kill(getpid(), SIGKILL);
    _exit(4);
}

static void test_killed_writer_leaves_whole_blocks(void)
{
    char p[600];
    path_of(p, sizeof p, "killed.pcapng");
    pid_t pid = fork();
    if (pid == 0) {
        killed_writer(p);
    }
    int status = 0;
    CHECK_EQ(waitpid(pid, &status, 0), pid);
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    cap_reader_t r;
    char err[700] = "";
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    static cap_record_t rec;
    for (uint64_t i = 0; i < 4u; i++) {
        CHECK_EQ(cap_reader_next(&r, &rec), 1);
        CHECK_EQ(rec.t_ns, i * 300000000ull);
        CHECK_BYTES(rec.data, rec.len, 0xDC, 0x02, 0x01);
    }
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    CHECK_EQ(r.records, 4);
    cap_reader_close(&r);

    /* Cut inside the last block (a copy taken mid-write): the records before it read, then
     * the reader says the file is cut. */
    long size = file_size(p);
    CHECK(size > 0 && truncate(p, size - 5) == 0);
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    for (unsigned i = 0; i < 3u; i++) {
        CHECK_EQ(cap_reader_next(&r, &rec), 1);
    }
    CHECK_EQ(cap_reader_next(&r, &rec), -1);
    CHECK(r.error[0] != '\0');
    cap_reader_close(&r);
}

static void test_tick_flushes_once_a_second(void)
{
    char p[600];
    path_of(p, sizeof p, "tick.pcapng");
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {0};
    CHECK_EQ(pcapng_writer_open(&w, p, &opt, err, sizeof err), 0);
    long head = file_size(p);
    CHECK_EQ(head, 44 + 32); /* the SHB and the IDB are in the file at once */
    CHECK_EQ(pcapng_writer_telegram(&w, 10, sc, sizeof sc), 0);
    CHECK_EQ(pcapng_writer_tick(&w, 999999999ull), 0);
    CHECK_EQ(file_size(p), head);
    CHECK_EQ(pcapng_writer_tick(&w, 1000000000ull), 0);
    CHECK_EQ(file_size(p), head + 36);
    CHECK_EQ(pcapng_writer_telegram(&w, 1000000010ull, sc, sizeof sc), 0);
    CHECK_EQ(pcapng_writer_tick(&w, 1999999999ull), 0);
    CHECK_EQ(file_size(p), head + 36);
    CHECK_EQ(pcapng_writer_flush(&w), 0);
    CHECK_EQ(file_size(p), head + 72);
    CHECK_EQ(pcapng_writer_close(&w), 0);
}

/* The file may grow to 4 KiB: the writes that cross it fail with EFBIG. */
static int full_writer(const char *p)
{
    check_test_name_ = "full_writer (child)";
    (void)signal(SIGXFSZ, SIG_IGN);
    struct rlimit lim = {.rlim_cur = 4096, .rlim_max = 4096};
    CHECK_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {0};
    CHECK_EQ(pcapng_writer_open(&w, p, &opt, err, sizeof err), 0);
    CHECK(pcapng_writer_error(&w) == NULL);
    unsigned failed_at = 0;
    for (unsigned i = 1; i <= 300u && failed_at == 0u; i++) {
        CHECK_EQ(pcapng_writer_telegram(&w, i, dx, sizeof dx), 0);
        if (pcapng_writer_flush(&w) != 0) {
            failed_at = i;
        }
    }
    CHECK(failed_at > 50u && failed_at < 300u); /* 48 octets a record, 4 KiB */
    char want[800];
    snprintf(want, sizeof want, "cannot write capture file %s: File too large", p);
    CHECK_STR(pcapng_writer_error(&w), want);
    CHECK(pcapng_writer_error(&w) == NULL); /* told once */
    CHECK_EQ(pcapng_writer_telegram(&w, 1000, dx, sizeof dx), -1);
    CHECK_EQ(pcapng_writer_flush(&w), -1);
    CHECK(pcapng_writer_error(&w) == NULL);
    CHECK_EQ(w.dropped, 1);
    CHECK_EQ(pcapng_writer_close(&w), -1);
    return check_report();
}

static void test_failed_write_told_once(void)
{
    char p[600];
    path_of(p, sizeof p, "full.pcapng");
    fflush(stderr);
    pid_t pid = fork();
    if (pid == 0) {
        _exit(full_writer(p));
    }
    int status = 0;
    CHECK_EQ(waitpid(pid, &status, 0), pid);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    /* What was written before the limit still reads. */
    cap_reader_t r;
    char err[700] = "";
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_AUTO, err, sizeof err), 0);
    static cap_record_t rec;
    CHECK_EQ(cap_reader_next(&r, &rec), 1);
    CHECK_EQ(rec.t_ns, 1);
    cap_reader_close(&r);
}

static void test_refusals(void)
{
    char victim[600];
    path_of(victim, sizeof victim, "victim.txt");
    FILE *f = fopen(victim, "w");
    CHECK(f != NULL && fputs("keep\n", f) >= 0 && fclose(f) == 0);
    char p[600];
    path_of(p, sizeof p, "planted.pcapng");
    (void)unlink(p);
    CHECK_EQ(symlink(victim, p), 0);
    pcapng_writer_t w;
    char err[700] = "";
    pcapng_writer_opt_t opt = {0};
    CHECK_EQ(pcapng_writer_open(&w, p, &opt, err, sizeof err), -1);
    char want[800];
    snprintf(want, sizeof want, "cannot write capture file %s: a symbolic link: refused "
             "(dfp-sim writes no file through a link)", p);
    CHECK_STR(err, want);
    CHECK_EQ(file_size(victim), 5);
    opt.linktype = 1;
    CHECK_EQ(pcapng_writer_open(&w, victim, &opt, err, sizeof err), -1);
    CHECK_STR(err, "link type 1: only 257 (PROFIBUS_DL) and 147 (USER0)");
    opt.linktype = 0;
    CHECK_EQ(pcapng_writer_open(&w, "/nonexistent-dir/m.pcapng", &opt, err, sizeof err), -1);
    CHECK_STR(err, "cannot write capture file /nonexistent-dir/m.pcapng: "
                   "No such file or directory");
}

int main(int argc, char **argv)
{
    dir = argc > 1 ? argv[1] : ".";
    if (argc > 2 && strcmp(argv[2], "sample") == 0) {
        char p[600];
        path_of(p, sizeof p, "sample257.pcapng");
        write_sample(p, PCAP_LINKTYPE_PROFIBUS_DL);
        path_of(p, sizeof p, "sample147.pcapng");
        write_sample(p, PCAP_LINKTYPE_USER0);
        return check_report();
    }
    RUN_TEST(test_blocks_exact_bytes);
    RUN_TEST(test_read_back_through_the_capture_reader);
    RUN_TEST(test_killed_writer_leaves_whole_blocks);
    RUN_TEST(test_tick_flushes_once_a_second);
    RUN_TEST(test_failed_write_told_once);
    RUN_TEST(test_refusals);
    return check_report();
}
