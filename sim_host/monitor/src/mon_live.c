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

static sim_station_t station_of(mon_live_t *l)
{
    sim_station_t st = {.ctx = l, .rx_char = station_rx, .poll = station_poll};
    return st;
}

static void live_init(mon_live_t *l, mon_t *m, uint32_t baud)
{
    void (*tick)(void *, uint64_t) = l->tick;
    void *tick_ctx = l->tick_ctx;
    uint32_t tick_ms = l->tick_ms;
    memset(l, 0, sizeof *l);
    l->tick = tick;
    l->tick_ctx = tick_ctx;
    l->tick_ms = tick_ms;
    l->mon = m;
    if (m->cfg.answer_wait_ns == 0u) {
        m->cfg.answer_wait_ns = MON_LIVE_ANSWER_WAIT_NS;
    }
    mon_chars_init(&l->chars, m, baud);
    tty_runner_init(&l->runner);
}

int mon_live_open_port(mon_live_t *l, mon_t *m, const char *dev, uint32_t baud, char *err,
                       size_t n)
{
    live_init(l, m, baud);
    if (tty_port_open(&l->port, dev, baud, err, n) != 0) {
        return -1;
    }
    l->port_open = true;
    sim_station_t st = station_of(l);
    if (tty_runner_add(&l->runner, &l->port, &st) != 0) {
        (void)snprintf(err, n, "cannot listen on %s", dev);
        return -1;
    }
    return 0;
}

int mon_live_open_lcm(mon_live_t *l, mon_t *m, const char *url, const char *channel,
                      const uint8_t *key, uint32_t baud, char *err, size_t n)
{
    live_init(l, m, baud);
    if (dfp_lcm_segment_open(&l->seg, url, channel, -1, baud, err, n) != 0) {
        return -1;
    }
    l->lcm_open = true;
    if (key != NULL && dfp_lcm_segment_set_key(&l->seg, key) != 0) {
        (void)snprintf(err, n, "libsodium did not start: the segment's key cannot be used");
        return -1;
    }
    sim_station_t st = station_of(l);
    if (dfp_lcm_segment_attach(&l->seg, &l->runner, &st) != 0) {
        (void)snprintf(err, n, "cannot listen on segment %s", channel);
        return -1;
    }
    return 0;
}

int mon_live_run(mon_live_t *l, uint32_t seconds, volatile const int *stop, char *err, size_t n)
{
    hal_time_us_t start = tty_now_us();
    /* The runner's limit is a 32-bit instant: run in slices of at most 100 s. */
    uint64_t left_us = seconds != 0u ? (uint64_t)seconds * 1000000u : UINT64_MAX;
    while (left_us != 0u && (stop == NULL || *stop == 0)) {
        uint64_t slice = left_us < 100000000u ? left_us : 100000000u;
        hal_time_us_t end = tty_now_us() + (hal_time_us_t)slice;
        if (tty_runner_run_until(&l->runner, end, stop) != 0) {
            (void)snprintf(err, n, "%s", tty_runner_error(&l->runner));
            return -1;
        }
        if (seconds != 0u) {
            uint64_t spent = (uint32_t)(tty_now_us() - start);
            left_us = spent >= (uint64_t)seconds * 1000000u ? 0u
                                                              : (uint64_t)seconds * 1000000u - spent;
        }
    }
    return 0;
}

void mon_live_close(mon_live_t *l)
{
    if (l->lcm_open) {
        dfp_lcm_segment_close(&l->seg);
        l->lcm_open = false;
    }
    if (l->port_open) {
        tty_port_close(&l->port);
        l->port_open = false;
    }
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
    int rc;
    while ((rc = cap_reader_next(reader, &rec)) == 1 && (stop == NULL || *stop == 0)) {
        count++;
        uint32_t rate = rec.baud != 0u ? rec.baud : (reader->if_baud != 0u ? reader->if_baud : baud);
        uint64_t t = rec.has_time ? rec.t_ns : 0u;
        if (!have_t0 && rec.has_time) {
            t0 = t;
            have_t0 = true;
        }
        t = t >= t0 ? t - t0 : 0u;
        uint64_t dur = rate != 0u ? (uint64_t)rec.len * FDL_CHAR_BITS * 1000000000ull / rate : 0u;
        mon_idle(m, t);
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
