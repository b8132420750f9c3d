/* LCM event logs read as captures (sim_host/capture/src/cap_lcm.c through capture.h): a log
 * written here with lcm_eventlog holding telegrams on two channels between events of other
 * types, read back record by record; then the same log damaged (truncated, a cut header,
 * garbage between events, a bad sync word, absurd lengths, a telegram that does not decode):
 * every damage ends the reading with the event number and byte offset, and the records before
 * it stay. Usage: test_cap_lcm DIR (a directory for the files). */
#include <lcm/eventlog.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cap_lcm.h" /* the backend's own interface, for cap_lcm_sniff */
#include "capture/capture.h"
#include "check.h"
#include "dfp_lcm/dfp_lcm_card_state_t.h"
#include "dfp_lcm/dfp_lcm_telegram_t.h"

static const char *dir = ".";

#define T0 1700000000000000LL /* µs since the epoch */

static void path_of(char *out, size_t max, const char *name)
{
    snprintf(out, max, "%s/%s", dir, name);
}

/* ---- writing a log ------------------------------------------------------------------------- */

typedef struct log_writer {
    lcm_eventlog_t *log;
    long offsets[16]; /* byte offset of each event, 1-based like the reader's event numbers */
    int events;
} log_writer_t;

static void raw_event(log_writer_t *w, const char *channel, int64_t timestamp, const void *data,
                      int32_t len)
{
    w->offsets[++w->events] = ftell(w->log->f);
    lcm_eventlog_event_t ev = {.timestamp = timestamp,
                               .channellen = (int32_t)strlen(channel),
                               .datalen = len,
                               .channel = (char *)channel,
                               .data = (void *)data};
    CHECK_EQ(lcm_eventlog_write_event(w->log, &ev), 0);
}

static void telegram_event(log_writer_t *w, const char *channel, int64_t utime, int8_t dir_,
                           int32_t baud, int16_t flags, const uint8_t *data, int16_t len)
{
    dfp_lcm_telegram_t m = {.utime = utime, .source_id = 77, .process_id = 1234, .station = 4,
                            .direction = dir_, .baud = baud, .error_flags = flags, .length = len,
                            .data = (uint8_t *)data};
    static uint8_t buf[1024];
    int n = dfp_lcm_telegram_t_encode(buf, 0, sizeof buf, &m);
    CHECK(n > 0);
    raw_event(w, channel, utime + 5, buf, n);
}

static const uint8_t req[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t bad_fcs[] = {0x10, 0x04, 0x02, 0x49, 0x50, 0x16};
static uint8_t long_record[600];

/* Events: 1 telegram, 2 card state, 3 a short foreign message, 4 telegram on SEG, 5 bad FCS,
 * 6 telegram without utime, 7 a 600-octet record. */
static long write_log(const char *path, log_writer_t *w)
{
    memset(w, 0, sizeof *w);
    w->log = lcm_eventlog_create(path, "w");
    CHECK(w->log != NULL);
    telegram_event(w, "DFP_TELEGRAM", T0, DFP_LCM_TELEGRAM_T_DIR_RX, 1500000, 0, req,
                   sizeof req);
    int32_t po[3] = {6, 1500, 0};
    dfp_lcm_card_state_t cs = {.utime = T0 + 100, .dp_state = (char *)"Data_Exch",
                               .led_run = (char *)"on", .led_bus_fault = (char *)"off",
                               .p090_pd_config = (char *)"3PD + PARAM",
                               .p091_fieldbus_type = (char *)"PROFIBUS DP", .pd_words = 3,
                               .po = po, .pi = po};
    uint8_t buf[512];
    int n = dfp_lcm_card_state_t_encode(buf, 0, sizeof buf, &cs);
    CHECK(n > 0);
    raw_event(w, "DFP_CARD_STATE", T0 + 100, buf, n);
    raw_event(w, "OTHER", T0 + 150, "abc", 3);
    telegram_event(w, "SEG", T0 + 250, DFP_LCM_TELEGRAM_T_DIR_TX, 1500000,
                   DFP_LCM_TELEGRAM_T_ERR_PARITY, (const uint8_t[]){0xE5}, 1);
    telegram_event(w, "DFP_TELEGRAM", T0 + 500, DFP_LCM_TELEGRAM_T_DIR_UNKNOWN, 0, 0, bad_fcs,
                   sizeof bad_fcs);
    telegram_event(w, "DFP_TELEGRAM", 0, DFP_LCM_TELEGRAM_T_DIR_RX, 19200, 0, req, sizeof req);
    for (size_t i = 0; i < sizeof long_record; i++) {
        long_record[i] = (uint8_t)i;
    }
    telegram_event(w, "DFP_TELEGRAM", T0 + 900, DFP_LCM_TELEGRAM_T_DIR_RX, 19200, 0,
                   long_record, (int16_t)sizeof long_record);
    long size = ftell(w->log->f);
    w->offsets[w->events + 1] = size;
    lcm_eventlog_destroy(w->log);
    return size;
}

/* Every channel unless one is named ("*" all, NULL: the reader's choice, its note in note). */
static const char *channel = "*";
static char note[240];

static void read_all(const char *path, cap_format_t format, cap_record_t *recs, int max,
                     int *count, int *last_rc, char *error, size_t error_max)
{
    cap_reader_t r;
    char err[512] = "";
    *count = 0;
    *last_rc = -2;
    error[0] = '\0';
    memset(&r, 0, sizeof r);
    if (cap_reader_open_channel(&r, path, format, channel, err, sizeof err) != 0) {
        snprintf(error, error_max, "open: %s", err);
        return;
    }
    snprintf(note, sizeof note, "%s", r.lcm_note);
    CHECK_EQ(r.format, CAP_FORMAT_LCM);
    static cap_record_t rec;
    int rc;
    while ((rc = cap_reader_next(&r, &rec)) == 1) {
        if (*count < max) {
            recs[*count] = rec;
        }
        (*count)++;
    }
    *last_rc = rc;
    snprintf(error, error_max, "%s", r.error);
    cap_reader_close(&r);
}

static cap_record_t recs[16];

static void test_log_read_back_exactly(void)
{
    char p[600];
    path_of(p, sizeof p, "good.lcm");
    log_writer_t w;
    write_log(p, &w);
    int n = 0;
    int rc = 0;
    char error[1024];
    read_all(p, CAP_FORMAT_AUTO, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, 5);
    CHECK_EQ(rc, 0);
    CHECK_STR(error, "");

    CHECK_EQ(recs[0].index, 1);
    CHECK_EQ(recs[0].position, 1);
    CHECK(recs[0].has_time);
    CHECK_EQ(recs[0].t_ns, (uint64_t)T0 * 1000u);
    CHECK_EQ(recs[0].baud, 1500000);
    CHECK_EQ(recs[0].dir, CAP_DIR_RX);
    CHECK_EQ(recs[0].error_flags, 0);
    CHECK_BYTES(recs[0].data, recs[0].len, 0x10, 0x04, 0x02, 0x49, 0x4F, 0x16);
    CHECK_EQ(recs[0].orig_len, 6);
    CHECK_STR(recs[0].problem, "");

    CHECK_EQ(recs[1].index, 2);
    CHECK_EQ(recs[1].position, 4); /* events 2 and 3 are not telegrams */
    CHECK_EQ(recs[1].t_ns, (uint64_t)(T0 + 250) * 1000u);
    CHECK_EQ(recs[1].dir, CAP_DIR_TX);
    CHECK_EQ(recs[1].error_flags, 0x01); /* HAL_UART_RX_PARITY_ERR */
    CHECK_BYTES(recs[1].data, recs[1].len, 0xE5);
    CHECK_STR(recs[1].problem, "");

    CHECK_EQ(recs[2].position, 5);
    CHECK_EQ(recs[2].dir, CAP_DIR_UNKNOWN);
    CHECK_EQ(recs[2].baud, 0);
    CHECK_BYTES(recs[2].data, recs[2].len, 0x10, 0x04, 0x02, 0x49, 0x50, 0x16);
    CHECK_STR(recs[2].problem, "bad FCS (0x50, computed 0x4F)");

    /* No utime: the log's own receive time (utime + 5 as written here, i.e. 5 µs). */
    CHECK_EQ(recs[3].position, 6);
    CHECK_EQ(recs[3].t_ns, 5000u);
    CHECK_EQ(recs[3].baud, 19200);

    CHECK_EQ(recs[4].position, 7);
    CHECK_EQ(recs[4].len, CAP_MAX_RECORD);
    CHECK_EQ(recs[4].orig_len, 600);
    CHECK_EQ(recs[4].data[511], 511 & 0xFF);
    CHECK_STR(recs[4].problem, "600 octets, longer than any telegram");

    /* The same when the format is named. */
    read_all(p, CAP_FORMAT_LCM, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, 5);
    CHECK_EQ(rc, 0);
}

/* ---- damaged logs --------------------------------------------------------------------------- */

static unsigned char *slurp(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    rewind(f);
    unsigned char *b = malloc((size_t)*size + 64u);
    CHECK_EQ(fread(b, 1, (size_t)*size, f), (size_t)*size);
    fclose(f);
    return b;
}

static void spill(const char *path, const unsigned char *b, long size)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    CHECK_EQ(fwrite(b, 1, (size_t)size, f), (size_t)size);
    fclose(f);
}

static void put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* Reads path as LCM and expects `records` records and then exactly the error `want` (with the
 * path in front). */
static void expect_damage(const char *name, const unsigned char *b, long size, int records,
                          const char *want)
{
    char p[600];
    path_of(p, sizeof p, name);
    spill(p, b, size);
    int n = 0;
    int rc = 0;
    char error[1024];
    read_all(p, CAP_FORMAT_LCM, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, records);
    CHECK_EQ(rc, -1);
    char full[1200];
    snprintf(full, sizeof full, "%s: %s", p, want);
    CHECK_STR(error, full);
}

static void test_damaged_logs(void)
{
    char p[600];
    path_of(p, sizeof p, "good.lcm");
    log_writer_t w;
    write_log(p, &w);
    long size = 0;
    unsigned char *good = slurp(p, &size);
    unsigned char *b = malloc((size_t)size + 64u);
    char want[300];

    /* The last event cut in its data. */
    long e7 = w.offsets[7];
    snprintf(want, sizeof want, "event 7 at byte %ld: truncated event: %ld octets, the file has "
             "%ld left", e7, size - e7, size - e7 - 100);
    expect_damage("cut.lcm", good, size - 100, 4, want);

    /* Cut inside the last event's header. */
    snprintf(want, sizeof want, "event 7 at byte %ld: truncated event header: 10 of 28 octets",
             e7);
    expect_damage("cut_header.lcm", good, e7 + 10, 4, want);

    /* Five octets of garbage between events 1 and 2. */
    long e2 = w.offsets[2];
    memcpy(b, good, (size_t)e2);
    memcpy(b + e2, "\x12\x34\x56\x78\x9A", 5);
    memcpy(b + e2 + 5, good + e2, (size_t)(size - e2));
    snprintf(want, sizeof want, "event 2 at byte %ld: bad sync word 0x12345678 (expected "
             "0xEDA1DA01): garbage or a damaged event", e2);
    expect_damage("garbage.lcm", b, size + 5, 1, want);

    /* A bad sync word at the very start. */
    memcpy(b, good, (size_t)size);
    b[0] = 0xEE;
    expect_damage("bad_sync.lcm", b, size, 0,
                  "event 1 at byte 0: bad sync word 0xEEA1DA01 (expected 0xEDA1DA01): garbage "
                  "or a damaged event");

    /* Event 4's data length 2^31 - 16: the reader must not believe it. */
    long e4 = w.offsets[4];
    memcpy(b, good, (size_t)size);
    put_be32(b + e4 + 24, 0x7FFFFFF0u);
    snprintf(want, sizeof want, "event 4 at byte %ld: truncated event: %lld octets, the file has "
             "%ld left", e4, 28LL + 3 + 0x7FFFFFF0LL, size - e4);
    expect_damage("huge.lcm", b, size, 1, want);
    put_be32(b + e4 + 24, 0xFFFFFFF0u);
    snprintf(want, sizeof want, "event 4 at byte %ld: data length 4294967280 out of range", e4);
    expect_damage("negative.lcm", b, size, 1, want);
    memcpy(b, good, (size_t)size);
    put_be32(b + e4 + 20, 0);
    snprintf(want, sizeof want, "event 4 at byte %ld: channel name length 0 out of range "
             "(1..999)", e4);
    expect_damage("channel0.lcm", b, size, 1, want);

    /* A telegram whose own length field is negative: lcm-gen's decoder would copy 4 GB. The
     * message starts after the 28-octet header and the channel name "DFP_TELEGRAM". */
    memcpy(b, good, (size_t)size);
    long len_field = w.offsets[1] + 28 + 12 + 37;
    b[len_field] = 0xFF;
    b[len_field + 1] = 0xFA;
    expect_damage("bad_telegram.lcm", b, size, 0,
                  "event 1 at byte 0: channel DFP_TELEGRAM: telegram_t length field -6");

    /* A telegram with no octets: lcm-gen's decoder would pass memcpy a NULL buffer. */
    {
        char p0[600];
        path_of(p0, sizeof p0, "empty_telegram.lcm");
        log_writer_t w0;
        memset(&w0, 0, sizeof w0);
        w0.log = lcm_eventlog_create(p0, "w");
        CHECK(w0.log != NULL);
        telegram_event(&w0, "DFP_TELEGRAM", T0, DFP_LCM_TELEGRAM_T_DIR_RX, 1500000, 0, req,
                       sizeof req);
        telegram_event(&w0, "SEG", T0 + 10, DFP_LCM_TELEGRAM_T_DIR_RX, 1500000, 0, req, 0);
        long size0 = ftell(w0.log->f);
        lcm_eventlog_destroy(w0.log);
        unsigned char *b0 = slurp(p0, &size0);
        snprintf(want, sizeof want, "event 2 at byte %ld: channel SEG: telegram_t length 0: a "
                 "telegram has at least one octet", w0.offsets[2]);
        expect_damage("empty_telegram.lcm", b0, size0, 1, want);
        free(b0);
    }

    /* Garbage only. */
    for (int i = 0; i < 200; i++) {
        b[i] = (unsigned char)(i * 37 + 11);
    }
    expect_damage("noise.lcm", b, 200, 0,
                  "event 1 at byte 0: bad sync word 0x0B30557A (expected 0xEDA1DA01): garbage "
                  "or a damaged event");
    free(b);
    free(good);
}

/* A log with the card's telemetry (DFP_TELEGRAM) and a segment's frames (SEG): unless told, the
 * reader takes DFP_TELEGRAM alone and says so; a named channel is read alone; a channel without
 * telegrams is refused with the ones there are. */
static void test_channel_choice(void)
{
    char p[600];
    path_of(p, sizeof p, "two_channels.lcm");
    log_writer_t w;
    write_log(p, &w);
    int n = 0;
    int rc = 0;
    char error[1024];
    channel = NULL;
    read_all(p, CAP_FORMAT_AUTO, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, 4);
    CHECK_EQ(rc, 0);
    CHECK_EQ(recs[0].position, 1);
    CHECK_EQ(recs[1].position, 5); /* event 4 is on SEG */
    CHECK_STR(note, "LCM log: read channel DFP_TELEGRAM (the card's telemetry); not read: SEG "
                    "(--channel NAME, or '*' for all)");
    channel = "SEG";
    read_all(p, CAP_FORMAT_AUTO, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, 1);
    CHECK_EQ(recs[0].position, 4);
    CHECK_BYTES(recs[0].data, recs[0].len, 0xE5);
    CHECK_STR(note, "");
    channel = "OTHER"; /* has events, but no telegram_t */
    read_all(p, CAP_FORMAT_AUTO, recs, 16, &n, &rc, error, sizeof error);
    char want[800];
    snprintf(want, sizeof want, "open: %s: no telegram_t on LCM channel 'OTHER' (channels with "
             "telegrams: DFP_TELEGRAM, SEG)", p);
    CHECK_STR(error, want);
    CHECK_EQ(n, 0);
    /* One telegram channel only: read as it is, nothing to say. */
    path_of(p, sizeof p, "one_channel.lcm");
    memset(&w, 0, sizeof w);
    w.log = lcm_eventlog_create(p, "w");
    CHECK(w.log != NULL);
    telegram_event(&w, "SEG", T0, DFP_LCM_TELEGRAM_T_DIR_TX, 1500000, 0, req, sizeof req);
    lcm_eventlog_destroy(w.log);
    channel = NULL;
    read_all(p, CAP_FORMAT_AUTO, recs, 16, &n, &rc, error, sizeof error);
    CHECK_EQ(n, 1);
    CHECK_STR(note, "");
    channel = "*";
}

static void test_empty_and_missing(void)
{
    char p[600];
    path_of(p, sizeof p, "empty.lcm");
    spill(p, (const unsigned char *)"", 0);
    cap_reader_t r;
    memset(&r, 0, sizeof r);
    char err[512] = "";
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_LCM, err, sizeof err), 0);
    cap_record_t rec;
    CHECK_EQ(cap_reader_next(&r, &rec), 0);
    CHECK_EQ(r.records, 0);
    cap_reader_close(&r);
    path_of(p, sizeof p, "missing.lcm");
    memset(&r, 0, sizeof r);
    CHECK_EQ(cap_reader_open(&r, p, CAP_FORMAT_LCM, err, sizeof err), -1);
    CHECK(strstr(err, "missing.lcm") != NULL);
}

static void test_sniff(void)
{
    const uint8_t lcm[] = {0xED, 0xA1, 0xDA, 0x01, 0x00};
    const uint8_t pcap[] = {0xD4, 0xC3, 0xB2, 0xA1};
    CHECK(cap_lcm_sniff(lcm, sizeof lcm));
    CHECK(!cap_lcm_sniff(pcap, sizeof pcap));
    CHECK(!cap_lcm_sniff(lcm, 3));
}

int main(int argc, char **argv)
{
    if (argc > 1) {
        dir = argv[1];
    }
    RUN_TEST(test_log_read_back_exactly);
    RUN_TEST(test_damaged_logs);
    RUN_TEST(test_channel_choice);
    RUN_TEST(test_empty_and_missing);
    RUN_TEST(test_sniff);
    return check_report();
}
