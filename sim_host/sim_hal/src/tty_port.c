/* Linux tty backend of the HAL UART: line settings, open/close, the 0xFF parity marks, echo
 * suppression and transmit. The runner that drives ports is tty_runner.c. See sim_hal/tty_port.h
 * for the model. Built with _GNU_SOURCE. */
#include "sim_hal/tty_port.h"
#include "sim_hal/error_text.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/serial.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>
#include "sim_hal/host_clock.h"
#include "tty_internal.h"

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

/* Longest wait for not_before a transmit accepts (the longest PROFIBUS delays are slot times
 * of a few ms at 9.6 kbit/s). */
#define TTY_MAX_TX_DELAY_US 10000000
/* Sleep until this close to not_before, then spin: nanosleep overshoots by tens of µs. */
#define TTY_SPIN_US 200

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
        sim_error_text(err, errlen, "%s: cannot make non-blocking: %s", p->name, strerror(errno));
        return -1;
    }
    if (tcgetattr(p->fd, &t) != 0) {
        sim_error_text(err, errlen, "%s is not a terminal: %s", p->name, strerror(errno));
        return -1;
    }
    make_8e1(&t);
    if (apply_termios(p->fd, &t) != 0 || check_parity(p) != 0) {
        sim_error_text(err, errlen, "%s: cannot set raw 8E1: %s", p->name, strerror(errno));
        return -1;
    }
    if (set_speed(p->fd, baud) != 0) {
        sim_error_text(err, errlen, "%s: cannot set %u baud: %s", p->name, (unsigned)baud,
                strerror(errno));
        return -1;
    }
    if (enable_rs485(p) != 0 || enable_low_latency(p) != 0) {
        sim_error_text(err, errlen, "%s: serial driver failed: %s", p->name, strerror(errno));
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
        sim_error_text(err, errlen, "cannot open %s: %s", path, strerror(errno));
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
        sim_error_text(err, errlen, "invalid file descriptor %d", fd);
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


int tty_port_set_baud(tty_port_t *p, uint32_t baud)
{
    if (p->fd < 0 || set_speed(p->fd, baud) != 0) {
        return -1;
    }
    p->baud = baud;
    p->echo_len = 0; /* an echo still in flight arrives garbled at the new rate */
    p->mark_state = MARK_NONE;
    tty_runner_baud_changed(p);
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
bool tty_port_echo_swallow(tty_port_t *p, uint8_t b, uint8_t f, hal_time_us_t t)
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


static int tty_uart_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    tty_port_t *p = ctx;
    if (len == 0u || p->fd < 0) {
        return -1;
    }
    if (hal_time_diff(not_before, tty_now_us()) > TTY_MAX_TX_DELAY_US) {
        /* Far beyond any PROFIBUS delay: almost surely a time from another clock (e.g. the
         * simulated one); blocking the runner for minutes would hide that mistake. */
        tty_runner_tx_failed(p, "not_before more than 10 s ahead (a time from another clock?)");
        return -1;
    }
    wait_until(not_before);
    uint64_t t_ns = host_clock_mono_ns();
    if (write_all(p->fd, frame, len) != 0) {
        tty_runner_tx_failed(p, strerror(errno));
        return -1;
    }
    p->frames_sent++;
    if (p->echo_suppress) {
        echo_expect(p, frame, len);
    }
    tty_runner_transmitted(p, t_ns, frame, len);
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
