/* Streaming a capture file through the replay or the address scan: one record in memory. */
#include <stdio.h>
#include <string.h>

#include "capture/capture.h"
#include "replay/replay.h"

#define PROGRESS_EVERY 4096u

const char *replay_position_unit(cap_format_t f)
{
    switch (f) {
    case CAP_FORMAT_TEXT: return "line";
    case CAP_FORMAT_LCM: return "event";
    default: return "byte";
    }
}

typedef void (*feed_fn)(void *target, const cap_record_t *rec);

/* limit: records to read at most, 0 for all. */
static int stream(const replay_input_t *src, feed_fn feed, void *target, uint64_t limit,
                  volatile const int *stop, replay_progress_t progress, void *ctx,
                  replay_file_status_t *st)
{
    static cap_reader_t rd; /* large (path, text state): not on the stack */
    static cap_record_t rec;
    memset(st, 0, sizeof *st);
    if (cap_reader_open_channel(&rd, src->path, src->format, src->lcm_channel, st->error,
                                sizeof st->error) != 0) {
        return -1;
    }
    snprintf(st->note, sizeof st->note, "%s", rd.lcm_note);
    st->format = rd.format;
    st->linktype = rd.linktype;
    while (limit == 0u || st->records < limit) {
        if (stop != NULL && *stop != 0) {
            st->interrupted = true;
            break;
        }
        int rc = cap_reader_next(&rd, &rec);
        if (rc == 0) {
            break;
        }
        if (rc < 0) {
            st->read_error = true;
            snprintf(st->error, sizeof st->error, "%s", rd.error);
            break;
        }
        st->records++;
        feed(target, &rec);
        if (progress != NULL && st->records % PROGRESS_EVERY == 0u) {
            progress(ctx, st->records, rd.file_pos, rd.file_size);
        }
    }
    if (progress != NULL) {
        progress(ctx, st->records, rd.file_pos, rd.file_size);
    }
    cap_reader_close(&rd);
    return 0;
}

static void feed_replay(void *target, const cap_record_t *rec)
{
    replay_feed(target, rec);
}

static void feed_scan(void *target, const cap_record_t *rec)
{
    replay_scan_feed(target, rec);
}

typedef struct scan_and_replay {
    replay_scan_t *scan;
    replay_t *replay;
} scan_and_replay_t;

static void feed_both(void *target, const cap_record_t *rec)
{
    scan_and_replay_t *b = target;
    if (rec->len == 0u) {
        replay_scan_feed(b->scan, rec);
        replay_feed(b->replay, rec);
        return;
    }
    replay_frame_t m; /* read once for both */
    replay_frame_parse(rec->data, rec->len, &m);
    replay_scan_feed_frame(b->scan, rec, &m);
    replay_feed_frame(b->replay, rec, &m);
}

int replay_run_file(replay_t *r, const replay_input_t *src, volatile const int *stop,
                    replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    int rc = stream(src, feed_replay, r, 0u, stop, progress, ctx, st);
    if (rc == 0) {
        replay_finish(r);
    }
    return rc;
}

int replay_scan_file(replay_scan_t *s, const replay_input_t *src, volatile const int *stop,
                     replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    return stream(src, feed_scan, s, 0u, stop, progress, ctx, st);
}

int replay_scan_file_head(replay_scan_t *s, const replay_input_t *src, uint64_t records,
                          volatile const int *stop, replay_file_status_t *st)
{
    return stream(src, feed_scan, s, records, stop, NULL, NULL, st);
}

int replay_scan_run_file(replay_scan_t *s, replay_t *r, const replay_input_t *src,
                         volatile const int *stop, replay_progress_t progress, void *ctx,
                         replay_file_status_t *st)
{
    scan_and_replay_t both = {.scan = s, .replay = r};
    int rc = stream(src, feed_both, &both, 0u, stop, progress, ctx, st);
    if (rc == 0) {
        replay_finish(r);
    }
    return rc;
}
