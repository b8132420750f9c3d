#!/usr/bin/env python3
"""Writes a classic pcap of PROFIBUS telegrams, one record per input line, for the dissector test.

Usage: mkpcap.py OUT.pcap [--linktype N] < frames.txt

Input lines (blank lines and text after '#' are ignored):
  raw HEX...            the octets exactly as given (damaged telegrams, SC, tokens, spec examples)
  sd1 DA SA FC          SD1 telegram, FCS and ED computed
  sd2 DA SA FC DU...    SD2 telegram, LE/LEr, FCS and ED computed
  sd3 DA SA FC DU*8     SD3 telegram, FCS and ED computed (DU must be 8 octets)
  empty                 a record of length 0
The FCS is computed here independently of the dissector, so a correct FCS in the dissector's
output confirms both sides.
"""
import struct
import sys


def fcs(octets):
    return sum(octets) % 256


def build(kind, octets, lineno):
    if kind == "raw":
        return bytes(octets)
    if kind == "empty":
        return b""
    if kind == "sd1":
        if len(octets) != 3:
            raise SystemExit(f"line {lineno}: sd1 takes DA SA FC")
        return bytes([0x10] + octets + [fcs(octets), 0x16])
    if kind == "sd2":
        if len(octets) < 3:
            raise SystemExit(f"line {lineno}: sd2 takes DA SA FC DU...")
        le = len(octets)
        return bytes([0x68, le, le, 0x68] + octets + [fcs(octets), 0x16])
    if kind == "sd3":
        if len(octets) != 11:
            raise SystemExit(f"line {lineno}: sd3 takes DA SA FC and 8 DU octets")
        return bytes([0xA2] + octets + [fcs(octets), 0x16])
    raise SystemExit(f"line {lineno}: unknown kind '{kind}'")


def main():
    args = sys.argv[1:]
    if not args:
        raise SystemExit("usage: mkpcap.py OUT.pcap [--linktype N] < frames")
    out, linktype = args[0], 147
    if len(args) == 3 and args[1] == "--linktype":
        linktype = int(args[2])
    records = []
    for lineno, line in enumerate(sys.stdin, 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        try:
            octets = [int(w, 16) for w in words[1:]]
        except ValueError:
            raise SystemExit(f"line {lineno}: not hex: {line.strip()}")
        if any(o < 0 or o > 255 for o in octets):
            raise SystemExit(f"line {lineno}: octet out of range")
        records.append(build(words[0].lower(), octets, lineno))
    with open(out, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, linktype))
        for i, rec in enumerate(records):
            f.write(struct.pack("<IIII", 1700000000 + i, 0, len(rec), len(rec)))
            f.write(rec)
    print(f"{len(records)} records")


if __name__ == "__main__":
    main()
