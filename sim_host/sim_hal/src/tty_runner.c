/* The one-thread runner of sim_hal/tty_port.h: up to eight ports with their stations, extra
 * descriptors and timers, one ppoll() loop. Built with _GNU_SOURCE (ppoll). */
#include <errno.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "sim_hal/host_clock.h"
#include "sim_hal/tty_port.h"
#include "tty_internal.h"

#define TTY_READ_CHUNK 4096u
/* Longest single wait in the runner, so a stop flag set from another thread is seen. */
#define TTY_RUNNER_MAX_WAIT_US 50000
/* Waits up to this long are spun (descriptors polled without blocking) rather than slept: a
 * timed ppoll() returns tens of microseconds late on a loaded host or in a VM even with 1 us of
 * timer slack, which is longer than the wait itself (the idle before a request is 26 us at
 * 1.5 Mbit/s, 4 us at 12 Mbit/s). Longer waits sleep; their lateness is a small part of them. */
#define TTY_RUNNER_SPIN_US 100

static int runner_fail(tty_runner_t *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static int runner_fail(tty_runner_t *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(r->error, sizeof r->error, fmt, ap);
    va_end(ap);
    return -1;
}

void tty_runner_init(tty_runner_t *r)
{
    memset(r, 0, sizeof *r);
    r->t0_ns = host_clock_mono_ns();
}

int tty_runner_add(tty_runner_t *r, tty_port_t *p, const sim_station_t *st)
{
    if (r->num_slots >= TTY_RUNNER_MAX_PORTS || p->runner != NULL) {
        return -1;
    }
    tty_runner_slot_t *s = &r->slots[r->num_slots];
    memset(s, 0, sizeof *s);
    s->port = p;
    s->station = *st;
    s->deadline = tty_now_us(); /* first poll as soon as the runner runs */
    fdl_rx_init(&s->rx, p->baud, false);
    p->runner = r;
    p->slot = r->num_slots;
    r->num_slots++;
    return 0;
}

void tty_runner_set_tap(tty_runner_t *r, sim_frame_tap_t tap, void *ctx)
{
    r->tap = tap;
    r->tap_ctx = ctx;
}

const char *tty_runner_error(const tty_runner_t *r)
{
    return r->error;
}

int tty_runner_add_fd(tty_runner_t *r, int fd, tty_fd_readable_fn readable, void *ctx)
{
    if (r->num_fds >= TTY_RUNNER_MAX_FDS || fd < 0 || readable == NULL) {
        return -1;
    }
    r->fds[r->num_fds++] = (tty_runner_fd_t){.fd = fd, .readable = readable, .ctx = ctx};
    return 0;
}

int tty_runner_remove_fd(tty_runner_t *r, int fd)
{
    for (uint8_t i = 0; i < r->num_fds; i++) {
        if (r->fds[i].fd == fd) {
            memmove(&r->fds[i], &r->fds[i + 1u], (size_t)(r->num_fds - i - 1u) * sizeof r->fds[0]);
            r->num_fds--;
            return 0;
        }
    }
    return -1;
}

int tty_runner_add_timer(tty_runner_t *r, tty_timer_fn poll, void *ctx)
{
    if (r->num_timers >= TTY_RUNNER_MAX_TIMERS || poll == NULL) {
        return -1;
    }
    r->timers[r->num_timers++] =
        (tty_runner_timer_t){.poll = poll, .ctx = ctx, .deadline = tty_now_us()};
    return 0;
}

void tty_runner_wake(tty_runner_t *r)
{
    hal_time_us_t now = tty_now_us();
    for (uint8_t i = 0; i < r->num_timers; i++) {
        r->timers[i].deadline = now;
    }
}

int tty_runner_remove_timer(tty_runner_t *r, tty_timer_fn poll, const void *ctx)
{
    for (uint8_t i = 0; i < r->num_timers; i++) {
        if (r->timers[i].poll == poll && r->timers[i].ctx == ctx) {
            memmove(&r->timers[i], &r->timers[i + 1u],
                    (size_t)(r->num_timers - i - 1u) * sizeof r->timers[0]);
            r->num_timers--;
            return 0;
        }
    }
    return -1;
}

void tty_runner_set_error(tty_runner_t *r, const char *fmt, ...)
{
    if (r->error[0] != '\0') {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(r->error, sizeof r->error, fmt, ap);
    va_end(ap);
}

void tty_runner_baud_changed(tty_port_t *p)
{
    if (p->runner != NULL) {
        fdl_rx_set_baud(&p->runner->slots[p->slot].rx, p->baud);
    }
}

void tty_runner_transmitted(tty_port_t *p, uint64_t t_ns, const uint8_t *frame, size_t len)
{
    tty_runner_t *r = p->runner;
    if (r != NULL && r->tap != NULL) {
        r->tap(r->tap_ctx, t_ns - r->t0_ns, frame, len, true, p->baud);
    }
}

/* A failed write happens inside a station callback; the run ends at the next loop turn. */
void tty_runner_tx_failed(tty_port_t *p, const char *why)
{
    if (p->runner != NULL && p->runner->error[0] == '\0') {
        (void)runner_fail(p->runner, "transmit on %s: %s", p->name, why);
    }
}

/* Feed the frame assembler for the tap; a frame's time is the arrival of its first byte. */
static void tap_rx(tty_runner_t *r, tty_runner_slot_t *s, uint8_t b, uint8_t f, hal_time_us_t t,
                   uint64_t t_ns)
{
    uint64_t rel_ns = t_ns - r->t0_ns;
    fdl_rx_result_t res = fdl_rx_char(&s->rx, b, f, t);
    if (s->rx.collecting && s->rx.len == 1u) {
        s->rx_frame_start_ns = rel_ns;
    }
    if (res == FDL_RX_FRAME) {
        uint64_t start = s->rx.frame_len == 1u ? rel_ns : s->rx_frame_start_ns;
        r->tap(r->tap_ctx, start, s->rx.buf, s->rx.frame_len, false, s->port->baud);
    }
}

static void poll_slot(tty_runner_slot_t *s)
{
    hal_time_us_t now = tty_now_us();
    if (s->station.poll == NULL) {
        s->deadline = now + HAL_TIME_NO_DEADLINE_US;
        return;
    }
    s->deadline = s->station.poll(s->station.ctx, now);
}

/* Every character of one read() gets the time that read returned. */
static void deliver_chunk(tty_runner_t *r, tty_runner_slot_t *s, const uint8_t *raw, size_t n)
{
    uint8_t bytes[TTY_READ_CHUNK + 1u];
    uint8_t flags[TTY_READ_CHUNK + 1u];
    uint64_t t_ns = host_clock_mono_ns();
    hal_time_us_t t = (hal_time_us_t)(t_ns / 1000u);
    tty_port_t *p = s->port;
    size_t m = tty_port_decode(p, raw, n, bytes, flags);
    for (size_t i = 0; i < m; i++) {
        if (tty_port_echo_swallow(p, bytes[i], flags[i], t)) {
            continue;
        }
        p->chars_received++;
        /* The tap first: the station may answer from inside rx_char, and a capture must show
         * the request before its answer. */
        if (r->tap != NULL) {
            tap_rx(r, s, bytes[i], flags[i], t, t_ns);
        }
        if (s->station.rx_char != NULL) {
            s->station.rx_char(s->station.ctx, bytes[i], flags[i], t);
        }
    }
    poll_slot(s); /* let the station answer without waiting for its next deadline */
}

/* A PTY master whose slave closed reads EIO; a slave whose master closed reads 0. */
static int read_port(tty_runner_t *r, tty_runner_slot_t *s, short revents)
{
    uint8_t raw[TTY_READ_CHUNK];
    ssize_t n = read(s->port->fd, raw, sizeof raw);
    if (n > 0) {
        deliver_chunk(r, s, raw, (size_t)n);
        return 0;
    }
    if (n == 0) {
        return runner_fail(r, "%s: hang-up (end of file)", s->port->name);
    }
    int e = errno;
    if (e == EAGAIN || e == EINTR) {
        if ((revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
            return runner_fail(r, "%s: hang-up", s->port->name);
        }
        return 0;
    }
    return runner_fail(r, "read %s: %s%s", s->port->name, strerror(e),
                       e == EIO ? " (device gone or PTY peer closed)" : "");
}

static void poll_timer(tty_runner_timer_t *t)
{
    t->deadline = t->poll(t->ctx, tty_now_us());
}

static void poll_due_stations(tty_runner_t *r)
{
    for (uint8_t i = 0; i < r->num_slots; i++) {
        if (hal_time_reached(tty_now_us(), r->slots[i].deadline)) {
            poll_slot(&r->slots[i]);
        }
    }
    for (uint8_t i = 0; i < r->num_timers; i++) {
        if (hal_time_reached(tty_now_us(), r->timers[i].deadline)) {
            poll_timer(&r->timers[i]);
        }
    }
}

/* After an fd delivered something: everybody may have news. */
static void poll_all(tty_runner_t *r)
{
    for (uint8_t i = 0; i < r->num_slots; i++) {
        poll_slot(&r->slots[i]);
    }
    for (uint8_t i = 0; i < r->num_timers; i++) {
        poll_timer(&r->timers[i]);
    }
}

/* Until the earliest station deadline or t_end, capped so a stop flag is noticed. */
static int32_t wait_budget_us(const tty_runner_t *r, hal_time_us_t t_end)
{
    hal_time_us_t now = tty_now_us();
    int32_t w = hal_time_diff(t_end, now);
    if (w > TTY_RUNNER_MAX_WAIT_US) {
        w = TTY_RUNNER_MAX_WAIT_US;
    }
    for (uint8_t i = 0; i < r->num_slots; i++) {
        int32_t d = hal_time_diff(r->slots[i].deadline, now);
        if (d < w) {
            w = d;
        }
    }
    for (uint8_t i = 0; i < r->num_timers; i++) {
        int32_t d = hal_time_diff(r->timers[i].deadline, now);
        if (d < w) {
            w = d;
        }
    }
    return w < 0 ? 0 : w;
}

/* ppoll() for wait_us, or for a short wait, ppoll() without blocking until something is
 * readable or the time is up: the descriptors are watched all the same, so a character that
 * arrives during the idle before a request is seen as soon as it would be when sleeping. */
static int poll_or_spin(struct pollfd *pfd, nfds_t n, int32_t wait_us)
{
    if (wait_us > TTY_RUNNER_SPIN_US) {
        struct timespec ts = {.tv_sec = wait_us / 1000000,
                              .tv_nsec = (long)(wait_us % 1000000) * 1000L};
        return ppoll(pfd, n, &ts, NULL);
    }
    const struct timespec zero = {.tv_sec = 0, .tv_nsec = 0};
    hal_time_us_t end = tty_now_us() + (hal_time_us_t)wait_us;
    for (;;) {
        int rc = ppoll(pfd, n, &zero, NULL);
        if (rc != 0 || hal_time_reached(tty_now_us(), end)) {
            return rc;
        }
    }
}

/* Ports first, then the other descriptors. A callback may remove its own descriptor, so the
 * fd entries are looked up by descriptor after the wait rather than by position. */
static int wait_and_read(tty_runner_t *r, int32_t wait_us)
{
    struct pollfd pfd[TTY_RUNNER_MAX_PORTS + TTY_RUNNER_MAX_FDS];
    nfds_t n = 0;
    for (uint8_t i = 0; i < r->num_slots; i++) {
        pfd[n++] = (struct pollfd){.fd = r->slots[i].port->fd, .events = POLLIN};
    }
    uint8_t num_fds = r->num_fds;
    for (uint8_t i = 0; i < num_fds; i++) {
        pfd[n++] = (struct pollfd){.fd = r->fds[i].fd, .events = POLLIN};
    }
    int rc = poll_or_spin(pfd, n, wait_us);
    if (rc < 0) {
        return errno == EINTR ? 0 : runner_fail(r, "poll: %s", strerror(errno));
    }
    for (uint8_t i = 0; i < r->num_slots && rc > 0; i++) {
        if (pfd[i].revents != 0 && read_port(r, &r->slots[i], pfd[i].revents) != 0) {
            return -1;
        }
    }
    bool delivered = false;
    for (nfds_t k = r->num_slots; k < n && rc > 0; k++) {
        if (pfd[k].revents == 0) {
            continue;
        }
        if ((pfd[k].revents & POLLNVAL) != 0) {
            return runner_fail(r, "fd %d: not an open descriptor", pfd[k].fd);
        }
        for (uint8_t i = 0; i < r->num_fds; i++) {
            if (r->fds[i].fd == pfd[k].fd) {
                r->fds[i].readable(r->fds[i].ctx, tty_now_us());
                delivered = true;
                break;
            }
        }
    }
    if (delivered && r->error[0] == '\0') {
        poll_all(r);
    }
    return 0;
}

int tty_runner_run_until(tty_runner_t *r, hal_time_us_t t_end, volatile const int *stop)
{
    r->error[0] = '\0';
    for (;;) {
        if (stop != NULL && *stop != 0) {
            return 0;
        }
        poll_due_stations(r);
        if (r->error[0] != '\0') {
            return -1; /* a transmit failed inside a station callback */
        }
        if (hal_time_reached(tty_now_us(), t_end)) {
            return 0;
        }
        if (wait_and_read(r, wait_budget_us(r, t_end)) != 0 || r->error[0] != '\0') {
            return -1;
        }
    }
}
