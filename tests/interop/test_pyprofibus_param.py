#!/usr/bin/env python3
"""pyprofibus, as DP master, uses the cyclic 8-byte MOVILINK parameter channel of the card.

usage: test_pyprofibus_param.py --dfp-sim PATH --gsd-dir DIR [--baud 19200] [--verbose]

Module "Param + 3 PD" (Chk_Cfg F3 F2, 14 bytes each way: the 8-byte channel, then PO1..PO3 /
PI1..PI3) against `dfp-sim slave --inverter sim --eeprom TMP/ee.bin --capture TMP/sN.pcap` on a
socat PTY pair (plumbing shared with test_pyprofibus_interop.py). The master side follows
protocol.md §B6: every new service toggles the handshake bit 6 of the management byte; a service is
done when a reply carries the sent handshake value AND the sent index (every wait is bounded).
The card starts with handshake 0 and the master first sends eight 00 bytes ("no service"), so
the first service goes out with bit 6 = 1.

Session 1 (fresh EEPROM file):
  1. read index 8300 (P076 firmware), management 0x41 -> reply bytes 0..7 exactly
     41 00 20 6C 31 1C 72 89 (protocol.md §C1.5);
  2. write (service 2, non-volatile) P160 n11 (8489 = 0x2129) = 300000 (300 rpm) -> the write's
     reply echoes the value; read 8489 -> 300000;
  3. write volatile (service 3) H0 (11000 = 0x2AF8) = 3000 -> read 11000 -> 3000;
  4. write P160 = 5000001 (max is 5000000) -> management | 0x80, bytes 4..7 = 08 00 00 15
     (class 8 "other", additional code 0x15 value too large); P160 still reads 300000;
  5. exactly once: one non-volatile write of H1 (11001) held unchanged, handshake included, for
     HOLD_CYCLES Data_Exchange cycles. What proves what:
     - the EEPROM file's generation counter (file_nvm header bytes 12..15, +1 for every NVM
       write; every non-volatile parameter write of the emulated inverter is exactly one NVM
       write, whatever the value) went up by exactly 1 over the hold: the inverter executed the
       write service once, not once per cycle -- re-executing it would give byte-identical
       replies, so the replies alone could not show this;
     - in dfp-sim's own capture, the held request is byte-identical in >= HOLD_CYCLES
       consecutive Data_Exchange requests, and over the replies to them the parameter channel
       (bytes 0..7) changed exactly once, from the previous service's reply to this write's
       reply: the card did not answer with anything else (no busy/old answer reappearing) while
       the request stayed. (With the in-process inverter answering at once, the card already
       carries the result in its reply to the first held request; pyprofibus hands a reply to
       its caller one cycle later, hence "reply after 2 cycles" in its view.)
  SIGTERM -> dfp-sim exits 0.
Session 2 (same EEPROM file, a new dfp-sim, a new pyprofibus master):
  - P160 reads 300000 (the non-volatile write survived), H1 reads the held write's value, H0
    reads 0 again (the volatile write did not survive, protocol.md §C1.2);
  6. write P100 = 3 FIELDBUS (8461) and P101 = 2 FIELDBUS (8462) through the channel, then
     PO1 = 0x0006, PO2 = 1500 -> PI1 (status word) low byte has bits 0..2 set within
     ENABLE_TIME, PI2 (speed, 0.2 rpm/digit) rises monotonically to 1500 and not beyond.

Prints one PASS/FAIL line per check and "N passed, M failed"; exit 0 when all passed, 1
otherwise, 77 (a ctest skip) when pyprofibus, pyserial or socat is missing. On a failure it
prints dfp-sim's and socat's output, pyprofibus's debug log and the last telegrams on the wire.
"""

import contextlib
import io
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time

from checker import pyprofibus_main  # sibling modules in tests/interop
from test_pyprofibus_interop import (SD2, SLAVE_ADDR, is_dx_frame,
                                     make_tap_phy, read_text, stop_process, wait_for, words,
                                     write_conf)

MODULE = "Param + 3 PD"
SIZE = 14             # 8-byte channel + 3 words, each way
HS = 0x40             # handshake bit of the management byte
ERR = 0x80            # status bit: error
STARTUP_TIME = 5.0    # Data_Exchange must be reached by then
SERVICE_TIME = 3.0    # a service's reply must come within this (and SERVICE_CYCLES)
SERVICE_CYCLES = 300
EXCHANGE_TIME = 1.0   # one Data_Exchange cycle through pyprofibus, at most
HOLD_CYCLES = 60      # the exactly-once write is held this many cycles (>= 50)
ENABLE_TIME = 5.0     # PI1 bits 0..2 and PI2 = 1500 must come within this
SESSION_TIME = 15.0   # a whole session's master loop, at most

IDX_FIRMWARE = 8300   # P076
IDX_P160 = 8489       # n11, 0.001 rpm, -5000000..5000000
IDX_P100 = 8461
IDX_P101 = 8462
IDX_H0 = 11000
IDX_H1 = 11001
P160_NEW = 300000     # 300 rpm
P160_TOO_HIGH = 5000001
H0_VALUE = 3000
H1_VALUE = 0x12345678

SVC_READ, SVC_WRITE, SVC_WRITE_VOLATILE = 0x01, 0x02, 0x03
LEN4 = 0x30           # data length bits 5..4 = 11: 4 bytes


class Timeout(Exception):
    pass


class Session:
    """One socat PTY pair, one dfp-sim slave, one pyprofibus master, driven cycle by cycle."""

    def __init__(self, pb, name, tmp, dfp_sim, gsd_dir, baud, eeprom):
        self.pb = pb
        self.name = name
        self.dir = os.path.join(tmp, name)
        os.mkdir(self.dir)
        self.dfp_sim, self.gsd_dir, self.baud, self.eeprom = dfp_sim, gsd_dir, baud, eeprom
        self.capture = os.path.join(self.dir, "dfp-sim.pcap")
        self.sim_out = os.path.join(self.dir, "dfp-sim.out")
        self.sim_err = os.path.join(self.dir, "dfp-sim.err")
        self.socat_err = os.path.join(self.dir, "socat.err")
        self.log = io.StringIO()
        self.socat = self.sim = self.master = self.desc = self.phy = None
        self.sim_rc = "not started"
        self.deadline = None
        # master side of the channel
        self.hs = 0               # handshake of the last request sent (the card starts at 0)
        self.req = bytes(8)       # "no service"
        self.po = [0, 0, 0]
        self.exchanges = 0
        self.last_in = bytes(SIZE)

    # ---- plumbing ------------------------------------------------------------------------

    def start(self, c):
        """socat, dfp-sim and pyprofibus up to Data_Exchange; False (after a FAIL) if not."""
        a, b = os.path.join(self.dir, "a"), os.path.join(self.dir, "b")
        with open(self.socat_err, "w") as err:
            self.socat = subprocess_popen(["socat", "-d", "-d", "pty,raw,echo=0,link=" + a,
                                           "pty,raw,echo=0,link=" + b], err)
        if not c.check(wait_for(lambda: os.path.exists(a) and os.path.exists(b), 5.0),
                       self.name + ": socat PTY pair up"):
            return False
        with open(self.sim_out, "w") as out, open(self.sim_err, "w") as err:
            self.sim = subprocess_popen(
                [self.dfp_sim, "slave", "--inverter", "sim", "--eeprom", self.eeprom,
                 "--capture", self.capture, "--port", a, "--address", str(SLAVE_ADDR),
                 "--baud", str(self.baud)], err, out)
        wait_for(lambda: self.sim.poll() is not None or "dfp-sim" in read_text(self.sim_out),
                 3.0)
        if not c.check(self.sim.poll() is None, self.name + ": dfp-sim slave running",
                       "exited with %r" % self.sim.poll()):
            return False
        conf = os.path.join(self.dir, "pyprofibus.conf")
        write_conf(conf, b, self.baud, os.path.join(self.gsd_dir, "SEW_6003.GSD"), MODULE, SIZE)
        self.deadline = time.monotonic() + SESSION_TIME
        with contextlib.redirect_stdout(self.log):
            config = self.pb.PbConf.fromFile(conf)
            self.phy = make_tap_phy(self.pb.phy_serial.CpPhySerial)(port=config.phyDev,
                                                                      debug=False)
            self.phy.setConfig(baudrate=config.phyBaud)
            self.master = config.makeDPM(phy=self.phy)
            self.desc = config.slaveConfs[0].makeDpSlaveDesc()
            self.master.addSlave(self.desc)
            self.master.initialize()
        t0 = time.monotonic()
        try:
            # a few cycles of "no service" once connected, as a master starts the channel
            self.cycle(STARTUP_TIME)
            while self.exchanges < 3:
                self.cycle()
        except Timeout as e:
            c.check(False, self.name + ": pyprofibus reaches Data_Exchange", str(e))
            return False
        return c.check(True, self.name + ": pyprofibus in Data_Exchange after %.2f s"
                       % (time.monotonic() - t0))

    def stop(self, c):
        """pyprofibus off, dfp-sim SIGTERM (must exit 0), socat off."""
        if self.master is not None:
            with contextlib.redirect_stdout(self.log):
                self.master.destroy()
            self.master = None
        elif self.phy is not None:
            self.phy.close()
        if self.sim is not None:
            self.sim_rc = stop_process(self.sim)
            c.check(self.sim_rc == 0, self.name + ": dfp-sim exited 0 on SIGTERM",
                    "exit %r" % self.sim_rc)
        stop_process(self.socat)

    def outputs(self):
        return self.req + words(*self.po)

    def cycle(self, timeout=EXCHANGE_TIME):
        """One Data_Exchange with the current outputs; returns the 14 input bytes."""
        end = time.monotonic() + timeout
        if self.deadline is not None:
            end = min(end, self.deadline)
        with contextlib.redirect_stdout(self.log):
            while time.monotonic() < end:
                self.desc.setMasterOutData(bytearray(self.outputs()))
                handled = self.master.run()
                if handled is self.desc:
                    data = self.desc.getMasterInData()
                    if data is not None:
                        self.exchanges += 1
                        self.last_in = bytes(data)
                        return self.last_in
        raise Timeout("no Data_Exchange reply within %.1f s (%d exchanges so far)"
                      % (timeout, self.exchanges))

    # ---- the parameter channel, master side (protocol.md §B6) ------------------------------

    def send(self, service, index, value=0):
        """Put a new service into the outputs, handshake toggled; returns the request."""
        self.hs ^= HS
        # reads as 0x01 / 0x41 like the manual (length bits ignored), writes with length 11
        mgmt = service | (LEN4 if service != SVC_READ else 0) | self.hs
        self.req = bytes([mgmt, 0x00]) + index.to_bytes(2, "big") + \
            (value & 0xFFFFFFFF).to_bytes(4, "big")
        return self.req

    def done(self, rsp):
        return (rsp[0] & HS) == (self.req[0] & HS) and rsp[2:4] == self.req[2:4]

    def wait_reply(self):
        """Cycles until the reply carries the sent handshake and index; (reply, cycles)."""
        end = time.monotonic() + SERVICE_TIME
        n = 0
        while n < SERVICE_CYCLES and time.monotonic() < end:
            rsp = self.cycle()[:8]
            n += 1
            if self.done(rsp):
                return rsp, n
        raise Timeout("no reply to %s after %d cycles: last channel reply %s"
                      % (self.req.hex(" "), n, self.last_in[:8].hex(" ")))

    def service(self, service, index, value=0):
        req = self.send(service, index, value)
        rsp, n = self.wait_reply()
        return req, rsp, n


def subprocess_popen(argv, err, out=None):
    return subprocess.Popen(argv, stdin=subprocess.DEVNULL,
                            stdout=out if out is not None else subprocess.DEVNULL, stderr=err)


def be32(v):
    return (v & 0xFFFFFFFF).to_bytes(4, "big")


def hx(b):
    return b.hex(" ").upper() if b is not None else "None"


def expect(c, got, want, what):
    return c.check(got == want, what + ": " + hx(want), "got %s" % hx(got))


def eeprom_generation(path):
    """The file_nvm header's sequence number (bytes 12..15), or None without a valid file."""
    try:
        with open(path, "rb") as f:
            h = f.read(20)
    except OSError:
        return None
    if len(h) < 20 or h[:4] != b"DFPE":
        return None
    return struct.unpack(">I", h[12:16])[0]


def read_pcap(path):
    """The frames of a pcap file, in order."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return []
    if len(data) < 24:
        return []
    magic = data[:4]
    if magic in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1"):
        e = "<"
    elif magic in (b"\xa1\xb2\xc3\xd4", b"\xa1\xb2\x3c\x4d"):
        e = ">"
    else:
        return []
    frames, off = [], 24
    while off + 16 <= len(data):
        _, _, incl, _ = struct.unpack(e + "IIII", data[off:off + 16])
        frames.append(data[off + 16:off + 16 + incl])
        off += 16 + incl
    return frames


def dx_pairs(frames):
    """(request DU, reply DU or None) for every Data_Exchange request in the capture."""
    pairs = []
    for k, f in enumerate(frames):
        if f[:1] == bytes([SD2]) and is_dx_frame(f, "TX"):
            nxt = frames[k + 1] if k + 1 < len(frames) else b""
            rsp = bytes(nxt[7:-2]) if nxt[:1] == bytes([SD2]) and is_dx_frame(nxt, "RX") \
                else None
            pairs.append((bytes(f[7:-2]), rsp))
    return pairs


def check_held_write(c, s, held, want, prev):
    """Step 5 in dfp-sim's capture: the held request's run and the replies to it."""
    pairs = dx_pairs(read_pcap(s.capture))
    idx = [k for k, (q, _) in enumerate(pairs) if q[:8] == held]
    run = pairs[idx[0]:idx[-1] + 1] if idx else []
    c.check(bool(run) and len(run) == len(idx) and len({q for q, _ in run}) == 1
            and len(run) >= 50,
            "5: capture: the held request %s (with PO) went out in %d consecutive "
            "Data_Exchange requests, all 14 bytes identical (>= 50)" % (hx(held), len(run)),
            "%d requests carry it, %d in its run, %d different DUs"
            % (len(idx), len(run), len({q for q, _ in run})))
    # the reply to the request just before the run, then the replies to the run's requests
    # (pyprofibus stops after its last request, which so has no reply in the capture)
    before = pairs[idx[0] - 1][1] if idx and idx[0] > 0 else None
    replies = [r[:8] for _, r in ([(None, before)] if before else []) + run if r is not None]
    changes = [k for k in range(1, len(replies)) if replies[k] != replies[k - 1]]
    c.check(len(replies) >= 51 and len(changes) == 1 and replies[0] == prev
            and replies[-1] == want and (replies[changes[0]][0] ^ prev[0]) & HS,
            "5: capture: over the reply before the run and the %d replies to it the channel "
            "changed exactly once, %s -> %s (handshake toggled), in the reply to the run's "
            "request no. %s (1 = its first)" % (len(replies) - 1, hx(prev), hx(want),
                            changes[0] if changes else "-"),
            "%d replies, %d changes, sequence: %s" % (
                len(replies), len(changes),
                " | ".join("%dx %s" % (n, hx(r)) for r, n in runs(replies))))


def runs(seq):
    out = []
    for x in seq:
        if out and out[-1][0] == x:
            out[-1][1] += 1
        else:
            out.append([x, 1])
    return out


def session1(c, s, eeprom):
    # 1. read the firmware index
    req, rsp, n = s.service(SVC_READ, IDX_FIRMWARE)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("00206C311C7289"),
           "1: read 8300 with %02X -> reply after %d cycles" % (req[0], n))
    # 2. non-volatile write of P160, read back
    req, rsp, n = s.service(SVC_WRITE, IDX_P160, P160_NEW)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002129") + be32(P160_NEW),
           "2: write P160 = %d with %02X -> reply" % (P160_NEW, req[0]))
    gen_after_p160 = eeprom_generation(eeprom)
    c.check(gen_after_p160 is not None, "2: the write created the EEPROM file %s (generation "
            "%s)" % (os.path.basename(eeprom), gen_after_p160), "no valid file_nvm image")
    req, rsp, n = s.service(SVC_READ, IDX_P160)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002129") + be32(P160_NEW),
           "2: read P160 with %02X -> reply" % req[0])
    # 3. volatile write of H0, read back
    req, rsp, n = s.service(SVC_WRITE_VOLATILE, IDX_H0, H0_VALUE)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002AF8") + be32(H0_VALUE),
           "3: write volatile H0 = %d with %02X -> reply" % (H0_VALUE, req[0]))
    req, rsp, n = s.service(SVC_READ, IDX_H0)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002AF8") + be32(H0_VALUE),
           "3: read H0 with %02X -> reply" % req[0])
    c.equal(eeprom_generation(eeprom), gen_after_p160,
            "3: the volatile write left the EEPROM file alone (generation %s)" % gen_after_p160)
    # 4. a value above P160's maximum
    req, rsp, n = s.service(SVC_WRITE, IDX_P160, P160_TOO_HIGH)
    c.check(rsp[0] == req[0] | ERR and rsp[4:8] == bytes.fromhex("08000015"),
            "4: write P160 = %d (max 5000000) with %02X -> management %02X (bit 7), bytes 4..7 "
            "08 00 00 15 (full reply %s)" % (P160_TOO_HIGH, req[0], req[0] | ERR, hx(rsp)),
            "got %s" % hx(rsp))
    expect(c, rsp[1:4], bytes.fromhex("002129"), "4: the error reply keeps byte 1 and the index")
    req, rsp, n = s.service(SVC_READ, IDX_P160)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002129") + be32(P160_NEW),
           "4: P160 unchanged after the refused write, read with %02X" % req[0])
    prev = rsp
    # 5. exactly once: a non-volatile write held for HOLD_CYCLES cycles
    gen0 = eeprom_generation(eeprom)
    held = s.send(SVC_WRITE, IDX_H1, H1_VALUE)
    want = bytes([held[0]]) + bytes.fromhex("002AF9") + be32(H1_VALUE)
    got_at = None
    for k in range(HOLD_CYCLES):
        rsp = s.cycle()[:8]
        if got_at is None and s.done(rsp):
            got_at = k + 1
    gen1 = eeprom_generation(eeprom)
    c.check(got_at is not None and rsp == want,
            "5: write H1 = 0x%08X with %02X held %d cycles: reply %s from cycle %s on"
            % (H1_VALUE, held[0], HOLD_CYCLES, hx(want), got_at), "last reply %s" % hx(rsp))
    c.check(gen0 is not None and gen1 == gen0 + 1,
            "5: the inverter executed the held write once: EEPROM generation %s -> %s over %d "
            "cycles" % (gen0, gen1, HOLD_CYCLES), "expected %s -> %s"
            % (gen0, None if gen0 is None else gen0 + 1))
    return held, want, prev


def session2(c, s):
    req, rsp, n = s.service(SVC_READ, IDX_P160)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002129") + be32(P160_NEW),
           "2: after the restart with the same --eeprom, read P160 with %02X -> reply" % req[0])
    req, rsp, n = s.service(SVC_READ, IDX_H1)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002AF9") + be32(H1_VALUE),
           "5: after the restart, H1 (written non-volatile) read with %02X -> reply" % req[0])
    req, rsp, n = s.service(SVC_READ, IDX_H0)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002AF8") + be32(0),
           "3: after the restart, H0 (written volatile) is 0 again, read with %02X" % req[0])
    # 6. fieldbus control, then PO words next to the channel
    for idx, val, name in ((IDX_P100, 3, "P100 = 3 FIELDBUS"), (IDX_P101, 2, "P101 = 2 FIELDBUS")):
        req, rsp, n = s.service(SVC_WRITE, idx, val)
        expect(c, rsp, bytes([req[0], 0]) + idx.to_bytes(2, "big") + be32(val),
               "6: write %s with %02X -> reply" % (name, req[0]))
    s.po = [0x0006, 1500, 0]
    t0 = time.monotonic()
    pi = []
    t_status = t_speed = None
    while time.monotonic() - t0 < ENABLE_TIME:
        d = s.cycle()
        pi1, pi2 = struct.unpack(">HH", d[8:12])
        pi.append((time.monotonic() - t0, pi1, pi2))
        if t_status is None and pi1 & 0x07 == 0x07:
            t_status = pi[-1][0]
        if t_speed is None and pi2 == 1500:
            t_speed = pi[-1][0]
        if t_status is not None and t_speed is not None and len(pi) >= 20 and \
                pi[-1][0] - t_speed > 0.2:
            break
    c.check(t_status is not None,
            "6: PO1 = 0006, PO2 = 1500 -> PI1 low byte has bits 0..2 set (PI1 %04X) after "
            "%s s" % (pi[-1][1], "-" if t_status is None else "%.2f" % t_status),
            "PI1 values: %s" % " ".join("%04X" % v for v in sorted({p[1] for p in pi})))
    speeds = [p[2] for p in pi]
    sp = [v - 0x10000 if v >= 0x8000 else v for v in speeds]
    mono = all(sp[k] >= sp[k - 1] for k in range(1, len(sp)))
    c.check(t_speed is not None and mono and max(sp) == 1500 and sp[-1] == 1500,
            "6: PI2 rose monotonically %d -> 1500 (300 rpm) in %s s (%d distinct values) and "
            "stayed there" % (sp[0], "-" if t_speed is None else "%.2f" % t_speed,
                              len(set(sp))),
            "PI2 values: %s" % " ".join(str(v) for v, _ in runs(sp)))
    # the channel still works while the drive runs
    req, rsp, n = s.service(SVC_READ, IDX_P160)
    expect(c, rsp, bytes([req[0]]) + bytes.fromhex("002129") + be32(P160_NEW),
           "6: read P160 with %02X while the drive is enabled -> reply" % req[0])


def dump(s):
    def block(title, text, max_lines=80):
        lines = text.rstrip("\n").splitlines()
        if len(lines) > max_lines:
            lines = ["... (%d lines before)" % (len(lines) - max_lines)] + lines[-max_lines:]
        print("---- %s: %s ----" % (s.name, title))
        for line in lines:
            print("  " + line)
    block("dfp-sim stdout", read_text(s.sim_out))
    block("dfp-sim stderr", read_text(s.sim_err))
    block("socat stderr", read_text(s.socat_err), 20)
    block("pyprofibus log", s.log.getvalue(), 40)
    if s.phy is not None:
        wire = s.phy.wire
        t0 = wire[0][0] if wire else 0.0
        block("wire as pyprofibus saw it (last 40)",
              "\n".join("%9.3f ms %s %s" % ((t - t0) * 1e3, d, f.hex(" ")) for t, d, f in wire),
              40)


def run(c, pb, args):
    tmp = tempfile.mkdtemp(prefix="dfp-param-")
    eeprom = os.path.join(tmp, "ee.bin")
    sessions = []
    try:
        held = None  # session 1's held write: (request, its reply, the reply before it)
        for name, body in (("session 1", session1), ("session 2", session2)):
            s = Session(pb, name, tmp, args.dfp_sim, args.gsd_dir, args.baud, eeprom)
            sessions.append(s)
            failed_before = c.failed
            t0 = time.monotonic()
            try:
                if s.start(c):
                    if body is session1:
                        held = session1(c, s, eeprom)
                    else:
                        session2(c, s)
            except Timeout as e:
                c.check(False, s.name + ": every service answered in time", str(e))
            except Exception as e:  # ProfibusError and others: a failure, not a crash
                c.check(False, s.name + ": pyprofibus master loop ran without an exception",
                        "%s: %s" % (type(e).__name__, e))
            finally:
                s.stop(c)
            if body is session1 and held is not None:
                check_held_write(c, s, *held)
            c.check("Data_Exch" in read_text(s.sim_out),
                    s.name + ": dfp-sim printed a Data_Exch state line")
            print("     %s: %.2f s, %d exchanges" % (s.name, time.monotonic() - t0,
                                                     s.exchanges))
            if c.failed != failed_before or args.verbose:
                dump(s)
            if body is session1 and c.failed != failed_before and held is None:
                break  # session 2 checks what session 1 wrote
    finally:
        for s in sessions:
            if s.sim is not None and s.sim.poll() is None:
                stop_process(s.sim)
            stop_process(s.socat)
        shutil.rmtree(tmp, ignore_errors=True)


def main():
    return pyprofibus_main(__doc__, run)


if __name__ == "__main__":
    sys.exit(main())
