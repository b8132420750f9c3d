#!/usr/bin/env python3
"""The three speed ratios of docs/performance.md ("Against other tools"), each measured side by
side in one run: prints figures and ratios, asserts nothing.

  1. replay: `dfp-sim replay FILE --check --speed max` on a capture of about 10^6 telegrams
     (written by `dfp-sim record --baud 12M`, Param + 3 PD) against a
     `tshark -r FILE -T fields -e frame.len` pass over the same capture converted to USER0;
  2. in process: start-up + Data_Exchange cycles of the built-in master with the card on the
     in-memory bus (`dfp-bench --cycles N --baud 12000000`) against pyprofibus's master with its
     in-process dummy slave (CpPhyDummySlave), the same configuration Param + 3 PD;
  3. PTY: `dfp-sim master` against `dfp-sim slave --pty LINK` (the card's own PTY pair, the
     master on LINK) at a nominal 1.5 Mbit/s, against pyprofibus's master with the same
     `dfp-sim slave`, Data_Exchange cycles per second of wall time (a PTY has no bit timing:
     the rate sets the timeouts and the waits the line's rules demand, TSYN before a request and
     min TSDR before a reply). --pty-medium socat puts a socat PTY pair between them instead
     (`dfp-sim slave --port` on one end, the master on the other); both: one line each. After
     the ratios, the ceiling those two waits put on the PTY ratio: no master that keeps them
     can run faster than one cycle per 44 bit times, so its ratio to pyprofibus's measured
     rate cannot exceed that.

Each figure is the best of --runs runs (the machine's other load only ever slows a run down).

    tools/bench/ratio_bench.py [--build DIR] [--python PY] [--telegrams N] [--cycles N]
                               [--pty-cycles N] [--pty-medium direct|socat|both]
                               [--baud RATE] [--runs N] [--dir DIR]
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "interop"))
# pyprofibus's configuration and the PTY plumbing, as the interop tests use them
from test_pyprofibus_interop import (MASTER_ADDR, SLAVE_ADDR,  # noqa: E402
                                     start_socat_pair, stop_process, wait_for, write_conf)

CFG = "F3F2"  # Param + 3 PD: 14 octets each way
IO_LEN = 14


def timed(cmd, **kw):
    """Wall time and output of one command; a failure ends the benchmark."""
    t0 = time.monotonic()
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)
    dt = time.monotonic() - t0
    if r.returncode != 0:
        sys.exit("ratio_bench: %s failed (exit %d): %s" % (" ".join(cmd), r.returncode,
                                                          r.stderr.strip()[-400:]))
    return dt, r.stdout


# ---- 1. replay against tshark ----------------------------------------------------------------

def ratio_replay(a, dfp_sim, tmp):
    cap = os.path.join(tmp, "bench.pcap")
    user0 = os.path.join(tmp, "bench_user0.pcap")
    timed([dfp_sim, "record", "--capture", cap, "--cycles", str(a.telegrams // 2),
           "--baud", "12M", "--param-every", "10"])
    timed([dfp_sim, "convert", cap, user0, "--linktype", "user0", "--quiet"])
    _, out = timed(["tshark", "-r", user0, "-T", "fields", "-e", "frame.len"])
    n = len(out.split())
    # Taken in turns, so that both see the same swings of the machine's speed: a 0.2 s replay
    # run seven times in a row sees one moment, the 4 s tshark passes a minute.
    replay = tshark = float("inf")
    for _ in range(a.runs):
        replay = min(replay, timed([dfp_sim, "replay", cap, "--check", "--speed", "max",
                                    "--address", str(SLAVE_ADDR), "--baud", "12M"])[0])
        tshark = min(tshark, timed(["tshark", "-r", user0, "-T", "fields", "-e", "frame.len"])[0])
    print("replay:     %d telegrams: dfp-sim replay --check --speed max %.2f s = %.0f "
          "telegrams/s; tshark -T fields -e frame.len (USER0) %.2f s" % (n, replay, n / replay,
                                                                         tshark))
    return tshark / replay


# ---- 2. in process against pyprofibus with its dummy slave ---------------------------------

def dfp_inprocess_rate(dfp_bench, cycles):
    _, out = timed([dfp_bench, "--cycles", str(cycles), "--baud", "12000000"])
    m = re.search(r"(\d+) cycles in .* simulated in\s+([\d.]+) ms wall", out)
    if m is None:
        sys.exit("ratio_bench: unexpected dfp-bench output: %s" % out.strip())
    return int(m.group(1)) / (float(m.group(2)) / 1000.0)


# pyprofibus's master for N Data_Exchange cycles, start-up included: with its in-process dummy
# slave (DEV "dummy") or over a serial device. Run by the venv's interpreter, which has it.
PYPROFIBUS_MASTER = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
from test_pyprofibus_interop import write_conf
import pyprofibus, pyprofibus.phy_dummy, pyprofibus.phy_serial
conf, dev, gsd, baud, cycles = sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]), int(sys.argv[6])
write_conf(conf, dev, baud, gsd, "Param + 3 PD", 14)
config = pyprofibus.PbConf.fromFile(conf)
t0 = time.monotonic()
if dev == "dummy":
    phy = pyprofibus.phy_dummy.CpPhyDummySlave(debug=False, echoDX=True, echoDXSize=14)
else:
    phy = pyprofibus.phy_serial.CpPhySerial(port=config.phyDev, debug=False)
phy.setConfig(baudrate=config.phyBaud)
master = config.makeDPM(phy=phy)
desc = config.slaveConfs[0].makeDpSlaveDesc()
master.addSlave(desc)
master.initialize()
n = 0
out = bytearray(14)
while n < cycles and time.monotonic() - t0 < 120:
    desc.setMasterOutData(out)
    if master.run() is desc and desc.getMasterInData() is not None:
        n += 1
dt = time.monotonic() - t0
master.destroy()
print(n, dt)
"""


def pyprofibus_rate(a, conf, dev, baud, cycles):
    gsd = os.path.join(ROOT, "firmware", "gsd", "SEW_6003.GSD")
    _, out = timed([a.python, "-c", PYPROFIBUS_MASTER, os.path.join(ROOT, "tests", "interop"),
                    conf, dev, gsd, str(baud), str(cycles)])
    n, dt = out.split()[-2:]
    return int(n) / float(dt)


def ratio_inprocess(a, dfp_bench, tmp):
    conf = os.path.join(tmp, "dummy.conf")
    ours = max(dfp_inprocess_rate(dfp_bench, a.cycles) for _ in range(a.runs))
    n = max(a.cycles // 100, 1000)
    theirs = max(pyprofibus_rate(a, conf, "dummy", 12000000, n) for _ in range(a.runs))
    print("in process: start-up + Data_Exchange cycles, Param + 3 PD: dfp-sim master + card on "
          "the in-memory bus %.0f cycles/s (%d cycles at 12 Mbit/s); pyprofibus master + "
          "CpPhyDummySlave %.0f cycles/s (%d cycles)" % (ours, a.cycles, theirs, n))
    return ours / theirs


# ---- 3. PTY: dfp-sim master against pyprofibus, both with dfp-sim slave ---------------------

def slave_cmd(a, dfp_sim, medium_args):
    return [dfp_sim, "slave"] + medium_args + ["--address", str(SLAVE_ADDR), "--baud",
                                               str(a.baud), "--inverter", "none", "--quiet"]


def with_slave(a, dfp_sim, tmp, medium, fn):
    """A fresh dfp-sim slave on its own PTY pair (direct) or on one end of a socat pair;
    fn(the device the master opens) runs the master."""
    pa, pb = os.path.join(tmp, "pty_a"), os.path.join(tmp, "pty_b")
    socat = slave = None
    try:
        if medium == "direct":
            slave = subprocess.Popen(slave_cmd(a, dfp_sim, ["--pty", pb]),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            if not wait_for(lambda: os.path.islink(pb), 5.0):
                sys.exit("ratio_bench: dfp-sim slave --pty did not make its link")
        else:
            socat, up = start_socat_pair(pa, pb)
            if not up:
                sys.exit("ratio_bench: socat did not make the PTY pair")
            slave = subprocess.Popen(slave_cmd(a, dfp_sim, ["--port", pa]),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(0.3)
        return fn(pb)
    finally:
        stop_process(slave)
        stop_process(socat)


def ratio_pty(a, dfp_sim, tmp, medium):
    conf = os.path.join(tmp, "pty.conf")

    def ours_once(dev):
        dt, _ = timed([dfp_sim, "master", "--port", dev, "--address", str(SLAVE_ADDR),
                       "--master-address", str(MASTER_ADDR), "--config", CFG, "--baud",
                       str(a.baud), "--cycles", str(a.pty_cycles), "--quiet"])
        return a.pty_cycles / dt

    def theirs_once(dev):
        return pyprofibus_rate(a, conf, dev, a.baud, a.pty_cycles)

    ours_all = [with_slave(a, dfp_sim, tmp, medium, ours_once) for _ in range(a.runs)]
    theirs_all = [with_slave(a, dfp_sim, tmp, medium, theirs_once) for _ in range(a.runs)]
    ours, theirs = max(ours_all), max(theirs_all)
    ran = ("dfp-sim slave --pty LINK, the master on LINK" if medium == "direct" else
           "socat pty,raw,echo=0 pair, dfp-sim slave --port on one end, the master on the other")
    print("PTY (%s):%s %d Data_Exchange cycles against dfp-sim slave at a nominal %d bit/s, "
          "start-up included (%s): dfp-sim master %.0f cycles/s (runs %s); pyprofibus master "
          "%.0f cycles/s (runs %s)"
          % (medium, " " * (6 - len(medium)), a.pty_cycles, a.baud, ran, ours,
             " ".join("%.0f" % x for x in ours_all), theirs,
             " ".join("%.0f" % x for x in theirs_all)))
    return ours / theirs, theirs


# The waits a PTY cannot shorten: the master's idle before each request (TSYN, 33 bit) and the
# slave's minimum station delay before its reply (min TSDR, 11 bit by default). A PTY moves
# octets without bit time, so these are all of a cycle's line time; a master that keeps them
# runs at most 1 / (44 bit) cycles per second, whatever its own speed and the kernel's.
TSYN_BITS, MIN_TSDR_BITS = 33, 11


def pty_ceiling(baud, theirs):
    most = baud / float(TSYN_BITS + MIN_TSDR_BITS)
    return most, most / theirs


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build", "host"))
    venv_python = os.path.join(ROOT, "build", "venv", "bin", "python3")
    # The checkout's venv (it has pyprofibus), else the interpreter running this (a worktree
    # without a venv of its own, run by another checkout's).
    ap.add_argument("--python", default=venv_python if os.access(venv_python, os.X_OK)
                    else sys.executable)
    ap.add_argument("--telegrams", type=int, default=1000000)
    ap.add_argument("--cycles", type=int, default=1000000)
    ap.add_argument("--pty-cycles", type=int, default=2000)
    ap.add_argument("--pty-medium", choices=("direct", "socat", "both"), default="direct",
                    help="the PTY pair: dfp-sim slave --pty's own (default), socat's, or both")
    ap.add_argument("--baud", type=int, default=1500000)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--dir", help="for the captures (default: a temporary directory)")
    a = ap.parse_args()
    if min(a.telegrams, a.cycles, a.pty_cycles, a.runs) < 1:
        ap.error("--telegrams, --cycles, --pty-cycles and --runs must be at least 1")
    dfp_sim = os.path.join(a.build, "sim_host", "dfp_sim", "dfp-sim")
    dfp_bench = os.path.join(a.build, "sim_host", "bench", "dfp-bench")
    for tool in (dfp_sim, dfp_bench, a.python):
        if not os.access(tool, os.X_OK):
            sys.exit("ratio_bench: %s is not executable (build first, or --build DIR)" % tool)
    for tool in ("tshark",) + (("socat",) if a.pty_medium != "direct" else ()):
        if shutil.which(tool) is None:
            sys.exit("ratio_bench: %s not found" % tool)
    tmp = tempfile.mkdtemp(prefix="dfp-ratio-", dir=a.dir)
    try:
        r1 = ratio_replay(a, dfp_sim, tmp)
        r2 = ratio_inprocess(a, dfp_bench, tmp)
        media = ("direct", "socat") if a.pty_medium == "both" else (a.pty_medium,)
        r3 = [(m,) + ratio_pty(a, dfp_sim, tmp, m) for m in media]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print("ratio replay / tshark:               %.1fx" % r1)
    print("ratio in-process / pyprofibus dummy: %.1fx" % r2)
    for m, r, theirs in r3:
        print("ratio PTY master / pyprofibus:       %.2fx (%s)" % (r, m))
    for m, r, theirs in r3:
        most, ceiling = pty_ceiling(a.baud, theirs)
        print("ceiling PTY master / pyprofibus:     %.2fx (%s: TSYN + min TSDR = %d bit at %d "
              "bit/s allow at most %.0f cycles/s)"
              % (ceiling, m, TSYN_BITS + MIN_TSDR_BITS, a.baud, most))
    return 0


if __name__ == "__main__":
    sys.exit(main())
