/* Streaming a capture file through the replay or the address scan. */
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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

/* What the reading side does with each record before the replay gets it: parse it once (for
 * the scan and the replay alike) and, when the first pass goes along, feed the scan. The scan
 * needs nothing but the records, so it can run wherever the reading runs. */
typedef struct slot {
    replay_frame_t m;
    uint64_t file_pos;
    cap_record_t rec;
} slot_t;

static void prepare(slot_t *sl, replay_scan_t *scan)
{
    if (sl->rec.len == 0u) {
        if (scan != NULL) {
            replay_scan_feed(scan, &sl->rec); /* an unreadable text line */
        }
        return;
    }
    replay_frame_parse(sl->rec.data, sl->rec.len, &sl->m);
    if (scan != NULL) {
        replay_scan_feed_frame(scan, &sl->rec, &sl->m);
    }
}

static void deliver(replay_t *r, const slot_t *sl)
{
    if (sl->rec.len == 0u) {
        replay_feed(r, &sl->rec);
    } else {
        replay_feed_frame(r, &sl->rec, &sl->m);
    }
}

/* With a replay to feed, the reading, parsing and scan run on a thread of their own, a ring of
 * RING_RECORDS records ahead of the replay (memory stays flat). Records change hands BATCH at a
 * time, and a side that waits is woken only when half the ring is ready for it, so the two
 * threads meet a few thousand times per million records, not once per record. */
#define RING_RECORDS 1024u
#define BATCH 128u

typedef struct pipe {
    cap_reader_t rd;
    replay_scan_t *scan; /* the reading thread's until it is joined */
    pthread_mutex_t mu;
    pthread_cond_t cv;
    uint64_t head;      /* records read and prepared */
    uint64_t tail;      /* records the replay is done with */
    uint64_t wake_head; /* the replay waits until head reaches this, or the reading ends */
    uint64_t wake_tail; /* the reading waits until tail reaches this */
    bool replay_waits;
    bool reader_waits;
    bool done; /* the reading ended: end of file (rc 0) or an error (rc -1, rd.error) */
    int rc;
    bool quit; /* the replay stopped: read no further */
    slot_t ring[RING_RECORDS];
} pipe_t;

static void publish(pipe_t *p, uint64_t head, bool done, int rc)
{
    pthread_mutex_lock(&p->mu);
    p->head = head;
    p->done = done;
    p->rc = rc;
    if (p->replay_waits && (done || head >= p->wake_head)) {
        pthread_cond_broadcast(&p->cv);
    }
    pthread_mutex_unlock(&p->mu);
}

/* Blocks until slot n may be written; false when the replay stopped. */
static bool reader_room(pipe_t *p, uint64_t n, uint64_t *tail_seen)
{
    if (n - *tail_seen < RING_RECORDS) {
        return true;
    }
    pthread_mutex_lock(&p->mu);
    p->head = n; /* what is ready goes over before waiting */
    if (p->replay_waits) {
        pthread_cond_broadcast(&p->cv);
    }
    p->wake_tail = n - RING_RECORDS / 2u;
    while (n - p->tail >= RING_RECORDS && !p->quit) {
        p->reader_waits = true;
        pthread_cond_wait(&p->cv, &p->mu);
    }
    p->reader_waits = false;
    *tail_seen = p->tail;
    bool go = !p->quit;
    pthread_mutex_unlock(&p->mu);
    return go;
}

static void *reader_thread(void *arg)
{
    pipe_t *p = arg;
    uint64_t n = 0;
    uint64_t tail_seen = 0;
    int rc = 0;
    while (reader_room(p, n, &tail_seen)) {
        slot_t *sl = &p->ring[n % RING_RECORDS];
        rc = cap_reader_next(&p->rd, &sl->rec);
        if (rc <= 0) {
            break;
        }
        sl->file_pos = p->rd.file_pos;
        prepare(sl, p->scan);
        n++;
        if (n % BATCH == 0u) {
            publish(p, n, false, 0);
        }
    }
    publish(p, n, true, rc);
    return NULL;
}

/* Hands back the records before n and waits for more: the number ready (> n), or n when the
 * reading has ended. */
static uint64_t replay_take(pipe_t *p, uint64_t n)
{
    pthread_mutex_lock(&p->mu);
    p->tail = n;
    if (p->reader_waits && n >= p->wake_tail) {
        pthread_cond_broadcast(&p->cv);
    }
    p->wake_head = n + BATCH;
    while (p->head == n && !p->done) {
        p->replay_waits = true;
        pthread_cond_wait(&p->cv, &p->mu);
    }
    p->replay_waits = false;
    uint64_t head = p->head;
    pthread_mutex_unlock(&p->mu);
    return head;
}

/* Signals go to the replay's thread, which watches stop; the reader never sees them. 0, or -1
 * when no thread could start (the caller then reads in its own thread). */
static int start_reader(pthread_t *t, pipe_t *p)
{
    if (pthread_mutex_init(&p->mu, NULL) != 0) {
        return -1;
    }
    if (pthread_cond_init(&p->cv, NULL) != 0) {
        pthread_mutex_destroy(&p->mu);
        return -1;
    }
    sigset_t all;
    sigset_t old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    int rc = pthread_create(t, NULL, reader_thread, p);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (rc != 0) {
        pthread_cond_destroy(&p->cv);
        pthread_mutex_destroy(&p->mu);
        return -1;
    }
    return 0;
}

static void join_reader(pthread_t t, pipe_t *p)
{
    pthread_mutex_lock(&p->mu);
    p->quit = true;
    pthread_cond_broadcast(&p->cv);
    pthread_mutex_unlock(&p->mu);
    pthread_join(t, NULL);
    pthread_cond_destroy(&p->cv);
    pthread_mutex_destroy(&p->mu);
}

typedef struct stream_job {
    replay_scan_t *scan; /* may be NULL */
    replay_t *replay;    /* NULL: only the scan */
    uint64_t limit;      /* records to read at most, 0 for all (scan only) */
    volatile const int *stop;
    replay_progress_t progress;
    void *ctx;
} stream_job_t;

static void show_progress(const stream_job_t *job, uint64_t records, uint64_t pos, uint64_t size,
                          bool last)
{
    if (job->progress != NULL && (last || records % PROGRESS_EVERY == 0u)) {
        job->progress(job->ctx, records, pos, size);
    }
}

static bool stopped(const stream_job_t *job)
{
    return job->stop != NULL && *job->stop != 0;
}

/* One thread: the scan alone (nothing to overlap it with), or a replay when no thread starts. */
static void stream_here(pipe_t *p, const stream_job_t *job, replay_file_status_t *st)
{
    slot_t *sl = &p->ring[0];
    while (job->limit == 0u || st->records < job->limit) {
        if (stopped(job)) {
            st->interrupted = true;
            break;
        }
        int rc = cap_reader_next(&p->rd, &sl->rec);
        if (rc == 0) {
            break;
        }
        if (rc < 0) {
            st->read_error = true;
            snprintf(st->error, sizeof st->error, "%s", p->rd.error);
            break;
        }
        st->records++;
        prepare(sl, job->scan);
        if (job->replay != NULL) {
            deliver(job->replay, sl);
        }
        show_progress(job, st->records, p->rd.file_pos, p->rd.file_size, false);
    }
    show_progress(job, st->records, p->rd.file_pos, p->rd.file_size, true);
}

static void stream_threaded(pipe_t *p, pthread_t reader, const stream_job_t *job,
                            replay_file_status_t *st)
{
    uint64_t n = 0;
    uint64_t ready = 0;
    uint64_t pos = 0;
    for (;;) {
        if (stopped(job)) {
            st->interrupted = true;
            break;
        }
        if (n == ready || n % BATCH == 0u) {
            ready = replay_take(p, n);
            if (ready == n) {
                break;
            }
        }
        const slot_t *sl = &p->ring[n % RING_RECORDS];
        deliver(job->replay, sl);
        pos = sl->file_pos;
        n++;
        show_progress(job, n, pos, p->rd.file_size, false);
    }
    join_reader(reader, p);
    st->records = n;
    if (!st->interrupted && p->rc < 0) {
        st->read_error = true;
        snprintf(st->error, sizeof st->error, "%s", p->rd.error);
    }
    show_progress(job, n, st->interrupted ? pos : p->rd.file_pos, p->rd.file_size, true);
}

/* A second thread for the reading only pays on a second CPU (not for a process held to one by
 * taskset or a container's cpuset), and only reads a regular file: a read from a pipe or FIFO
 * may block for good, and a replay stopped by SIGINT would then wait for its reader forever. */
static bool reader_thread_pays(const char *path)
{
    cpu_set_t set;
    struct stat fst;
    return sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 1 &&
           stat(path, &fst) == 0 && S_ISREG(fst.st_mode);
}

static int stream(const replay_input_t *src, const stream_job_t *job, replay_file_status_t *st)
{
    memset(st, 0, sizeof *st);
    pipe_t *p = calloc(1, sizeof *p); /* large (the reader's text state, the ring): not on the stack */
    if (p == NULL) {
        snprintf(st->error, sizeof st->error, "%s: out of memory", src->path);
        return -1;
    }
    if (cap_reader_open_channel(&p->rd, src->path, src->format, src->lcm_channel, st->error,
                                sizeof st->error) != 0) {
        free(p);
        return -1;
    }
    snprintf(st->note, sizeof st->note, "%s", p->rd.lcm_note);
    st->format = p->rd.format;
    st->linktype = p->rd.linktype;
    p->scan = job->scan;
    pthread_t reader;
    if (job->replay != NULL && job->limit == 0u && reader_thread_pays(src->path) &&
        start_reader(&reader, p) == 0) {
        stream_threaded(p, reader, job, st);
    } else {
        stream_here(p, job, st);
    }
    cap_reader_close(&p->rd);
    free(p);
    return 0;
}

int replay_run_file(replay_t *r, const replay_input_t *src, volatile const int *stop,
                    replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    stream_job_t job = {.replay = r, .stop = stop, .progress = progress, .ctx = ctx};
    int rc = stream(src, &job, st);
    if (rc == 0) {
        replay_finish(r);
    }
    return rc;
}

int replay_scan_file(replay_scan_t *s, const replay_input_t *src, volatile const int *stop,
                     replay_progress_t progress, void *ctx, replay_file_status_t *st)
{
    stream_job_t job = {.scan = s, .stop = stop, .progress = progress, .ctx = ctx};
    return stream(src, &job, st);
}

int replay_scan_file_head(replay_scan_t *s, const replay_input_t *src, uint64_t records,
                          volatile const int *stop, replay_file_status_t *st)
{
    stream_job_t job = {.scan = s, .limit = records, .stop = stop};
    return stream(src, &job, st);
}

int replay_scan_run_file(replay_scan_t *s, replay_t *r, const replay_input_t *src,
                         volatile const int *stop, replay_progress_t progress, void *ctx,
                         replay_file_status_t *st)
{
    stream_job_t job = {.scan = s, .replay = r, .stop = stop, .progress = progress, .ctx = ctx};
    int rc = stream(src, &job, st);
    if (rc == 0) {
        replay_finish(r);
    }
    return rc;
}
