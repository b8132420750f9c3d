/* Linux tty backend of the HAL UART, and a one-thread runner for up to eight ports.
 * See sim_hal/tty_port.h for the model. Built with _GNU_SOURCE (ppoll). */
#include "sim_hal/tty_port.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/serial.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>
#include "sim_hal/host_clock.h"

/* struct termios2 is declared by <asm/termbits.h>, which redefines struct termios and clashes
 * with glibc's <termios.h>. The layout is stable kernel ABI, so it is declared here under its own
 * name, with the ioctl numbers built from it. Architectures with a different layout (or none)
 * only get the standard rates. */
#if defined(__linux__) && !defined(__powerpc__) && !defined(__powerpc64__) && \
    !defined(__sparc__) && !defined(__mips__) && !defined(__alpha__)
#define TTY_HAVE_TERMIOS2 1
struct tty_termios2 {
    tcflag_t c_iflag;
    tcflag_t c_oflag;
    tcflag_t c_cflag;
    tcflag_t c_lflag;
    cc_t c_line;
    cc_t c_cc[19];
    speed_t c_ispeed;
    speed_t c_ospeed;
};
_Static_assert(sizeof(struct tty_termios2) == 44u, "kernel struct termios2 is 44 bytes");
#define TTY_TCGETS2 _IOR('T', 0x2A, struct tty_termios2)
#define TTY_TCSETS2 _IOW('T', 0x2B, struct tty_termios2)
#define TTY_BOTHER 0010000u
#define TTY_IBSHIFT 16u
#endif

#define TTY_READ_CHUNK 4096u
/* Longest wait for not_before a transmit accepts (the longest PROFIBUS delays are slot times
 * of a few ms at 9.6 kbit/s). */
#define TTY_MAX_TX_DELAY_US 10000000
/* Sleep until this close to not_before, then spin: nanosleep overshoots by tens of µs. */
#define TTY_SPIN_US 200
/* Longest single wait in the runner, so a stop flag set from another thread is seen. */
#define TTY_RUNNER_MAX_WAIT_US 50000

enum { MARK_NONE = 0, MARK_FF = 1, MARK_FF00 = 2 };

/* ---------------------------------------------------------------------------------------------
 * Clock */

hal_time_us_t tty_now_us(void)
{
    return (hal_time_us_t)(host_clock_mono_ns() / 1000u);
}

static void sleep_us(int32_t us)
{
    struct timespec ts = {.tv_sec = us / 1000000, .tv_nsec = (long)(us % 1000000) * 1000L};
    (void)nanosleep(&ts, NULL); /* EINTR: the caller re-reads the clock anyway */
}

/* Block until the wall clock reaches t; a t in the past returns at once. */
static void wait_until(hal_time_us_t t)
{
    for (;;) {
        int32_t d = hal_time_diff(t, tty_now_us());
        if (d <= 0) {
            return;
        }
        if (d > TTY_SPIN_US) {
            sleep_us(d - TTY_SPIN_US);
        }
    }
}

/* ---------------------------------------------------------------------------------------------
 * Line settings */

static void set_err(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void set_err(char *err, size_t errlen, const char *fmt, ...)
{
    if (err == NULL || errlen == 0u) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

static bool standard_speed(uint32_t baud, speed_t *code)
{
    static const struct {
        uint32_t baud;
        speed_t code;
    } table[] = {
        {1200u, B1200},       {2400u, B2400},       {4800u, B4800},       {9600u, B9600},
        {19200u, B19200},     {38400u, B38400},     {57600u, B57600},     {115200u, B115200},
        {230400u, B230400},   {460800u, B460800},   {500000u, B500000},   {921600u, B921600},
        {1000000u, B1000000}, {1500000u, B1500000}, {2000000u, B2000000}, {3000000u, B3000000},
        {4000000u, B4000000},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++) {
        if (table[i].baud == baud) {
            *code = table[i].code;
            return true;
        }
    }
    return false;
}

/* Any rate the driver can divide down to: BOTHER with the rate in c_ospeed. Input bits are
 * cleared so the input rate follows the output rate. */
static int set_custom_speed(int fd, uint32_t baud)
{
#ifdef TTY_HAVE_TERMIOS2
    struct tty_termios2 t2;
    if (ioctl(fd, TTY_TCGETS2, &t2) != 0) {
        return -1;
    }
    t2.c_cflag &= ~(tcflag_t)(CBAUD | ((tcflag_t)CBAUD << TTY_IBSHIFT));
    t2.c_cflag |= TTY_BOTHER;
    t2.c_ispeed = baud;
    t2.c_ospeed = baud;
    return ioctl(fd, TTY_TCSETS2, &t2);
#else
    (void)fd;
    (void)baud;
    errno = EINVAL;
    return -1;
#endif
}

/* glibc's tcsetattr() reads the settings back and fails with EINVAL when a requested PARENB is
 * missing and nothing else changed (POSIX: "none of the changes could be made"), which is what
 * a PTY already in raw mode does. Parity is judged separately (check_parity), so only a
 * difference in anything else counts as failure here. */
static bool same_but_parity(const struct termios *a, const struct termios *b)
{
    const tcflag_t parity = PARENB | PARODD;
    return a->c_iflag == b->c_iflag && a->c_oflag == b->c_oflag && a->c_lflag == b->c_lflag &&
           (a->c_cflag & ~parity) == (b->c_cflag & ~parity) &&
           a->c_cc[VMIN] == b->c_cc[VMIN] && a->c_cc[VTIME] == b->c_cc[VTIME];
}

/* TCSANOW: the baud search must switch at once, not after the output drains. */
static int apply_termios(int fd, const struct termios *want)
{
    if (tcsetattr(fd, TCSANOW, want) == 0) {
        return 0;
    }
    int e = errno;
    struct termios got;
    if (e == EINVAL && tcgetattr(fd, &got) == 0 && same_but_parity(want, &got)) {
        return 0;
    }
    errno = e;
    return -1;
}

int tty_port_read_baud(const tty_port_t *p, uint32_t *baud)
{
#ifdef TTY_HAVE_TERMIOS2
    struct tty_termios2 t2;
    if (p->fd < 0 || ioctl(p->fd, TTY_TCGETS2, &t2) != 0) {
        return -1;
    }
    *baud = t2.c_ospeed;
    return 0;
#else
    (void)p;
    (void)baud;
    errno = ENOTSUP;
    return -1;
#endif
}

/* Standard rates through the termios speed codes, any other through termios2. */
static int set_speed(int fd, uint32_t baud)
{
    speed_t code;
    if (baud == 0u) {
        errno = EINVAL;
        return -1;
    }
    if (!standard_speed(baud, &code)) {
        return set_custom_speed(fd, baud);
    }
    struct termios t;
    if (tcgetattr(fd, &t) != 0) {
        return -1;
    }
    if (cfsetispeed(&t, code) != 0 || cfsetospeed(&t, code) != 0) {
        return -1;
    }
    return apply_termios(fd, &t);
}

/* Raw 8E1. INPCK+PARMRK make the line discipline mark characters with parity or framing errors
 * as 0xFF 0x00 X (and double a data 0xFF) instead of silently passing or dropping them. */
static void make_8e1(struct termios *t)
{
    cfmakeraw(t);
    t->c_cflag &= ~(tcflag_t)(CSIZE | PARODD | CSTOPB | CRTSCTS);
    t->c_cflag |= CS8 | PARENB | CLOCAL | CREAD;
    t->c_iflag &= ~(tcflag_t)(IGNPAR | ISTRIP | IXON | IXOFF | IXANY | IGNBRK | BRKINT);
    t->c_iflag |= INPCK | PARMRK;
    t->c_cc[VMIN] = 0;
    t->c_cc[VTIME] = 0;
}

/* A PTY accepts PARENB and then clears it. Without parity there are no marks to decode, and
 * marking must be switched off as well: the two ends of a PTY share one termios, but only the
 * slave side's reads are marked, so a 0xFF written by the slave would reach the master undoubled
 * and be misread. */
static int check_parity(tty_port_t *p)
{
    struct termios t;
    if (tcgetattr(p->fd, &t) != 0) {
        return -1;
    }
    p->parity_ok = (t.c_cflag & PARENB) != 0u && (t.c_cflag & PARODD) == 0u &&
                   (t.c_cflag & CSIZE) == CS8;
    if (!p->parity_ok && (t.c_iflag & (INPCK | PARMRK)) != 0u) {
        t.c_iflag &= ~(tcflag_t)(INPCK | PARMRK);
        if (apply_termios(p->fd, &t) != 0 || tcgetattr(p->fd, &t) != 0) {
            return -1;
        }
    }
    p->parmrk = (t.c_iflag & PARMRK) != 0u && (t.c_iflag & IGNPAR) == 0u;
    return 0;
}

/* The optional ioctls: a driver without the feature answers ENOTTY or EINVAL (EOPNOTSUPP on
 * some, EPERM from a few TIOCSSERIAL implementations); anything else is a device failure. */
static bool feature_missing(int e)
{
    return e == ENOTTY || e == EINVAL || e == EOPNOTSUPP || e == EPERM;
}

/* Let the UART drive RTS (the transceiver's driver-enable) around each transmission, and keep
 * the receiver deaf while sending so the station does not hear itself. */
static int enable_rs485(tty_port_t *p)
{
    struct serial_rs485 rs;
    memset(&rs, 0, sizeof rs);
    if (ioctl(p->fd, TIOCGRS485, &rs) != 0) {
        return feature_missing(errno) ? 0 : -1;
    }
    rs.flags |= SER_RS485_ENABLED | SER_RS485_RTS_ON_SEND;
    rs.flags &= ~(uint32_t)(SER_RS485_RTS_AFTER_SEND | SER_RS485_RX_DURING_TX);
    if (ioctl(p->fd, TIOCSRS485, &rs) != 0) {
        return feature_missing(errno) ? 0 : -1;
    }
    p->rs485_ok = true;
    return 0;
}

/* Without low latency, 8250-style drivers hand bytes to the tty layer from a work queue, adding
 * milliseconds that eat into slot time. */
static int enable_low_latency(tty_port_t *p)
{
    struct serial_struct ss;
    memset(&ss, 0, sizeof ss);
    if (ioctl(p->fd, TIOCGSERIAL, &ss) != 0) {
        return feature_missing(errno) ? 0 : -1;
    }
    ss.flags |= (int)ASYNC_LOW_LATENCY; /* 1U << 13: fits the int field */
    if (ioctl(p->fd, TIOCSSERIAL, &ss) != 0) {
        return feature_missing(errno) ? 0 : -1;
    }
    p->low_latency_ok = true;
    return 0;
}

static int configure(tty_port_t *p, uint32_t baud, char *err, size_t errlen)
{
    struct termios t;
    int fl = fcntl(p->fd, F_GETFL);
    if (fl < 0 || fcntl(p->fd, F_SETFL, fl | O_NONBLOCK) != 0) {
        set_err(err, errlen, "%s: cannot make non-blocking: %s", p->name, strerror(errno));
        return -1;
    }
    if (tcgetattr(p->fd, &t) != 0) {
        set_err(err, errlen, "%s is not a terminal: %s", p->name, strerror(errno));
        return -1;
    }
    make_8e1(&t);
    if (apply_termios(p->fd, &t) != 0 || check_parity(p) != 0) {
        set_err(err, errlen, "%s: cannot set raw 8E1: %s", p->name, strerror(errno));
        return -1;
    }
    if (set_speed(p->fd, baud) != 0) {
        set_err(err, errlen, "%s: cannot set %u baud: %s", p->name, (unsigned)baud,
                strerror(errno));
        return -1;
    }
    if (enable_rs485(p) != 0 || enable_low_latency(p) != 0) {
        set_err(err, errlen, "%s: serial driver failed: %s", p->name, strerror(errno));
        return -1;
    }
    p->baud = baud;
    (void)tcflush(p->fd, TCIFLUSH); /* whatever arrived before we were listening is stale */
    return 0;
}

static void port_reset(tty_port_t *p)
{
    memset(p, 0, sizeof *p);
    p->fd = -1;
}

int tty_port_open(tty_port_t *p, const char *path, uint32_t baud, char *err, size_t errlen)
{
    port_reset(p);
    (void)snprintf(p->name, sizeof p->name, "%s", path);
    int fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        set_err(err, errlen, "cannot open %s: %s", path, strerror(errno));
        return -1;
    }
    p->fd = fd;
    if (configure(p, baud, err, errlen) != 0) {
        (void)close(fd);
        p->fd = -1;
        return -1;
    }
    return 0;
}

int tty_port_open_fd(tty_port_t *p, int fd, uint32_t baud, char *err, size_t errlen)
{
    port_reset(p);
    (void)snprintf(p->name, sizeof p->name, "fd %d", fd);
    if (fd < 0) {
        set_err(err, errlen, "invalid file descriptor %d", fd);
        return -1;
    }
    p->fd = fd;
    if (configure(p, baud, err, errlen) != 0) {
        p->fd = -1; /* still the caller's */
        return -1;
    }
    return 0;
}

void tty_port_close(tty_port_t *p)
{
    if (p->fd >= 0) {
        (void)close(p->fd);
    }
    p->fd = -1;
}

static void runner_baud_changed(tty_port_t *p);

int tty_port_set_baud(tty_port_t *p, uint32_t baud)
{
    if (p->fd < 0 || set_speed(p->fd, baud) != 0) {
        return -1;
    }
    p->baud = baud;
    p->echo_len = 0; /* an echo still in flight arrives garbled at the new rate */
    p->mark_state = MARK_NONE;
    runner_baud_changed(p);
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Receive decoding */

static size_t emit(uint8_t *bytes, uint8_t *flags, size_t out, uint8_t b, uint8_t f)
{
    bytes[out] = b;
    flags[out] = f;
    return out + 1u;
}

/* One raw byte through the PARMRK state machine; returns the new output count. */
static size_t decode_byte(tty_port_t *p, uint8_t c, uint8_t *bytes, uint8_t *flags, size_t out)
{
    switch (p->mark_state) {
    case MARK_NONE:
        if (c == 0xFFu) {
            p->mark_state = MARK_FF;
            return out;
        }
        return emit(bytes, flags, out, c, 0u);
    case MARK_FF:
        if (c == 0x00u) {
            p->mark_state = MARK_FF00;
            return out;
        }
        p->mark_state = MARK_NONE;
        /* 0xFF 0xFF is a data 0xFF; anything else is not a mark the tty layer makes, so both
         * bytes pass through unchanged (this is how n raw bytes can give n + 1 characters). */
        out = emit(bytes, flags, out, 0xFFu, 0u);
        return c == 0xFFu ? out : emit(bytes, flags, out, c, 0u);
    default:
        p->mark_state = MARK_NONE;
        p->char_errors++;
        return emit(bytes, flags, out, c, HAL_UART_RX_PARITY_ERR);
    }
}

/* The tty layer reports parity and framing errors alike (0xFF 0x00 X), so both become
 * HAL_UART_RX_PARITY_ERR; either way the character is bad. */
size_t tty_port_decode(tty_port_t *p, const uint8_t *raw, size_t n, uint8_t *bytes,
                       uint8_t *flags)
{
    size_t out = 0;
    for (size_t i = 0; i < n; i++) {
        out = p->parmrk ? decode_byte(p, raw[i], bytes, flags, out)
                        : emit(bytes, flags, out, raw[i], 0u);
    }
    return out;
}

/* Echo suppression: the bytes of our own frames that the adapter may still play back to us. */
static void echo_expect(tty_port_t *p, const uint8_t *frame, size_t len)
{
    for (size_t i = 0; i < len; i++) {
        if (p->echo_len == TTY_ECHO_MAX) { /* forget the oldest rather than the newest */
            p->echo_head = (uint16_t)((p->echo_head + 1u) % TTY_ECHO_MAX);
            p->echo_len--;
        }
        p->echo[(p->echo_head + p->echo_len) % TTY_ECHO_MAX] = frame[i];
        p->echo_len++;
    }
    uint64_t frame_us = ((uint64_t)hal_uart_char_ns(p->baud) * len + 999u) / 1000u;
    p->echo_expire = tty_now_us() + (hal_time_us_t)frame_us + TTY_ECHO_SLACK_US;
}

/* True when this character is the expected echo and must not reach the station. A mismatch,
 * an error flag or a late byte means the echo was lost or garbled: stop expecting it and hand
 * the character on, since it may be another station's. */
static bool echo_swallow(tty_port_t *p, uint8_t b, uint8_t f, hal_time_us_t t)
{
    if (!p->echo_suppress || p->echo_len == 0u) {
        return false;
    }
    if (f != 0u || hal_time_reached(t, p->echo_expire) || p->echo[p->echo_head] != b) {
        p->echo_len = 0;
        return false;
    }
    p->echo_head = (uint16_t)((p->echo_head + 1u) % TTY_ECHO_MAX);
    p->echo_len--;
    p->echo_dropped++;
    return true;
}

/* ---------------------------------------------------------------------------------------------
 * Transmit */

static int wait_writable(int fd)
{
    struct pollfd pfd = {.fd = fd, .events = POLLOUT};
    int rc = poll(&pfd, 1, TTY_WRITE_TIMEOUT_MS);
    if (rc < 0) {
        return errno == EINTR ? 0 : -1;
    }
    if (rc == 0) {
        errno = ETIMEDOUT; /* nobody drains the device (e.g. a PTY peer that is not read) */
        return -1;
    }
    if ((pfd.revents & POLLOUT) == 0) {
        errno = EIO;
        return -1;
    }
    return 0;
}

/* The whole frame goes out back to back: partial writes continue at once. */
static int write_all(int fd, const uint8_t *buf, size_t len)
{
    size_t done = 0;
    while (done < len) {
        ssize_t n = write(fd, buf + done, len - done);
        if (n > 0) {
            done += (size_t)n;
        } else if (n < 0 && errno == EINTR) {
            continue;
        } else if ((n < 0 && errno != EAGAIN) || wait_writable(fd) != 0) {
            return -1;
        }
    }
    return 0;
}

static void runner_transmitted(tty_port_t *p, uint64_t t_ns, const uint8_t *frame, size_t len);
static void runner_tx_failed(tty_port_t *p, const char *why);

static int tty_uart_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    tty_port_t *p = ctx;
    if (len == 0u || p->fd < 0) {
        return -1;
    }
    if (hal_time_diff(not_before, tty_now_us()) > TTY_MAX_TX_DELAY_US) {
        /* Far beyond any PROFIBUS delay: almost surely a time from another clock (e.g. the
         * simulated one); blocking the runner for minutes would hide that mistake. */
        runner_tx_failed(p, "not_before more than 10 s ahead (a time from another clock?)");
        return -1;
    }
    wait_until(not_before);
    uint64_t t_ns = host_clock_mono_ns();
    if (write_all(p->fd, frame, len) != 0) {
        runner_tx_failed(p, strerror(errno));
        return -1;
    }
    p->frames_sent++;
    if (p->echo_suppress) {
        echo_expect(p, frame, len);
    }
    runner_transmitted(p, t_ns, frame, len);
    return 0;
}

static int tty_uart_set_baud(void *ctx, uint32_t baud)
{
    return tty_port_set_baud(ctx, baud);
}

static const hal_uart_ops_t tty_uart_ops = {
    .set_baud = tty_uart_set_baud,
    .transmit = tty_uart_transmit,
};

hal_uart_t tty_port_uart(tty_port_t *p)
{
    return (hal_uart_t){.ops = &tty_uart_ops, .ctx = p};
}

/* ---------------------------------------------------------------------------------------------
 * Runner */

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

static void runner_baud_changed(tty_port_t *p)
{
    if (p->runner != NULL) {
        fdl_rx_set_baud(&p->runner->slots[p->slot].rx, p->baud);
    }
}

static void runner_transmitted(tty_port_t *p, uint64_t t_ns, const uint8_t *frame, size_t len)
{
    tty_runner_t *r = p->runner;
    if (r != NULL && r->tap != NULL) {
        r->tap(r->tap_ctx, t_ns - r->t0_ns, frame, len, true, p->baud);
    }
}

/* A failed write happens inside a station callback; the run ends at the next loop turn. */
static void runner_tx_failed(tty_port_t *p, const char *why)
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
        if (echo_swallow(p, bytes[i], flags[i], t)) {
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
    struct timespec ts = {.tv_sec = wait_us / 1000000,
                          .tv_nsec = (long)(wait_us % 1000000) * 1000L};
    int rc = ppoll(pfd, n, &ts, NULL);
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
