/* The HAL CAN on Linux SocketCAN (PF_CAN, SOCK_RAW, CAN_RAW): a real adapter (can0) or a virtual
 * bus (vcan0) shared by several processes on one host.
 *
 * The socket is non-blocking. Only 11-bit data frames are received (a kernel filter drops
 * extended, remote and error frames). SocketCAN's defaults are kept and set explicitly:
 * CAN_RAW_LOOPBACK on (other sockets on this host hear our frames: that is what lets two programs
 * share vcan0) and CAN_RAW_RECV_OWN_MSGS off (a socket never receives its own frames, as on the
 * in-memory bus).
 *
 * Receiving fits the tty runner (sim_hal/tty_port.h): socketcan_attach() adds the socket to a
 * runner, which then calls the node's rx function for each frame; without a runner call
 * socketcan_receive() when the descriptor is readable.
 *
 * Structs are caller-owned; nothing is allocated. */
#ifndef SIM_HAL_SOCKETCAN_H
#define SIM_HAL_SOCKETCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "sim_hal/tty_port.h"

/* A send that finds the kernel queue full (ENOBUFS on an adapter with a short txqueuelen) retries
 * for up to this long before it reports failure. */
#define SOCKETCAN_SEND_RETRY_US 2000

typedef struct socketcan {
    int fd;
    int ifindex;
    char ifname[32];
    hal_can_rx_fn rx;
    void *rx_ctx;
    tty_runner_t *runner;
    /* Counters. */
    uint64_t frames_sent;
    uint64_t frames_received;
    uint64_t send_errors;
    uint64_t rx_ignored; /* anything but an 11-bit data frame (should not pass the filter) */
    int last_errno;      /* of the last failed send or receive */
} socketcan_t;

/* Open interface ifname and bind a raw CAN socket to it. Returns 0, or -1 with one line in err:
 *   "cannot open CAN interface vcan0: Address family not supported by protocol (this kernel has
 *    no SocketCAN)"
 *   "cannot open CAN interface vcan9: No such device (create it: ip link add dev vcan9 type vcan;
 *    ip link set up vcan9)"
 *   "cannot open CAN interface vcan0: interface is down (ip link set up vcan0)"
 *   "cannot open CAN interface eth0: not a CAN interface" */
int socketcan_open(socketcan_t *s, const char *ifname, hal_can_rx_fn rx, void *rx_ctx, char *err,
                   size_t errlen);
void socketcan_close(socketcan_t *s);
hal_can_t socketcan_can(socketcan_t *s);
/* Read every frame waiting on the socket and hand it to rx. Returns the number of frames, or -1
 * when the socket failed (errno in last_errno; ENETDOWN when the interface went down). */
int socketcan_receive(socketcan_t *s);
/* Let a tty runner wait on the socket and call socketcan_receive(); a receive failure ends the
 * run with "CAN interface vcan0: <reason>". Returns 0 or -1 (runner full). */
int socketcan_attach(socketcan_t *s, tty_runner_t *r);

#endif
