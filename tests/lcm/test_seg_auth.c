/* Keyed LCM segments (seg_auth.h, lcm_segment.h): the signed layout, the tag over channel and
 * message, the clock window, the per-sender sequence and its bounded table, key files, the
 * rate-limited drop log; and a segment over memq:// fed octets as LCM would deliver them, with
 * exact counts of what its station heard and what it dropped, by reason. */
#include <fcntl.h>
#include <lcm/lcm.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "dfp_lcm/dfp_lcm_signed_telegram_t.h"
#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "lcm_bridge/lcm_bridge.h"
#include "sim_hal/tty_port.h"
#include "lcm_bridge/lcm_segment.h"
#include "lcm_bridge/seg_auth.h"
#include "lcm_bridge/telegram_decode.h"

#define NOW 1700000000000000LL /* µs since the epoch: a receiver's clock in these tests */

static const uint8_t key1[DFP_SEG_KEY_BYTES] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14,
                                                 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25,
                                                 26, 27, 28, 29, 30, 31, 32};
static const uint8_t key2[DFP_SEG_KEY_BYTES] = {99};

/* An encoded telegram_t of frame from source. */
static size_t telegram(int64_t source, const uint8_t *frame, size_t len, uint8_t *out)
{
    dfp_lcm_telegram_t m = {.utime = NOW, .source_id = source, .process_id = 7, .station = 2,
                            .direction = DFP_LCM_TELEGRAM_T_DIR_TX, .baud = 19200,
                            .length = (int16_t)len, .data = (uint8_t *)frame};
    return (size_t)dfp_lcm_telegram_t_encode(out, 0, DFP_SEG_TELEGRAM_MAX, &m);
}

static const uint8_t sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16}; /* FDL status 2 -> 4 */

static size_t signed_msg(const uint8_t *key, const char *channel, int64_t source, int64_t seq,
                         uint8_t *out)
{
    dfp_seg_auth_t a;
    CHECK_EQ(dfp_seg_auth_init(&a, key), 0);
    uint8_t t[DFP_SEG_TELEGRAM_MAX];
    size_t tl = telegram(source, sd1, sizeof sd1, t);
    return dfp_seg_sign(&a, channel, source, seq, t, tl, out, DFP_SEG_SIGNED_MAX);
}

static int verify(dfp_seg_auth_t *a, const char *channel, const uint8_t *buf, size_t len,
                  int64_t now)
{
    dfp_seg_msg_t m;
    if (dfp_seg_parse(buf, len, &m) != 0) {
        return 100;
    }
    return dfp_seg_verify(a, channel, buf, len, &m, now);
}

static void test_layout_is_lcm_gens(void)
{
    uint8_t buf[DFP_SEG_SIGNED_MAX];
    size_t n = signed_msg(key1, "SEG", 77, NOW, buf);
    uint8_t t[DFP_SEG_TELEGRAM_MAX];
    size_t tl = telegram(77, sd1, sizeof sd1, t);
    CHECK_EQ(n, DFP_SEG_HEAD + tl + DFP_SEG_TAG);
    /* lcm-gen's decoder reads the same fields: the layout is the .lcm type's. */
    dfp_lcm_signed_telegram_t d;
    CHECK_EQ(dfp_lcm_signed_telegram_t_decode(buf, 0, (int)n, &d), (int)n);
    CHECK_EQ(d.version, 1);
    CHECK_EQ(d.sender_id, 77);
    CHECK_EQ(d.sequence, NOW);
    CHECK_EQ(d.length, (int)tl);
    CHECK(memcmp(d.telegram, t, tl) == 0);
    dfp_lcm_signed_telegram_t_decode_cleanup(&d);
    CHECK(dfp_seg_is_signed(buf, n));
    CHECK(!dfp_seg_is_signed(t, tl));
    /* A wrong length field or version is malformed, before any tag is computed. */
    buf[26]++;
    CHECK_EQ(verify(NULL, "SEG", buf, n, NOW), 100);
    buf[26]--;
    buf[8] = 2;
    CHECK_EQ(verify(NULL, "SEG", buf, n, NOW), 100);
    CHECK_EQ(verify(NULL, "SEG", buf, n - 1u, NOW), 100);
}

static void test_tag_covers_key_channel_and_octets(void)
{
    dfp_seg_auth_t rx;
    CHECK_EQ(dfp_seg_auth_init(&rx, key1), 0);
    uint8_t buf[DFP_SEG_SIGNED_MAX];
    size_t n = signed_msg(key1, "SEG", 77, NOW, buf);
    CHECK_EQ(verify(&rx, "SEGX", buf, n, NOW), DFP_SEG_DROP_BAD_TAG);
    CHECK_EQ(verify(&rx, "SE", buf, n, NOW), DFP_SEG_DROP_BAD_TAG);
    n = signed_msg(key2, "SEG", 77, NOW, buf);
    CHECK_EQ(verify(&rx, "SEG", buf, n, NOW), DFP_SEG_DROP_BAD_TAG);
    n = signed_msg(key1, "SEG", 77, NOW, buf);
    for (size_t i = 8; i < n; i++) { /* every octet after the fingerprint counts */
        buf[i] ^= 0x01u;
        int r = verify(&rx, "SEG", buf, n, NOW);
        CHECK(r == DFP_SEG_DROP_BAD_TAG || r == 100);
        buf[i] ^= 0x01u;
    }
    CHECK_EQ(rx.num_senders, 0); /* nothing without a good tag reaches the sender table */
    CHECK_EQ(verify(&rx, "SEG", buf, n, NOW), -1);
    CHECK_EQ(rx.num_senders, 1);
}

static void test_window_and_sequence(void)
{
    dfp_seg_auth_t rx;
    CHECK_EQ(dfp_seg_auth_init(&rx, key1), 0);
    uint8_t buf[DFP_SEG_SIGNED_MAX];
    size_t n = signed_msg(key1, "S", 5, NOW - DFP_SEG_WINDOW_US - 1, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), DFP_SEG_DROP_STALE);
    n = signed_msg(key1, "S", 5, NOW + DFP_SEG_WINDOW_US + 1, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), DFP_SEG_DROP_STALE);
    n = signed_msg(key1, "S", 5, NOW - DFP_SEG_WINDOW_US, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), -1);
    n = signed_msg(key1, "S", 5, NOW, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), -1);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), DFP_SEG_DROP_REPLAYED); /* the same again */
    n = signed_msg(key1, "S", 5, NOW - 1, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), DFP_SEG_DROP_REPLAYED); /* an older one */
    n = signed_msg(key1, "S", 6, NOW - 1, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), -1); /* another sender has its own sequence */
    /* The sender's side: strictly increasing whatever the clock does. */
    dfp_seg_auth_t tx;
    CHECK_EQ(dfp_seg_auth_init(&tx, key1), 0);
    CHECK_EQ(dfp_seg_next_seq(&tx, NOW), NOW);
    CHECK_EQ(dfp_seg_next_seq(&tx, NOW), NOW + 1);
    CHECK_EQ(dfp_seg_next_seq(&tx, NOW - 500), NOW + 2);
    CHECK_EQ(dfp_seg_next_seq(&tx, NOW + 10), NOW + 10);
}

static void test_sender_table_bounded(void)
{
    static dfp_seg_auth_t rx;
    CHECK_EQ(dfp_seg_auth_init(&rx, key1), 0);
    uint8_t buf[DFP_SEG_SIGNED_MAX];
    size_t n;
    for (int64_t id = 1; id <= (int64_t)DFP_SEG_SENDERS; id++) {
        n = signed_msg(key1, "S", id, NOW - 1000000, buf);
        CHECK_EQ(verify(&rx, "S", buf, n, NOW), -1);
    }
    /* Full, and every entry could still be replayed within the window: a new one is refused. */
    n = signed_msg(key1, "S", 1000, NOW, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, NOW), DFP_SEG_DROP_SENDERS_FULL);
    /* 1.5 s later the old entries are out of the window: one of them makes room. */
    int64_t later = NOW + 1500000;
    n = signed_msg(key1, "S", 1000, later, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, later), -1);
    CHECK_EQ(rx.num_senders, DFP_SEG_SENDERS);
    /* The evicted sender's old telegram is still refused: out of the window. */
    n = signed_msg(key1, "S", 1, NOW - 1000000, buf);
    CHECK_EQ(verify(&rx, "S", buf, n, later), DFP_SEG_DROP_STALE);
}

static void write_file(const char *path, const char *text, mode_t mode)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    CHECK(fd >= 0);
    CHECK_EQ(write(fd, text, strlen(text)), (long long)strlen(text));
    close(fd);
    CHECK_EQ(chmod(path, mode), 0);
}

static void test_key_files(void)
{
    char dir[] = "/tmp/test_seg_auth.XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[64]; /* "/tmp/test_seg_auth.XXXXXX/k" */
    char err[400];
    char want[400];
    uint8_t key[DFP_SEG_KEY_BYTES];
    snprintf(path, sizeof path, "%s/k", dir);
    write_file(path, "0102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F20\n", 0600);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), 0);
    CHECK(memcmp(key, key1, sizeof key) == 0);
    write_file(path, "0102030405060708090a0b0c0d0e0f10111213141516171819", 0600);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), -1);
    snprintf(want, sizeof want, "--key %s: 50 hex digits, a key is 64 (32 octets) (head -c 32 "
             "/dev/urandom | od -An -tx1 | tr -d ' \\n' >FILE; chmod 600 FILE)", path);
    CHECK_STR(err, want);
    write_file(path, "0102030405060708090a0b0c0d0e0f10111213141516171819 A1B1C1D1E1F20\n", 0600);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), -1);
    CHECK(strstr(err, "not hex digits on one line (character 51)") != NULL);
    write_file(path, "", 0600);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), -1);
    CHECK(strstr(err, ": 0 hex digits, a key is 64") != NULL);
    write_file(path, "0102030405060708090a0b0c0d0e0f10111213141516171819a1b1c1d1e1f20\n", 0604);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), -1);
    snprintf(want, sizeof want, "--key %s: readable by others than its owner (mode 0604): "
             "chmod 600 %s", path, path);
    CHECK_STR(err, want);
    unlink(path);
    CHECK_EQ(dfp_seg_key_load(path, key, err, sizeof err), -1);
    snprintf(want, sizeof want, "--key %s: No such file or directory", path);
    CHECK_STR(err, want);
    rmdir(dir);
}

static char lines[8][320];
static int nlines;
static void keep_line(void *ctx, const char *line)
{
    (void)ctx;
    if (nlines < 8) {
        snprintf(lines[nlines], sizeof lines[0], "%s", line);
    }
    nlines++;
}

static void test_drop_log_rate_limited(void)
{
    dfp_seg_drops_t d = {0};
    nlines = 0;
    dfp_seg_drops_add(&d, DFP_SEG_DROP_UNSIGNED, "S", "station 2", 0, keep_line, NULL);
    for (int i = 0; i < 500; i++) { /* a flood within the second: no line */
        dfp_seg_drops_add(&d, i % 2 ? DFP_SEG_DROP_REPLAYED : DFP_SEG_DROP_UNSIGNED, "S", "",
                          1000 + i, keep_line, NULL);
    }
    dfp_seg_drops_flush(&d, "S", 999999, keep_line, NULL);
    CHECK_EQ(nlines, 1);
    dfp_seg_drops_flush(&d, "S", 1000000, keep_line, NULL);
    CHECK_EQ(nlines, 2);
    dfp_seg_drops_flush(&d, "S", 3000000, keep_line, NULL); /* nothing new: no line */
    CHECK_EQ(nlines, 2);
    CHECK_STR(lines[0], "segment S: dropped a telegram: unsigned, station 2 (further drops: a "
                        "summary at most every second)");
    CHECK_STR(lines[1], "segment S: 500 more dropped (unsigned 250, replayed 250)");
    CHECK_EQ(d.total[DFP_SEG_DROP_UNSIGNED], 251);
    CHECK_EQ(d.total[DFP_SEG_DROP_REPLAYED], 250);
}

/* ---- a segment over memq://, fed as LCM delivers ---- */

static int heard;
static void count_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    (void)ctx;
    (void)byte;
    (void)t;
    if (flags == 0u) {
        heard++;
    }
}

static void open_segment(dfp_lcm_segment_t *s, const uint8_t *key)
{
    char err[320];
    CHECK_EQ(dfp_lcm_segment_open(s, "memq://", "SEG", 4, 19200, err, sizeof err), 0);
    if (key != NULL) {
        CHECK_EQ(dfp_lcm_segment_set_key(s, key), 0);
    }
    dfp_lcm_segment_set_log(s, keep_line, NULL);
    s->station = (sim_station_t){.rx_char = count_rx};
    s->station_attached = true;
    heard = 0;
    nlines = 0;
}

static void test_keyed_segment_counts(void)
{
    static dfp_lcm_segment_t s;
    open_segment(&s, key1);
    uint8_t buf[DFP_SEG_SIGNED_MAX];
    int64_t now = dfp_lcm_wall_us();
    size_t n = signed_msg(key1, "SEG", 9, now, buf);
    dfp_lcm_segment_receive(&s, buf, n);
    dfp_lcm_segment_receive(&s, buf, n);                       /* replayed */
    dfp_lcm_segment_receive(&s, buf, signed_msg(key2, "SEG", 9, now + 1, buf)); /* bad tag */
    dfp_lcm_segment_receive(&s, buf, signed_msg(key1, "OTHER", 9, now + 2, buf));
    dfp_lcm_segment_receive(&s, buf, signed_msg(key1, "SEG", 9, now - 3000000, buf)); /* stale */
    uint8_t t[DFP_SEG_TELEGRAM_MAX];
    dfp_lcm_segment_receive(&s, t, telegram(9, sd1, sizeof sd1, t)); /* unsigned */
    dfp_lcm_segment_receive(&s, (const uint8_t *)"garbage!", 8);
    /* Signed, but by another sender than the telegram inside names. */
    dfp_seg_auth_t a;
    CHECK_EQ(dfp_seg_auth_init(&a, key1), 0);
    dfp_lcm_segment_receive(&s, buf, dfp_seg_sign(&a, "SEG", 10, now + 3, t,
                                                  telegram(9, sd1, sizeof sd1, t), buf,
                                                  sizeof buf));
    CHECK_EQ(heard, (int)sizeof sd1);
    CHECK_EQ(s.frames_received, 1);
    const uint64_t want[DFP_SEG_DROP_REASONS] = {1, 0, 2, 1, 1, 0, 2};
    CHECK(memcmp(s.drops.total, want, sizeof want) == 0);
    /* Its totals at close; the first drop was logged at once. */
    CHECK_EQ(nlines, 1);
    dfp_lcm_segment_close(&s);
    CHECK_EQ(nlines, 2);
    CHECK_STR(lines[1], "segment SEG (keyed): 1 telegrams taken, 7 dropped (unsigned 1, "
                        "signed 0, bad signature 2, stale 1, replayed 1, senders full 0, malformed 2)");
}

static uint8_t sent[DFP_SEG_SIGNED_MAX];
static size_t sent_len;
static void keep_sent(const lcm_recv_buf_t *rbuf, const char *channel, void *user)
{
    (void)channel;
    (void)user;
    sent_len = rbuf->data_size <= sizeof sent ? rbuf->data_size : 0u;
    memcpy(sent, rbuf->data, sent_len);
}

/* What a keyed segment sends is signed for its channel: a keyed receiver takes it once, a plain
 * one drops it as signed; a plain segment's telegram is dropped by a keyed one as unsigned. */
static void test_sent_telegrams(void)
{
    static dfp_lcm_segment_t tx;
    static dfp_lcm_segment_t rx;
    open_segment(&tx, key1);
    CHECK(lcm_subscribe(tx.lcm, "SEG", keep_sent, NULL) != NULL);
    hal_uart_t u = dfp_lcm_segment_uart(&tx);
    /* Now, on the port's clock: it wraps (32 bits of us), so 0 is no fixed "past". */
    CHECK_EQ(u.ops->transmit(u.ctx, sd1, sizeof sd1, tty_now_us()), 0);
    CHECK_EQ(lcm_handle_timeout(tx.lcm, 100), 1);
    CHECK_EQ(tx.own_ignored, 1);
    CHECK(dfp_seg_is_signed(sent, sent_len));
    CHECK_EQ(sent_len, DFP_SEG_HEAD + DFP_LCM_TELEGRAM_FIXED + sizeof sd1 + DFP_SEG_TAG);
    open_segment(&rx, key1);
    dfp_lcm_segment_receive(&rx, sent, sent_len);
    dfp_lcm_segment_receive(&rx, sent, sent_len);
    CHECK_EQ(heard, (int)sizeof sd1);
    CHECK_EQ(rx.drops.total[DFP_SEG_DROP_REPLAYED], 1);
    dfp_lcm_segment_close(&rx);
    open_segment(&rx, NULL);
    dfp_lcm_segment_receive(&rx, sent, sent_len);
    CHECK_EQ(heard, 0);
    CHECK_EQ(rx.drops.total[DFP_SEG_DROP_SIGNED], 1);
    dfp_lcm_segment_close(&rx);
    dfp_lcm_segment_close(&tx);
    /* A plain sender's telegram on a keyed segment. */
    open_segment(&tx, NULL);
    CHECK(lcm_subscribe(tx.lcm, "SEG", keep_sent, NULL) != NULL);
    u = dfp_lcm_segment_uart(&tx);
    CHECK_EQ(u.ops->transmit(u.ctx, sd1, sizeof sd1, tty_now_us()), 0);
    CHECK_EQ(lcm_handle_timeout(tx.lcm, 100), 1);
    CHECK(dfp_lcm_is_telegram(sent, sent_len));
    open_segment(&rx, key1);
    dfp_lcm_segment_receive(&rx, sent, sent_len);
    CHECK_EQ(heard, 0);
    CHECK_EQ(rx.drops.total[DFP_SEG_DROP_UNSIGNED], 1);
    dfp_lcm_segment_close(&rx);
    dfp_lcm_segment_close(&tx);
}

int main(void)
{
    RUN_TEST(test_layout_is_lcm_gens);
    RUN_TEST(test_tag_covers_key_channel_and_octets);
    RUN_TEST(test_window_and_sequence);
    RUN_TEST(test_sender_table_bounded);
    RUN_TEST(test_key_files);
    RUN_TEST(test_drop_log_rate_limited);
    RUN_TEST(test_keyed_segment_counts);
    RUN_TEST(test_sent_telegrams);
    return check_report();
}
