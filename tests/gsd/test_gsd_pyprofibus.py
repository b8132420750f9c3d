#!/usr/bin/env python3
"""sim_host/gsd's reading of GSD files (through `dfp-sim gsd FILE --json`) against pyprofibus's
GSD parser reading the same files: an independent implementation must agree on what the file
says.

usage: test_gsd_pyprofibus.py --dfp-sim PATH FILE...

For each FILE, both readers agree on: ident, GSD revision, vendor, model, revision, DP-V1 and
modular flags, the length keys pyprofibus knows, each rate's <rate>_supp and MaxTsdr, the
modules in order with their names and config octets, the Ext_User_Prm_Data_Const/Ref lines
(offset and reference number), ExtUserPrmData numbers, names and Prm_Text_Ref, PrmText
tables, and the User_Prm_Data a master sends by default (pyprofibus builds it from
User_Prm_Data and the Const lines only, so the files compared spell every default out as a
Const too) -- with the modules a compact station plugs, and again with each module that has
parameters of its own configured alone. dfp-sim gsd exits 0 (consistent) on each FILE.

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise, 77 (a
ctest skip) when pyprofibus is not installed for this interpreter.
"""

import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "interop"))
from checker import Checker  # noqa: E402  (tests/interop/checker.py)

SKIP = 77

# The keys both readers keep as numbers (pyprofibus's parser lists them by these names).
NUMBER_KEYS = ["GSD_Revision", "Ident_Number", "Protocol_Ident", "Station_Type",
               "Repeater_Ctrl_Sig", "24V_Pins", "Min_Slave_Intervall", "Max_Diag_Data_Len",
               "Modul_Offset", "Max_Module", "Max_Input_Len", "Max_Output_Len", "Max_Data_Len",
               "User_Prm_Data_Len", "Max_User_Prm_Data_Len"]
BOOL_KEYS = ["Freeze_Mode_supp", "Sync_Mode_supp", "Set_Slave_Add_supp", "Fail_Safe",
             "Modular_Station", "Auto_Baud_supp", "DPV1_Slave"]


def ours(dfp_sim, path, modules=()):
    cmd = [dfp_sim, "gsd", path, "--json"]
    for m in modules:
        cmd += ["--module", m]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    if r.returncode not in (0, 1):
        raise RuntimeError("%s: exit %d: %s" % (" ".join(cmd), r.returncode, r.stderr.strip()))
    return r.returncode, json.loads(r.stdout)


def compare_header(c, name, me, py):
    c.equal(me["ident"], py.getIdentNumber(), "%s: Ident_Number" % name)
    for key, field in (("vendor", "Vendor_Name"), ("model", "Model_Name"),
                       ("revision", "Revision")):
        c.equal(me[key], py.getField(field, ""), "%s: %s" % (name, field))
    c.equal(me["dpv1"], bool(py.isDPV1()), "%s: DPV1_Slave" % name)
    c.equal(me["modular"], bool(py.isModular()), "%s: Modular_Station" % name)
    for key in NUMBER_KEYS:
        c.equal(me["keys"].get(key), py.getField(key), "%s: %s" % (name, key))
    for key in BOOL_KEYS:
        mine = me["keys"].get(key)
        c.equal(None if mine is None else bool(mine), py.getField(key), "%s: %s" % (name, key))


def compare_rates(c, name, me, py):
    for rate in me["rates"]:
        c.equal(rate["supported"], py.getField("%s_supp" % rate["name"]),
                "%s: %s_supp" % (name, rate["name"]))
        c.equal(rate["max_tsdr"], py.getMaxTSDR(rate["baud"]),
                "%s: MaxTsdr at %d bit/s" % (name, rate["baud"]))


def compare_modules(c, name, me, py):
    py_modules = [(m.name, bytes(m.configBytes).hex().upper()) for m in py.getField("Module", [])]
    c.equal([(m["name"], m["cfg"]) for m in me["modules"]], py_modules,
            "%s: %d modules, names and config octets in order" % (name, len(py_modules)))


def compare_prm_definitions(c, name, me, py):
    refs = [(r.offset, r.refNr) for r in py.getField("Ext_User_Prm_Data_Ref", [])]
    for m in py.getField("Module", []):
        refs += [(r.offset, r.refNr) for r in m.getField("Ext_User_Prm_Data_Ref", [])]
    c.equal([(r["offset"], r["number"]) for r in me["refs"]], refs,
            "%s: Ext_User_Prm_Data_Ref offsets and numbers" % name)
    py_defs = [(d.refNr, d.name, d.getField("Prm_Text_Ref", -1))
               for d in py.getField("ExtUserPrmData", [])]
    c.equal([(d["number"], d["name"], d["text_ref"]) for d in me["prm_defs"]], py_defs,
            "%s: ExtUserPrmData numbers, names, Prm_Text_Ref" % name)
    py_texts = [(t.refNr, [(v.offset, v.text) for v in t.texts])
                for t in py.getField("PrmText", [])]
    c.equal([(t["number"], [tuple(v) for v in t["texts"]]) for t in me["prm_texts"]], py_texts,
            "%s: PrmText tables" % name)


def compare_user_prm(c, name, dfp_sim, path, me, py_class):
    py = py_class.fromFile(path)
    plugged = [] if py.isModular() else [m["name"] for m in me["modules"]]
    _, mine = ours(dfp_sim, path, plugged)
    c.equal(mine["user_prm"], py.getUserPrmData().hex().upper(),
            "%s: default User_Prm_Data%s" % (name, "" if py.isModular() else " (all modules)"))
    if not py.isModular():
        return
    for m in me["modules"]:
        if m["prm_len"] == 0:
            continue
        py = py_class.fromFile(path)
        py.setConfiguredModule(m["name"])
        _, mine = ours(dfp_sim, path, [m["name"]])
        c.equal(mine["user_prm"], py.getUserPrmData().hex().upper(),
                "%s: User_Prm_Data with module \"%s\"" % (name, m["name"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dfp-sim", required=True)
    ap.add_argument("files", nargs="+")
    args = ap.parse_args()
    try:
        from pyprofibus.gsd.interp import GsdInterp
    except ImportError as e:
        print("skip: pyprofibus is not installed for %s (%s)" % (sys.executable, e))
        return SKIP
    c = Checker()
    for path in args.files:
        name = os.path.basename(path)
        rc, me = ours(args.dfp_sim, path)
        c.equal(rc, 0, "%s: dfp-sim gsd exit status (consistent)" % name)
        c.equal(me["problems"], [], "%s: no consistency problems" % name)
        py = GsdInterp.fromFile(path)
        compare_header(c, name, me, py)
        compare_rates(c, name, me, py)
        compare_modules(c, name, me, py)
        compare_prm_definitions(c, name, me, py)
        compare_user_prm(c, name, args.dfp_sim, path, me, GsdInterp)
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
