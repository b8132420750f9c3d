/* A station that is no dfp-sim, for the keyed-segment tests (test_lcm_keys.sh): puts PROFIBUS
 * frames on an LCM segment as plain telegram_t, or signed with a key file (optionally for
 * another channel than the one it publishes on), and saves what it published so that it can be
 * published again byte for byte (a recording played back).
 *
 * usage: lcm_seg_inject URL CHANNEL plain|sign:KEYFILE[:SIGN_CHANNEL]|replay:FILE
 *                       [--save FILE] [HEXFRAME ...]
 * Frames are hex without spaces; 20 ms apart. Prints "published N". Exit 0, 1 when LCM fails,
 * 2 for a bad argument. */
#include <errno.h>
#include <lcm/lcm.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

#include "dfp_lcm/dfp_lcm_telegram_t.h"
#include "lcm_bridge/seg_auth.h"

#define MAX_MSG DFP_SEG_SIGNED_MAX

static int64_t wall_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void pause_ms(long ms)
{
    struct timespec ts = {.tv_sec = 0, .tv_nsec = ms * 1000000L};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

static size_t unhex(const char *text, uint8_t *out, size_t max)
{
    size_t n = strlen(text);
    if (n == 0u || n % 2u != 0u || n / 2u > max) {
        return 0;
    }
    for (size_t i = 0; i < n / 2u; i++) {
        unsigned v;
        if (sscanf(text + 2u * i, "%2x", &v) != 1) {
            return 0;
        }
        out[i] = (uint8_t)v;
    }
    return n / 2u;
}

/* The message for one frame: a telegram_t, signed when auth is given. 0 on failure. */
static size_t build(const uint8_t *frame, size_t len, int64_t source_id, dfp_seg_auth_t *auth,
                    const char *sign_channel, uint8_t *out)
{
    int16_t station = len >= 6u && frame[0] == 0x68u ? (int16_t)(frame[5] & 0x7Fu) : -1;
    dfp_lcm_telegram_t m = {.utime = wall_us(), .source_id = source_id, .process_id = 1,
                            .station = station, .direction = DFP_LCM_TELEGRAM_T_DIR_TX,
                            .baud = 19200, .length = (int16_t)len, .data = (uint8_t *)frame};
    uint8_t plain[DFP_SEG_TELEGRAM_MAX];
    int n = dfp_lcm_telegram_t_encode(plain, 0, (int)sizeof plain, &m);
    if (n <= 0) {
        return 0;
    }
    if (auth == NULL) {
        memcpy(out, plain, (size_t)n);
        return (size_t)n;
    }
    return dfp_seg_sign(auth, sign_channel, source_id, dfp_seg_next_seq(auth, m.utime), plain,
                        (size_t)n, out, MAX_MSG);
}

static int publish(lcm_t *lcm, const char *channel, const uint8_t *msg, size_t len, FILE *save)
{
    if (lcm_publish(lcm, channel, msg, (unsigned)len) != 0) {
        fprintf(stderr, "lcm_seg_inject: publishing failed\n");
        return -1;
    }
    if (save != NULL) {
        uint8_t hdr[2] = {(uint8_t)(len >> 8), (uint8_t)len};
        (void)fwrite(hdr, 1, 2, save);
        (void)fwrite(msg, 1, len, save);
    }
    pause_ms(20);
    return 0;
}

static int replay(lcm_t *lcm, const char *channel, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "lcm_seg_inject: %s: %s\n", path, strerror(errno));
        return 2;
    }
    uint8_t hdr[2];
    uint8_t msg[MAX_MSG];
    int count = 0;
    while (fread(hdr, 1, 2, f) == 2u) {
        size_t len = (size_t)hdr[0] << 8 | hdr[1];
        if (len > sizeof msg || fread(msg, 1, len, f) != len ||
            publish(lcm, channel, msg, len, NULL) != 0) {
            fclose(f);
            return 1;
        }
        count++;
    }
    fclose(f);
    printf("published %d\n", count);
    return 0;
}

/* mode "sign:KEY[:CH]": the key and the channel the tag is for. */
static int sign_mode(const char *mode, const char *channel, dfp_seg_auth_t *auth, char *sign_ch,
                     size_t n)
{
    char path[512];
    snprintf(path, sizeof path, "%s", mode + 5);
    char *colon = strchr(path, ':');
    snprintf(sign_ch, n, "%s", colon != NULL ? colon + 1 : channel);
    if (colon != NULL) {
        *colon = '\0';
    }
    uint8_t key[DFP_SEG_KEY_BYTES];
    char err[400];
    if (dfp_seg_key_load(path, key, err, sizeof err) != 0 || dfp_seg_auth_init(auth, key) != 0) {
        fprintf(stderr, "lcm_seg_inject: %s\n", err);
        return -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: lcm_seg_inject URL CHANNEL plain|sign:KEY[:CH]|replay:FILE "
                        "[--save FILE] [HEXFRAME ...]\n");
        return 2;
    }
    const char *channel = argv[2];
    const char *mode = argv[3];
    static dfp_seg_auth_t auth;
    char sign_ch[64];
    bool signing = strncmp(mode, "sign:", 5) == 0;
    if (signing && sign_mode(mode, channel, &auth, sign_ch, sizeof sign_ch) != 0) {
        return 2;
    }
    if (!signing && strcmp(mode, "plain") != 0 && strncmp(mode, "replay:", 7) != 0) {
        fprintf(stderr, "lcm_seg_inject: unknown mode '%s'\n", mode);
        return 2;
    }
    lcm_t *lcm = lcm_create(argv[1]);
    if (lcm == NULL) {
        fprintf(stderr, "lcm_seg_inject: cannot open %s\n", argv[1]);
        return 1;
    }
    if (strncmp(mode, "replay:", 7) == 0) {
        int rc = replay(lcm, channel, mode + 7);
        lcm_destroy(lcm);
        return rc;
    }
    int first = 4;
    FILE *save = NULL;
    if (argc > 5 && strcmp(argv[4], "--save") == 0) {
        save = fopen(argv[5], "wb");
        first = 6;
    }
    int64_t source_id = 0;
    if (getrandom(&source_id, sizeof source_id, 0) != (ssize_t)sizeof source_id) {
        source_id = (int64_t)wall_us();
    }
    source_id = (source_id & INT64_MAX) | 1;
    int count = 0;
    int rc = 0;
    for (int i = first; i < argc && rc == 0; i++) {
        uint8_t frame[300];
        uint8_t msg[MAX_MSG];
        size_t len = unhex(argv[i], frame, sizeof frame);
        size_t mlen = len > 0u ? build(frame, len, source_id, signing ? &auth : NULL, sign_ch,
                                       msg)
                               : 0u;
        if (mlen == 0u) {
            fprintf(stderr, "lcm_seg_inject: frame '%s' is not hex\n", argv[i]);
            rc = 2;
        } else if (publish(lcm, channel, msg, mlen, save) != 0) {
            rc = 1;
        } else {
            count++;
        }
    }
    if (save != NULL) {
        fclose(save);
    }
    lcm_destroy(lcm);
    printf("published %d\n", count);
    return rc;
}
