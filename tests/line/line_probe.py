#!/usr/bin/env python3
"""Talks to the ports of a running `dfp-sim line` for test_line.sh; prints what it saw.

usage: line_probe.py exact DIR       port1 writes 64 octets; prints what port1..3 read (hex)
       line_probe.py collide DIR     port1 writes 100 octets, port2 writes 20 octets 20 ms later
                                     (inside port1's transmission at 9600 bit/s); then port1
                                     writes 8 octets alone; prints what port3 read each time
       line_probe.py flood DIR       port1 writes 200000 octets (port3 is never opened); prints
                                     how many port2 read
       line_probe.py spread DIR      port1 writes 100 octets; prints the ms from the write to
                                     port2's first and last octet, and how many arrived
"""
import os
import sys
import time
import tty


def open_ports(d, n):
    fds = []
    for k in range(1, n + 1):
        fd = os.open("%s/port%d" % (d, k), os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        fds.append(fd)
    return fds


def drain(fd):
    out = b""
    while True:
        try:
            b = os.read(fd, 4096)
        except BlockingIOError:
            return out
        if not b:
            return out
        out += b


def collect(fds, seconds):
    got = [b""] * len(fds)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for i, fd in enumerate(fds):
            got[i] += drain(fd)
        time.sleep(0.005)
    return got


def exact(d):
    fds = open_ports(d, 3)
    os.write(fds[0], bytes((i * 37 + 11) & 0xFF for i in range(64)))
    for i, g in enumerate(collect(fds, 0.5)):
        print("port%d %s" % (i + 1, g.hex() or "-"))


def collide(d):
    fds = open_ports(d, 3)
    os.write(fds[0], bytes([0x68]) * 100)
    time.sleep(0.02)
    os.write(fds[1], bytes([0x10]) * 20)
    print("port3 %s" % collect(fds, 0.4)[2].hex())
    os.write(fds[0], bytes(range(1, 9)))
    print("port3 %s" % collect(fds, 0.3)[2].hex())


def flood(d):
    fds = open_ports(d, 2)
    data = bytes((i * 7) & 0xFF for i in range(200000))
    got = b""
    for i in range(0, len(data), 1000):
        os.write(fds[0], data[i:i + 1000])
        time.sleep(0.001)
        got += drain(fds[1])
    got += collect(fds, 0.5)[1]
    print("port2 %d %s" % (len(got), "same" if got == data else "different"))


def spread(d):
    fds = open_ports(d, 2)
    drain(fds[1])
    t0 = time.monotonic()
    os.write(fds[0], bytes(range(100)))
    first = last = None
    n = 0
    while time.monotonic() - t0 < 2.0 and n < 100:
        b = drain(fds[1])
        if b:
            now = time.monotonic()
            first = first if first is not None else now
            last = now
            n += len(b)
        time.sleep(0.001)
    if first is None:
        print("nothing")
        return
    print("first %.1f last %.1f octets %d" % ((first - t0) * 1e3, (last - t0) * 1e3, n))


if __name__ == "__main__":
    {"exact": exact, "collide": collide, "flood": flood, "spread": spread}[sys.argv[1]](sys.argv[2])
