#!/usr/bin/env python3
"""A PTY that hands a slave's answers to the tester late: the tester's side is a new PTY whose
name goes to NAME_FILE; what the tester writes goes to the slave's port at once, what the slave
answers comes back DELAY seconds later (longer than the tester's slot time), as a slave on a
loaded host or in an emulator may answer. Runs until killed.

usage: late_relay.py SLAVE_PORT DELAY NAME_FILE"""
import os
import select
import sys
import time
import tty


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    slave_port, delay, name_file = sys.argv[1], float(sys.argv[2]), sys.argv[3]
    master, tester_side = os.openpty()
    tty.setraw(tester_side)  # kept open: the tester's close must not hang the line up
    peer = os.open(slave_port, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(peer)
    with open(name_file + ".tmp", "w") as f:
        f.write(os.ttyname(tester_side))
    os.rename(name_file + ".tmp", name_file)
    pending = []  # (when, octets), in order
    while True:
        now = time.monotonic()
        timeout = max(0.0, pending[0][0] - now) if pending else 1.0
        ready, _, _ = select.select([master, peer], [], [], timeout)
        if master in ready:
            os.write(peer, os.read(master, 4096))
        if peer in ready:
            pending.append((time.monotonic() + delay, os.read(peer, 4096)))
        now = time.monotonic()
        while pending and pending[0][0] <= now:
            os.write(master, pending.pop(0)[1])


if __name__ == "__main__":
    main()
