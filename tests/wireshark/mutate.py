#!/usr/bin/env python3
"""Writes a pcap (link type 147) of damaged and random telegrams for the dissector's robustness test.

Usage: mutate.py OUT.pcap SEED IN.pcap...

From every record of the inputs: each proper prefix (a truncated telegram) and a few copies with random
octets changed, inserted or dropped. Besides these, telegrams with correct framing (LE, FCS, ED)
around random data units for every SAP the dissector decodes, both as request and as response,
so the DP and DP-V1 decoders see arbitrary content and not only FCS errors. Seeded: the same
SEED gives the same file.
"""
import random
import struct
import sys

SAPS = [None, 0, 1, 48, 49, 50, 51, 53, 54, 55, 56, 57, 58, 59, 60, 61, 62]
DPV1_FUNCTIONS = [0x48, 0x51, 0x56, 0x57, 0x58, 0x5C, 0x5E, 0x5F, 0xDE, 0xDF, 0xD7, 0x00, 0xFF]


def read_pcap(path):
    data = open(path, "rb").read()
    if len(data) < 24 or struct.unpack("<I", data[:4])[0] not in (0xA1B2C3D4, 0xA1B23C4D):
        raise SystemExit(f"{path}: not a little-endian pcap file")
    off, records = 24, []
    while off + 16 <= len(data):
        incl = struct.unpack("<I", data[off + 8:off + 12])[0]
        records.append(data[off + 16:off + 16 + incl])
        off += 16 + incl
    return records


def frame(da, sa, fc, du):
    body = [da, sa, fc] + du
    fcs = sum(body) % 256
    if not du:
        return bytes([0x10] + body + [fcs, 0x16])
    if len(du) == 8 and random.random() < 0.5:
        return bytes([0xA2] + body + [fcs, 0x16])
    return bytes([0x68, len(body), len(body), 0x68] + body + [fcs, 0x16])


def random_du(sap):
    """Data unit after the SAP octets: mostly plausible heads, random tails."""
    n = random.choice([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 20, 30, 60, 120, 200])
    du = [random.randrange(256) for _ in range(n)]
    if sap is not None and sap <= 51 and du:
        du[0] = random.choice(DPV1_FUNCTIONS)
        if len(du) > 2 and random.random() < 0.7:
            du[2] = random.choice([47, 255, 0])
        if len(du) > 3 and random.random() < 0.7:
            du[3] = len(du) - 4 if random.random() < 0.7 else random.randrange(256)
        if len(du) > 5 and random.random() < 0.5:
            du[5] = random.choice([0x01, 0x02, 0x40, 0x81, 0xC0])
    return du


def sap_telegram(sap, request):
    master, slave = random.choice([1, 2]), random.choice([4, 5])
    if request:
        fc = random.choice([0x4D, 0x5D, 0x6D, 0x7D, 0x4C, 0x46, 0x49])
        da, sa = slave, master
    else:
        fc = random.choice([0x00, 0x08, 0x0A, 0x03, 0x02, 0x01, 0x09, 0x0C, 0x0D, 0x28])
        da, sa = master, slave
    du = random_du(sap)
    if sap is not None:
        other = random.choice([62, 51, 50])
        dsap, ssap = (sap, other) if request else (other, sap)
        da, sa = da | 0x80, sa | 0x80
        du = [dsap, ssap] + du
    telegram = frame(da, sa, fc, du[:246])
    return telegram


def mutate(rec):
    b = bytearray(rec)
    for _ in range(random.randint(1, 3)):
        op = random.randrange(3)
        if op == 0 and b:
            b[random.randrange(len(b))] = random.randrange(256)
        elif op == 1:
            b.insert(random.randrange(len(b) + 1), random.randrange(256))
        elif b:
            del b[random.randrange(len(b))]
    return bytes(b)


def main():
    if len(sys.argv) < 4:
        raise SystemExit("usage: mutate.py OUT.pcap SEED IN.pcap...")
    random.seed(int(sys.argv[2]))
    out = []
    for path in sys.argv[3:]:
        for rec in read_pcap(path):
            out.extend(rec[:n] for n in range(len(rec)))
            out.extend(mutate(rec) for _ in range(5))
    for sap in SAPS:
        for request in (True, False):
            out.extend(sap_telegram(sap, request) for _ in range(300))
    with open(sys.argv[1], "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 147))
        for i, rec in enumerate(out):
            f.write(struct.pack("<IIII", 1700000000 + i // 1000, i % 1000, len(rec), len(rec)))
            f.write(rec)
    print(len(out))


if __name__ == "__main__":
    main()
