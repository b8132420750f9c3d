/* The monitor's sources (mon_live.h). */
#include "monitor/mon_live.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/capture.h"
#include "dp_slave/fdl_wire.h"

#define NS_PER_US 1000ull
/* A tty, a PTY or LCM hands characters on milliseconds after they were on the line: an answer
 * is taken as missing only this long after its request was read. */
#define MON_LIVE_ANSWER_WAIT_NS 50000000ull

static uint64_t extend_us(mon_live_t *l, hal_time_us_t t)
{
    if (!l->have_t) {
        l->have_t = true;
        l->last_us = t;
        l->now_us = 0u;
    }
    l->now_us += (uint32_t)(t - l->last_us);
    l->last_us = t;
    return l->now_us * NS_PER_US;
}

static void station_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    mon_live_t *l = ctx;
    l->chars_in++;
    if (flags != 0u) {
        l->char_errors++;
    }
    mon_chars_feed(&l->chars, &byte, &flags, 1u, extend_us(l, t));
}

/* The station's poll: the monitor's idle time and the caller's turn, never a transmission. */
static hal_time_us_t station_poll(void *ctx, hal_time_us_t now)
{
    mon_live_t *l = ctx;
    uint64_t now_ns = extend_us(l, now);
    mon_chars_idle(&l->chars, now_ns);
    if (l->tick != NULL) {
        l->tick(l->tick_ctx, now_ns);
    }
    return now + (l->tick_ms != 0u ? l->tick_ms : 100u) * 1000u;
}

sim_station_t mon_live_station(mon_live_t *l)
{
    sim_station_t st = {.ctx = l, .rx_char = station_rx, .poll = station_poll};
    return st;
}

void mon_live_init(mon_live_t *l, mon_t *m, uint32_t baud)
{
    memset(l, 0, sizeof *l);
    l->mon = m;
    if (m->cfg.answer_wait_ns == 0u) {
        m->cfg.answer_wait_ns = MON_LIVE_ANSWER_WAIT_NS;
    }
    mon_chars_init(&l->chars, m, baud);
}

int64_t mon_file_run(mon_t *m, const char *path, uint32_t baud, volatile const int *stop,
                     char *err, size_t n)
{
    cap_reader_t *reader = malloc(sizeof *reader); /* large: its line buffers */
    if (reader == NULL) {
        (void)snprintf(err, n, "out of memory");
        return -1;
    }
    if (cap_reader_open(reader, path, CAP_FORMAT_AUTO, err, n) != 0) {
        free(reader);
        return -1;
    }
    cap_record_t rec;
    int64_t count = 0;
    uint64_t t0 = 0;
    bool have_t0 = false;
    /* The monitor's time never goes back (its spans are differences): a record earlier than
     * the one before it (a merged or hand-made capture, a clock stepped while recording, a
     * record without a time among timed ones) is taken at that one's time, and the records
     * after it keep their spacing. */
    int64_t shift = 0;
    uint64_t last = 0;
    int rc;
    while ((rc = cap_reader_next(reader, &rec)) == 1 && (stop == NULL || *stop == 0)) {
        count++;
        uint32_t rate = rec.baud != 0u ? rec.baud : (reader->if_baud != 0u ? reader->if_baud : baud);
        if (!have_t0 && rec.has_time) {
            t0 = rec.t_ns;
            have_t0 = true;
        }
        int64_t rel = rec.has_time ? (int64_t)(rec.t_ns - t0) + shift : (int64_t)last;
        if (rel < (int64_t)last) {
            shift += (int64_t)last - rel;
            rel = (int64_t)last;
        }
        uint64_t t = (uint64_t)rel;
        last = t;
        uint64_t dur = rate != 0u ? (uint64_t)rec.len * FDL_CHAR_BITS * 1000000000ull / rate : 0u;
        mon_idle(m, t);
        if (rec.len == 0u) {
            /* a line the reader found no octets in (its problem says why): not a telegram */
            mon_garbled(m, rec.data, 0u, t);
            continue;
        }
        mon_telegram(m, rec.data, rec.len, t, t + dur);
    }
    if (rc < 0) {
        (void)snprintf(err, n, "%s", reader->error);
        cap_reader_close(reader);
        free(reader);
        return -1;
    }
    cap_reader_close(reader);
    free(reader);
    return count;
}
