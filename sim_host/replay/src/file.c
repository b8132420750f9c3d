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

static int stream(const replay_input_t *src, feed_fn feed, void *target,
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
    for (;;) {
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

int replay_run_file(replay_t *r, const replay_input_t *src, volatile const int *stop,
                    replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    int rc = stream(src, feed_replay, r, stop, progress, ctx, st);
    if (rc == 0) {
        replay_finish(r);
    }
    return rc;
}

int replay_scan_file(replay_scan_t *s, const replay_input_t *src, volatile const int *stop,
                     replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    return stream(src, feed_scan, s, stop, progress, ctx, st);
}
