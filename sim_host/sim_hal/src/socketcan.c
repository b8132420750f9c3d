/* SocketCAN backend of the HAL CAN. See sim_hal/socketcan.h. Built with _GNU_SOURCE. */
#include "sim_hal/socketcan.h"
#include "sim_hal/error_text.h"

#include <errno.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* Frames read per receive call at most, so one busy bus cannot starve the rest of the runner. */
#define SOCKETCAN_RX_BATCH 256

static const char *hint_for(int e, const char *ifname, char *buf, size_t len)
{
    switch (e) {
    case EAFNOSUPPORT:
    case EPROTONOSUPPORT:
        return " (this kernel has no SocketCAN)";
    case ENODEV:
    case ENXIO:
        (void)snprintf(buf, len, " (create it: ip link add dev %s type vcan; ip link set up %s)",
                       ifname, ifname);
        return buf;
    default:
        return "";
    }
}

static int fail_errno(socketcan_t *s, const char *ifname, char *err, size_t errlen)
{
    int e = errno;
    char hint[160];
    sim_error_text(err, errlen, "cannot open CAN interface %s: %s%s", ifname, strerror(e),
            hint_for(e, ifname, hint, sizeof hint));
    if (s->fd >= 0) {
        (void)close(s->fd);
        s->fd = -1;
    }
    errno = e;
    return -1;
}

static int fail_msg(socketcan_t *s, const char *ifname, const char *why, char *err, size_t errlen)
{
    sim_error_text(err, errlen, "cannot open CAN interface %s: %s", ifname, why);
    if (s->fd >= 0) {
        (void)close(s->fd);
        s->fd = -1;
    }
    return -1;
}

int socketcan_open(socketcan_t *s, const char *ifname, hal_can_rx_fn rx, void *rx_ctx, char *err,
                   size_t errlen)
{
    memset(s, 0, sizeof *s);
    s->fd = -1;
    s->rx = rx;
    s->rx_ctx = rx_ctx;
    if (ifname == NULL || ifname[0] == '\0' || strlen(ifname) >= IFNAMSIZ) {
        sim_error_text(err, errlen, "cannot open CAN interface '%s': invalid interface name",
                ifname != NULL ? ifname : "");
        return -1;
    }
    (void)snprintf(s->ifname, sizeof s->ifname, "%s", ifname);
    s->fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (s->fd < 0) {
        return fail_errno(s, ifname, err, errlen);
    }
    struct ifreq ifr;
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", ifname);
    if (ioctl(s->fd, SIOCGIFINDEX, &ifr) != 0) {
        return fail_errno(s, ifname, err, errlen);
    }
    s->ifindex = ifr.ifr_ifindex;
    if (ioctl(s->fd, SIOCGIFHWADDR, &ifr) == 0 && ifr.ifr_hwaddr.sa_family != ARPHRD_CAN) {
        return fail_msg(s, ifname, "not a CAN interface", err, errlen);
    }
    if (ioctl(s->fd, SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_UP) == 0) {
        char why[96];
        (void)snprintf(why, sizeof why, "interface is down (ip link set up %s)", ifname);
        return fail_msg(s, ifname, why, err, errlen);
    }
    /* 11-bit data frames only: EFF and RTR must be clear; error frames are off by default. */
    struct can_filter filter = {.can_id = 0, .can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG};
    int off = 0;
    int on = 1;
    can_err_mask_t no_errors = 0;
    if (setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof filter) != 0 ||
        setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &no_errors, sizeof no_errors) != 0 ||
        setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_LOOPBACK, &on, sizeof on) != 0 ||
        setsockopt(s->fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &off, sizeof off) != 0) {
        return fail_errno(s, ifname, err, errlen);
    }
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = s->ifindex;
    if (bind(s->fd, (const struct sockaddr *)&addr, sizeof addr) != 0) {
        return fail_errno(s, ifname, err, errlen);
    }
    return 0;
}

void socketcan_close(socketcan_t *s)
{
    if (s->runner != NULL) {
        (void)tty_runner_remove_fd(s->runner, s->fd);
        s->runner = NULL;
    }
    if (s->fd >= 0) {
        (void)close(s->fd);
    }
    s->fd = -1;
}

static void pause_us(long us)
{
    struct timespec ts = {.tv_sec = 0, .tv_nsec = us * 1000L};
    (void)nanosleep(&ts, NULL);
}

static int socketcan_send(void *ctx, const hal_can_frame_t *frame)
{
    socketcan_t *s = ctx;
    if (s->fd < 0 || frame == NULL || frame->id > HAL_CAN_ID_MASK ||
        frame->len > HAL_CAN_MAX_DLC) {
        s->send_errors++;
        return -1;
    }
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = frame->id;
    cf.len = frame->len;
    memcpy(cf.data, frame->data, frame->len);
    long waited = 0;
    for (;;) {
        ssize_t n = write(s->fd, &cf, sizeof cf);
        if (n == (ssize_t)sizeof cf) {
            s->frames_sent++;
            return 0;
        }
        int e = n < 0 ? errno : EIO;
        if (e == EINTR) {
            continue;
        }
        if ((e == ENOBUFS || e == EAGAIN) && waited < SOCKETCAN_SEND_RETRY_US) {
            pause_us(100);
            waited += 100;
            continue;
        }
        s->last_errno = e;
        s->send_errors++;
        return -1;
    }
}

static const hal_can_ops_t socketcan_ops = {.send = socketcan_send};

hal_can_t socketcan_can(socketcan_t *s)
{
    return (hal_can_t){.ops = &socketcan_ops, .ctx = s};
}

int socketcan_receive(socketcan_t *s)
{
    int count = 0;
    while (count < SOCKETCAN_RX_BATCH) {
        struct can_frame cf;
        ssize_t n = read(s->fd, &cf, sizeof cf);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return count;
            }
            s->last_errno = errno;
            return -1;
        }
        if (n != (ssize_t)sizeof cf || (cf.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) != 0u ||
            cf.len > CAN_MAX_DLEN) {
            s->rx_ignored++;
            continue;
        }
        hal_can_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = (uint16_t)(cf.can_id & CAN_SFF_MASK);
        f.len = cf.len;
        memcpy(f.data, cf.data, cf.len);
        s->frames_received++;
        count++;
        if (s->rx != NULL) {
            s->rx(s->rx_ctx, &f);
        }
    }
    return count;
}

static void socketcan_readable(void *ctx, hal_time_us_t now)
{
    (void)now;
    socketcan_t *s = ctx;
    if (socketcan_receive(s) < 0 && s->runner != NULL) {
        tty_runner_set_error(s->runner, "CAN interface %s: %s", s->ifname,
                             strerror(s->last_errno));
    }
}

int socketcan_attach(socketcan_t *s, tty_runner_t *r)
{
    if (s->fd < 0 || s->runner != NULL || tty_runner_add_fd(r, s->fd, socketcan_readable, s) != 0) {
        return -1;
    }
    s->runner = r;
    return 0;
}
