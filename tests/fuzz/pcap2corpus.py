#!/usr/bin/env python3
"""Seed corpora for the fuzz targets from real telegrams.

Reads pcap files of bus telegrams (LINKTYPE_PROFIBUS_DL = 257, as `dfp-sim demo --capture`
and `dfp-sim slave/master/param --capture` write them; micro- or nanosecond pcap) plus the
worked frames of protocol.md §A1.6, and writes one input file per seed in each
target's input format (tests/fuzz/README.md):

    pcap2corpus.py OUT_DIR [CAPTURE.pcap ...]

OUT_DIR/<target>/seed-* for fdl_rx, card, dpv1, ds47 and movilink. Duplicates are skipped.
"""
import hashlib
import os
import struct
import sys

# protocol.md §A1.6 (master 2, slave 4).
SPEC_FRAMES = [
    "10 04 02 49 4F 16",
    "10 02 04 00 06 16",
    "68 05 05 68 84 82 6D 3C 3E ED 16",
    "68 0B 0B 68 82 84 08 3E 3C 02 05 00 FF 60 03 F1 16",
    "A2 82 84 08 3E 3C 02 05 00 FF 60 03 F1 16",
    "68 15 15 68 84 82 5D 3D 3E 88 01 64 0B 60 03 00 00 00 00 06 81 00 00 01 01 C2 16",
    "68 07 07 68 84 82 7D 3E 3E F3 F2 E4 16",
    "E5",
    "68 07 07 68 FF 82 46 3A 3E 20 00 5F 16",
    "68 11 11 68 04 02 5D 01 00 20 6C 00 00 00 00 00 06 05 DC 12 34 1D 16",
    "10 02 04 03 09 16",
    "68 13 13 68 84 82 7D 33 33 5F 00 2F 0A 01 40 00 01 10 00 20 6C 00 00 5F 16",
    "68 09 09 68 84 82 5D 33 33 5E 00 2F F0 46 16",
    "68 09 09 68 82 84 08 33 33 DE 80 B5 00 87 16",
]

LINKTYPE_PROFIBUS_DL = 257


def read_pcap(path):
    data = open(path, "rb").read()
    if len(data) < 24:
        raise ValueError(f"{path}: not a pcap file")
    magic = struct.unpack("<I", data[:4])[0]
    if magic in (0xA1B2C3D4, 0xA1B23C4D):
        end = "<"
    elif magic in (0xD4C3B2A1, 0x4D3CB2A1):
        end = ">"
    else:
        raise ValueError(f"{path}: not a pcap file (magic {magic:08x})")
    linktype = struct.unpack(end + "I", data[20:24])[0]
    if linktype != LINKTYPE_PROFIBUS_DL:
        raise ValueError(f"{path}: link type {linktype}, expected {LINKTYPE_PROFIBUS_DL}")
    frames = []
    off = 24
    while off + 16 <= len(data):
        _, _, caplen, _ = struct.unpack(end + "IIII", data[off:off + 16])
        off += 16
        frames.append(data[off:off + caplen])
        off += caplen
    return frames


def parse(frame):
    """(da, sa, fc, dsap, ssap, du) of an SD1/SD2/SD3 telegram, or None."""
    if not frame:
        return None
    sd = frame[0]
    if sd == 0x10 and len(frame) == 6:
        hdr, du = 1, b""
    elif sd == 0xA2 and len(frame) == 14:
        hdr, du = 1, frame[4:12]
    elif sd == 0x68 and len(frame) >= 9:
        hdr, du = 4, frame[7:-2]
    else:
        return None
    da, sa, fc = frame[hdr], frame[hdr + 1], frame[hdr + 2]
    dsap = ssap = None
    if da & 0x80 and du:
        dsap, du = du[0] & 0x3F, du[1:]
    if sa & 0x80 and du:
        ssap, du = du[0] & 0x3F, du[1:]
    return da & 0x7F, sa & 0x7F, fc, dsap, ssap, bytes(du)


def chunks(seq, n):
    for i in range(0, len(seq), n):
        yield seq[i:i + n]


class Writer:
    def __init__(self, out):
        self.out = out
        self.seen = set()
        self.count = {}

    def put(self, target, blob):
        h = hashlib.sha1(blob).hexdigest()
        if (target, h) in self.seen or not blob:
            return
        self.seen.add((target, h))
        d = os.path.join(self.out, target)
        os.makedirs(d, exist_ok=True)
        with open(os.path.join(d, "seed-" + h[:16]), "wb") as f:
            f.write(blob)
        self.count[target] = self.count.get(target, 0) + 1


def seeds(frames, w, label):
    start_time = b"\x55\xC0\x00\x00"
    # fdl_rx: every telegram as a raw telegram op after an idle line (strict, 12 Mbit/s and
    # 1.5 Mbit/s = rate index 2), 40 telegrams per seed.
    for mode in (0x00, 0x04):
        for part in chunks(frames, 40):
            blob = bytes([mode]) + start_time
            for fr in part:
                if 1 <= len(fr) <= 255:
                    blob += bytes([0xC0, len(fr) - 1]) + fr
            w.put("fdl_rx", blob)
    # card: the master's requests (and the replies, which the card must ignore) as raw
    # telegrams, card at address 4, fake inverter and emulated MOVIDRIVE; a little time
    # passes between telegrams so watchdogs and inverter answers run.
    for cfg in (0x04, 0x14):
        for part in chunks(frames, 60):
            blob = bytes([cfg, 0x00]) + start_time
            for fr in part:
                if 1 <= len(fr) <= 255:
                    blob += bytes([0x00, len(fr) - 1]) + fr
                    p = parse(fr)
                    if p and p[2] & 0x40:
                        blob += bytes([0x0C, 0x00, 0x40])  # 64 us pass
            w.put("card", blob)
    # dpv1 / ds47 / movilink: what the telegrams carry for them.
    dpv1 = bytes([0x1A]) + b""  # Data_Exch + DP-V1 for master 2: MSAC1 open
    movilink = b""
    for fr in frames:
        p = parse(fr)
        if not p:
            continue
        da, sa, fc, dsap, ssap, du = p
        if not fc & 0x40:
            continue
        if dsap in (51, 49, 0, 1) and ssap is not None and len(du) < 245:
            sel = {51: 0x00, 49: 0x08, 0: 0x10, 1: 0x18}[dsap]
            blob = bytes([sel, sa])
            if dsap != 51:
                blob += bytes([ssap])
            blob += bytes([len(du)]) + du
            dpv1 += blob + bytes([0x03, 0x00, 0x10])  # let the main loop run
            if dsap == 51 and len(du) > 4 and du[0] == 0x5F and du[2] == 47:
                w.put("ds47", start_time + bytes([0x00, len(du) - 4]) + du[4:] +
                      bytes([0x02, 0x00, 0x03, 0x00, 0x10, 0x04, 0xF0]))
        if dsap is None and len(du) >= 8 and da == 4:
            movilink += bytes([0x00]) + du[:8] + bytes([0x02, 0x00, 0x20, 0x01, 0x00, 0x00])
    if len(dpv1) > 1:
        w.put("dpv1", start_time + dpv1)
    if movilink:
        for part in chunks(movilink, 15 * 40):
            w.put("movilink", start_time + part)


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    w = Writer(argv[1])
    spec = [bytes.fromhex(s) for s in SPEC_FRAMES]
    seeds(spec, w, "spec")
    for path in argv[2:]:
        seeds(read_pcap(path), w, path)
    for t in sorted(w.count):
        print(f"{t}: {w.count[t]} seeds")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
