"""Our token ring with profirust on the virtual line: dfp-sim master and dfp-profirust-peer as two
FDL active stations, each with its own card, on `dfp-sim line` (cards 5 and 6 inside the line).

usage: test_profirust_ring.py --scenario ring|param|pyprofibus --dfp-sim PATH --peer PATH
                              [--gsd-dir DIR] [--why TEXT] [--verbose]

  dfp-sim line --dir D --ports N --card 5 --card 6 [--card 4] --baud B --timing
  port1: dfp-profirust-peer --address 2 --slave 5   (profirust's master)
  port2: dfp-sim master --master-address 3 --address 6 --config F3F2 --cycles 0
  both with TSL, TTR, HSA = 7 and G equal (G = 100 in the ring scenario, 10 in the others).

ring: at 1.5 Mbit/s with TSL 60000 bit times (40 ms: a PTY's time is the host's, so the slot
  time must cover the scheduling of three processes; the rate only shortens the telegrams) until
  the peer counted ROTATIONS token receipts (about 10 ms a rotation). Asserted: the peer stopped
  on its rotation count, every token it got came from master 3 after its claim, slave 5 went
  online and was configured once and never lost, the peer's live list has 3 active ("master in
  the ring", from its LiveList and its LAS), the LAS is [2, 3], no bad frame or warning; the line
  counted no collision; master 3's log names master 2 and itself in the ring and has slave 6 in
  data exchange once, with no other line until the peer left; each card entered Data_Exch once.
ring with param: a third port, `dfp-sim param --via c2` as master 1 and 4 (joining the ring
  through master 3's GAP) reads and writes P160 on card 6 (master 3's slave) and on card 5
  (profirust's); every result is exact, the peer heard 1 and 4 holding the token, master 3's
  log has only the ring's joins and leaves of 1 and 4, both slaves stay in data exchange.
pyprofibus: a third port with pyprofibus (no token passing, master 1) polling card 4 beside the
  ring at 19200 bit/s (TSL 1920 = 100 ms): the line counts collisions (the documented behaviour:
  docs/commissioning.md, "Joining the PLC's token ring"); the figures are printed.

Exit 0 when all passed, 1 otherwise, 77 (a ctest skip unless the interop tests are required)
when the peer was not built (--why says why) or, for pyprofibus, pyprofibus is missing.
"""
import argparse
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from checker import Checker  # noqa: E402 (tests/interop/checker.py)

ROTATIONS = 10000
FAST = {"baud": "1.5M", "tsl": 60000, "ttr": 150000}
SLOW = {"baud": "19200", "tsl": 1920, "ttr": 20000}
GAP, HSA = 10, 7
# The 10 000 rotations: both masters sweep their GAP (each silent address a slot time) only every
# 100 rotations, so the count is reached in about half the time; the second master still enters
# through the sweep that follows the first claim.
GAP_RING = 100
BURSTS = 5
P160 = "P160 internal setpoint n11"
# Lines master 3 writes when its slave comes up and the ring forms (the rest is a fault).
STARTUP = re.compile(r"token ring: master [23] is in the ring$|slave 6: (Slave_Diag|Set_Prm|"
                     r"Chk_Cfg)|slave 6 diagnosis: |slave 6 is in data exchange$")
PARAM_RING = re.compile(r"token ring: (GAP: station [14] answers: master ready|master [14] is "
                        r"in the ring|master [14] did not take the token: skipped|master [14] "
                        r"left the ring)$")
MASTER_FAULT = re.compile(r"retry|lost|skipped|dropped|claims|in the ring|not answer|fault|"
                          r"restart", re.I)
LOG_LINE = re.compile(r"\s*[\d.]+ ms\s+(\S+)\s+(.*)$")


def read_text(path):
    try:
        with open(path, errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def wait_for(pred, timeout, step=0.05):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(step)
    return pred()


def stop(p, timeout=15.0):
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
    try:
        return p.wait(timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        return p.wait()


def bus_options(bus):
    return ["--baud", bus["baud"], "--tsl", str(bus["tsl"]), "--ttr", str(bus["ttr"]),
            "--gap-factor", str(GAP), "--hsa", str(HSA)]


class Run:
    """The line, the peer on port1 and master 3 on port2, their outputs in tmp."""

    def __init__(self, args, tmp, bus, ports, cards):
        self.args, self.tmp, self.bus = args, tmp, bus
        self.dir = os.path.join(tmp, "line")
        os.mkdir(self.dir)
        self.procs = {}
        argv = [args.dfp_sim, "line", "--dir", self.dir, "--ports", str(ports), "--baud",
                bus["baud"], "--timing"]
        for card in cards:
            argv += ["--card", str(card)]
        self.start("line", argv)
        self.json = os.path.join(tmp, "peer.json")

    def path(self, name, ext):
        return os.path.join(self.tmp, name + "." + ext)

    def port(self, k):
        return os.path.join(self.dir, "port%d" % k)

    def start(self, name, argv):
        with open(self.path(name, "out"), "w") as out, open(self.path(name, "err"), "w") as err:
            self.procs[name] = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out,
                                                stderr=err)

    def ready(self):
        return wait_for(lambda: "Ctrl-C ends it" in self.text("line", "out"), 10.0)

    def start_masters(self, rotations, seconds):
        self.start("peer", [self.args.peer, "--port", self.port(1), "--address", "2",
                            "--slave", "5", "--baud", self.bus["baud"],
                            "--slot-bits", str(self.bus["tsl"]),
                            "--ttr-bits", str(self.bus["ttr"]), "--gap", str(GAP),
                            "--hsa", str(HSA), "--live-interval", "1000",
                            "--rotations", str(rotations), "--seconds", str(seconds),
                            "--json", self.json])
        self.start("master", [self.args.dfp_sim, "master", "--port", self.port(2),
                              "--master-address", "3", "--address", "6", "--config", "F3F2",
                              "--cycles", "0"] + bus_options(self.bus))

    def text(self, name, ext):
        return read_text(self.path(name, ext))

    def in_dx(self):
        return ("slave 6 is in data exchange" in self.text("master", "out")
                and self.text("line", "out").count("-> Data_Exch") == 2)

    def stop(self, names):
        return {n: stop(self.procs[n]) for n in names if n in self.procs}

    def summary(self):
        try:
            with open(self.json) as f:
                return json.load(f)
        except (OSError, ValueError):
            return None

    def dump(self):
        for name in self.procs:
            for ext in ("out", "err"):
                text = self.text(name, ext)
                if text:
                    print("---- %s %s (last 3000 characters)\n%s" % (name, ext, text[-3000:]))


def master_lines(text):
    """master 3's log lines (source, text) from its start to its first line after the peer
    left (the first that says master 2 did not take the token), that line excluded."""
    out = []
    for line in text.splitlines():
        m = LOG_LINE.match(line)
        if not m:
            continue
        if "master 2 did not take the token" in m.group(2) or "stopping (signal)" in m.group(2):
            break
        out.append((m.group(1), m.group(2)))
    return out


def check_line(c, run, rcs, want_collisions):
    out, err = run.text("line", "out"), run.text("line", "err")
    told = len(re.findall(r"^line: collision at ", err, re.M))
    m = re.search(r"dfp-sim line: (\d+) collisions", out)
    total = int(m.group(1)) if m else None
    print("     line: %s collisions in its figures, %d told on stderr" % (total, told))
    if want_collisions:
        c.check(total is not None and total > 0 and told > 0,
                "the line counted and told collisions", "%r figures, %d told" % (total, told))
    else:
        c.check(total == 0 and told == 0, "no collision on the line",
                "%r in the figures, %d told" % (total, told))
    c.equal(rcs.get("line"), 0, "the line exits 0 on SIGTERM")
    return total


def check_cards(c, run):
    out = run.text("line", "out")
    for card in (5, 6):
        n = len(re.findall(r"card %d\s.*-> Data_Exch" % card, out))
        c.equal(n, 1, "card %d entered Data_Exch once (never left it)" % card)


def check_peer(c, s, rotations):
    if not c.check(s is not None, "the peer wrote its summary"):
        return
    if rotations:
        c.equal(s["stopped_by"], "rotations", "the peer stopped after %d receipts" % rotations)
    tok = s["token"]
    c.check(tok["receipts"] >= rotations and tok["received"] >= tok["receipts"] - 20,
            "%d token receipts, each (but the claim's) a token from the ring" %
            tok["receipts"], str(tok))
    c.equal(s["slave"]["state"], "data_exchange", "slave 5 is in Data_Exchange at the end")
    ev = s["slave"]["events"]
    c.check(ev.get("online") == 1 and ev.get("configured") == 1 and "offline" not in ev
            and "config_error" not in ev and "parameter_error" not in ev,
            "slave 5 came online and was configured once, never lost", str(ev))
    # Joins and leaves (param's) cost rotations: GAP sweeps over silent addresses, a skipped
    # successor's three token passes; profirust's late-token visits carry one telegram, not
    # always its Data_Exchange. Most visits still do.
    share = 0.9 if rotations else 0.8  # 0: the param scenario
    c.check(s["slave"]["dx_cycles"] >= share * tok["receipts"],
            "slave 5: a Data_Exchange on (nearly) every token visit",
            "%d cycles for %d receipts" % (s["slave"]["dx_cycles"], tok["receipts"]))
    live = {e["address"]: e for e in s["live_list"]}
    three = live.get(3, {})
    c.check(three.get("type") == "active" and three.get("fdl_status") == "master_in_ring"
            and set(three.get("from", [])) == {"live_list", "las"},
            "profirust's live list: 3 active, master in the ring, in its LAS", str(three))
    c.equal((s["las"], s["in_ring"]), ([2, 3], True), "profirust's LAS is [2, 3], in the ring")
    c.equal((s["telegrams"]["bad_frames"], s["telegrams"]["bad_bytes"], s["warnings"]),
            (0, 0, 0), "profirust: no bad frame, no warning")


def scenario_ring(c, args, tmp):
    run = Run(args, tmp, FAST, 2, [5, 6])
    try:
        if not c.check(run.ready(), "the line starts", run.text("line", "err")):
            return
        run.start_masters(ROTATIONS, 600)
        t0 = time.monotonic()
        try:
            rc = run.procs["peer"].wait(700)
        except subprocess.TimeoutExpired:
            rc = None
        print("     %d rotations took %.1f s" % (ROTATIONS, time.monotonic() - t0))
        c.equal(rc, 0, "the peer exits 0 (slave 5 reached Data_Exchange and stayed)")
    finally:
        rcs = run.stop(["peer", "master", "line"])
    s = run.summary()
    check_peer(c, s, ROTATIONS)
    if s:
        r = s["token"]["rotation_us"]
        print("     rotation min %d, mean %d, max %d us" % (r["min"], r["mean"], r["max"]))
    check_master(c, run, rcs, STARTUP)
    check_cards(c, run)
    check_line(c, run, rcs, False)
    if c.failed or args.verbose:
        run.dump()


def check_master(c, run, rcs, allowed):
    lines = master_lines(run.text("master", "out") + run.text("master", "err"))
    texts = [t for _, t in lines]
    for a in (2, 3):
        c.check("token ring: master %d is in the ring" % a in texts,
                "master 3's log: 'token ring: master %d is in the ring'" % a)
    c.equal(texts.count("slave 6 is in data exchange"), 1, "slave 6 in data exchange once")
    other = [t for src, t in lines if src == "master" and not allowed.search(t)]
    c.equal(other, [], "master 3's log has nothing else while the peer runs")
    c.equal(rcs.get("master"), 0, "master 3 exits 0 on SIGTERM")


def param(run, argv):
    r = subprocess.run([run.args.dfp_sim, "param", "--port", run.port(3), "--via", "c2",
                        "--timeout", "20"] + bus_options(run.bus) + argv,
                       capture_output=True, text=True, timeout=60)
    return r.returncode, r.stdout.strip(), r.stderr.strip()


def raw(v):
    return "%s = %.3f rpm (raw %d, 0x%08X)" % (P160, v / 1000.0, v, v)


def scenario_param(c, args, tmp):
    run = Run(args, tmp, FAST, 3, [5, 6])
    try:
        if not c.check(run.ready(), "the line starts", run.text("line", "err")):
            return
        run.start_masters(0, 600)
        if not c.check(wait_for(run.in_dx, 30.0), "both slaves in data exchange"):
            return
        steps = [
            (6, 1, ["write", "8489", "2250"], "write 8489 = 2250 via c2: ok (%s)" % raw(2250)),
            (6, 4, ["read", "8489"], "read 8489 via c2: %s" % raw(2250)),
            (5, 4, ["write", "8489", "1750"], "write 8489 = 1750 via c2: ok (%s)" % raw(1750)),
            (5, 1, ["read", "8489"], "read 8489 via c2: %s" % raw(1750)),
            (6, 1, ["read", "8489"], "read 8489 via c2: %s" % raw(2250)),
        ]
        for card, ma, argv, want in steps:
            rc, out, err = param(run, ["--address", str(card), "--master-address", str(ma)]
                                 + argv)
            c.check(rc == 0 and out == want, "param as master %d, card %d: %s" %
                    (ma, card, " ".join(argv)), "exit %d, %r, %r" % (rc, out, err))
        time.sleep(2.0)  # the ring goes on without them for a while
        c.check(run.procs["peer"].poll() is None and run.procs["master"].poll() is None,
                "both masters still run")
    finally:
        rcs = run.stop(["peer", "master", "line"])
    s = run.summary()
    c.equal(rcs.get("peer"), 0, "the peer exits 0 on SIGTERM (slave 5 stayed in Data_Exchange)")
    check_peer(c, s, 0)
    if s:
        c.check({1, 4} <= set(s["token"]["holders_heard"]),
                "the peer heard masters 1 and 4 (param) holding the token",
                str(s["token"]["holders_heard"]))
    allowed = re.compile(STARTUP.pattern + "|" + PARAM_RING.pattern)
    check_master(c, run, rcs, allowed)
    texts = run.text("master", "out")
    c.check(all("token ring: master %d is in the ring" % a in texts for a in (1, 4)),
            "master 3's log: masters 1 and 4 came into the ring")
    check_cards(c, run)
    check_line(c, run, rcs, False)
    if c.failed or args.verbose:
        run.dump()


def scenario_pyprofibus(c, args, tmp):
    try:
        import pyprofibus
        import pyprofibus.phy_serial  # noqa: F401 (needs pyserial)
    except ImportError as e:
        print("SKIP: pyprofibus/pyserial not installed for %s (%s)" % (sys.executable, e))
        return 77
    from test_pyprofibus_interop import write_conf  # noqa: E402 (tests/interop)
    run = Run(args, tmp, SLOW, 3, [4, 5, 6])
    res = {"exchanges": 0, "error": None}
    try:
        if not c.check(run.ready(), "the line starts", run.text("line", "err")):
            return 1
        run.start_masters(0, 600)
        if not c.check(wait_for(run.in_dx, 30.0), "both slaves in data exchange"):
            return 1
        conf = os.path.join(tmp, "pyprofibus.conf")
        write_conf(conf, run.port(3), 19200, os.path.join(args.gsd_dir, "SEW_6003.GSD"),
                   "Param + 3 PD", 14)
        text = read_text(conf).replace("master_addr=2", "master_addr=1")
        with open(conf, "w") as f:
            f.write(text)
        # Each burst starts into the running ring (the line is busy about 3/4 of the time at
        # 19200 bit/s); between bursts the line falls silent and the ring's masters claim the
        # token again.
        for _ in range(BURSTS):
            poll_pyprofibus(pyprofibus, conf, res, 2.0)
            time.sleep(2.5)
    finally:
        rcs = run.stop(["peer", "master", "line"])
    print("     pyprofibus: %d exchanges with card 4, error: %s" % (res["exchanges"],
                                                                   res["error"]))
    s = run.summary()
    if s:
        print("     profirust: %s bad frames, %d warnings, slave 5 %s, events %s" % (
            s["telegrams"]["bad_frames"], s["warnings"], s["slave"]["state"],
            s["slave"]["events"]))
    mlog = run.text("master", "out") + run.text("master", "err")
    for line in mlog.splitlines():
        if MASTER_FAULT.search(line):
            print("     master 3: " + line.strip())
    check_line(c, run, rcs, True)
    if c.failed or args.verbose:
        run.dump()
    return None


def poll_pyprofibus(pb, conf_path, res, seconds):
    config = pb.PbConf.fromFile(conf_path)
    master = None
    try:
        phy = config.makePhy()
        master = config.makeDPM(phy=phy)
        desc = config.slaveConfs[0].makeDpSlaveDesc()
        master.addSlave(desc)
        master.initialize()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            desc.setMasterOutData(bytearray(14))
            if master.run() is desc and desc.getMasterInData() is not None:
                res["exchanges"] += 1
    except Exception as e:  # a ProfibusError ends pyprofibus's loop
        res["error"] = "%s: %s" % (type(e).__name__, e)
    finally:
        if master is not None:
            master.destroy()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenario", required=True, choices=["ring", "param", "pyprofibus"])
    ap.add_argument("--dfp-sim", required=True)
    ap.add_argument("--peer", required=True)
    ap.add_argument("--gsd-dir", default="")
    ap.add_argument("--why", default="", help="why the peer may be missing (no cargo)")
    ap.add_argument("--verbose", action="store_true")
    args = ap.parse_args()
    if not os.access(args.peer, os.X_OK):
        print("SKIP: dfp-profirust-peer was not built (%s): %s" %
              (args.why or "the cargo build failed; see its warning in the build log",
               args.peer))
        return 77
    c = Checker()
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="dfp-ring-") as tmp:
        if args.scenario == "ring":
            global GAP  # pylint: disable=global-statement
            GAP = GAP_RING
            scenario_ring(c, args, tmp)
        elif args.scenario == "param":
            scenario_param(c, args, tmp)
        elif scenario_pyprofibus(c, args, tmp) == 77:
            return 77
    print("     total %.2f s" % (time.monotonic() - t0))
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
