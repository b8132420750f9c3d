/* LCM event logs as captures. An event is: sync word 0xEDA1DA01, event number (8), timestamp
 * (8), channel length (4), data length (4), all big-endian, then the channel name and the
 * message. lcm_eventlog_read_next_event() reads them, but on a bad sync word it silently scans
 * forward to the next one, and it believes any data length; so every event header is checked
 * here first, and a damaged log ends the reading with the event number and byte offset instead
 * of being skipped over or read into a huge buffer. The library also refuses a good event that
 * is followed by anything but another sync word; that one event is read here directly, so the
 * records before the damage all come out and the error names the damage itself. */
#include "cap_lcm.h"

#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <lcm/eventlog.h>

#include "lcm_bridge/telegram_decode.h"

#define LCM_LOG_SYNC 0xEDA1DA01u
#define LCM_LOG_HEADER 28u
/* lcm_eventlog_read_next_event refuses longer channel names itself. */
#define LCM_LOG_MAX_CHANNEL 1000u

/* Kept in cap_reader_t.lcm_log. */
typedef struct cap_lcm_state {
    lcm_eventlog_t *log;
    uint64_t events;   /* events read so far, telegrams or not */
    uint64_t size;     /* of the file at open */
} cap_lcm_state_t;

bool cap_lcm_sniff(const uint8_t *head, size_t n)
{
    return n >= 4u && head[0] == 0xEDu && head[1] == 0xA1u && head[2] == 0xDAu &&
           head[3] == 0x01u;
}

#define LCM_MAX_LISTED 8u

/* The channels of a log that carry telegram_t messages. */
typedef struct channel_list {
    char name[LCM_MAX_LISTED][sizeof ((cap_reader_t *)0)->lcm_channel];
    unsigned n;
    bool more; /* others that did not fit (or whose names are too long to choose) */
} channel_list_t;

static uint32_t be32(const uint8_t *p);

static bool listed(const channel_list_t *l, const char *name)
{
    for (unsigned i = 0; i < l->n; i++) {
        if (strcmp(l->name[i], name) == 0) {
            return true;
        }
    }
    return false;
}

static void list_add(channel_list_t *l, const char *name)
{
    if (listed(l, name)) {
        return;
    }
    if (l->n >= LCM_MAX_LISTED || strlen(name) >= sizeof l->name[0]) {
        l->more = true;
        return;
    }
    snprintf(l->name[l->n++], sizeof l->name[0], "%s", name);
}

static void list_text(const channel_list_t *l, const char *except, char *out, size_t max)
{
    size_t used = 0;
    out[0] = '\0';
    for (unsigned i = 0; i < l->n && used < max; i++) {
        if (except == NULL || strcmp(l->name[i], except) != 0) {
            int w = snprintf(out + used, max - used, "%s%s", used > 0 ? ", " : "", l->name[i]);
            used += w > 0 ? (size_t)w : 0u;
        }
    }
    if (l->more && used < max) {
        (void)snprintf(out + used, max - used, "%s...", used > 0 ? ", " : "");
    }
}

/* An event header's fields, once its octets passed event_header_ok. */
typedef struct event_header {
    uint32_t channel_len;
    uint32_t data_len;
    uint64_t total; /* header + channel name + data */
} event_header_t;

/* The rules an event header at `at` of a size-octet file must meet (got: octets read of it).
 * True with out filled, else false with the reason in why. One place for both the channel scan
 * and the reading proper, so they cannot disagree on what a damaged event is. */
static bool event_header_ok(const uint8_t h[LCM_LOG_HEADER], size_t got, uint64_t at,
                            uint64_t size, event_header_t *out, char *why, size_t whylen)
{
    if (got >= 4u && be32(h) != LCM_LOG_SYNC) {
        snprintf(why, whylen, "bad sync word 0x%08" PRIX32 " (expected 0xEDA1DA01): garbage or a "
                 "damaged event", be32(h));
        return false;
    }
    if (got < LCM_LOG_HEADER) {
        snprintf(why, whylen, "truncated event header: %zu of %u octets", got, LCM_LOG_HEADER);
        return false;
    }
    out->channel_len = be32(&h[20]);
    out->data_len = be32(&h[24]);
    if (out->channel_len == 0u || out->channel_len >= LCM_LOG_MAX_CHANNEL) {
        snprintf(why, whylen, "channel name length %" PRIu32 " out of range (1..%u)",
                 out->channel_len, LCM_LOG_MAX_CHANNEL - 1u);
        return false;
    }
    if (out->data_len > (uint32_t)INT32_MAX) {
        snprintf(why, whylen, "data length %" PRIu32 " out of range", out->data_len);
        return false;
    }
    out->total = LCM_LOG_HEADER + (uint64_t)out->channel_len + out->data_len;
    if (at + out->total > size) {
        snprintf(why, whylen, "truncated event: %" PRIu64 " octets, the file has %" PRIu64
                 " left", out->total, size - at);
        return false;
    }
    return true;
}

/* Which channels carry telegrams, from the event headers and the first octets of each event's
 * data (the type fingerprint). Stops quietly at the first damage: the reading proper reports it
 * with its position. */
static void telegram_channels(FILE *f, uint64_t size, channel_list_t *out)
{
    memset(out, 0, sizeof *out);
    uint64_t at = 0;
    while (at < size) {
        uint8_t h[LCM_LOG_HEADER] = {0}; /* a short read fills only part of it */
        event_header_t eh;
        char why[160];
        if (fseeko(f, (off_t)at, SEEK_SET) != 0 ||
            !event_header_ok(h, fread(h, 1, sizeof h, f), at, size, &eh, why, sizeof why)) {
            break;
        }
        uint32_t channel_len = eh.channel_len;
        uint32_t data_len = eh.data_len;
        char name[LCM_LOG_MAX_CHANNEL];
        uint8_t fingerprint[8];
        if (fread(name, 1, channel_len, f) != channel_len) {
            break;
        }
        name[channel_len] = '\0';
        if (data_len >= sizeof fingerprint &&
            fread(fingerprint, 1, sizeof fingerprint, f) == sizeof fingerprint &&
            dfp_lcm_is_telegram(fingerprint, sizeof fingerprint)) {
            list_add(out, name);
        }
        at += eh.total;
    }
    (void)fseeko(f, 0, SEEK_SET);
}

/* cap_reader_open_channel's rule for r->lcm_channel; false with err when the named channel has
 * no telegrams. */
static bool choose_channel(cap_reader_t *r, FILE *f, uint64_t size, const char *channel,
                           char *err, size_t errlen)
{
    channel_list_t l;
    telegram_channels(f, size, &l);
    char others[200];
    if (channel != NULL && strcmp(channel, "*") != 0) {
        if (!listed(&l, channel)) {
            list_text(&l, NULL, others, sizeof others);
            snprintf(err, errlen, "%s: no telegram_t on LCM channel '%.63s' (channels with "
                     "telegrams: %s)", r->path, channel, l.n > 0u ? others : "none");
            return false;
        }
        snprintf(r->lcm_channel, sizeof r->lcm_channel, "%s", channel);
        return true;
    }
    if (channel == NULL && (l.n > 1u || l.more) && listed(&l, CAP_LCM_TELEMETRY_CHANNEL)) {
        snprintf(r->lcm_channel, sizeof r->lcm_channel, "%s", CAP_LCM_TELEMETRY_CHANNEL);
        list_text(&l, CAP_LCM_TELEMETRY_CHANNEL, others, sizeof others);
        snprintf(r->lcm_note, sizeof r->lcm_note, "LCM log: read channel %s (the card's "
                 "telemetry); not read: %.100s (--channel NAME, or '*' for all)",
                 CAP_LCM_TELEMETRY_CHANNEL, others);
    }
    return true;
}

int cap_lcm_open(cap_reader_t *r, const char *channel, char *err, size_t errlen)
{
    cap_lcm_state_t *st = calloc(1, sizeof *st);
    if (st == NULL) {
        snprintf(err, errlen, "%s: out of memory", r->path);
        return -1;
    }
    errno = 0;
    st->log = lcm_eventlog_create(r->path, "r");
    if (st->log == NULL) {
        snprintf(err, errlen, "cannot open %s: %s", r->path,
                 errno != 0 ? strerror(errno) : "not readable as an LCM log");
        free(st);
        return -1;
    }
    struct stat sb;
    if (fstat(fileno(st->log->f), &sb) != 0 || !S_ISREG(sb.st_mode)) {
        snprintf(err, errlen, "%s: not a regular file", r->path);
        lcm_eventlog_destroy(st->log);
        free(st);
        return -1;
    }
    st->size = (uint64_t)sb.st_size;
    if (!choose_channel(r, st->log->f, st->size, channel, err, errlen)) {
        lcm_eventlog_destroy(st->log);
        free(st);
        return -1;
    }
    r->file_size = st->size;
    r->file_pos = 0;
    r->linktype = 0;
    r->lcm_log = st;
    return 0;
}

void cap_lcm_close(cap_reader_t *r)
{
    cap_lcm_state_t *st = r->lcm_log;
    if (st != NULL) {
        if (st->log != NULL) {
            lcm_eventlog_destroy(st->log);
        }
        free(st);
        r->lcm_log = NULL;
    }
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static int fail(cap_reader_t *r, uint64_t event, uint64_t at, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int fail(cap_reader_t *r, uint64_t event, uint64_t at, const char *fmt, ...)
{
    char why[320];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    snprintf(r->error, sizeof r->error, "%s: event %" PRIu64 " at byte %" PRIu64 ": %s",
             r->path, event, at, why);
    return -1;
}

/* Checks the event header at the current position. 1: an event of total octets follows; 0: end
 * of file; -1: damage (r->error). */
static int check_header(cap_reader_t *r, cap_lcm_state_t *st, uint64_t at, uint32_t *channel_out,
                        uint32_t *data_out, uint64_t *total)
{
    FILE *f = st->log->f;
    uint64_t event = st->events + 1u;
    if (at >= st->size) {
        return 0;
    }
    uint8_t h[LCM_LOG_HEADER] = {0};
    size_t got = fread(h, 1, sizeof h, f);
    if (fseeko(f, (off_t)at, SEEK_SET) != 0) {
        return fail(r, event, at, "cannot seek back: %s", strerror(errno));
    }
    event_header_t eh;
    char why[160];
    if (!event_header_ok(h, got, at, st->size, &eh, why, sizeof why)) {
        return fail(r, event, at, "%s", why);
    }
    *channel_out = eh.channel_len;
    *data_out = eh.data_len;
    *total = eh.total;
    return 1;
}

/* True when the octets at `at` are a sync word, or fewer than 4 octets remain (what the library
 * checks after an event's data). */
static bool sync_follows(cap_lcm_state_t *st, uint64_t at)
{
    if (at + 4u > st->size) {
        return true;
    }
    FILE *f = st->log->f;
    off_t back = ftello(f);
    uint8_t w[4];
    bool ok = back >= 0 && fseeko(f, (off_t)at, SEEK_SET) == 0 && fread(w, 1, 4, f) == 4u &&
              be32(w) == LCM_LOG_SYNC;
    if (back >= 0) {
        (void)fseeko(f, back, SEEK_SET);
    }
    return ok;
}

/* The event at the current position, header already checked; the same allocation the library
 * makes, so lcm_eventlog_free_event releases it. NULL when it cannot be read. */
static lcm_eventlog_event_t *read_event_here(cap_lcm_state_t *st, uint32_t channel_len,
                                             uint32_t data_len)
{
    FILE *f = st->log->f;
    uint8_t h[LCM_LOG_HEADER];
    lcm_eventlog_event_t *ev = calloc(1, sizeof *ev);
    if (ev == NULL || fread(h, 1, sizeof h, f) != sizeof h) {
        free(ev);
        return NULL;
    }
    ev->channel = calloc(1, (size_t)channel_len + 1u);
    ev->data = calloc(1, (size_t)data_len + 1u);
    ev->channellen = (int32_t)channel_len;
    ev->datalen = (int32_t)data_len;
    if (ev->channel == NULL || ev->data == NULL ||
        fread(ev->channel, 1, channel_len, f) != channel_len ||
        fread(ev->data, 1, data_len, f) != data_len) {
        /* What lcm_eventlog_free_event does, spelled out so the analyser sees the frees. */
        free(ev->channel);
        free(ev->data);
        free(ev);
        return NULL;
    }
    uint64_t ts = 0;
    for (unsigned i = 12; i < 20u; i++) {
        ts = ts << 8 | h[i];
    }
    ev->timestamp = (int64_t)ts;
    return ev;
}

static void fill(cap_reader_t *r, cap_record_t *rec, uint64_t event,
                 const lcm_eventlog_event_t *ev, const dfp_lcm_telegram_t *m)
{
    memset(rec, 0, offsetof(cap_record_t, data));
    r->records++;
    rec->index = r->records;
    rec->position = event;
    rec->has_time = true;
    /* The telegram's own time (when it was on the wire); the log's receive time only when the
     * publisher left it out. */
    int64_t us = m->utime > 0 ? m->utime : ev->timestamp;
    rec->t_ns = us > 0 ? (uint64_t)us * 1000u : 0u;
    rec->baud = m->baud > 0 ? cap_profibus_rate((uint64_t)m->baud) : 0u;
    rec->error_flags = (uint16_t)m->error_flags;
    rec->dir = m->direction == DFP_LCM_TELEGRAM_T_DIR_TX   ? CAP_DIR_TX
               : m->direction == DFP_LCM_TELEGRAM_T_DIR_RX ? CAP_DIR_RX
                                                            : CAP_DIR_UNKNOWN;
    size_t len = (size_t)m->length;
    rec->orig_len = len;
    rec->len = len > CAP_MAX_RECORD ? CAP_MAX_RECORD : len;
    /* cppcheck 2.10 reads rec->len as 0 from the memset above; it is not. */
    if (rec->len > 0u) { // cppcheck-suppress knownConditionTrueFalse
        memcpy(rec->data, m->data, rec->len);
    }
    if (len > CAP_MAX_RECORD) {
        snprintf(rec->problem, sizeof rec->problem, "%zu octets, longer than any telegram", len);
    } else {
        (void)cap_check_telegram(rec->data, rec->len, rec->problem, sizeof rec->problem);
    }
}

int cap_lcm_next(cap_reader_t *r, cap_record_t *rec)
{
    cap_lcm_state_t *st = r->lcm_log;
    if (st == NULL || st->log == NULL) {
        return 0;
    }
    for (;;) {
        off_t pos = ftello(st->log->f);
        if (pos < 0) {
            snprintf(r->error, sizeof r->error, "%s: event %" PRIu64 ": %s", r->path,
                     st->events + 1u, strerror(errno));
            return -1;
        }
        uint64_t at = (uint64_t)pos;
        uint64_t total = 0;
        uint32_t channel_len = 0;
        uint32_t data_len = 0;
        int h = check_header(r, st, at, &channel_len, &data_len, &total);
        if (h <= 0) {
            return h;
        }
        uint64_t event = ++st->events;
        lcm_eventlog_event_t *ev = sync_follows(st, at + total)
                                       ? lcm_eventlog_read_next_event(st->log)
                                       : read_event_here(st, channel_len, data_len);
        off_t after = ftello(st->log->f);
        if (ev == NULL || after < 0 || (uint64_t)after != at + total) {
            if (ev != NULL) {
                lcm_eventlog_free_event(ev);
            }
            return fail(r, event, at, "the LCM library could not read this event");
        }
        r->file_pos = (uint64_t)after;
        if (!dfp_lcm_is_telegram(ev->data, (size_t)ev->datalen) ||
            (r->lcm_channel[0] != '\0' && strcmp(ev->channel, r->lcm_channel) != 0)) {
            lcm_eventlog_free_event(ev); /* another message type or channel: not ours */
            continue;
        }
        dfp_lcm_telegram_t m;
        char why[96];
        if (dfp_lcm_telegram_decode_checked(ev->data, (size_t)ev->datalen, &m, why,
                                            sizeof why) != 0) {
            int rc = fail(r, event, at, "channel %.64s: %s", ev->channel, why);
            lcm_eventlog_free_event(ev);
            return rc;
        }
        fill(r, rec, event, ev, &m);
        dfp_lcm_telegram_t_decode_cleanup(&m);
        lcm_eventlog_free_event(ev);
        return 1;
    }
}
