#!/usr/bin/env python3
"""pyprofibus, an independent DP master, on a port of `dfp-sim line` against the card inside it.

usage: test_line_pyprofibus.py --dfp-sim PATH --gsd-dir DIR [--baud 19200] [--verbose]

  dfp-sim line --dir TMP --ports 1 --card 4 --baud 19200
  pyprofibus DPM1 (serial PHY on TMP/port1, module "Param + 3 PD" from SEW_6003.GSD, slave 4)

The card runs on the line's in-memory bus and reaches the port through the line's bridge: what
pyprofibus writes on the port is injected on the bus, what the card sends comes back through the
line. Asserted: pyprofibus has the slave in Data_Exchange within STARTUP_TIME and never loses it
while it exchanges EXCHANGES cycles of 14 octets each way (MASTER_TIME s at most); the line
printed the card's "Wait_Cfg -> Data_Exch", counted no collision, and ended with 0 on SIGTERM
with its link gone. Exit 0 when all passed, 1 otherwise, 77 (a ctest skip) when pyprofibus or
pyserial is missing.
"""

import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "interop"))
from checker import pyprofibus_main  # noqa: E402 (tests/interop)
from test_pyprofibus_interop import (SLAVE_ADDR, make_tap_phy, read_text,  # noqa: E402
                                     stop_process, wait_for, write_conf)

MODULE = "Param + 3 PD"
SIZE = 14
STARTUP_TIME = 5.0
MASTER_TIME = 20.0
EXCHANGES = 200


def run_master(pb, conf_path):
    config = pb.PbConf.fromFile(conf_path)
    phy = make_tap_phy(pb.phy_serial.CpPhySerial)(port=config.phyDev, debug=False)
    res = {"dx_time": None, "drops": 0, "exchanges": 0, "sizes": set(), "error": None}
    master = None
    try:
        phy.setConfig(baudrate=config.phyBaud)
        master = config.makeDPM(phy=phy)
        desc = config.slaveConfs[0].makeDpSlaveDesc()
        master.addSlave(desc)
        master.initialize()
        t0 = time.monotonic()
        connected = False
        while time.monotonic() - t0 < MASTER_TIME and res["exchanges"] < EXCHANGES:
            if res["dx_time"] is None and time.monotonic() - t0 > STARTUP_TIME:
                break
            desc.setMasterOutData(bytearray(bytes(SIZE)))
            handled = master.run()
            now = desc.isConnected()
            res["drops"] += connected and not now
            if now and res["dx_time"] is None:
                res["dx_time"] = time.monotonic() - t0
            connected = now
            if handled is desc:
                data = desc.getMasterInData()
                if data is not None:
                    res["exchanges"] += 1
                    res["sizes"].add(len(data))
    except Exception as e:  # a ProfibusError ends pyprofibus's loop
        res["error"] = "%s: %s" % (type(e).__name__, e)
    finally:
        if master is not None:
            master.destroy()
        else:
            phy.close()
    return res


def body(c, pb, args):
    with tempfile.TemporaryDirectory() as tmp:
        out_path = os.path.join(tmp, "line.out")
        with open(out_path, "w") as out:
            line = subprocess.Popen([args.dfp_sim, "line", "--dir", tmp, "--ports", "1",
                                     "--card", str(SLAVE_ADDR), "--baud", str(args.baud)],
                                    stdin=subprocess.DEVNULL, stdout=out, stderr=out)
        try:
            port = os.path.join(tmp, "port1")
            c.check(wait_for(lambda: "Ctrl-C ends it" in read_text(out_path), 5.0),
                    "the line starts", read_text(out_path))
            conf = os.path.join(tmp, "pyprofibus.conf")
            write_conf(conf, port, args.baud, os.path.join(args.gsd_dir, "SEW_6003.GSD"),
                       MODULE, SIZE)
            res = run_master(pb, conf)
        finally:
            rc = stop_process(line)
        text = read_text(out_path)
        c.check(res["error"] is None, "pyprofibus ran without an error", str(res["error"]))
        c.check(res["dx_time"] is not None, "slave %d in Data_Exchange in pyprofibus" % SLAVE_ADDR,
                "not within %.0f s" % STARTUP_TIME)
        c.check(res["exchanges"] >= EXCHANGES, "%d Data_Exchange cycles" % EXCHANGES,
                "only %d" % res["exchanges"])
        c.check(res["sizes"] == {SIZE}, "every reply has %d octets" % SIZE, str(res["sizes"]))
        c.check(res["drops"] == 0, "the slave stayed connected", "%d drops" % res["drops"])
        c.check("Wait_Cfg -> Data_Exch" in text, "the line's card reached Data_Exch")
        c.check("dfp-sim line: 0 collisions" in text, "no collision on the line")
        c.check(rc == 0, "the line exits 0 on SIGTERM", "exit %s" % rc)
        c.check(not os.path.lexists(port), "the link is gone")
        if c.failed or args.verbose:
            print(text)


if __name__ == "__main__":
    sys.exit(pyprofibus_main(__doc__, body))
