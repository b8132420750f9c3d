#!/usr/bin/env python3
"""Copies a little-endian pcap of Data_Exchange with Param + 3 PD and alters answers in it: the
FIRST-th Data_Exchange answer (an SD2 from station 4 with FC 0x08, data low) and the COUNT-1
after it get PI1's low octet + 1, with the FCS fixed, so each stays a valid telegram and only
its content differs. Prints the first altered answer's record number, byte position, and its
octets before and after (one per line, octets as "68 ...").

    alter_answers.py IN OUT [FIRST [COUNT]]     (FIRST default 60, COUNT default 1)
"""
import struct
import sys

PI1_LOW = 7 + 8 + 1  # SD2 header (7) + the 8-octet parameter channel, PI1's second octet


def hexs(b):
    return " ".join("%02X" % x for x in b)


def main():
    src, dst = sys.argv[1], sys.argv[2]
    first = int(sys.argv[3]) if len(sys.argv) > 3 else 60
    count = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    with open(src, "rb") as f:
        d = bytearray(f.read())
    o, n, seen = 24, 0, 0
    while o < len(d) and seen < first + count - 1:
        incl = struct.unpack_from("<I", d, o + 8)[0]
        n += 1
        f = d[o + 16:o + 16 + incl]
        if f[0] == 0x68 and f[5] == 0x04 and f[6] == 0x08:
            seen += 1
            if seen >= first:
                old = hexs(f)
                d[o + 16 + PI1_LOW] = (d[o + 16 + PI1_LOW] + 1) & 0xFF
                d[o + 16 + incl - 2] = sum(d[o + 16 + 4:o + 16 + incl - 2]) & 0xFF
                if seen == first:
                    print(n, o, old, hexs(d[o + 16:o + 16 + incl]), sep="\n")
        o += 16 + incl
    if seen < first + count - 1:
        sys.exit("alter_answers: %s has %d Data_Exchange answers, fewer than %d"
                 % (src, seen, first + count - 1))
    with open(dst, "wb") as f:
        f.write(d)


main()
