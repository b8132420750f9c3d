/* dfp-seg-auth-bench: what --key costs per telegram on an LCM segment (docs/performance.md):
 * encoding a telegram_t and signing it (the sender), parsing, verifying and decoding it (each
 * receiver), against the plain encode and checked decode of an unkeyed segment, for three frame
 * sizes: a short acknowledgement (1 octet), a Data_Exchange of Param + 3 PD (23 octets) and the
 * largest SD2 frame (255 octets). The receiver's sender table holds 32 senders, as a segment of
 * 32 slaves and a master does.
 *
 * Usage: dfp-seg-auth-bench [--telegrams N]   (default 200 000 per size) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "lcm_bridge/seg_auth.h"
#include "lcm_bridge/telegram_decode.h"

#include <sodium.h>

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int64_t wall_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static size_t encode(const uint8_t *frame, size_t len, int64_t source, uint8_t *out)
{
    dfp_lcm_telegram_t m = {.utime = wall_us(), .source_id = source, .process_id = 1,
                            .station = 2, .direction = DFP_LCM_TELEGRAM_T_DIR_TX,
                            .baud = 19200, .length = (int16_t)len, .data = (uint8_t *)frame};
    return (size_t)dfp_lcm_telegram_t_encode(out, 0, DFP_SEG_TELEGRAM_MAX, &m);
}

/* ns per telegram: plain (encode + checked decode) and keyed (encode + sign, parse + verify +
 * checked decode). */
static void run(size_t frame_len, long n, dfp_seg_auth_t *tx, dfp_seg_auth_t *rx)
{
    uint8_t frame[255];
    memset(frame, 0x5A, sizeof frame);
    uint8_t t[DFP_SEG_TELEGRAM_MAX];
    uint8_t s[DFP_SEG_SIGNED_MAX];
    dfp_lcm_telegram_t d;
    char why[96];
    long bad = 0;
    double t0 = now_s();
    for (long i = 0; i < n; i++) {
        size_t tl = encode(frame, frame_len, 7, t);
        bad += dfp_lcm_telegram_decode_checked(t, tl, &d, why, sizeof why) != 0;
        dfp_lcm_telegram_t_decode_cleanup(&d);
    }
    double t1 = now_s();
    size_t sl = 0;
    for (long i = 0; i < n; i++) {
        size_t tl = encode(frame, frame_len, 7, t);
        int64_t seq = dfp_seg_next_seq(tx, wall_us());
        sl = dfp_seg_sign(tx, "SEG", 7, seq, t, tl, s, sizeof s);
        dfp_seg_msg_t m;
        bad += dfp_seg_parse(s, sl, &m) != 0 ||
               dfp_seg_verify(rx, "SEG", s, sl, &m, wall_us()) != -1;
        bad += dfp_lcm_telegram_decode_checked(m.telegram, m.tlen, &d, why, sizeof why) != 0;
        dfp_lcm_telegram_t_decode_cleanup(&d);
    }
    double t2 = now_s();
    double plain = (t1 - t0) / (double)n * 1e9;
    double keyed = (t2 - t1) / (double)n * 1e9;
    printf("frame %3zu octets (message %3zu plain, %3zu signed): plain %6.0f ns, keyed %6.0f ns, "
           "--key adds %6.0f ns per telegram%s\n", frame_len, encode(frame, frame_len, 7, t), sl,
           plain, keyed, keyed - plain, bad != 0 ? " (FAILURES)" : "");
}

int main(int argc, char **argv)
{
    long n = 200000;
    if (argc == 3 && strcmp(argv[1], "--telegrams") == 0) {
        n = strtol(argv[2], NULL, 10);
    }
    if ((argc != 1 && argc != 3) || (argc == 3 && strcmp(argv[1], "--telegrams") != 0) ||
        n <= 0) {
        fprintf(stderr, "usage: dfp-seg-auth-bench [--telegrams N]\n");
        return 2;
    }
    static dfp_seg_auth_t tx;
    static dfp_seg_auth_t rx;
    const uint8_t key[DFP_SEG_KEY_BYTES] = {42};
    if (dfp_seg_auth_init(&tx, key) != 0 || dfp_seg_auth_init(&rx, key) != 0) {
        fprintf(stderr, "dfp-seg-auth-bench: libsodium cannot start\n");
        return 1;
    }
    /* 31 other senders in the receiver's table, as on a segment of 32 slaves and a master. */
    for (int64_t id = 100; id < 131; id++) {
        rx.senders[rx.num_senders++] = (dfp_seg_sender_t){.id = id, .last_seq = wall_us()};
    }
    printf("%ld telegrams per size, HMAC-SHA-512-256 (libsodium %s)\n", n,
           sodium_version_string());
    run(1, n, &tx, &rx);
    run(23, n, &tx, &rx);
    run(255, n, &tx, &rx);
    return 0;
}
