#!/usr/bin/env python3
"""pyprofibus, an independent DP master, polls a line of three cards on one port.

usage: test_pyprofibus_line.py --dfp-sim PATH --gsd-dir DIR [--baud 19200] [--verbose]

  socat -d -d pty,raw,echo=0,link=TMP/a pty,raw,echo=0,link=TMP/b
  dfp-sim slave --port TMP/a --address 4-6 --baud 19200 --eeprom TMP/ee
  pyprofibus DPM1 (serial PHY on TMP/b, config file written to TMP from SEW_6003.GSD with three
  slaves 4, 5 and 6, module "Param + 3 PD": Chk_Cfg F3 F2, 14 bytes each way)
driven in-process for at most MASTER_TIME s (plumbing shared with test_pyprofibus_interop.py).

Every card has its own emulated MOVIDRIVE (--inverter sim, the default; --eeprom needs it), so
the PI words are the drive's status word and actual speed, not an echo of the PO words (only
--inverter none echoes, and it refuses --eeprom). What must come back from a slave is what its
own drive makes of its own outputs, with values distinct per slave: slave a uses (a << 8) + k
(slave 4 0x0400 + k, slave 5 0x0500 + k, slave 6 0x0600 + k). Each slave runs, independently
and interleaved on the line by pyprofibus's round robin:
  1. parameter channel (8 bytes, protocol.md §B6; every service toggles the handshake, done when
     a reply carries the sent handshake and index): write volatile H0 (11000) = (a << 8) + k,
     k = 0..2; write volatile P130/P131 (ramp up/down) = 0 ms; write non-volatile P100 = 3 and
     P101 = 2 (FIELDBUS); read H0 -> (a << 8) + 2 (its own last write). Every reply must be
     exactly the expected one (a write's reply echoes the value);
  2. process data: PO1 = 0006 (enable), PO2 (speed setpoint, 0.2 rpm/digit) = (a << 8) + k for
     k = 0..PD_PATTERNS-1, each held until PI2 (actual speed) shows it in the last PD_CHECKED
     replies (at least PD_HOLD replies; at most PD_MAX_HOLD, or FIRST_PD_TIME s for the first
     pattern, which enables the drive). With ramp time 0 the speed follows at once, so PI2 shows
     only the previous or the current pattern: an echo one or two replies late.
pyprofibus brings the slaves up one at a time: a slave is added (DpMaster.addSlave) once the one
added before has answered a Data_Exchange. Started together, pyprofibus 1.13 loses its way: it
takes an E5 short acknowledgement as the reply for every slave waiting for one, drops a queued
Chk_Cfg on the resulting state change, and then sends a slave a new request with an unchanged
FCB, which the card (rightly, protocol.md §A1.5) answers with its cached E5 again; pyprofibus
re-initialises slaves, some after Data_Exchange. Once up, all three are polled together.

Asserted:
  - all three slaves reach Data_Exchange in pyprofibus (isConnected) within STARTUP_TIME; none
    is re-initialised: isConnected never drops, one "Trying to initialize slave N" each in
    pyprofibus's log, no Set_Prm/Chk_Cfg to a slave on the wire after its first Data_Exchange;
  - the channel services and the PD patterns above, for every slave;
  - every channel reply and every PI2 pyprofibus got from slave a belongs to slave a's own
    sequence (8 x 00 before its first service, PI2 = 0 before the enable), never to another
    slave's, and the channel keeps the read's reply through the PD phase: the addressing on the
    shared line;
  - on the wire as pyprofibus's PHY saw it, every reply comes from a station that had a request
    outstanding (pyprofibus keeps two requests in flight once its slaves are out of step:
    reported, not checked);
  - dfp-sim printed "card N ... -> Data_Exch" for each address and had each card in Data_Exch
    when stopped (every "Data_Exch ->" followed by a new "-> Data_Exch"), and exited 0 on
    SIGTERM;
  - the EEPROM directory holds one image per address afterwards, drive4.ee, drive5.ee and
    drive6.ee (with file_nvm's previous generations drive<N>.ee.bak and its lock files
    drive<N>.ee.lock, nothing else), each a
    file_nvm image ("DFPE") of the same generation (each drive got the same non-volatile
    writes).

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise, 77 (a
ctest skip) when pyprofibus, pyserial or socat is missing. On a failure it prints dfp-sim's and
socat's output, pyprofibus's debug log, each slave's PD history and the last telegrams on the
wire.
"""

import contextlib
import io
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time

from checker import pyprofibus_main  # sibling modules in tests/interop
from test_pyprofibus_interop import (MASTER_ADDR, SD2, make_tap_phy, read_text,
                                     start_socat_pair, stop_process, wait_for, words)

ADDRS = (4, 5, 6)
MODULE = "Param + 3 PD"
SIZE = 14             # 8-byte channel + 3 words, each way
MASTER_TIME = 20.0    # seconds of master loop, at most
STARTUP_TIME = 5.0    # all three slaves in Data_Exchange by then
SERVICE_CYCLES = 60   # a parameter service must be answered within this many replies
PD_PATTERNS = 200     # process data patterns per slave
PD_HOLD = 3           # each held at least this many replies of its slave
PD_CHECKED = 2        # the last this many replies must carry it
PD_MAX_HOLD = 30      # a pattern not followed within this many replies fails
FIRST_PD_TIME = 3.0   # the first pattern (enable from inhibit) may take this long
REPLY_WINDOW = 0.5    # wire check: a reply later than this after its request is not matched

HS = 0x40             # handshake bit of the management byte
SVC_READ, SVC_WRITE, SVC_WRITE_VOLATILE = 0x01, 0x02, 0x03
LEN4 = 0x30           # data length bits 5..4 = 11: 4 bytes
IDX_H0 = 11000
IDX_P130, IDX_P131 = 8470, 8471   # ramp t11 up / down CW, ms
IDX_P100, IDX_P101 = 8461, 8462   # setpoint source / control signal source
FIELDBUS_SETPOINT, FIELDBUS_CONTROL = 3, 2
CW_ENABLE = 0x0006


def pattern(a, k):
    return (a << 8) + k


def services(a):
    """Slave a's parameter services: (name, service, index, value, expected reply value)."""
    s = [("write volatile H0 = 0x%04X" % pattern(a, k), SVC_WRITE_VOLATILE, IDX_H0,
          pattern(a, k), pattern(a, k)) for k in range(3)]
    s += [("write volatile P130 = 0 ms", SVC_WRITE_VOLATILE, IDX_P130, 0, 0),
          ("write volatile P131 = 0 ms", SVC_WRITE_VOLATILE, IDX_P131, 0, 0),
          ("write P100 = 3 FIELDBUS", SVC_WRITE, IDX_P100, FIELDBUS_SETPOINT, FIELDBUS_SETPOINT),
          ("write P101 = 2 FIELDBUS", SVC_WRITE, IDX_P101, FIELDBUS_CONTROL, FIELDBUS_CONTROL),
          ("read H0", SVC_READ, IDX_H0, 0, pattern(a, 2))]
    return s


def hx(b):
    return b.hex(" ").upper() if b is not None else "None"


class Drive:
    """Master side for one slave: its parameter services, then its process data patterns."""

    def __init__(self, addr):
        self.addr = addr
        self.desc = None
        self.hs = 0                 # the card starts at handshake 0
        self.req = bytes(8)         # "no service" until connected
        self.po = [0, 0, 0]
        self.todo = services(addr)
        self.svc = None             # (name, request, wanted reply, replies so far)
        self.svc_results = []       # (name, request, wanted reply, reply or None, replies)
        self.channel_seen = []      # every channel reply (bytes 0..7) from this slave
        self.pi2_seen = []          # every PI2 from this slave
        self.pd_channel = []        # the channel replies during the process data phase
        self.groups = []            # PD phase: (PO2 pattern, [(PI1, PI2), ...], t start)
        self.phase = "wait"         # wait, channel, pd, done, failed
        self.failure = None
        self.dx_time = None
        self.added_time = 0.0       # when the master loop added it (pyprofibus addSlave)
        self.connected = False
        self.restarts = 0
        self.exchanges = 0
        self.last_in = None

    def outputs(self):
        return self.req + words(*self.po)

    def next_service(self):
        if not self.todo:
            self.phase = "pd"
            self.po = [CW_ENABLE, pattern(self.addr, 0), 0]
            self.groups.append((pattern(self.addr, 0), [], time.monotonic()))
            return
        name, service, index, value, want_value = self.todo.pop(0)
        self.hs ^= HS
        mgmt = service | (LEN4 if service != SVC_READ else 0) | self.hs
        self.req = bytes([mgmt, 0x00]) + index.to_bytes(2, "big") + \
            (value & 0xFFFFFFFF).to_bytes(4, "big")
        want = bytes([mgmt, 0x00]) + index.to_bytes(2, "big") + \
            (want_value & 0xFFFFFFFF).to_bytes(4, "big")
        self.svc = (name, self.req, want, 0)
        self.phase = "channel"

    def on_input(self, data):
        """One Data_Exchange reply of this slave: record it, advance its sequence."""
        self.exchanges += 1
        self.last_in = data
        ch = data[:8]
        pi1, pi2 = struct.unpack(">HH", data[8:12])
        self.channel_seen.append(ch)
        self.pi2_seen.append(pi2)
        if self.phase == "wait":
            if self.exchanges >= 3:   # a few cycles of "no service" first, as a master starts
                self.next_service()
        elif self.phase == "channel":
            name, req, want, n = self.svc
            n += 1
            self.svc = (name, req, want, n)
            if (ch[0] & HS) == (req[0] & HS) and ch[2:4] == req[2:4]:
                self.svc_results.append((name, req, want, ch, n))
                if ch != want:
                    self.fail("%s: reply %s, expected %s" % (name, hx(ch), hx(want)))
                else:
                    self.next_service()
            elif n >= SERVICE_CYCLES:
                self.svc_results.append((name, req, want, None, n))
                self.fail("%s: no reply in %d cycles (last channel reply %s)"
                          % (name, n, hx(ch)))
        elif self.phase == "pd":
            self.pd_channel.append(ch)
            out, got, t0 = self.groups[-1]
            got.append((pi1, pi2))
            first = len(self.groups) == 1
            echoed = len(got) >= max(PD_HOLD, PD_CHECKED) and \
                all(g[1] == out for g in got[-PD_CHECKED:])
            if echoed:
                k = len(self.groups)
                if k >= PD_PATTERNS:
                    self.phase = "done"
                else:
                    self.po = [CW_ENABLE, pattern(self.addr, k), 0]
                    self.groups.append((pattern(self.addr, k), [], time.monotonic()))
            elif (first and time.monotonic() - t0 > FIRST_PD_TIME) or \
                    (not first and len(got) >= PD_MAX_HOLD):
                self.fail("PO2 0x%04X not followed by PI2 (last PI1 %04X PI2 %04X after %d "
                          "replies)" % (out, pi1, pi2, len(got)))

    def fail(self, why):
        self.phase = "failed"
        self.failure = why


def write_conf(path, dev, baud, gsd_path):
    # pyprofibus's conf format (see its example_*.conf): comments on their own lines only.
    # input_size = bytes the master sends to the slave, output_size = bytes it gets back.
    text = """[PROFIBUS]
debug=1

[PHY]
type=serial
dev=%s
baud=%d
rtscts=False
dsrdtr=False

[DP]
master_class=1
master_addr=%d
""" % (dev, baud, MASTER_ADDR)
    for n, a in enumerate(ADDRS):
        text += """
[SLAVE_%d]
name=dfp21b_%d
addr=%d
gsd=%s
sync_mode=0
freeze_mode=0
group_mask=1
watchdog_ms=1000
module_0=%s
output_size=%d
input_size=%d
diag_period=0
""" % (n, a, a, gsd_path, MODULE, SIZE, SIZE)
    with open(path, "w") as f:
        f.write(text)


def run_master(pb, conf_path, drives, deadline):
    """Drive pyprofibus until every slave's sequence is done (or failed) or the deadline."""
    config = pb.PbConf.fromFile(conf_path)
    phy = make_tap_phy(pb.phy_serial.CpPhySerial)(port=config.phyDev, debug=False)
    res = {"error": None, "phy": phy, "all_dx_time": None, "loop_time": 0.0}
    master = None
    try:
        phy.setConfig(baudrate=config.phyBaud)
        master = config.makeDPM(phy=phy)
        by_desc = {}
        for sc in config.slaveConfs:
            desc = sc.makeDpSlaveDesc()
            d = next(d for d in drives if d.addr == desc.slaveAddr)
            d.desc = desc
            by_desc[id(desc)] = d
        # One slave at a time into Data_Exchange (see the docstring): the next one is added
        # once the last one added has answered a Data_Exchange.
        added = [drives[0]]
        master.addSlave(drives[0].desc)
        master.initialize()
        t0 = time.monotonic()
        while time.monotonic() < deadline:
            now = time.monotonic()
            if res["all_dx_time"] is None and now - t0 > STARTUP_TIME:
                break
            if all(d.phase in ("done", "failed") for d in drives):
                break
            if len(added) < len(drives) and added[-1].exchanges > 0:
                nxt = drives[len(added)]
                added.append(nxt)
                nxt.added_time = time.monotonic() - t0
                master.addSlave(nxt.desc)
            for d in added:
                d.desc.setMasterOutData(bytearray(d.outputs()))
            handled = master.run()
            d = by_desc.get(id(handled)) if handled is not None else None
            if d is None:
                continue
            conn = d.desc.isConnected()
            if d.connected and not conn:
                d.restarts += 1
            if conn and d.dx_time is None:
                d.dx_time = time.monotonic() - t0
            d.connected = conn
            if res["all_dx_time"] is None and all(x.dx_time is not None for x in drives):
                res["all_dx_time"] = time.monotonic() - t0
            data = d.desc.getMasterInData()
            if data is not None and d.phase not in ("done", "failed"):
                d.on_input(bytes(data))
        res["loop_time"] = time.monotonic() - t0
    except Exception as e:  # ProfibusError (e.g. an RS reply ends pyprofibus's loop) and others
        res["error"] = "%s: %s" % (type(e).__name__, e)
    finally:
        if master is not None:
            master.destroy()
        else:
            phy.close()
    return res


def frame_addrs(frame):
    """(DA, SA, DSAP or None) of an SD1/SD2/SD3 telegram (address extension bits stripped),
    None for a short acknowledgement or anything else."""
    if not frame:
        return None
    if frame[0] == SD2:
        hdr = 4
    elif frame[0] in (0x10, 0xA2):   # SD1, SD3
        hdr = 1
    else:
        return None
    if len(frame) < hdr + 3:
        return None
    da, sa = frame[hdr], frame[hdr + 1]
    dsap = frame[hdr + 3] if (da & 0x80) and len(frame) > hdr + 4 else None
    return da & 0x7F, sa & 0x7F, dsap


def check_wire(c, wire):
    """Every reply from a station with a request outstanding; no re-initialisation after DX."""
    pending = {}       # DA -> [(time, DSAP)] of requests not answered yet (within REPLY_WINDOW)
    replies = {a: 0 for a in ADDRS}
    wrong = []
    acks = unattributed_acks = 0
    overlaps = 0       # requests pyprofibus sent while another station's reply was still due
    first_dx = {}      # address -> time of its first Data_Exchange reply on the wire
    after_dx = {a: [] for a in ADDRS}   # Set_Prm / Chk_Cfg sent to it after that
    t_start = wire[0][0] if wire else 0.0

    def prune(now):
        for da in pending:
            pending[da] = [p for p in pending[da] if now - p[0] <= REPLY_WINDOW]

    for t, d, f in wire:
        prune(t)
        ad = frame_addrs(f)
        if d == "TX":
            if ad is None:
                continue
            if any(v for da, v in pending.items() if da != ad[0]):
                overlaps += 1
            pending.setdefault(ad[0], []).append((t, ad[2]))
            if ad[2] in (61, 62) and ad[0] in first_dx:
                after_dx[ad[0]].append("%s at %.3f s" % ("Set_Prm" if ad[2] == 61 else "Chk_Cfg",
                                                          t - t_start))
        elif f == b"\xe5":
            # a short acknowledgement names no station: the oldest Set_Prm/Chk_Cfg due
            acks += 1
            due = [(v[i][0], da, i) for da, v in pending.items() for i in range(len(v))
                   if v[i][1] in (61, 62)]
            if due:
                _, da, i = min(due)
                del pending[da][i]
            else:
                unattributed_acks += 1
        elif ad is not None:
            if ad[0] != MASTER_ADDR or not pending.get(ad[1]):
                wrong.append("%.3f s: reply from %d to %d with no request to it outstanding "
                             "(outstanding: %s): %s"
                             % (t - t_start, ad[1], ad[0],
                                {k: len(v) for k, v in pending.items() if v}, hx(f)))
                continue
            pending[ad[1]].pop(0)
            if ad[1] in replies:
                replies[ad[1]] += 1
                if ad[2] is None and f[0] == SD2 and ad[1] not in first_dx:
                    first_dx[ad[1]] = t
    c.check(not wrong and all(replies[a] > 0 for a in ADDRS),
            "wire: each of the %d addressed replies came from a station with a request to it "
            "outstanding (%s; %d E5 acknowledgements, %d with no Set_Prm/Chk_Cfg due; "
            "pyprofibus sent %d requests while another station's reply was still due)"
            % (sum(replies.values()), ", ".join("%d: %d" % (a, replies[a]) for a in ADDRS),
               acks, unattributed_acks, overlaps),
            "%d wrong, first: %s" % (len(wrong), wrong[0] if wrong else "-"))
    c.check(all(a in first_dx for a in ADDRS) and not any(after_dx.values()),
            "wire: no Set_Prm or Chk_Cfg to a slave after its first Data_Exchange reply (no "
            "restart)", "after DX: %s; slaves with DX replies: %s" % (after_dx, sorted(first_dx)))


def check_drive(c, d, others):
    tag = "slave %d: " % d.addr
    c.check(d.restarts == 0, tag + "pyprofibus never dropped the slave out of Data_Exchange",
            "%d restarts" % d.restarts)
    # 1. the parameter channel
    names = [s[0] for s in services(d.addr)]
    ok_svcs = [r for r in d.svc_results if r[3] == r[2]]
    c.check(len(ok_svcs) == len(names),
            tag + "all %d parameter services answered exactly (%s)"
            % (len(names), "; ".join("%s -> %s after %d" % (r[0], hx(r[3]), r[4])
                                      for r in d.svc_results)),
            "%d of %d; %s" % (len(ok_svcs), len(names), d.failure))
    last_read = d.svc_results[-1][2] if len(ok_svcs) == len(names) else None
    own_channel = {bytes(8)} | {r[2] for r in d.svc_results}
    foreign = [ch for ch in d.channel_seen if ch not in own_channel]
    c.check(not foreign,
            tag + "every one of its %d channel replies was 8 x 00 or a reply to one of its own "
            "services" % len(d.channel_seen),
            "%d others, first %s" % (len(foreign), hx(foreign[0]) if foreign else "-"))
    # 2. process data
    n_ok = 0
    bad = None
    lags = []
    for j, (out, got, _) in enumerate(d.groups):
        prev = d.groups[j - 1][0] if j > 0 else 0
        pi2 = [g[1] for g in got]
        lag = next((k for k, v in enumerate(pi2) if v == out), None)
        ok = (lag is not None and len(pi2) >= PD_CHECKED and all(v == out for v in pi2[lag:])
              and all(v == prev for v in pi2[:lag]))
        if ok:
            n_ok += 1
            lags.append(lag)
        elif bad is None:
            bad = "pattern %d: PO2 %04X -> PI2 %s" % (j, out, " ".join("%04X" % v for v in pi2))
    c.check(n_ok == PD_PATTERNS and len(d.groups) == PD_PATTERNS,
            tag + "PO2 = 0x%04X..0x%04X (%d patterns): PI2 followed each, showing only the "
            "previous or the current one (from reply %s on)"
            % (pattern(d.addr, 0), pattern(d.addr, PD_PATTERNS - 1), PD_PATTERNS,
               "..".join(str(x) for x in sorted({min(lags or [0]), max(lags or [0])}))),
            "%d of %d patterns followed; %s; %s" % (n_ok, PD_PATTERNS, bad, d.failure))
    last_pi1 = d.groups[-1][1][-1][0] if d.groups and d.groups[-1][1] else None
    c.check(last_pi1 is not None and last_pi1 & 0x07 == 0x07,
            tag + "PI1 (status word) %s: output stage on, ready, PO data enabled"
            % ("-" if last_pi1 is None else "%04X" % last_pi1))
    c.check(last_read is not None and d.pd_channel and
            all(ch == last_read for ch in d.pd_channel),
            tag + "the channel kept the read's reply %s through the %d process data replies"
            % (hx(last_read), len(d.pd_channel)),
            "channel replies: %s" % sorted({hx(ch) for ch in d.pd_channel}))
    own_pi2 = {0} | {pattern(d.addr, k) for k in range(PD_PATTERNS)}
    c.check(set(d.pi2_seen) <= own_pi2 and not (set(d.pi2_seen) & others),
            tag + "PI2 only ever showed 0 or its own patterns, never another slave's (%d "
            "replies, %d distinct values)" % (len(d.pi2_seen), len(set(d.pi2_seen))),
            "foreign values: %s" % " ".join("%04X" % v for v in sorted(set(d.pi2_seen) -
                                                                     own_pi2)))


def check_sim_log(c, text):
    for a in ADDRS:
        enter = re.findall(r"^\s*[\d.]+ ms\s+card %d\s+\S+ -> Data_Exch\s*$" % a, text, re.M)
        leave = re.findall(r"^\s*[\d.]+ ms\s+card %d\s+Data_Exch -> \S+\s*$" % a, text, re.M)
        stop = re.search(r"stopping \(signal\); card %d state (\S+)" % a, text)
        c.check(len(enter) >= 1 and len(leave) == len(enter) - 1 and stop is not None and
                stop.group(1) == "Data_Exch",
                "dfp-sim: card %d printed \"-> Data_Exch\" (%d time%s) and was in Data_Exch "
                "when stopped" % (a, len(enter), "" if len(enter) == 1 else "s"),
                "entered %d, left %d times, state at stop: %s"
                % (len(enter), len(leave), stop.group(1) if stop else "-"))


def nvm_generation(path):
    """The file_nvm header's sequence number (bytes 12..15), or None without a valid image."""
    try:
        with open(path, "rb") as f:
            h = f.read(20)
    except OSError:
        return None
    if len(h) < 20 or h[:4] != b"DFPE":
        return None
    return struct.unpack(">I", h[12:16])[0]


def check_eeprom(c, ee_dir):
    """drive<a>.ee per address (file_nvm keeps the previous generation as drive<a>.ee.bak and
    its lock as drive<a>.ee.lock)."""
    try:
        names = sorted(os.listdir(ee_dir))
    except OSError as e:
        names = ["<%s>" % e]
    want = ["drive%d.ee" % a for a in ADDRS]
    extra = [n for n in names
             if n not in want and n not in [w + s for w in want for s in (".bak", ".lock")]]
    c.check(all(w in names for w in want) and not extra,
            "EEPROM directory holds one image per address: %s (%s)"
            % (", ".join(want), ", ".join(names)),
            "it holds %s" % (", ".join(names) or "nothing"))
    gens = [nvm_generation(os.path.join(ee_dir, n)) for n in want]
    c.check(all(g is not None for g in gens) and len(set(gens)) == 1,
            "each drive's EEPROM file is a file_nvm image (DFPE), all with generation %s (the "
            "same non-volatile writes each)" % gens[0], "generations: %s" % gens)


def run(c, pb, args):
    tmp = tempfile.mkdtemp(prefix="dfp-line-")
    a, b = os.path.join(tmp, "a"), os.path.join(tmp, "b")
    ee_dir = os.path.join(tmp, "ee")
    os.mkdir(ee_dir)
    sim_out, sim_err = os.path.join(tmp, "dfp-sim.out"), os.path.join(tmp, "dfp-sim.err")
    socat_err = os.path.join(tmp, "socat.err")
    log = io.StringIO()
    socat = sim = res = None
    drives = [Drive(x) for x in ADDRS]
    t_start = time.monotonic()
    try:
        socat, up = start_socat_pair(a, b, socat_err)
        if not c.check(up, "socat PTY pair up"):
            return
        with open(sim_out, "w") as out, open(sim_err, "w") as err:
            sim = subprocess.Popen([args.dfp_sim, "slave", "--port", a, "--address",
                                    "%d-%d" % (ADDRS[0], ADDRS[-1]), "--baud", str(args.baud),
                                    "--eeprom", ee_dir],
                                   stdin=subprocess.DEVNULL, stdout=out, stderr=err)
        wait_for(lambda: sim.poll() is not None or "dfp-sim" in read_text(sim_out), 3.0)
        if not c.check(sim.poll() is None, "dfp-sim slave running (addresses 4-6)",
                       "exited with %r" % sim.poll()):
            return
        conf = os.path.join(tmp, "pyprofibus.conf")
        write_conf(conf, b, args.baud, os.path.join(args.gsd_dir, "SEW_6003.GSD"))
        with contextlib.redirect_stdout(log):
            res = run_master(pb, conf, drives, time.monotonic() + MASTER_TIME)

        c.check(res["error"] is None, "pyprofibus master loop ran without an exception",
                str(res["error"]))
        c.check(res["all_dx_time"] is not None,
                "pyprofibus reports all three slaves in Data_Exchange (isConnected)%s"
                % ("" if res["all_dx_time"] is None else " after %.2f s (%s)" % (
                    res["all_dx_time"], ", ".join("%d: %.2f s" % (d.addr, d.dx_time)
                                                  for d in drives))),
                "in Data_Exchange after: %s" % ", ".join(
                    "%d: %s" % (d.addr, "never" if d.dx_time is None else "%.2f s" % d.dx_time)
                    for d in drives))
        inits = {d.addr: len(re.findall(r"Trying to initialize slave %d\.\.\." % d.addr,
                                        log.getvalue())) for d in drives}
        c.check(all(n == 1 for n in inits.values()),
                "pyprofibus initialised each slave exactly once (added %s)"
                % ", ".join("%d at %.2f s" % (d.addr, d.added_time) for d in drives),
                "per slave: %s" % inits)
        if res["all_dx_time"] is None:
            return
        c.check(all(d.phase == "done" for d in drives),
                "all three sequences completed within %.0f s of master loop (%.2f s, "
                "exchanges %s)" % (MASTER_TIME, res["loop_time"],
                                   ", ".join("%d: %d" % (d.addr, d.exchanges) for d in drives)),
                "; ".join("%d: %s %s" % (d.addr, d.phase, d.failure or "") for d in drives))
        for d in drives:
            others = {pattern(o, k) for o in ADDRS if o != d.addr
                      for k in range(max(PD_PATTERNS, 3))}
            check_drive(c, d, others)
        check_wire(c, res["phy"].wire)
    finally:
        sim_rc = stop_process(sim) if sim is not None else "not started"
        stop_process(socat)
        sim_text = read_text(sim_out)
        if sim is not None:
            check_sim_log(c, sim_text)
            c.check(sim_rc == 0, "dfp-sim exited 0 on SIGTERM", "exit %r" % sim_rc)
            if res is not None and res["all_dx_time"] is not None:
                check_eeprom(c, ee_dir)
        print("     %.2f s" % (time.monotonic() - t_start))
        if c.failed or args.verbose:
            dump(sim_text, read_text(sim_err), read_text(socat_err), log.getvalue(), res,
                 drives)
        shutil.rmtree(tmp, ignore_errors=True)


def dump(sim_out, sim_err, socat_err, pb_log, res, drives):
    def block(title, text, max_lines=80):
        lines = text.rstrip("\n").splitlines()
        if len(lines) > max_lines:
            lines = ["... (%d lines before)" % (len(lines) - max_lines)] + lines[-max_lines:]
        print("---- %s ----" % title)
        for line in lines:
            print("  " + line)
    block("dfp-sim stdout", sim_out)
    block("dfp-sim stderr", sim_err)
    block("socat stderr", socat_err, 20)
    block("pyprofibus log", pb_log, 60)
    for d in drives:
        block("slave %d: phase %s, last input %s" % (d.addr, d.phase, hx(d.last_in)),
              "\n".join("PO2 %04X: %s" % (out, " ".join("%04X/%04X" % g for g in got))
                        for out, got, _ in d.groups), 20)
    if res is not None:
        wire = res["phy"].wire
        t0 = wire[0][0] if wire else 0.0
        block("wire as pyprofibus saw it (last 40)",
              "\n".join("%9.3f ms %s %s" % ((t - t0) * 1e3, d, f.hex(" ")) for t, d, f in wire),
              40)


def main():
    return pyprofibus_main(__doc__, run)


if __name__ == "__main__":
    sys.exit(main())
