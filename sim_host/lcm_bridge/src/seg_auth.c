#include "lcm_bridge/seg_auth.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <sodium.h>

#include "dfp_lcm/dfp_lcm_signed_telegram_t.h"

#define KEY_HOWTO "(head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \\n' >FILE; chmod 600 FILE)"

static const char *const drop_names[DFP_SEG_DROP_REASONS] = {
    "unsigned", "signed", "bad signature", "stale", "replayed", "senders full", "malformed",
};

const char *dfp_seg_drop_name(dfp_seg_drop_t why)
{
    return (unsigned)why < DFP_SEG_DROP_REASONS ? drop_names[why] : "?";
}

static int key_check_file(int fd, const char *path, char *err, size_t errlen)
{
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(err, errlen, "--key %s: %s", path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "--key %s: not a regular file", path);
        return -1;
    }
    if ((st.st_mode & 077u) != 0u) {
        snprintf(err, errlen,
                 "--key %s: readable by others than its owner (mode %04o): chmod 600 %s", path,
                 (unsigned)(st.st_mode & 07777u), path);
        return -1;
    }
    return 0;
}

/* The text of the file: 64 hex digits, an optional final newline. */
static int key_parse(const char *path, char *text, size_t n, uint8_t key[DFP_SEG_KEY_BYTES],
                     char *err, size_t errlen)
{
    if (n > 0u && text[n - 1u] == '\n') {
        text[--n] = '\0';
    }
    size_t digits = strspn(text, "0123456789abcdefABCDEF");
    if (digits != n) {
        snprintf(err, errlen, "--key %s: not hex digits on one line (character %zu); a key is "
                 "64 hex digits %s", path, digits + 1u, KEY_HOWTO);
        return -1;
    }
    if (n != (size_t)2u * DFP_SEG_KEY_BYTES) {
        snprintf(err, errlen, "--key %s: %zu hex digits, a key is 64 (32 octets) %s", path, n,
                 KEY_HOWTO);
        return -1;
    }
    size_t got = 0;
    if (sodium_hex2bin(key, DFP_SEG_KEY_BYTES, text, n, NULL, &got, NULL) != 0 ||
        got != DFP_SEG_KEY_BYTES) {
        snprintf(err, errlen, "--key %s: not 64 hex digits %s", path, KEY_HOWTO);
        return -1;
    }
    return 0;
}

int dfp_seg_key_load(const char *path, uint8_t key[DFP_SEG_KEY_BYTES], char *err, size_t errlen)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
        snprintf(err, errlen, "--key %s: %s", path, strerror(errno));
        return -1;
    }
    char text[2u * DFP_SEG_KEY_BYTES + 8u];
    ssize_t n = -1;
    if (key_check_file(fd, path, err, errlen) == 0) {
        n = read(fd, text, sizeof text - 1u);
        if (n < 0) {
            snprintf(err, errlen, "--key %s: %s", path, strerror(errno));
        }
    }
    (void)close(fd);
    int rc = -1;
    if (n >= 0) {
        text[n] = '\0';
        rc = key_parse(path, text, (size_t)n, key, err, errlen);
    }
    sodium_memzero(text, sizeof text);
    return rc;
}

int dfp_seg_auth_init(dfp_seg_auth_t *a, const uint8_t key[DFP_SEG_KEY_BYTES])
{
    memset(a, 0, sizeof *a);
    if (sodium_init() < 0) {
        return -1;
    }
    memcpy(a->key, key, DFP_SEG_KEY_BYTES);
    return 0;
}

void dfp_seg_auth_clear(dfp_seg_auth_t *a)
{
    sodium_memzero(a, sizeof *a);
}

int64_t dfp_seg_next_seq(dfp_seg_auth_t *a, int64_t now_us)
{
    a->last_sent_seq = now_us > a->last_sent_seq ? now_us : a->last_sent_seq + 1;
    return a->last_sent_seq;
}

static void put_be(uint8_t *p, uint64_t v, unsigned octets)
{
    for (unsigned i = 0; i < octets; i++) {
        p[i] = (uint8_t)(v >> (8u * (octets - 1u - i)));
    }
}

static uint64_t get_be(const uint8_t *p, unsigned octets)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < octets; i++) {
        v = v << 8 | p[i];
    }
    return v;
}

/* The tag of body (the message up to the tag) sent on channel. */
static void seg_tag(const uint8_t key[DFP_SEG_KEY_BYTES], const char *channel,
                    const uint8_t *body, size_t len, uint8_t tag[DFP_SEG_TAG])
{
    crypto_auth_hmacsha512256_state st;
    size_t cn = strlen(channel);
    uint8_t clen = (uint8_t)(cn > 255u ? 255u : cn);
    crypto_auth_hmacsha512256_init(&st, key, DFP_SEG_KEY_BYTES);
    crypto_auth_hmacsha512256_update(&st, &clen, 1u);
    crypto_auth_hmacsha512256_update(&st, (const uint8_t *)channel, clen);
    crypto_auth_hmacsha512256_update(&st, body, len);
    crypto_auth_hmacsha512256_final(&st, tag);
}

size_t dfp_seg_sign(const dfp_seg_auth_t *a, const char *channel, int64_t sender_id,
                    int64_t seq, const uint8_t *telegram, size_t tlen, uint8_t *out,
                    size_t outmax)
{
    size_t total = DFP_SEG_HEAD + tlen + DFP_SEG_TAG;
    if (tlen == 0u || tlen > DFP_SEG_TELEGRAM_MAX || outmax < total) {
        return 0;
    }
    put_be(out, (uint64_t)__dfp_lcm_signed_telegram_t_get_hash(), 8u);
    out[8] = (uint8_t)DFP_LCM_SIGNED_TELEGRAM_T_VERSION;
    put_be(out + 9, (uint64_t)sender_id, 8u);
    put_be(out + 17, (uint64_t)seq, 8u);
    put_be(out + 25, tlen, 2u);
    memcpy(out + DFP_SEG_HEAD, telegram, tlen);
    seg_tag(a->key, channel, out, DFP_SEG_HEAD + tlen, out + DFP_SEG_HEAD + tlen);
    return total;
}

bool dfp_seg_is_signed(const uint8_t *buf, size_t len)
{
    return len >= 8u && get_be(buf, 8u) == (uint64_t)__dfp_lcm_signed_telegram_t_get_hash();
}

int dfp_seg_parse(const uint8_t *buf, size_t len, dfp_seg_msg_t *m)
{
    if (!dfp_seg_is_signed(buf, len) || len < DFP_SEG_HEAD + DFP_SEG_TAG ||
        buf[8] != (uint8_t)DFP_LCM_SIGNED_TELEGRAM_T_VERSION) {
        return -1;
    }
    size_t tlen = (size_t)get_be(buf + 25, 2u);
    if (tlen == 0u || tlen > DFP_SEG_TELEGRAM_MAX || len != DFP_SEG_HEAD + tlen + DFP_SEG_TAG) {
        return -1;
    }
    m->sender_id = (int64_t)get_be(buf + 9, 8u);
    m->seq = (int64_t)get_be(buf + 17, 8u);
    m->telegram = buf + DFP_SEG_HEAD;
    m->tlen = tlen;
    return 0;
}

/* The sender's entry, or a new one (a free slot, else one whose last sequence is out of the
 * window: nothing it sent can be taken any more); NULL when every entry is in the window. */
static dfp_seg_sender_t *sender_slot(dfp_seg_auth_t *a, int64_t id, int64_t now_us)
{
    dfp_seg_sender_t *old = NULL;
    for (unsigned i = 0; i < a->num_senders; i++) {
        dfp_seg_sender_t *e = &a->senders[i];
        if (e->id == id) {
            return e;
        }
        if (old == NULL && e->last_seq < now_us - DFP_SEG_WINDOW_US) {
            old = e;
        }
    }
    if (a->num_senders < DFP_SEG_SENDERS) {
        old = &a->senders[a->num_senders++];
    }
    if (old != NULL) {
        *old = (dfp_seg_sender_t){.id = id, .last_seq = INT64_MIN};
    }
    return old;
}

int dfp_seg_verify(dfp_seg_auth_t *a, const char *channel, const uint8_t *buf, size_t len,
                   const dfp_seg_msg_t *m, int64_t now_us)
{
    uint8_t tag[DFP_SEG_TAG];
    size_t body = DFP_SEG_HEAD + m->tlen;
    if (len != body + DFP_SEG_TAG) {
        return DFP_SEG_DROP_MALFORMED;
    }
    seg_tag(a->key, channel, buf, body, tag);
    if (crypto_verify_32(tag, buf + body) != 0) {
        return DFP_SEG_DROP_BAD_TAG;
    }
    if (m->seq < now_us - DFP_SEG_WINDOW_US || m->seq > now_us + DFP_SEG_WINDOW_US) {
        return DFP_SEG_DROP_STALE;
    }
    dfp_seg_sender_t *e = sender_slot(a, m->sender_id, now_us);
    if (e == NULL) {
        return DFP_SEG_DROP_SENDERS_FULL;
    }
    if (m->seq <= e->last_seq) {
        return DFP_SEG_DROP_REPLAYED;
    }
    e->last_seq = m->seq;
    return -1;
}

const char *dfp_seg_drops_text(const uint64_t counts[DFP_SEG_DROP_REASONS], bool all,
                               char *buf, size_t n)
{
    size_t at = 0;
    buf[0] = '\0';
    for (unsigned i = 0; i < DFP_SEG_DROP_REASONS && at < n; i++) {
        if (!all && counts[i] == 0u) {
            continue;
        }
        int w = snprintf(buf + at, n - at, "%s%s %llu", at > 0u ? ", " : "", drop_names[i],
                         (unsigned long long)counts[i]);
        if (w < 0) {
            break;
        }
        at += (size_t)w;
    }
    return buf;
}

static void drops_summary(dfp_seg_drops_t *d, const char *channel, int64_t now_us,
                          dfp_seg_log_fn log, void *ctx)
{
    uint64_t sum = 0;
    for (unsigned i = 0; i < DFP_SEG_DROP_REASONS; i++) {
        sum += d->pending[i];
    }
    if (sum == 0u) {
        return;
    }
    char text[200];
    char line[300];
    snprintf(line, sizeof line, "segment %s: %llu more dropped (%s)", channel,
             (unsigned long long)sum, dfp_seg_drops_text(d->pending, false, text, sizeof text));
    memset(d->pending, 0, sizeof d->pending);
    d->last_line_us = now_us;
    if (log != NULL) {
        log(ctx, line);
    }
}

void dfp_seg_drops_add(dfp_seg_drops_t *d, dfp_seg_drop_t why, const char *channel,
                       const char *detail, int64_t now_us, dfp_seg_log_fn log, void *ctx)
{
    d->total[why]++;
    if (!d->logged) {
        d->logged = true;
        d->last_line_us = now_us;
        char line[300];
        snprintf(line, sizeof line, "segment %s: dropped a telegram: %s%s%s (further drops: a "
                 "summary at most every second)", channel, drop_names[why],
                 detail[0] != '\0' ? ", " : "", detail);
        if (log != NULL) {
            log(ctx, line);
        }
        return;
    }
    d->pending[why]++;
    dfp_seg_drops_flush(d, channel, now_us, log, ctx);
}

void dfp_seg_drops_flush(dfp_seg_drops_t *d, const char *channel, int64_t now_us,
                         dfp_seg_log_fn log, void *ctx)
{
    if (d->logged && now_us - d->last_line_us >= DFP_SEG_LOG_INTERVAL_US) {
        drops_summary(d, channel, now_us, log, ctx);
    }
}
