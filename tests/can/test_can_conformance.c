/* The HAL CAN contract (hal/hal_can.h), checked by one test body on every backend.
 *
 *   test_can_conformance                     the in-memory bus, plus what a host without
 *                                            SocketCAN can check (open errors, runner fds)
 *   test_can_conformance --socketcan vcan0   the same body on SocketCAN as well (run inside the
 *                                            VM: tests/vm/vm-run.sh), plus SocketCAN-only checks
 *
 * A backend is reached through a small adapter (open, attach a recorder node, run until the
 * recorders have what they expect or a time limit passes). The shared body asserts: frames of
 * length 0..8 arrive byte-exact with their identifiers, in send order, at every other node and
 * never at the sender; the whole 11-bit identifier range passes and identifiers above 0x7FF or
 * more than 8 octets are refused by send(); a burst of 200 frames arrives complete and in order;
 * a node may send from inside its receive callback (request/response). */
#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "hal/hal_can.h"
#include "sim_hal/memcan.h"
#include "sim_hal/socketcan.h"
#include "sim_hal/tty_port.h"

#define REC_MAX 4096u
#define BURST 200u
#define RUN_LIMIT_US 3000000u

/* ---------------------------------------------------------------------------------------------
 * Recorder node */

typedef struct rec {
    hal_can_t can;
    hal_can_frame_t got[REC_MAX];
    size_t n;
    size_t overflow;
    bool responder;          /* answers every frame with id ^ 0x400, same data */
    int respond_errors;
} rec_t;

static rec_t rec_a, rec_b, rec_c; /* large: off the stack */

static void rec_rx(void *ctx, const hal_can_frame_t *f)
{
    rec_t *r = ctx;
    if (r->n < REC_MAX) {
        r->got[r->n++] = *f;
    } else {
        r->overflow++;
    }
    if (r->responder) {
        hal_can_frame_t a = *f;
        a.id = (uint16_t)(f->id ^ 0x400u);
        if (r->can.ops->send(r->can.ctx, &a) != 0) {
            r->respond_errors++;
        }
    }
}

static void rec_reset(rec_t *r)
{
    memset(r, 0, sizeof *r);
}

static int rec_send(rec_t *r, uint16_t id, const uint8_t *data, uint8_t len)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    if (len <= HAL_CAN_MAX_DLC && data != NULL) {
        memcpy(f.data, data, len);
    }
    return r->can.ops->send(r->can.ctx, &f);
}

/* ---------------------------------------------------------------------------------------------
 * Backend adapters */

typedef struct medium {
    const char *name;
    int (*open)(void);
    int (*attach)(rec_t *r);
    /* Run until a, b, c hold at least na, nb, nc frames (then a little longer, so anything extra
     * shows up) or RUN_LIMIT_US passes. */
    void (*run)(size_t na, size_t nb, size_t nc);
    void (*close)(void);
} medium_t;

/* In-memory bus. */
static memcan_t mc;

static int mc_open(void)
{
    memcan_init(&mc);
    return 0;
}

static int mc_attach(rec_t *r)
{
    return memcan_attach(&mc, rec_rx, r, &r->can) != NULL ? 0 : -1;
}

static void mc_run(size_t na, size_t nb, size_t nc)
{
    (void)na;
    (void)nb;
    (void)nc;
    (void)memcan_deliver(&mc, 100000u);
}

static void mc_close(void)
{
}

static const medium_t memcan_medium = {
    .name = "memcan", .open = mc_open, .attach = mc_attach, .run = mc_run, .close = mc_close,
};

/* SocketCAN: one socket per node on the same interface, all in one tty runner. */
static const char *sc_ifname;
static struct {
    tty_runner_t runner;
    socketcan_t sock[3];
    int n;
    volatile int stop;
    size_t want[3];
    hal_time_us_t settle_until;
    bool settling;
} sc;

static int sc_open(void)
{
    memset(&sc, 0, sizeof sc);
    tty_runner_init(&sc.runner);
    return 0;
}

static int sc_attach(rec_t *r)
{
    char err[256] = "";
    socketcan_t *s = &sc.sock[sc.n];
    if (socketcan_open(s, sc_ifname, rec_rx, r, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    if (socketcan_attach(s, &sc.runner) != 0) {
        return -1;
    }
    r->can = socketcan_can(s);
    sc.n++;
    return 0;
}

static hal_time_us_t sc_watch(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    bool done = rec_a.n >= sc.want[0] && rec_b.n >= sc.want[1] && rec_c.n >= sc.want[2];
    if (done && !sc.settling) {
        sc.settling = true;
        sc.settle_until = now + 20000u; /* anything extra (an echo) would arrive by then */
    }
    if (sc.settling && hal_time_reached(now, sc.settle_until)) {
        sc.stop = 1;
    }
    return sc.settling ? sc.settle_until : now + 5000u;
}

static bool sc_watch_added;

static void sc_run(size_t na, size_t nb, size_t nc)
{
    sc.want[0] = na;
    sc.want[1] = nb;
    sc.want[2] = nc;
    sc.stop = 0;
    sc.settling = false;
    if (!sc_watch_added) {
        sc_watch_added = tty_runner_add_timer(&sc.runner, sc_watch, NULL) == 0;
    }
    if (tty_runner_run_until(&sc.runner, tty_now_us() + RUN_LIMIT_US, &sc.stop) != 0) {
        fprintf(stderr, "runner: %s\n", tty_runner_error(&sc.runner));
    }
}

static void sc_close(void)
{
    for (int i = 0; i < sc.n; i++) {
        socketcan_close(&sc.sock[i]);
    }
    sc.n = 0;
    sc_watch_added = false;
}

static const medium_t socketcan_medium = {
    .name = "socketcan", .open = sc_open, .attach = sc_attach, .run = sc_run, .close = sc_close,
};

static bool setup3(const medium_t *m)
{
    rec_reset(&rec_a);
    rec_reset(&rec_b);
    rec_reset(&rec_c);
    bool ok = m->open() == 0 && m->attach(&rec_a) == 0 && m->attach(&rec_b) == 0 &&
              m->attach(&rec_c) == 0;
    CHECK(ok);
    return ok;
}

static bool same_frame(const hal_can_frame_t *a, const hal_can_frame_t *b)
{
    return a->id == b->id && a->len == b->len && memcmp(a->data, b->data, a->len) == 0;
}

/* ---------------------------------------------------------------------------------------------
 * The shared body */

/* Lengths 0..8, distinct identifiers and contents; B and C get all of them in order. */
static void body_lengths(const medium_t *m)
{
    if (!setup3(m)) {
        return;
    }
    hal_can_frame_t sent[9];
    for (uint8_t len = 0; len <= 8u; len++) {
        memset(&sent[len], 0, sizeof sent[len]);
        sent[len].id = (uint16_t)(0x100u + len);
        sent[len].len = len;
        for (uint8_t i = 0; i < len; i++) {
            sent[len].data[i] = (uint8_t)((i & 1u) ? 0xFFu - i * 17u : i * 31u + len);
        }
        CHECK_EQ(rec_a.can.ops->send(rec_a.can.ctx, &sent[len]), 0);
    }
    m->run(0, 9, 9);
    CHECK_EQ(rec_b.n, 9);
    CHECK_EQ(rec_c.n, 9);
    CHECK_EQ(rec_a.n, 0); /* no echo to the sender */
    for (size_t i = 0; i < 9u && i < rec_b.n && i < rec_c.n; i++) {
        CHECK(same_frame(&rec_b.got[i], &sent[i]));
        CHECK(same_frame(&rec_c.got[i], &sent[i]));
    }
    m->close();
}

/* Every 11-bit identifier boundary passes; 0x800.. and 9 octets are refused by send(). */
static void body_id_range(const medium_t *m)
{
    if (!setup3(m)) {
        return;
    }
    static const uint16_t ids[] = {0x000, 0x001, 0x7FF, 0x7FE, 0x400, 0x3FF, 0x555, 0x2AA,
                                   523,   524,   11,    12};
    const size_t n = sizeof ids / sizeof ids[0];
    const uint8_t data[8] = {0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89};
    for (size_t i = 0; i < n; i++) {
        CHECK_EQ(rec_send(&rec_b, ids[i], data, 8), 0);
    }
    CHECK(rec_send(&rec_b, 0x800, data, 8) != 0);
    CHECK(rec_send(&rec_b, 0xFFFF, data, 8) != 0);
    CHECK(rec_send(&rec_b, 0x123, data, 9) != 0);
    m->run(n, 0, n);
    CHECK_EQ(rec_a.n, n);
    CHECK_EQ(rec_c.n, n);
    CHECK_EQ(rec_b.n, 0);
    for (size_t i = 0; i < n && i < rec_a.n; i++) {
        CHECK_EQ(rec_a.got[i].id, ids[i]);
        CHECK_BYTES(rec_a.got[i].data, rec_a.got[i].len, 0x01, 0x00, 0x20, 0x6C, 0x31, 0x1C,
                    0x72, 0x89);
    }
    m->close();
}

/* 200 frames back to back from A; then A and B interleaved: per-sender order is kept. */
static void body_burst(const medium_t *m)
{
    if (!setup3(m)) {
        return;
    }
    int errors = 0;
    for (uint32_t i = 0; i < BURST; i++) {
        uint8_t d[8] = {(uint8_t)(i >> 8), (uint8_t)i, 0xA5, 0x5A, (uint8_t)~i, 0, 0xFF,
                        (uint8_t)(i * 7u)};
        errors += rec_send(&rec_a, (uint16_t)((i * 37u) & 0x7FFu), d, (uint8_t)(i % 9u)) != 0;
    }
    CHECK_EQ(errors, 0);
    m->run(0, BURST, BURST);
    CHECK_EQ(rec_b.n, BURST);
    CHECK_EQ(rec_c.n, BURST);
    CHECK_EQ(rec_a.n, 0);
    int bad = 0;
    for (uint32_t i = 0; i < BURST && i < rec_b.n && i < rec_c.n; i++) {
        uint8_t d[8] = {(uint8_t)(i >> 8), (uint8_t)i, 0xA5, 0x5A, (uint8_t)~i, 0, 0xFF,
                        (uint8_t)(i * 7u)};
        hal_can_frame_t e = {.id = (uint16_t)((i * 37u) & 0x7FFu), .len = (uint8_t)(i % 9u)};
        memcpy(e.data, d, e.len);
        bad += !same_frame(&rec_b.got[i], &e) || !same_frame(&rec_c.got[i], &e);
    }
    CHECK_EQ(bad, 0);

    rec_a.n = rec_b.n = rec_c.n = 0;
    for (uint32_t i = 0; i < 50u; i++) {
        uint8_t d[2] = {(uint8_t)i, 0xAA};
        uint8_t e[2] = {(uint8_t)i, 0xBB};
        errors += rec_send(&rec_a, 0x10, d, 2) != 0;
        errors += rec_send(&rec_b, 0x20, e, 2) != 0;
    }
    CHECK_EQ(errors, 0);
    m->run(50, 50, 100);
    CHECK_EQ(rec_a.n, 50);
    CHECK_EQ(rec_b.n, 50);
    CHECK_EQ(rec_c.n, 100);
    uint32_t next_a = 0;
    uint32_t next_b = 0;
    bad = 0;
    for (size_t i = 0; i < rec_c.n; i++) {
        const hal_can_frame_t *f = &rec_c.got[i];
        if (f->id == 0x10) {
            bad += f->data[0] != (uint8_t)next_a++ || f->data[1] != 0xAA;
        } else {
            bad += f->id != 0x20 || f->data[0] != (uint8_t)next_b++ || f->data[1] != 0xBB;
        }
    }
    CHECK_EQ(bad, 0);
    CHECK_EQ(next_a, 50);
    CHECK_EQ(next_b, 50);
    for (size_t i = 0; i < rec_a.n; i++) {
        bad += rec_a.got[i].id != 0x20; /* A hears only B */
    }
    for (size_t i = 0; i < rec_b.n; i++) {
        bad += rec_b.got[i].id != 0x10;
    }
    CHECK_EQ(bad, 0);
    m->close();
}

/* B answers from inside its receive callback: A gets one answer per request, in order. */
static void body_request_response(const medium_t *m)
{
    if (!setup3(m)) {
        return;
    }
    rec_b.responder = true;
    for (uint8_t i = 0; i < 20u; i++) {
        uint8_t d[8] = {0x01, 0x00, 0x20, 0x6C, 0, 0, 0, i};
        CHECK_EQ(rec_send(&rec_a, 523, d, 8), 0);
    }
    m->run(20, 20, 40);
    CHECK_EQ(rec_b.respond_errors, 0);
    CHECK_EQ(rec_a.n, 20);
    CHECK_EQ(rec_c.n, 40);
    int bad = 0;
    for (uint8_t i = 0; i < 20u && i < rec_a.n; i++) {
        bad += rec_a.got[i].id != (523u ^ 0x400u) || rec_a.got[i].len != 8u ||
               rec_a.got[i].data[7] != i;
    }
    CHECK_EQ(bad, 0);
    m->close();
}

static void run_body(const medium_t *m, void (*body)(const medium_t *), const char *what)
{
    char name[96];
    (void)snprintf(name, sizeof name, "%s/%s", m->name, what);
    check_test_name_ = name;
    body(m);
}

static void run_all_bodies(const medium_t *m)
{
    run_body(m, body_lengths, "lengths");
    run_body(m, body_id_range, "id_range");
    run_body(m, body_burst, "burst");
    run_body(m, body_request_response, "request_response");
}

/* ---------------------------------------------------------------------------------------------
 * In-memory bus only */

static void test_memcan_loss(void)
{
    memcan_t bus;
    memcan_init(&bus);
    rec_reset(&rec_a);
    rec_reset(&rec_b);
    CHECK(memcan_attach(&bus, rec_rx, &rec_a, &rec_a.can) != NULL);
    CHECK(memcan_attach(&bus, rec_rx, &rec_b, &rec_b.can) != NULL);
    uint8_t d[1];
    memcan_drop_next(&bus, 2);
    for (uint8_t i = 0; i < 5u; i++) {
        d[0] = i;
        CHECK_EQ(rec_send(&rec_a, 0x11, d, 1), 0); /* the sender cannot tell */
    }
    CHECK_EQ(memcan_deliver(&bus, 0), 3);
    CHECK_EQ(rec_b.n, 3);
    CHECK_EQ(rec_b.got[0].data[0], 2);
    CHECK_EQ(bus.frames_lost, 2);

    /* Random loss is the same for the same seed. */
    size_t got[2];
    for (int run = 0; run < 2; run++) {
        memcan_init(&bus);
        rec_reset(&rec_b);
        (void)memcan_attach(&bus, rec_rx, &rec_a, &rec_a.can);
        (void)memcan_attach(&bus, rec_rx, &rec_b, &rec_b.can);
        memcan_set_loss(&bus, 300, 12345);
        for (uint32_t i = 0; i < 400u; i++) {
            d[0] = (uint8_t)i;
            (void)rec_send(&rec_a, 0x12, d, 1);
            (void)memcan_deliver(&bus, 0);
        }
        got[run] = rec_b.n;
    }
    CHECK_EQ(got[0], got[1]);
    CHECK(got[0] > 220u && got[0] < 340u); /* about 70 % of 400 */
}

static void test_memcan_queue_and_offline(void)
{
    static memcan_t bus;
    memcan_init(&bus);
    rec_reset(&rec_a);
    rec_reset(&rec_b);
    rec_reset(&rec_c);
    memcan_node_t *na = memcan_attach(&bus, rec_rx, &rec_a, &rec_a.can);
    memcan_node_t *nb = memcan_attach(&bus, rec_rx, &rec_b, &rec_b.can);
    (void)na;
    int refused = 0;
    for (uint32_t i = 0; i < MEMCAN_QUEUE + 1u; i++) {
        refused += rec_send(&rec_a, 0x7, NULL, 0) != 0;
    }
    CHECK_EQ(refused, 1); /* a full queue refuses, like a full transmit mailbox */
    CHECK_EQ(memcan_deliver(&bus, 0), MEMCAN_QUEUE);
    /* An offline node hears nothing and its frames are lost. */
    nb->offline = true;
    CHECK_EQ(rec_send(&rec_a, 0x8, NULL, 0), 0);
    CHECK_EQ(rec_send(&rec_b, 0x9, NULL, 0), 0);
    size_t before = rec_b.n;
    (void)memcan_deliver(&bus, 0);
    CHECK_EQ(rec_b.n, before);
    CHECK_EQ(rec_a.n, 0);
    /* Two responders answering each other forever: the max_frames guard stops the loop. */
    memcan_init(&bus);
    rec_reset(&rec_a);
    rec_reset(&rec_b);
    rec_a.responder = rec_b.responder = true;
    (void)memcan_attach(&bus, rec_rx, &rec_a, &rec_a.can);
    (void)memcan_attach(&bus, rec_rx, &rec_b, &rec_b.can);
    CHECK_EQ(rec_send(&rec_a, 0x1, NULL, 0), 0);
    CHECK_EQ(memcan_deliver(&bus, 100), 100);
    CHECK_EQ(memcan_pending(&bus), 1);
    CHECK_EQ(memcan_attach(&bus, NULL, NULL, NULL) != NULL, 1);
    for (int i = 3; i < (int)MEMCAN_MAX_NODES; i++) {
        (void)memcan_attach(&bus, NULL, NULL, NULL);
    }
    CHECK(memcan_attach(&bus, NULL, NULL, NULL) == NULL);
}

/* ---------------------------------------------------------------------------------------------
 * SocketCAN, anywhere: opening errors */

static void test_socketcan_open_errors(void)
{
    socketcan_t s;
    char err[256] = "";
    CHECK_EQ(socketcan_open(&s, "nosuchcan0", NULL, NULL, err, sizeof err), -1);
    CHECK_EQ(s.fd, -1);
    const char *prefix = "cannot open CAN interface nosuchcan0: ";
    CHECK(strncmp(err, prefix, strlen(prefix)) == 0);
    CHECK(strchr(err, '\n') == NULL);
    if (errno == EAFNOSUPPORT) {
        CHECK(strstr(err, "Address family not supported by protocol (this kernel has no "
                          "SocketCAN)") != NULL);
        printf("note: this kernel has no SocketCAN: %s\n", err);
    } else {
        CHECK(strstr(err, "No such device (create it: ip link add dev nosuchcan0 type vcan; "
                          "ip link set up nosuchcan0)") != NULL);
    }
    CHECK_EQ(socketcan_open(&s, "a-name-longer-than-ifnamsiz", NULL, NULL, err, sizeof err), -1);
    CHECK(strstr(err, "invalid interface name") != NULL);
    CHECK_EQ(socketcan_open(&s, "", NULL, NULL, err, sizeof err), -1);
}

/* ---------------------------------------------------------------------------------------------
 * The runner's descriptor and timer API (tty_port.h), on a pipe */

static struct {
    int fds[2];
    int reads;
    uint8_t last;
    int timer_calls;
    hal_time_us_t t_first;
    hal_time_us_t t_second;
    volatile int stop;
    tty_runner_t runner;
} rt;

static void rt_readable(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    (void)now;
    uint8_t b;
    while (read(rt.fds[0], &b, 1) == 1) {
        rt.last = b;
        rt.reads++;
        if (b == 0xEE) {
            tty_runner_set_error(&rt.runner, "pipe said %s", "stop");
        }
    }
}

static hal_time_us_t rt_timer(void *ctx, hal_time_us_t now)
{
    (void)ctx;
    rt.timer_calls++;
    if (rt.timer_calls == 1) {
        rt.t_first = now;
        uint8_t b = 0x42;
        (void)!write(rt.fds[1], &b, 1);
        return now + 30000u;
    }
    if (rt.t_second == 0u && hal_time_diff(now, rt.t_first) >= 30000) {
        rt.t_second = now;
        rt.stop = 1;
    }
    return rt.t_second != 0u ? now + HAL_TIME_NO_DEADLINE_US : rt.t_first + 30000u;
}

static void test_runner_fd_and_timer(void)
{
    memset(&rt, 0, sizeof rt);
    CHECK_EQ(pipe2(rt.fds, O_NONBLOCK | O_CLOEXEC), 0);
    tty_runner_init(&rt.runner);
    CHECK_EQ(tty_runner_add_fd(&rt.runner, rt.fds[0], rt_readable, NULL), 0);
    CHECK_EQ(tty_runner_add_timer(&rt.runner, rt_timer, NULL), 0);
    hal_time_us_t t0 = tty_now_us();
    CHECK_EQ(tty_runner_run_until(&rt.runner, t0 + 2000000u, &rt.stop), 0);
    CHECK_EQ(rt.reads, 1);
    CHECK_EQ(rt.last, 0x42);
    CHECK(rt.t_second != 0u);
    int32_t gap = hal_time_diff(rt.t_second, rt.t_first);
    CHECK(gap >= 30000 && gap < 500000);
    CHECK(rt.timer_calls >= 3); /* first run, after the fd delivered, at its deadline */
    CHECK(hal_time_diff(tty_now_us(), t0) < 1000000);
    /* An fd user can end the run with a message. */
    uint8_t b = 0xEE;
    CHECK_EQ(write(rt.fds[1], &b, 1), 1);
    rt.stop = 0;
    CHECK_EQ(tty_runner_run_until(&rt.runner, tty_now_us() + 1000000u, &rt.stop), -1);
    CHECK_STR(tty_runner_error(&rt.runner), "pipe said stop");
    /* After removal the pipe is not watched any more. */
    CHECK_EQ(tty_runner_remove_fd(&rt.runner, rt.fds[0]), 0);
    CHECK_EQ(tty_runner_remove_fd(&rt.runner, rt.fds[0]), -1);
    b = 0x43;
    CHECK_EQ(write(rt.fds[1], &b, 1), 1);
    CHECK_EQ(tty_runner_run_until(&rt.runner, tty_now_us() + 100000u, NULL), 0);
    CHECK_EQ(rt.reads, 2);
    /* wake: a timer that asked for no deadline runs again at the next loop turn. */
    int before_wake = rt.timer_calls;
    CHECK_EQ(tty_runner_run_until(&rt.runner, tty_now_us() + 20000u, NULL), 0);
    CHECK_EQ(rt.timer_calls, before_wake);
    tty_runner_wake(&rt.runner);
    CHECK_EQ(tty_runner_run_until(&rt.runner, tty_now_us() + 20000u, NULL), 0);
    CHECK_EQ(rt.timer_calls, before_wake + 1);
    /* A removed timer is not run any more. */
    int calls = rt.timer_calls;
    CHECK_EQ(tty_runner_remove_timer(&rt.runner, rt_timer, NULL), 0);
    CHECK_EQ(tty_runner_remove_timer(&rt.runner, rt_timer, NULL), -1);
    CHECK_EQ(tty_runner_run_until(&rt.runner, tty_now_us() + 50000u, NULL), 0);
    CHECK_EQ(rt.timer_calls, calls);
    /* Limits. */
    for (unsigned i = 0; i < TTY_RUNNER_MAX_FDS; i++) {
        CHECK_EQ(tty_runner_add_fd(&rt.runner, rt.fds[0], rt_readable, NULL), 0);
    }
    CHECK_EQ(tty_runner_add_fd(&rt.runner, rt.fds[0], rt_readable, NULL), -1);
    CHECK_EQ(tty_runner_add_fd(&rt.runner, -1, rt_readable, NULL), -1);
    (void)close(rt.fds[0]);
    (void)close(rt.fds[1]);
}

/* ---------------------------------------------------------------------------------------------
 * SocketCAN inside the VM */

static int sh(const char *cmd)
{
    int rc = system(cmd);
    return rc == -1 ? -1 : WEXITSTATUS(rc);
}

static void test_socketcan_vm_errors(void)
{
    socketcan_t s;
    char err[256] = "";
    CHECK_EQ(socketcan_open(&s, "lo", NULL, NULL, err, sizeof err), -1);
    CHECK_STR(err, "cannot open CAN interface lo: not a CAN interface");
    if (sh("ip link add dev vcantest type vcan 2>/dev/null") != 0) {
        CHECK(false && "cannot create vcantest (not root?)");
        return;
    }
    CHECK_EQ(socketcan_open(&s, "vcantest", NULL, NULL, err, sizeof err), -1);
    CHECK_STR(err, "cannot open CAN interface vcantest: interface is down (ip link set up "
                   "vcantest)");
    CHECK_EQ(sh("ip link set up dev vcantest"), 0);
    rec_reset(&rec_a);
    CHECK_EQ(socketcan_open(&s, "vcantest", rec_rx, &rec_a, err, sizeof err), 0);
    /* The interface going down while a runner waits on it ends the run with one line. */
    tty_runner_t r;
    tty_runner_init(&r);
    CHECK_EQ(socketcan_attach(&s, &r), 0);
    CHECK_EQ(sh("ip link set down dev vcantest"), 0);
    int rc = tty_runner_run_until(&r, tty_now_us() + 1000000u, NULL);
    CHECK_EQ(rc, -1);
    CHECK_STR(tty_runner_error(&r), "CAN interface vcantest: Network is down");
    socketcan_close(&s);
    CHECK_EQ(r.num_fds, 0);
    CHECK_EQ(sh("ip link del dev vcantest"), 0);
}

/* Frames per second through vcan0 (sender and receiver in this process), for docs/sbus.md. */
static void measure_vcan_rate(void)
{
    if (!setup3(&socketcan_medium)) {
        return;
    }
    const uint32_t total = 20000u;
    const uint32_t chunk = 100u;
    struct timespec t0;
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int errors = 0;
    for (uint32_t sent = 0; sent < total; sent += chunk) {
        for (uint32_t i = 0; i < chunk; i++) {
            uint8_t d[8] = {(uint8_t)(sent >> 8), (uint8_t)i, 0, 0, 0, 0, 0, 0};
            errors += rec_send(&rec_a, 0x0B, d, 8) != 0;
        }
        rec_b.n = 0;
        while (rec_b.n < chunk) {
            if (socketcan_receive(&sc.sock[1]) <= 0) {
                struct timespec w = {0, 10000};
                nanosleep(&w, NULL);
                clock_gettime(CLOCK_MONOTONIC, &t1);
                if (t1.tv_sec - t0.tv_sec > 20) {
                    break;
                }
            }
        }
        (void)socketcan_receive(&sc.sock[2]);
        rec_c.n = 0;
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double s = (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) / 1e9;
    CHECK_EQ(errors, 0);
    printf("vcan0: %u frames of 8 octets, one sender and two receiving sockets: %.0f frames/s\n",
           total, (double)total / s);
    socketcan_medium.close();
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--socketcan") == 0 && i + 1 < argc) {
            sc_ifname = argv[++i];
        } else {
            fprintf(stderr, "usage: %s [--socketcan IFACE]\n", argv[0]);
            return 2;
        }
    }
    run_all_bodies(&memcan_medium);
    RUN_TEST(test_memcan_loss);
    RUN_TEST(test_memcan_queue_and_offline);
    RUN_TEST(test_socketcan_open_errors);
    RUN_TEST(test_runner_fd_and_timer);
    if (sc_ifname != NULL) {
        run_all_bodies(&socketcan_medium);
        RUN_TEST(test_socketcan_vm_errors);
        RUN_TEST(measure_vcan_rate);
    }
    return check_report();
}
