#!/usr/bin/env python3
"""pyprofibus, an independent DP master, against the simulated card over a PTY pair.

usage: test_pyprofibus_interop.py --dfp-sim PATH --gsd-dir DIR [--baud 19200] [--verbose]

For each scenario:
  socat -d -d pty,raw,echo=0,link=TMP/a pty,raw,echo=0,link=TMP/b
  dfp-sim slave --port TMP/a --address 4 --baud 19200
  pyprofibus DPM1 (serial PHY on TMP/b, config file written to TMP from SEW_6003.GSD, slave 4)
driven in-process for a bounded time. Asserted:
  - pyprofibus reaches Data_Exchange (slaveDesc.isConnected()) and never restarts the slave;
  - pyprofibus's Set_Prm carries ident 6003 and the GSD's user prm bytes, its Chk_Cfg the
    module's identifier bytes, and the card accepts both;
  - every output pattern, held constant (at least HOLD exchanges), comes back in the inputs: the
    card echoes PO word n into PI word n, normally one exchange late (the last CHECKED replies of
    each pattern must equal it; with the parameter channel the first 8 input bytes are 00 while
    the master sends "no service");
  - then SOAK_GROUPS generated patterns, each held until echoed, checked likewise; a reply is
    always the echo of the current or of the previous pattern, never anything else;
  - the Data_Exchange telegrams have the expected frame type both ways: pyprofibus's requests
    SD2, or SD3 when the output data are exactly 8 bytes; the card's replies SD2 always, 8 input
    bytes too (docs/architecture.md, "Data replies are SD2");
  - dfp-sim printed a line containing "Data_Exch" and exited 0 on SIGTERM.
Scenarios: module "Param + 3 PD" (F3 F2, 14 bytes each way) from the GSD, and the universal
"4 PD" module F3 alone (8 bytes each way, so pyprofibus sends SD3 and the card answers SD2),
added to a test-only copy of the GSD; then "Param + 3 PD" again without socat:
`dfp-sim slave --pty TMP/b` makes the PTY pair itself and pyprofibus opens the link TMP/b,
which dfp-sim removes on SIGTERM.

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise, 77 (a
ctest skip) when pyprofibus, pyserial or socat is missing. On a failure it prints dfp-sim's and
socat's output, pyprofibus's debug log and the last telegrams on the wire.
"""

import contextlib
import io
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from checker import pyprofibus_main  # sibling module in tests/interop

SLAVE_ADDR = 4
MASTER_ADDR = 2
# Each output pattern is held until the last CHECKED replies carry its echo (at least HOLD
# exchanges, at most MAX_HOLD). The echo normally arrives one exchange late. Seen on an overloaded
# machine: it came three exchanges late while dfp-sim logged "repeated request from master 2 (same
# FCB): cached reply sent" -- pyprofibus's 100 ms reply timeout had fired, its next request kept
# the FCB, and the card (rightly, FDL rules) answered with its cached reply.
HOLD = 8          # fixed patterns: at least this many exchanges each
CHECKED = 3
SOAK_GROUPS = 250  # then this many generated patterns
SOAK_HOLD = 3     # at least this many exchanges each
SOAK_CHECKED = 2
MAX_HOLD = 30     # a pattern not echoed within this many exchanges fails
SCENARIO_TIME = 20.0  # seconds of master loop per scenario, at most
STARTUP_TIME = 5.0    # give up on a scenario that is not in Data_Exchange by then
USER_PRM = bytes.fromhex("000000068100000101")
IDENT = 0x6003

SD2, SD3 = 0x68, 0xA2


def words(*ws):
    return b"".join(w.to_bytes(2, "big") for w in ws)


SCENARIOS = [
    {
        "name": "Param + 3 PD (F3 F2, 14 bytes, SD2)",
        "module": "Param + 3 PD",
        "extra_module": None,
        "cfg": bytes.fromhex("F3F2"),
        "size": 14,
        "param": True,
        "sd": SD2,  # of pyprofibus's requests; the card's replies are SD2 in every scenario
        # PO1..PO3 after a parameter channel sending "no service" (8 x 00); the first is the
        # manual's example (5.1): control word 0006 = enable, 1500 = 300 rpm.
        "patterns": [bytes(8) + words(0x0006, 0x05DC, 0x0000),
                     bytes(8) + words(0x1234, 0xA5A5, 0x5A5A),
                     bytes(8) + words(0xFFFF, 0x8001, 0x7FFE),
                     bytes(8) + words(0x0000, 0x0000, 0x0001)],
    },
    {
        "name": "4 PD universal module (F3, 8 bytes, SD3 requests)",
        "module": "4 PD universal (test)",
        "extra_module": ("4 PD universal (test)", "0xF3"),
        "cfg": bytes.fromhex("F3"),
        "size": 8,
        "param": False,
        "sd": SD3,
        "patterns": [words(0x0006, 0x05DC, 0x0102, 0x0304),
                     words(0xFFFF, 0x0000, 0xA5A5, 0x5A5A),
                     words(0x8000, 0x0001, 0x7FFF, 0xFFFE),
                     words(0x0000, 0x0000, 0x0000, 0x0000)],
    },
]
# The card's own PTY pair (dfp-sim slave --pty LINK) instead of socat's.
SCENARIOS.append(dict(SCENARIOS[0], name="Param + 3 PD over dfp-sim slave --pty (no socat)",
                      medium="pty"))


def wait_for(pred, timeout, step=0.02):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(step)
    return pred()


def start_socat_pair(a, b, err_path=None):
    """socat joining two fresh raw PTYs linked at a and b (with -d -d its log goes to err_path);
    returns the process and whether both links appeared within 5 s."""
    err = open(err_path, "w") if err_path is not None else subprocess.DEVNULL
    try:
        p = subprocess.Popen(["socat"] + (["-d", "-d"] if err_path is not None else []) +
                             ["pty,raw,echo=0,link=" + a, "pty,raw,echo=0,link=" + b],
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err)
    finally:
        if err_path is not None:
            err.close()
    return p, wait_for(lambda: os.path.exists(a) and os.path.exists(b), 5.0)


def stop_process(p, sig=signal.SIGTERM, timeout=5.0):
    """Stop one child we started; returns its exit code (None if it had to be killed)."""
    if p is None:
        return None
    if p.poll() is None:
        try:
            p.send_signal(sig)
            return p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(timeout=timeout)
            return None
    return p.returncode


def read_text(path):
    try:
        with open(path, "r", errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def make_tap_phy(CpPhySerial):
    class TapPhy(CpPhySerial):
        """pyprofibus's serial PHY, recording every telegram sent and received."""

        def __init__(self, *args, **kwargs):
            self.wire = []   # (monotonic time, "TX"/"RX", bytes)
            super().__init__(*args, **kwargs)

        def sendData(self, telegramData, srd):
            self.wire.append((time.monotonic(), "TX", bytes(telegramData)))
            return super().sendData(telegramData, srd)

        def pollData(self, timeout=0.0):
            data = super().pollData(timeout)
            if data:
                self.wire.append((time.monotonic(), "RX", bytes(data)))
            return data

    return TapPhy


def write_conf(path, dev, baud, gsd_path, module, size):
    # pyprofibus's conf format (see its example_*.conf): comments on their own lines only.
    # input_size = bytes the master sends to the slave, output_size = bytes it gets back.
    with open(path, "w") as f:
        f.write("""[PROFIBUS]
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

[SLAVE_0]
name=dfp21b
addr=%d
gsd=%s
sync_mode=0
freeze_mode=0
group_mask=1
; DP watchdog on: the card must also cope with WD_On
watchdog_ms=1000
module_0=%s
output_size=%d
input_size=%d
diag_period=0
""" % (dev, baud, MASTER_ADDR, SLAVE_ADDR, gsd_path, module, size, size))


def soak_pattern(sc, j):
    """Output pattern j of the soak: every PD word different from the last pattern's."""
    n = (sc["size"] - (8 if sc["param"] else 0)) // 2
    pd = words(*(((j * 0x9E37) + k * 0x1111 + 1) & 0xFFFF for k in range(n)))
    return (bytes(8) + pd) if sc["param"] else pd


def sap_request(frame):
    """(DSAP, DU) of an SD2 request from the master to the slave with SAP extension, else None."""
    if len(frame) < 11 or frame[0] != SD2 or frame[3] != SD2:
        return None
    da, sa = frame[4], frame[5]
    if (da & 0x7F) != SLAVE_ADDR or (sa & 0x7F) != MASTER_ADDR or not (da & 0x80):
        return None
    return frame[7], bytes(frame[9:-2])


def is_dx_frame(frame, direction):
    """Data_Exchange request (TX) or its data reply (RX): SD2/SD3 without SAP extension."""
    if not frame or frame[0] not in (SD2, SD3):
        return False
    hdr = 4 if frame[0] == SD2 else 1
    if len(frame) < hdr + 3:
        return False
    da, sa = frame[hdr], frame[hdr + 1]
    if (da & 0x80) or (sa & 0x80):
        return False
    if direction == "TX":
        return da == SLAVE_ADDR and sa == MASTER_ADDR
    return da == MASTER_ADDR and sa == SLAVE_ADDR


def run_master(pb, conf_path, sc, deadline):
    """Drive pyprofibus through the fixed and the generated patterns, or until the deadline."""
    config = pb.PbConf.fromFile(conf_path)
    TapPhy = make_tap_phy(pb.phy_serial.CpPhySerial)
    phy = TapPhy(port=config.phyDev, debug=False)
    res = {"groups": [], "dx_time": None, "restarts": 0, "error": None, "phy": phy,
           "exchanges": 0, "soak_time": 0.0}
    master = None
    try:
        phy.setConfig(baudrate=config.phyBaud)
        master = config.makeDPM(phy=phy)
        desc = config.slaveConfs[0].makeDpSlaveDesc()
        master.addSlave(desc)
        master.initialize()
        t0 = time.monotonic()
        connected = False
        fixed = len(sc["patterns"])
        groups = res["groups"]  # (pattern, replies while it was set), fixed ones first
        groups.append((sc["patterns"][0], []))
        soak_start = None
        while time.monotonic() < deadline:
            if res["dx_time"] is None and time.monotonic() - t0 > STARTUP_TIME:
                break
            out, got = groups[-1]
            fix = len(groups) <= fixed
            if hold_done(sc, out, got, HOLD if fix else SOAK_HOLD,
                         CHECKED if fix else SOAK_CHECKED):
                n = len(groups)
                if n == fixed:
                    soak_start = time.monotonic()
                if n >= fixed + SOAK_GROUPS:
                    res["soak_time"] = time.monotonic() - soak_start
                    break
                groups.append((sc["patterns"][n] if n < fixed else soak_pattern(sc, n), []))
                out = groups[-1][0]
            desc.setMasterOutData(bytearray(out))
            handled = master.run()
            now_connected = desc.isConnected()
            if connected and not now_connected:
                res["restarts"] += 1
            if now_connected and res["dx_time"] is None:
                res["dx_time"] = time.monotonic() - t0
            connected = now_connected
            if handled is desc:
                data = desc.getMasterInData()
                if data is not None:
                    res["exchanges"] += 1
                    groups[-1][1].append(bytes(data))
    except Exception as e:  # ProfibusError (e.g. an RS reply ends pyprofibus's loop) and others
        res["error"] = "%s: %s" % (type(e).__name__, e)
    finally:
        if master is not None:
            master.destroy()
        else:
            phy.close()
    return res


def hold_done(sc, out, got, min_hold, checked):
    """Move on to the next pattern: echoed in the last `checked` replies, or held too long."""
    if len(got) >= MAX_HOLD:
        return True
    want = expected_echo(sc, out)
    return len(got) >= max(min_hold, checked) and all(g == want for g in got[-checked:])


def judge_group(sc, prev_out, out, got, checked):
    """(ok, lag): every reply is the echo of the previous or of this pattern, once this one's
    echo appeared it stayed, and the last `checked` replies carry it. lag = index of the first
    reply with this pattern's echo (None if none)."""
    want = expected_echo(sc, out)
    before = expected_echo(sc, prev_out) if prev_out is not None else bytes(sc["size"])
    lag = next((k for k, g in enumerate(got) if g == want), None)
    ok = (lag is not None and len(got) >= checked and all(g == want for g in got[lag:])
          and all(g == before for g in got[:lag]))
    return ok, lag


def expected_echo(sc, out):
    return (bytes(8) + out[8:]) if sc["param"] else out


def check_exchange(c, tag, sc, res):
    """The checks on the data exchange pyprofibus ran."""
    groups = res["groups"]
    fixed = len(sc["patterns"])
    done = sum(len(got) for _, got in groups)
    c.check(len(groups) == fixed + SOAK_GROUPS and all(len(got) > 0 for _, got in groups),
            tag + "%d output patterns exchanged (%d fixed, %d generated)"
            % (fixed + SOAK_GROUPS, fixed, SOAK_GROUPS),
            "only %d patterns, %d exchanges" % (len(groups), done))
    lags = []
    bad = []
    for j, (out, got) in enumerate(groups):
        prev = groups[j - 1][0] if j > 0 else None
        ok, lag = judge_group(sc, prev, out, got, CHECKED if j < fixed else SOAK_CHECKED)
        lags.append(lag)
        if j < fixed:
            want = expected_echo(sc, out)
            c.check(ok, tag + "pattern %d: outputs %s echoed as inputs %s%s"
                    % (j, out.hex(" "), want.hex(" "),
                       "" if lag is None else " (from reply %d on)" % lag),
                    "replies: " + " | ".join(g.hex(" ") for g in got))
        elif not ok and (j < len(groups) - 1 or len(got) >= MAX_HOLD):
            bad.append(j)
    soak = groups[fixed:]
    n_soak = sum(len(got) for _, got in soak)
    soak_lags = [l for l in lags[fixed:] if l is not None]
    first_bad = ""
    if bad:
        j = bad[0]
        first_bad = "; first: pattern %d %s -> %s" % (
            j, groups[j][0].hex(" "), " | ".join(g.hex(" ") for g in groups[j][1]))
    c.check(len(soak) == SOAK_GROUPS and not bad,
            tag + "soak: %d generated patterns, %d exchanges in %.2f s (%.2f ms each), every "
            "one echoed (echo from reply %s on; later than 1: %d patterns)"
            % (len(soak), n_soak, res["soak_time"], 1e3 * res["soak_time"] / max(n_soak, 1),
               "..".join(str(x) for x in sorted({min(soak_lags or [0]),
                                                  max(soak_lags or [0])})),
               sum(1 for l in soak_lags if l > 1)),
            "%d patterns, %d not echoed as expected%s" % (len(soak), len(bad), first_bad))
    sap = [r for r in (sap_request(f) for _, d, f in res["phy"].wire if d == "TX") if r]
    prm = [du for dsap, du in sap if dsap == 61]
    cfg = [du for dsap, du in sap if dsap == 62]
    c.check(prm and all(du[4:6] == IDENT.to_bytes(2, "big") and du[7:] == USER_PRM
                        for du in prm),
            tag + "pyprofibus's Set_Prm carried ident 6003 and user prm %s from the GSD"
            % USER_PRM.hex(" "), "Set_Prm DUs: %s" % [du.hex(" ") for du in prm])
    c.check(cfg and all(du == sc["cfg"] for du in cfg),
            tag + "pyprofibus's Chk_Cfg carried %s" % sc["cfg"].hex(" ").upper(),
            "Chk_Cfg DUs: %s" % [du.hex(" ").upper() for du in cfg])
    dx_tx = [f for _, d, f in res["phy"].wire if d == "TX" and is_dx_frame(f, "TX")]
    dx_rx = [f for _, d, f in res["phy"].wire if d == "RX" and is_dx_frame(f, "RX")]
    sd_name = {SD2: "SD2", SD3: "SD3"}[sc["sd"]]
    c.check(len(dx_tx) >= done and dx_tx and all(f[0] == sc["sd"] for f in dx_tx),
            tag + "pyprofibus sent its %d Data_Exchange requests as %s"
            % (len(dx_tx), sd_name),
            "frame types: %s" % sorted({"%02X" % f[0] for f in dx_tx}))
    c.check(len(dx_rx) >= done and dx_rx and all(f[0] == SD2 for f in dx_rx),
            tag + "the card answered the %d Data_Exchange requests with SD2" % len(dx_rx),
            "frame types: %s" % sorted({"%02X" % f[0] for f in dx_rx}))


def run_scenario(c, pb, sc, dfp_sim, gsd_dir, baud, verbose):
    tag = sc["name"] + ": "
    tmp = tempfile.mkdtemp(prefix="dfp-interop-")
    a, b = os.path.join(tmp, "a"), os.path.join(tmp, "b")
    socat = sim = None
    sim_out, sim_err = os.path.join(tmp, "dfp-sim.out"), os.path.join(tmp, "dfp-sim.err")
    socat_err = os.path.join(tmp, "socat.err")
    log = io.StringIO()
    res = None
    sim_rc = "not run"
    failed_before = c.failed
    t_start = time.monotonic()
    try:
        gsd_path = os.path.join(gsd_dir, "SEW_6003.GSD")
        if sc["extra_module"]:
            # A test-only copy of the GSD with one more module: a universal configuration that
            # the card accepts but the GSD does not predefine.
            with open(gsd_path, "rb") as f:
                text = f.read()
            name, cfg = sc["extra_module"]
            text += ('Module = "%s" %s\r\nEndModule\r\n' % (name, cfg)).encode("ascii")
            gsd_path = os.path.join(tmp, "SEW_6003_TEST.GSD")
            with open(gsd_path, "wb") as f:
                f.write(text)
        conf = os.path.join(tmp, "pyprofibus.conf")
        write_conf(conf, b, baud, gsd_path, sc["module"], sc["size"])

        own_pty = sc.get("medium") == "pty"
        if not own_pty:
            socat, up = start_socat_pair(a, b, socat_err)
            if not c.check(up, tag + "socat PTY pair up"):
                return
        with open(sim_out, "w") as out, open(sim_err, "w") as err:
            sim = subprocess.Popen([dfp_sim, "slave", "--inverter", "none"] +
                                   (["--pty", b] if own_pty else ["--port", a]) +
                                   ["--address", str(SLAVE_ADDR), "--baud", str(baud)],
                                   stdin=subprocess.DEVNULL, stdout=out, stderr=err)
        # dfp-sim prints its banner once the port is open (and its link made); pyprofibus would
        # retry anyway.
        wait_for(lambda: sim.poll() is not None or "dfp-sim" in read_text(sim_out), 3.0)
        if not c.check(sim.poll() is None, tag + "dfp-sim slave running",
                       "exited with %r" % sim.poll()):
            return
        if own_pty and not c.check(os.path.islink(b) and
                                   os.readlink(b).startswith("/dev/pts/"),
                                   tag + "dfp-sim made the link to its PTY's slave side",
                                   "%s: %r" % (b, os.readlink(b) if os.path.islink(b) else None)):
            return

        with contextlib.redirect_stdout(log):
            res = run_master(pb, conf, sc, time.monotonic() + SCENARIO_TIME)

        c.check(res["error"] is None, tag + "pyprofibus master loop ran without an exception",
                str(res["error"]))
        c.check(res["dx_time"] is not None, tag + "pyprofibus reports Data_Exchange "
                "(slaveDesc.isConnected())" + ("" if res["dx_time"] is None else
                                               " after %.2f s" % res["dx_time"]))
        c.check(res["restarts"] == 0, tag + "pyprofibus never re-initialised the slave",
                "%d restarts" % res["restarts"])
        if res["dx_time"] is None:
            return  # the rest would only repeat that failure
        check_exchange(c, tag, sc, res)
    finally:
        sim_rc = stop_process(sim) if sim is not None else "not started"
        stop_process(socat)
        sim_text = read_text(sim_out)
        if sim is not None:
            c.check("Data_Exch" in sim_text, tag + "dfp-sim printed a Data_Exch state line")
            c.check(sim_rc == 0, tag + "dfp-sim exited 0 on SIGTERM", "exit %r" % sim_rc)
            if sc.get("medium") == "pty":
                c.check(not os.path.lexists(b), tag + "dfp-sim removed its link on SIGTERM")
        elapsed = time.monotonic() - t_start
        print("     %s%.2f s" % (tag, elapsed))
        if c.failed != failed_before or verbose:
            dump(tag, sim_text, read_text(sim_err), read_text(socat_err), log.getvalue(), res)
        shutil.rmtree(tmp, ignore_errors=True)


def dump(tag, sim_out, sim_err, socat_err, pb_log, res):
    def block(title, text, max_lines=80):
        lines = text.rstrip("\n").splitlines()
        if len(lines) > max_lines:
            lines = ["... (%d lines before)" % (len(lines) - max_lines)] + lines[-max_lines:]
        print("---- %s%s ----" % (tag, title))
        for line in lines:
            print("  " + line)
    block("dfp-sim stdout", sim_out)
    block("dfp-sim stderr", sim_err)
    block("socat stderr", socat_err, 20)
    block("pyprofibus log", pb_log, 60)
    if res is not None:
        wire = res["phy"].wire
        t0 = wire[0][0] if wire else 0.0
        block("wire as pyprofibus saw it (last 40)",
              "\n".join("%9.3f ms %s %s" % ((t - t0) * 1e3, d, f.hex(" ")) for t, d, f in wire),
              40)


def main():
    def scenarios(c, pyprofibus, args):
        for sc in SCENARIOS:
            run_scenario(c, pyprofibus, sc, args.dfp_sim, args.gsd_dir, args.baud, args.verbose)

    return pyprofibus_main(__doc__, scenarios)


if __name__ == "__main__":
    sys.exit(main())
