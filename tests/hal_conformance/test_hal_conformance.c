/* The HAL UART contract (hal/hal_uart.h), checked by one test body on every backend.
 *
 * A backend is reached through a small adapter (open a medium, attach a station, run until a
 * time, read its clock). The stations are recorder probes: they transmit scripted frames at
 * scripted times and record every received character with its flags and timestamp. The same
 * assertions then hold for the in-memory bus (simulated time) and for the tty backend over a PTY
 * pair (wall-clock time): byte-exact delivery in order, no self-reception, monotonic timestamps,
 * not_before honoured, every PROFIBUS rate accepted, nothing lost in a burst. What only one
 * backend can promise (exact bit timing on the bus; error messages, PARMRK decoding, echo
 * suppression and hang-up reporting on a tty) is tested after the shared body. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "check.h"
#include "dp_slave/fdl_frame.h"
#include "hal/hal_uart.h"
#include "sim_hal/membus.h"
#include "sim_hal/tty_port.h"

#define TEST_BAUD 1500000u /* fast enough that wall-clock runs stay short */
#define REC_MAX 65536u
#define SCRIPT_MAX 256u
#define BURST_FRAMES 200u
#define STEP_US 20000u

/* ---------------------------------------------------------------------------------------------
 * Recorder probe */

typedef struct script_entry {
    const uint8_t *data;
    size_t len;
    uint32_t lead_us; /* not_before = the poll time + lead_us */
} script_entry_t;

typedef struct probe {
    hal_uart_t uart;
    uint32_t baud;
    script_entry_t script[SCRIPT_MAX];
    size_t n_script;
    size_t next;
    hal_time_us_t due;
    uint32_t idle_us; /* line idle after each frame before the next is due */
    hal_time_us_t not_before[SCRIPT_MAX];
    int tx_errors;
    uint8_t byte[REC_MAX];
    uint8_t flags[REC_MAX];
    hal_time_us_t t[REC_MAX];
    size_t n_rx;
    size_t rx_overflow;
} probe_t;

static probe_t probe_a, probe_b, probe_c; /* large: off the stack */

static void probe_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    probe_t *p = ctx;
    if (p->n_rx >= REC_MAX) {
        p->rx_overflow++;
        return;
    }
    p->byte[p->n_rx] = byte;
    p->flags[p->n_rx] = flags;
    p->t[p->n_rx] = t;
    p->n_rx++;
}

static uint32_t frame_us(size_t len, uint32_t baud)
{
    return (uint32_t)(((uint64_t)hal_uart_char_ns(baud) * len + 999u) / 1000u);
}

/* One frame per poll; the next is due after this one has left the line plus idle_us, so the
 * probe never overlaps its own transmissions. */
static hal_time_us_t probe_poll(void *ctx, hal_time_us_t now)
{
    probe_t *p = ctx;
    if (p->next >= p->n_script) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    if (!hal_time_reached(now, p->due)) {
        return p->due;
    }
    const script_entry_t *e = &p->script[p->next];
    hal_time_us_t nb = now + e->lead_us;
    p->not_before[p->next] = nb;
    if (p->uart.ops->transmit(p->uart.ctx, e->data, e->len, nb) != 0) {
        p->tx_errors++;
    }
    p->due = nb + frame_us(e->len, p->baud) + p->idle_us;
    p->next++;
    return p->next < p->n_script ? p->due : now + HAL_TIME_NO_DEADLINE_US;
}

static void probe_reset(probe_t *p)
{
    memset(p, 0, sizeof *p);
}

static sim_station_t probe_station(probe_t *p)
{
    return (sim_station_t){.ctx = p, .rx_char = probe_rx, .poll = probe_poll};
}

static void probe_add(probe_t *p, const uint8_t *data, size_t len, uint32_t lead_us)
{
    if (p->n_script < SCRIPT_MAX) {
        p->script[p->n_script++] = (script_entry_t){.data = data, .len = len, .lead_us = lead_us};
    }
}

static size_t probe_script_bytes(const probe_t *p)
{
    size_t n = 0;
    for (size_t i = 0; i < p->n_script; i++) {
        n += p->script[i].len;
    }
    return n;
}

/* ---------------------------------------------------------------------------------------------
 * Backend adapters */

typedef struct medium {
    const char *name;
    int (*open)(uint32_t baud);
    int (*attach)(probe_t *p); /* gives the probe its uart at the medium's rate */
    int (*run_until)(hal_time_us_t t);
    hal_time_us_t (*now)(void);
    void (*close)(void);
} medium_t;

/* In-memory bus. */
static membus_t mb;
static uint32_t mb_baud;

static int mb_open(uint32_t baud)
{
    membus_init(&mb);
    mb_baud = baud;
    return 0;
}

static int mb_attach(probe_t *p)
{
    sim_station_t st = probe_station(p);
    if (membus_attach(&mb, &st, &p->uart) == NULL) {
        return -1;
    }
    p->baud = mb_baud;
    return p->uart.ops->set_baud(p->uart.ctx, mb_baud);
}

static hal_time_us_t mb_now(void)
{
    return membus_now_us(&mb);
}

static int mb_run_until(hal_time_us_t t)
{
    int32_t d = hal_time_diff(t, mb_now());
    if (d > 0) {
        membus_run_until_ns(&mb, ((uint64_t)mb_now() + (uint64_t)d) * 1000u);
    }
    return 0;
}

static void mb_close(void)
{
}

static const medium_t membus_medium = {
    .name = "membus", .open = mb_open, .attach = mb_attach, .run_until = mb_run_until,
    .now = mb_now, .close = mb_close,
};

/* tty backend over a PTY pair: port 0 on the master, port 1 on the slave, one runner. */
static struct {
    tty_runner_t runner;
    tty_port_t port[2];
    int attached;
    uint32_t baud;
    char slave_name[128];
} tt;

static int tt_open(uint32_t baud)
{
    char err[256] = "";
    memset(&tt, 0, sizeof tt);
    tt.port[0].fd = tt.port[1].fd = -1;
    tty_runner_init(&tt.runner);
    tt.baud = baud;
    int m = posix_openpt(O_RDWR | O_NOCTTY);
    if (m < 0 || grantpt(m) != 0 || unlockpt(m) != 0 ||
        ptsname_r(m, tt.slave_name, sizeof tt.slave_name) != 0) {
        fprintf(stderr, "posix_openpt: %s\n", strerror(errno));
        return -1;
    }
    if (tty_port_open_fd(&tt.port[0], m, baud, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        close(m);
        return -1;
    }
    if (tty_port_open(&tt.port[1], tt.slave_name, baud, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    return 0;
}

static int tt_attach(probe_t *p)
{
    if (tt.attached >= 2) {
        return -1;
    }
    tty_port_t *port = &tt.port[tt.attached++];
    sim_station_t st = probe_station(p);
    p->uart = tty_port_uart(port);
    p->baud = tt.baud;
    return tty_runner_add(&tt.runner, port, &st);
}

static int tt_run_until(hal_time_us_t t)
{
    int rc = tty_runner_run_until(&tt.runner, t, NULL);
    if (rc != 0) {
        fprintf(stderr, "tty runner: %s\n", tty_runner_error(&tt.runner));
    }
    return rc;
}

static void tt_close(void)
{
    tty_port_close(&tt.port[0]);
    tty_port_close(&tt.port[1]);
}

static const medium_t tty_medium = {
    .name = "tty/pty", .open = tt_open, .attach = tt_attach, .run_until = tt_run_until,
    .now = tty_now_us, .close = tt_close,
};

/* ---------------------------------------------------------------------------------------------
 * Helpers for the shared body */

static bool all_done(const probe_t *a, size_t expect_a, const probe_t *b, size_t expect_b)
{
    return a->next == a->n_script && b->next == b->n_script && a->n_rx >= expect_a &&
           b->n_rx >= expect_b;
}

/* Run in steps until both probes sent their scripts and received what they expect (or the
 * budget is spent), then one more step so that stray extra bytes would show up. Wall-clock
 * runs may slip under load; simulated ones finish in the first steps. */
static int run_until_done(const medium_t *m, probe_t *a, size_t expect_a, probe_t *b,
                          size_t expect_b, uint32_t budget_us)
{
    hal_time_us_t end = m->now() + budget_us;
    int rc = 0;
    while (rc == 0 && !all_done(a, expect_a, b, expect_b) && !hal_time_reached(m->now(), end)) {
        rc = m->run_until(m->now() + STEP_US);
    }
    if (rc == 0) {
        rc = m->run_until(m->now() + STEP_US);
    }
    return rc;
}

/* The receiver got exactly the sender's frames, in order, without error flags. */
static void check_stream(const probe_t *rx, const probe_t *tx)
{
    size_t expect = probe_script_bytes(tx);
    CHECK_EQ(rx->n_rx, expect);
    CHECK_EQ(rx->rx_overflow, 0);
    size_t i = 0;
    size_t bad_bytes = 0;
    size_t bad_flags = 0;
    for (size_t k = 0; k < tx->n_script; k++) {
        for (size_t j = 0; j < tx->script[k].len && i < rx->n_rx; j++, i++) {
            if (rx->byte[i] != tx->script[k].data[j] && bad_bytes++ == 0) {
                fprintf(stderr, "    first difference: frame %zu octet %zu: %02X, sent %02X\n",
                        k, j, rx->byte[i], tx->script[k].data[j]);
            }
            bad_flags += rx->flags[i] != 0u;
        }
    }
    CHECK_EQ(bad_bytes, 0);
    CHECK_EQ(bad_flags, 0);
}

static void check_monotonic(const probe_t *p)
{
    size_t backwards = 0;
    for (size_t i = 1; i < p->n_rx; i++) {
        backwards += hal_time_diff(p->t[i], p->t[i - 1u]) < 0;
    }
    CHECK_EQ(backwards, 0);
}

/* A frame's first character cannot have arrived before the instant it was allowed to start. */
static void check_not_before(const probe_t *rx, const probe_t *tx)
{
    size_t i = 0;
    size_t early = 0;
    for (size_t k = 0; k < tx->n_script && i < rx->n_rx; k++) {
        if (hal_time_diff(rx->t[i], tx->not_before[k]) < 0 && early++ == 0) {
            fprintf(stderr, "    frame %zu: first octet at %u, not_before %u\n", k,
                    (unsigned)rx->t[i], (unsigned)tx->not_before[k]);
        }
        i += tx->script[k].len;
    }
    CHECK_EQ(early, 0);
}

static bool setup_pair(const medium_t *m, uint32_t baud)
{
    probe_reset(&probe_a);
    probe_reset(&probe_b);
    bool ok = m->open(baud) == 0 && m->attach(&probe_a) == 0 && m->attach(&probe_b) == 0;
    CHECK(ok);
    return ok;
}

/* ---------------------------------------------------------------------------------------------
 * Test frames: together they carry every octet value, 0xFF in runs and the 0xFF 0x00 X pattern
 * a PARMRK decoder must not mistake for an error mark. */

static const uint8_t f1[1] = {0xFF};
static const uint8_t f6[6] = {0x10, 0xFF, 0x00, 0x41, 0xFF, 0xFF};
static const uint8_t f14[14] = {0xA2, 0x05, 0x02, 0x7D, 0xFF, 0x00, 0x00, 0xFF,
                                0xFF, 0xFF, 0x00, 0x80, 0x7F, 0x16};
static uint8_t f255_up[255];   /* 0x00 .. 0xFE */
static uint8_t f255_down[255]; /* 0xFF .. 0x01 */
static const uint8_t g1[1] = {0x00};
static const uint8_t g6[6] = {0xFF, 0x00, 0xFF, 0x00, 0x00, 0xFF};

static void init_frames(void)
{
    for (unsigned i = 0; i < 255u; i++) {
        f255_up[i] = (uint8_t)i;
        f255_down[i] = (uint8_t)(255u - i);
    }
}

/* ---------------------------------------------------------------------------------------------
 * The shared body */

static void body_exchange(const medium_t *m)
{
    if (!setup_pair(m, TEST_BAUD)) {
        m->close();
        return;
    }
    hal_time_us_t t0 = m->now();
    probe_add(&probe_a, f1, sizeof f1, 0);
    probe_add(&probe_a, f6, sizeof f6, 3000);
    probe_add(&probe_a, f14, sizeof f14, 500);
    probe_add(&probe_a, f255_up, sizeof f255_up, 2000);
    probe_add(&probe_a, f255_down, sizeof f255_down, 0);
    probe_a.idle_us = 100;
    probe_a.due = t0 + 1000;
    /* B answers only once A is finished, so the bus model sees no collision. */
    probe_add(&probe_b, g6, sizeof g6, 1000);
    probe_add(&probe_b, f14, sizeof f14, 0);
    probe_add(&probe_b, g1, sizeof g1, 0);
    probe_b.idle_us = 100;
    probe_b.due = t0 + 30000;
    int rc = run_until_done(m, &probe_a, probe_script_bytes(&probe_b), &probe_b,
                            probe_script_bytes(&probe_a), 3000000);
    CHECK_EQ(rc, 0);
    CHECK_EQ(probe_a.tx_errors, 0);
    CHECK_EQ(probe_b.tx_errors, 0);
    check_stream(&probe_b, &probe_a); /* byte-exact, in order */
    check_stream(&probe_a, &probe_b); /* ... and A heard only B, none of its own octets */
    check_monotonic(&probe_a);
    check_monotonic(&probe_b);
    check_not_before(&probe_b, &probe_a);
    check_not_before(&probe_a, &probe_b);
    m->close();
}

static void body_set_baud(const medium_t *m)
{
    if (!setup_pair(m, TEST_BAUD)) {
        m->close();
        return;
    }
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        CHECK_EQ(probe_a.uart.ops->set_baud(probe_a.uart.ctx, hal_uart_bauds[i]), 0);
        CHECK_EQ(probe_b.uart.ops->set_baud(probe_b.uart.ctx, hal_uart_bauds[i]), 0);
    }
    /* Back to the test rate: the port still carries a frame afterwards. */
    CHECK_EQ(probe_a.uart.ops->set_baud(probe_a.uart.ctx, TEST_BAUD), 0);
    CHECK_EQ(probe_b.uart.ops->set_baud(probe_b.uart.ctx, TEST_BAUD), 0);
    probe_add(&probe_a, f14, sizeof f14, 0);
    probe_a.due = m->now();
    CHECK_EQ(run_until_done(m, &probe_a, 0, &probe_b, sizeof f14, 2000000), 0);
    check_stream(&probe_b, &probe_a);
    CHECK_EQ(probe_a.n_rx, 0);
    m->close();
}

static uint8_t burst_data[BURST_FRAMES][255];

static void body_burst(const medium_t *m)
{
    if (!setup_pair(m, TEST_BAUD)) {
        m->close();
        return;
    }
    uint32_t x = 12345u;
    for (unsigned k = 0; k < BURST_FRAMES; k++) {
        size_t len = 1u + (k * 37u) % 255u;
        for (size_t j = 0; j < len; j++) {
            x = x * 1103515245u + 12345u;
            burst_data[k][j] = (uint8_t)(x >> 23);
        }
        probe_add(&probe_a, burst_data[k], len, 0);
    }
    probe_a.due = m->now();
    int rc = run_until_done(m, &probe_a, 0, &probe_b, probe_script_bytes(&probe_a), 10000000);
    CHECK_EQ(rc, 0);
    CHECK_EQ(probe_a.next, BURST_FRAMES);
    CHECK_EQ(probe_a.tx_errors, 0);
    check_stream(&probe_b, &probe_a);
    check_monotonic(&probe_b);
    CHECK_EQ(probe_a.n_rx, 0);
    m->close();
}

/* ---------------------------------------------------------------------------------------------
 * In-memory bus only: exact timing and the baud-mismatch model */

static void membus_spacing_at(uint32_t baud)
{
    if (!setup_pair(&membus_medium, baud)) {
        return;
    }
    probe_add(&probe_a, f255_up, sizeof f255_up, 1000);
    probe_add(&probe_a, f14, sizeof f14, 0);
    probe_a.idle_us = 37;
    probe_a.due = mb_now() + 500;
    CHECK_EQ(run_until_done(&membus_medium, &probe_a, 0, &probe_b, 255 + 14, 10000000), 0);
    check_stream(&probe_b, &probe_a);
    /* Character i of a frame ends (i + 1) * 11 bit times after its start, truncated to µs. */
    uint64_t char_ns = hal_uart_char_ns(baud);
    size_t i = 0;
    size_t off = 0;
    for (size_t k = 0; k < probe_a.n_script; k++) {
        uint64_t start_ns = (uint64_t)probe_a.not_before[k] * 1000u;
        for (size_t j = 0; j < probe_a.script[k].len && i < probe_b.n_rx; j++, i++) {
            uint64_t expect_us = (start_ns + (j + 1u) * char_ns) / 1000u;
            if (probe_b.t[i] != (hal_time_us_t)expect_us && off++ == 0) {
                fprintf(stderr, "    %u baud frame %zu octet %zu at %u us, expected %llu\n",
                        (unsigned)baud, k, j, (unsigned)probe_b.t[i],
                        (unsigned long long)expect_us);
            }
        }
    }
    CHECK_EQ(off, 0);
}

static void test_membus_exact_spacing(void)
{
    membus_spacing_at(19200u); /* 572.9 µs per character: not a whole number */
    membus_spacing_at(TEST_BAUD);
    membus_spacing_at(12000000u); /* 916.7 ns: several characters per µs */
}

static void test_membus_other_baud_framing_error(void)
{
    if (!setup_pair(&membus_medium, 19200u)) {
        return;
    }
    probe_reset(&probe_c);
    CHECK_EQ(mb_attach(&probe_c), 0);
    CHECK_EQ(probe_c.uart.ops->set_baud(probe_c.uart.ctx, 9600u), 0);
    probe_add(&probe_a, f14, sizeof f14, 0);
    probe_add(&probe_a, f6, sizeof f6, 0);
    probe_a.due = mb_now();
    CHECK_EQ(run_until_done(&membus_medium, &probe_a, 0, &probe_b, 20, 1000000), 0);
    check_stream(&probe_b, &probe_a);
    CHECK_EQ(probe_c.n_rx, 20);
    size_t framing = 0;
    for (size_t i = 0; i < probe_c.n_rx; i++) {
        framing += (probe_c.flags[i] & HAL_UART_RX_FRAMING_ERR) != 0u;
    }
    CHECK_EQ(framing, 20);
}

/* ---------------------------------------------------------------------------------------------
 * tty only */

static void test_tty_open_errors(void)
{
    tty_port_t p;
    char err[256] = "";
    CHECK_EQ(tty_port_open(&p, "/nonexistent/tty", 19200u, err, sizeof err), -1);
    CHECK(err[0] != '\0');
    CHECK(strstr(err, "/nonexistent/tty") != NULL);
    CHECK(strstr(err, "No such file") != NULL);
    CHECK_EQ(p.fd, -1);
    err[0] = '\0';
    CHECK_EQ(tty_port_open(&p, "/dev/null", 19200u, err, sizeof err), -1);
    CHECK(strstr(err, "not a terminal") != NULL);
    err[0] = '\0';
    CHECK_EQ(tty_port_open_fd(&p, -1, 19200u, err, sizeof err), -1);
    CHECK(err[0] != '\0');
}

/* A PTY drops PARENB: the port says so, and works anyway (the shared body ran on it). */
static void test_tty_pty_parity(void)
{
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    CHECK(!tt.port[0].parity_ok);
    CHECK(!tt.port[1].parity_ok);
    CHECK(!tt.port[0].parmrk); /* marking off, or a 0xFF from the slave side would be misread */
    CHECK(!tt.port[1].parmrk);
    CHECK(!tt.port[0].rs485_ok); /* ENOTTY on a PTY, not fatal */
    CHECK(tt.port[0].fd >= 0);
    CHECK(tt.port[1].fd >= 0);
    tt_close();
}

/* Every PROFIBUS rate, standard or not (45450, 93750, 187500, 6M, 12M need termios2/BOTHER),
 * is what the driver then reports. */
static void test_tty_rates_read_back(void)
{
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    hal_uart_t u = tty_port_uart(&tt.port[0]);
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        uint32_t got = 0;
        CHECK_EQ(u.ops->set_baud(u.ctx, hal_uart_bauds[i]), 0);
        CHECK_EQ(tty_port_read_baud(&tt.port[0], &got), 0);
        CHECK_EQ(got, hal_uart_bauds[i]);
        CHECK_EQ(tt.port[0].baud, hal_uart_bauds[i]);
    }
    CHECK_EQ(u.ops->set_baud(u.ctx, 0u), -1);
    tt_close();
}

/* A not_before from another clock (here: far ahead) is refused instead of blocking for minutes,
 * and the runner reports it. */
static void test_tty_not_before_sanity(void)
{
    static const uint8_t sc[1] = {0xE5};
    probe_reset(&probe_a);
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    CHECK_EQ(tt_attach(&probe_a), 0);
    probe_add(&probe_a, sc, sizeof sc, 600000000u); /* 10 minutes */
    probe_a.due = tty_now_us();
    hal_time_us_t t0 = tty_now_us();
    CHECK(tty_runner_run_until(&tt.runner, t0 + 1000000u, NULL) < 0);
    CHECK(hal_time_diff(tty_now_us(), t0) < 500000);
    CHECK_EQ(probe_a.tx_errors, 1);
    CHECK(strstr(tty_runner_error(&tt.runner), "not_before") != NULL);
    tt_close();
}

/* A PTY someone left in raw 8E1 with marking on (as a port on a real adapter would set it): the
 * only change left is PARENB, which the PTY refuses, and glibc's tcsetattr() then reports EINVAL.
 * Opening must still succeed. */
static void test_tty_open_preconfigured_pty(void)
{
    char err[256] = "";
    char name[128];
    int m = posix_openpt(O_RDWR | O_NOCTTY);
    CHECK(m >= 0 && grantpt(m) == 0 && unlockpt(m) == 0);
    CHECK_EQ(ptsname_r(m, name, sizeof name), 0);
    struct termios t;
    CHECK_EQ(tcgetattr(m, &t), 0);
    cfmakeraw(&t);
    t.c_cflag |= CS8 | PARENB | CLOCAL | CREAD;
    t.c_iflag |= INPCK | PARMRK;
    t.c_cc[VMIN] = 0;
    t.c_cc[VTIME] = 0;
    cfsetspeed(&t, B9600);
    (void)tcsetattr(m, TCSANOW, &t);
    tty_port_t p;
    CHECK_EQ(tty_port_open(&p, name, 9600u, err, sizeof err), 0);
    if (err[0] != '\0') {
        fprintf(stderr, "    %s\n", err);
    }
    CHECK(!p.parity_ok);
    CHECK(!p.parmrk);
    tty_port_close(&p);
    close(m);
}

/* PARMRK marks from a real adapter, fed in pieces as read() may split them. */
static void test_tty_decode_marks(void)
{
    tty_port_t p;
    memset(&p, 0, sizeof p);
    p.parmrk = true;
    uint8_t b[16];
    uint8_t f[16];
    const uint8_t r1[] = {0x41, 0xFF, 0xFF, 0xFF, 0x00, 0x42, 0xFF};
    const uint8_t r2[] = {0x00};
    const uint8_t r3[] = {0x43, 0xFF};
    const uint8_t r4[] = {0xFF, 0x00};
    size_t n = tty_port_decode(&p, r1, sizeof r1, b, f);
    CHECK_BYTES(b, n, 0x41, 0xFF, 0x42);
    CHECK_BYTES(f, n, 0x00, 0x00, HAL_UART_RX_PARITY_ERR);
    CHECK_EQ(tty_port_decode(&p, r2, sizeof r2, b, f), 0); /* escape still open */
    n = tty_port_decode(&p, r3, sizeof r3, b, f);
    CHECK_BYTES(b, n, 0x43);
    CHECK_BYTES(f, n, HAL_UART_RX_PARITY_ERR);
    n = tty_port_decode(&p, r4, sizeof r4, b, f);
    CHECK_BYTES(b, n, 0xFF, 0x00); /* the pending 0xFF 0xFF is a data 0xFF */
    CHECK_BYTES(f, n, 0x00, 0x00);
    CHECK_EQ(p.char_errors, 2);
    const uint8_t r5[] = {0x10, 0xFF};
    const uint8_t r6[] = {0x16};
    n = tty_port_decode(&p, r5, sizeof r5, b, f);
    CHECK_BYTES(b, n, 0x10);
    n = tty_port_decode(&p, r6, sizeof r6, b, f); /* not a mark: both bytes pass, n + 1 out */
    CHECK_BYTES(b, n, 0xFF, 0x16);
    CHECK_BYTES(f, n, 0x00, 0x00);
    p.parmrk = false; /* a PTY: bytes pass unchanged */
    n = tty_port_decode(&p, r1, sizeof r1, b, f);
    CHECK_EQ(n, sizeof r1);
    CHECK(memcmp(b, r1, sizeof r1) == 0);
}

typedef struct tap_rec {
    uint64_t t_ns;
    uint8_t bytes[16];
    size_t len;
    bool local;
    uint32_t baud;
} tap_rec_t;

static tap_rec_t taps[16];
static size_t n_taps;

static void record_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len,
                       bool from_local_station, uint32_t baud)
{
    (void)ctx;
    if (n_taps < 16u) {
        tap_rec_t *r = &taps[n_taps++];
        r->t_ns = t_start_ns;
        r->len = len < sizeof r->bytes ? len : sizeof r->bytes;
        memcpy(r->bytes, frame, r->len);
        r->local = from_local_station;
        r->baud = baud;
    }
}

/* Every frame shows up twice: as sent by one port and as received (and assembled) by the other. */
static void test_tty_tap(void)
{
    static uint8_t sd1_a[6] = {0x10, 0x05, 0x02, 0x49, 0x00, 0x16};
    static uint8_t sd1_b[6] = {0x10, 0x02, 0x05, 0x00, 0x00, 0x16};
    static const uint8_t sc[1] = {0xE5};
    sd1_a[4] = fdl_fcs(&sd1_a[1], 3);
    sd1_b[4] = fdl_fcs(&sd1_b[1], 3);
    n_taps = 0;
    if (!setup_pair(&tty_medium, TEST_BAUD)) {
        tt_close();
        return;
    }
    tty_runner_set_tap(&tt.runner, record_tap, NULL);
    hal_time_us_t t0 = tty_now_us();
    probe_add(&probe_a, sd1_a, sizeof sd1_a, 0);
    probe_add(&probe_a, sc, sizeof sc, 0);
    probe_a.idle_us = 5000;
    probe_a.due = t0 + 1000;
    probe_add(&probe_b, sd1_b, sizeof sd1_b, 0);
    probe_b.due = t0 + 30000;
    CHECK_EQ(run_until_done(&tty_medium, &probe_a, 6, &probe_b, 7, 2000000), 0);
    CHECK_EQ(n_taps, 6);
    /* Sent frames in script order, received ones in the same order, each no earlier than its
     * transmission; how the two interleave depends on when the kernel passes the bytes on. */
    const uint8_t *expect[3] = {sd1_a, sc, sd1_b};
    const size_t len[3] = {6, 1, 6};
    size_t k_tx = 0;
    size_t k_rx = 0;
    uint64_t t_tx[3] = {0};
    for (size_t i = 0; i < n_taps; i++) {
        size_t *k = taps[i].local ? &k_tx : &k_rx;
        if (*k >= 3u) {
            CHECK(*k < 3u);
            continue;
        }
        CHECK_EQ(taps[i].len, len[*k]);
        CHECK(memcmp(taps[i].bytes, expect[*k], len[*k]) == 0);
        CHECK_EQ(taps[i].baud, TEST_BAUD);
        if (taps[i].local) {
            t_tx[*k] = taps[i].t_ns;
        } else {
            CHECK(*k < k_tx && taps[i].t_ns >= t_tx[*k]);
        }
        (*k)++;
    }
    CHECK_EQ(k_tx, 3);
    CHECK_EQ(k_rx, 3);
    tt_close();
}

/* Run the PTY medium in short steps until probe p has sent `sent` frames and received `rx`
 * octets (or a second has passed), so the steps below do not depend on scheduling luck. */
static void tt_run_until_progress(const probe_t *p, size_t sent, size_t rx)
{
    hal_time_us_t end = tty_now_us() + 1000000u;
    while ((p->next < sent || p->n_rx < rx) && !hal_time_reached(tty_now_us(), end)) {
        if (tt_run_until(tty_now_us() + 1000u) != 0) {
            return;
        }
    }
}

/* Up to n octets from a raw fd within a second: a PTY hands data on through a kernel work
 * queue, so it is not always readable the instant the other side wrote it. */
static size_t read_peer(int fd, uint8_t *buf, size_t n)
{
    size_t got = 0;
    hal_time_us_t end = tty_now_us() + 1000000u;
    while (got < n && !hal_time_reached(tty_now_us(), end)) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        (void)poll(&pfd, 1, 10);
        ssize_t r = read(fd, buf + got, n - got);
        if (r > 0) {
            got += (size_t)r;
        }
    }
    return got;
}

/* An adapter that hears itself, played by the test on the PTY slave: the echo is dropped, the
 * other station's frame is delivered; a byte that is not the echo ends the expectation. */
static void test_tty_echo_suppression(void)
{
    static const uint8_t f_a[6] = {0x10, 0x22, 0x33, 0xFF, 0x00, 0x16};
    static const uint8_t g[3] = {0xDC, 0x01, 0x02};
    static const uint8_t f_a2[4] = {0x68, 0xFF, 0xFF, 0x68};
    static const uint8_t g2[2] = {0xE5, 0x68};
    uint8_t buf[64];
    probe_reset(&probe_a);
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    CHECK_EQ(tt_attach(&probe_a), 0);
    tt.port[0].echo_suppress = true;
    int peer = tt.port[1].fd;
    probe_add(&probe_a, f_a, sizeof f_a, 0);
    probe_add(&probe_a, f_a2, sizeof f_a2, 0);
    probe_a.idle_us = 100000; /* the second frame only after the first exchange is checked */
    probe_a.due = tty_now_us();
    tt_run_until_progress(&probe_a, 1, 0);
    CHECK_EQ(read_peer(peer, buf, sizeof f_a), sizeof f_a);
    CHECK(memcmp(buf, f_a, sizeof f_a) == 0);
    CHECK_EQ(write(peer, f_a, sizeof f_a), (ssize_t)sizeof f_a); /* the echo */
    CHECK_EQ(write(peer, g, sizeof g), (ssize_t)sizeof g);       /* another station */
    tt_run_until_progress(&probe_a, 1, sizeof g);
    CHECK_EQ(tt_run_until(tty_now_us() + 5000u), 0); /* time for anything extra to show up */
    CHECK_BYTES(probe_a.byte, probe_a.n_rx, 0xDC, 0x01, 0x02);
    CHECK_EQ(tt.port[0].echo_dropped, sizeof f_a);
    tt_run_until_progress(&probe_a, 2, sizeof g);
    CHECK_EQ(probe_a.next, 2);
    CHECK_EQ(read_peer(peer, buf, sizeof f_a2), sizeof f_a2);
    CHECK_EQ(write(peer, g2, sizeof g2), (ssize_t)sizeof g2); /* no echo this time */
    tt_run_until_progress(&probe_a, 2, sizeof g + sizeof g2);
    CHECK_BYTES(probe_a.byte, probe_a.n_rx, 0xDC, 0x01, 0x02, 0xE5, 0x68);
    CHECK_EQ(tt.port[0].echo_dropped, sizeof f_a);
    tt_close();
}

/* The peer closing ends the run at once with a message, instead of spinning until t_end. */
static void hangup_case(int runner_side)
{
    probe_reset(&probe_a);
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    sim_station_t st = probe_station(&probe_a);
    CHECK_EQ(tty_runner_add(&tt.runner, &tt.port[runner_side], &st), 0);
    tty_port_close(&tt.port[1 - runner_side]);
    hal_time_us_t t0 = tty_now_us();
    int rc = tty_runner_run_until(&tt.runner, t0 + 3000000u, NULL);
    int32_t took = hal_time_diff(tty_now_us(), t0);
    CHECK(rc < 0);
    CHECK(tty_runner_error(&tt.runner)[0] != '\0');
    CHECK(took < 1000000);
    tt_close();
}

static void test_tty_hangup(void)
{
    hangup_case(0); /* master in the runner: the slave closes, read() gives EIO */
    hangup_case(1); /* slave in the runner: the master closes, read() gives end of file */
}

static void test_tty_stop_flag(void)
{
    probe_reset(&probe_a);
    CHECK_EQ(tt_open(TEST_BAUD), 0);
    CHECK_EQ(tt_attach(&probe_a), 0);
    volatile int stop = 1;
    hal_time_us_t t0 = tty_now_us();
    CHECK_EQ(tty_runner_run_until(&tt.runner, t0 + 3000000u, &stop), 0);
    CHECK(hal_time_diff(tty_now_us(), t0) < 1000000);
    tt_close();
}

/* ---------------------------------------------------------------------------------------------
 */

static void run_body(const medium_t *m, void (*body)(const medium_t *), const char *what)
{
    static char name[96];
    (void)snprintf(name, sizeof name, "%s: %s", m->name, what);
    check_test_name_ = name;
    body(m);
}

int main(void)
{
    static const medium_t *const media[] = {&membus_medium, &tty_medium};
    init_frames();
    for (size_t i = 0; i < sizeof media / sizeof media[0]; i++) {
        run_body(media[i], body_exchange, "exchange");
        run_body(media[i], body_set_baud, "set_baud");
        run_body(media[i], body_burst, "burst");
    }
    RUN_TEST(test_membus_exact_spacing);
    RUN_TEST(test_membus_other_baud_framing_error);
    RUN_TEST(test_tty_open_errors);
    RUN_TEST(test_tty_pty_parity);
    RUN_TEST(test_tty_open_preconfigured_pty);
    RUN_TEST(test_tty_rates_read_back);
    RUN_TEST(test_tty_not_before_sanity);
    RUN_TEST(test_tty_decode_marks);
    RUN_TEST(test_tty_tap);
    RUN_TEST(test_tty_echo_suppression);
    RUN_TEST(test_tty_hangup);
    RUN_TEST(test_tty_stop_flag);
    return check_report();
}
