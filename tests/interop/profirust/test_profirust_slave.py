"""profirust (dfp-profirust-peer, an independent FDL active station and DP master) against the
card on its own PTY: dfp-sim slave --pty LINK --address 5 at 19200 bit/s.

The peer runs alone on the line with the slot time dfp-sim master uses on a PTY (100 ms = 1920
bit times at 19200) until 220 token receipts, and its summary must say:
  - the slave reached Data_Exchange, stayed there (no Offline/config/parameter event after it)
    and did at least 200 Data_Exchange cycles; the card says Wait_Cfg -> Data_Exch;
  - the live list has 5 as passive (FDL status "slave", from profirust's LiveList) and the peer's
    address 2 as active (its token ring's LAS), and nothing else; the LAS is [2];
  - every token was the peer's to itself (a lone master), no bad frame was received;
  - on the wire: the claim after the lost-token time-out 6*TSL + 2*2*TSL = 1 s is two tokens
    DC 02 02; Set_Prm carries Lock_Req, min TSDR 11, ident 6003 and the GSD's user prm; Chk_Cfg
    is F3 F2; Data_Exchange is SRD high (FC 5D/7D) with 14 bytes each way.
Bad arguments: exit 2 with one line; a port that does not exist: exit 1 with one line.

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise, 77 (a
ctest skip unless the interop tests are required) when the peer was not built (no cargo, or the
crate download failed: --why says which).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from checker import Checker  # noqa: E402 (tests/interop/checker.py)

USER_PRM = "00 00 00 06 81 00 00 01 01"
ROTATIONS = 220
MIN_DX = 200


def start_card(sim, link, out):
    p = subprocess.Popen([sim, "slave", "--pty", link, "--address", "5", "--baud", "19200",
                          "--inverter", "none"], stdout=out, stderr=subprocess.STDOUT)
    for _ in range(50):
        if os.path.islink(link) and os.readlink(link).startswith("/dev/pts/"):
            return p
        time.sleep(0.1)
    p.kill()
    return None


def tx_lines(capture):
    """(bytes as "AA BB ..", decoded note) of every telegram the peer sent, in order."""
    out = []
    for line in open(capture):
        m = re.match(r"\s*\d+ tx ((?:[0-9A-F]{2} ?)+)\s+(.*)$", line)
        if m:
            out.append((m.group(1).strip(), m.group(2)))
    return out


def check_run(c, args, tmp):
    link = os.path.join(tmp, "link")
    card_out = open(os.path.join(tmp, "card.out"), "w+")
    card = start_card(args.dfp_sim, link, card_out)
    if not c.check(card is not None, "the card made its PTY link"):
        return
    summary = os.path.join(tmp, "peer.json")
    capture = os.path.join(tmp, "capture.txt")
    try:
        r = subprocess.run([args.peer, "--port", link, "--address", "2", "--slave", "5",
                            "--baud", "19200", "--slot-bits", "1920", "--live-interval", "1000",
                            "--rotations", str(ROTATIONS), "--seconds", "90",
                            "--json", summary, "--capture", capture],
                           capture_output=True, text=True, timeout=120)
    finally:
        card.terminate()
        card.wait(10)
    card_out.seek(0)
    card_log = card_out.read()
    if args.verbose or r.returncode != 0:
        print(r.stdout + r.stderr + card_log)
    c.equal(r.returncode, 0, "the peer exits 0")
    if not c.check(os.path.exists(summary), "the peer wrote its --json summary"):
        return
    s = json.load(open(summary))
    c.equal(s["stopped_by"], "rotations", "the peer stopped after %d token receipts" % ROTATIONS)
    c.equal(s["phy"], "pty (the peer's own)", "a PTY gets the peer's PHY")
    c.equal(s["slave"]["state"], "data_exchange", "slave 5 is in Data_Exchange at the end")
    c.check(s["slave"]["dx_cycles"] >= MIN_DX, "at least %d Data_Exchange cycles" % MIN_DX,
            "got %d" % s["slave"]["dx_cycles"])
    ev = s["slave"]["events"]
    c.check(ev.get("online") == 1 and ev.get("configured") == 1 and "offline" not in ev
            and "config_error" not in ev and "parameter_error" not in ev,
            "slave 5 came online and was configured once, never lost", str(ev))
    c.check("Wait_Cfg -> Data_Exch" in card_log, "the card reached Data_Exch", card_log[-500:])
    live = {e["address"]: (e["type"], e["fdl_status"]) for e in s["live_list"]}
    c.equal(live, {2: ("active", None), 5: ("passive", "slave")},
            "live list: 5 passive (FDL status slave), 2 (the peer) active")
    c.equal(s["las"], [2], "the LAS holds the peer alone")
    c.equal(s["in_ring"], True, "the peer is in its ring")
    tok = s["token"]
    c.check(tok["receipts"] >= ROTATIONS and tok["passed_to_self"] == tok["receipts"]
            and tok["received"] == 0 and tok["holders_heard"] == [2],
            "every token was the peer's to itself", str(tok))
    c.equal((s["telegrams"]["bad_frames"], s["errors"]), (0, []),
            "no bad frame received, no error")
    c.equal(s["bus_parameters"]["token_lost_timeout_us"], 1000000,
            "lost-token time-out 6*TSL + 2*TS*TSL = 19200 bit times = 1 s")

    sent = tx_lines(capture)
    c.equal([b for b, _ in sent[:2]], ["DC 02 02", "DC 02 02"],
            "the first telegrams: the claim, two tokens 2 -> 2")
    # SD2 telegrams with both SAPs: 68 LE LEr 68 DA SA FC DSAP SSAP DU.. FCS 16
    prm = [b.split()[9:-2] for b, n in sent if "DSAP 61" in n]
    c.check(prm and all(" ".join(du) == "80 00 00 0B 60 03 00 " + USER_PRM for du in prm),
            "Set_Prm: Lock_Req, no watchdog, min TSDR 11, ident 6003, user prm " + USER_PRM,
            str(prm))
    cfg = [b.split()[9:-2] for b, n in sent if "DSAP 62 SSAP 62" in n]
    c.check(cfg and all(du == ["F3", "F2"] for du in cfg), "Chk_Cfg: F3 F2", str(cfg))
    dx = [(b, n) for b, n in sent if "SRD high" in n]
    c.check(len(dx) >= MIN_DX and all(b.startswith("68 11 11 68 05 02 ") and
                                      b[18:20] in ("5D", "7D") for b, _ in dx),
            "Data_Exchange: SRD high 2 -> 5, FC 5D/7D, 14 output bytes", str(dx[:3]))


def check_bad_args(c, args, tmp):
    peer = args.peer
    cases = [
        (["--port", "/dev/null", "--slave", "2"], 2, "--slave 2 is this master's own --address"),
        (["--port", "/dev/null", "--slave", "5", "--baud", "12M"], 2, "--baud 12M: the DFP21B"),
        (["--port", "/dev/null", "--slave", "5", "--slot-bits", "50"], 2, "--slot-bits 50:"),
        (["--port", "/dev/null", "--slave", "5", "--hsa", "1"], 2, "--hsa 1: must be above"),
        (["--port", "/dev/null", "--slave", "5", "--prm", "0G"], 2, "--prm '0G': not an even"),
        (["--port", "/dev/null", "--slave", "5", "--cfg", "C1"], 2, "--cfg: special identifier"),
        (["--slave", "5"], 2, "--port DEV is required"),
        (["--port", "/dev/null", "--slave", "5", "--seconds", "x"], 2, "--seconds 'x'"),
        (["--port", "/dev/null", "--slave", "5", "--frob", "1"], 2, "unknown option '--frob'"),
        (["--port", os.path.join(tmp, "none"), "--slave", "5"], 1, "No such file"),
        (["--port", "/dev/null", "--slave", "5"], 1, "not a tty or PTY"),
    ]
    for argv, rc, text in cases:
        r = subprocess.run([peer] + argv, capture_output=True, text=True, timeout=10)
        err = r.stderr.strip()
        c.check(r.returncode == rc and "\n" not in err and text in err
                and err.startswith("dfp-profirust-peer: "),
                "%s: exit %d, one line" % (" ".join(argv), rc),
                "exit %d, stderr %r" % (r.returncode, err))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dfp-sim", required=True)
    ap.add_argument("--peer", required=True)
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
    with tempfile.TemporaryDirectory(prefix="dfp-profirust-") as tmp:
        check_bad_args(c, args, tmp)
        check_run(c, args, tmp)
    print("     total %.2f s" % (time.monotonic() - t0))
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
