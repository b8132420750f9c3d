#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include "http_internal.h"
#include "sim_hal/host_clock.h"

#define STATE_EVERY_MS 100u

typedef struct stream {
    http_server_t *srv;
    uint64_t next_seq;
    uint64_t last_state_ms;
    char *pending;
    size_t pending_len;
    size_t pending_off;
} stream_t;

static uint64_t mono_ms(void)
{
    return host_clock_mono_ns() / 1000000u;
}

static void append(stream_t *st, const char *text)
{
    size_t n = strlen(text);
    char *p = realloc(st->pending, st->pending_len + n + 1u);
    if (p == NULL) {
        return;
    }
    st->pending = p;
    memcpy(p + st->pending_len, text, n + 1u);
    st->pending_len += n;
}

static void append_event(stream_t *st, const char *event, const char *id, cJSON *data)
{
    char *json = cJSON_PrintUnformatted(data);
    cJSON_Delete(data);
    if (json == NULL) {
        return;
    }
    char head[64];
    (void)snprintf(head, sizeof head, "event: %s\n", event);
    append(st, head);
    if (id != NULL) {
        (void)snprintf(head, sizeof head, "id: %s\n", id);
        append(st, head);
    }
    append(st, "data: ");
    append(st, json);
    append(st, "\n\n");
    cJSON_free(json);
}

static void append_lost(stream_t *st, uint64_t lost)
{
    cJSON *o = cJSON_CreateObject();
    char text[96];
    (void)snprintf(text, sizeof text, "this client fell behind: %llu events not sent",
                   (unsigned long long)lost);
    cJSON_AddNumberToObject(o, "seq", (double)st->next_seq);
    cJSON_AddStringToObject(o, "source", "sim");
    cJSON_AddStringToObject(o, "level", "warn");
    cJSON_AddStringToObject(o, "kind", "lost");
    cJSON_AddStringToObject(o, "text", text);
    append_event(st, "log", NULL, o);
    st->next_seq += lost;
}

static void append_log(stream_t *st)
{
    static const size_t batch = 64u;
    rig_ctl_event_t *ev = malloc(batch * sizeof *ev);
    if (ev == NULL) {
        return;
    }
    uint64_t lost = 0;
    size_t n = rig_ctl_events(st->srv->ctl, st->next_seq, ev, batch, &lost);
    if (lost > 0u) {
        append_lost(st, lost);
    }
    for (size_t i = 0; i < n; i++) {
        char id[24];
        (void)snprintf(id, sizeof id, "%llu", (unsigned long long)ev[i].seq);
        append_event(st, "log", id, http_json_event(&ev[i]));
        st->next_seq = ev[i].seq + 1u;
    }
    free(ev);
}

/* Fills the pending text with what is new: log events (or a `lost` notice), and a state event
 * every STATE_EVERY_MS. Waits at most that long for something to say. */
static void stream_collect(stream_t *st)
{
    rig_ctl_t *ctl = st->srv->ctl;
    uint64_t now = mono_ms();
    uint64_t wait_ms = st->last_state_ms + STATE_EVERY_MS > now
                           ? st->last_state_ms + STATE_EVERY_MS - now
                           : 0u;
    if (wait_ms > 0u) {
        rig_ctl_wait(ctl, st->next_seq, (unsigned)wait_ms);
    }
    append_log(st);
    now = mono_ms();
    if (now >= st->last_state_ms + STATE_EVERY_MS) {
        st->last_state_ms = now;
        rig_snapshot_t *s = http_snapshot(ctl);
        if (s != NULL) {
            append_event(st, "state", NULL, http_json_state(ctl, s));
            free(s);
        }
    }
}

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    stream_t *st = cls;
    while (st->pending_off >= st->pending_len) {
        if (st->srv->stopping || st->srv->ctl->closing) {
            return MHD_CONTENT_READER_END_OF_STREAM;
        }
        free(st->pending);
        st->pending = NULL;
        st->pending_len = 0;
        st->pending_off = 0;
        stream_collect(st);
    }
    size_t n = st->pending_len - st->pending_off;
    if (n > max) {
        n = max;
    }
    memcpy(buf, st->pending + st->pending_off, n);
    st->pending_off += n;
    return (ssize_t)n;
}

static void stream_free(void *cls)
{
    stream_t *st = cls;
    atomic_fetch_sub(&st->srv->streams, 1u);
    free(st->pending);
    free(st);
}

enum MHD_Result http_serve_events(http_server_t *srv, struct MHD_Connection *conn)
{
    /* Counted from here; stream_free gives the place back, also for a stream that never
     * started. */
    if (atomic_fetch_add(&srv->streams, 1u) >= MAX_STREAMS) {
        atomic_fetch_sub(&srv->streams, 1u);
        return http_send_error(conn, 503, "too many event streams (at most %u); close one and "
                               "try again", MAX_STREAMS);
    }
    stream_t *st = calloc(1, sizeof *st);
    if (st == NULL) {
        atomic_fetch_sub(&srv->streams, 1u);
        return MHD_NO;
    }
    st->srv = srv;
    uint64_t next = rig_ctl_next_seq(srv->ctl);
    const char *last = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Last-Event-ID");
    if (last != NULL) {
        char *end;
        unsigned long long v = strtoull(last, &end, 10);
        if (end != last && *end == '\0' && v < next) {
            next = v + 1u;
        }
    }
    st->next_seq = next;
    struct MHD_Response *r =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, stream_read, st, stream_free);
    if (r == NULL) {
        stream_free(st);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", "text/event-stream");
    return http_queue(conn, MHD_HTTP_OK, r);
}

