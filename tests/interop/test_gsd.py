#!/usr/bin/env python3
"""The GSD files of the card, read by an independent GSD parser (pyprofibus's), checked against
the DFP21B manual's values, and every configuration they offer checked against the card itself.

usage: test_gsd.py --gsd-dir DIR [--dfp-sim PATH]

For SEW_6003.GSD (DP-V0) and SEWA6003.GSD (DP-V1):
  - the file is ASCII with CRLF line ends and pyprofibus.gsd.interp.GsdInterp loads it;
  - ident 0x6003, vendor, model, GSD revision, DP-V1 flag, the ten baud rates with the
    MaxTsdr table, the DP service flags and the length limits;
  - the module list is exactly the ten predefined configurations of protocol.md §B3 and the ten
    4/5/7/8/9-word ones the manual builds as universal modules, in order, with their identifier
    bytes, and selecting each module by name makes pyprofibus put exactly those bytes into
    Chk_Cfg; Max_Module is 1 (each module is a whole configuration);
  - the User_Prm_Data pyprofibus builds is 00 00 00 06 81 00 00 01 01 (protocol.md §B4);
  - SEWA6003.GSD carries the DP-V1 keys (pyprofibus ignores them, so they are read from the text).
With --dfp-sim (the card's own configuration check, `dfp-sim check-cfg HEX`):
  - every module's Chk_Cfg bytes are accepted (exit 0) with the expected in/out lengths;
  - universal configurations the manual allows are accepted, wrong ones refused (exit 1);
  - any two modules side by side (what Max_Module = 2 would let a configurator build) refused.

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise, 77 (a
ctest skip) when pyprofibus is not installed for this interpreter.
"""

import argparse
import os
import re
import subprocess
import sys

from checker import Checker  # sibling module in tests/interop

SKIP = 77

IDENT = 0x6003
USER_PRM = bytes.fromhex("000000068100000101")

# protocol.md §B3: name, Chk_Cfg bytes, parameter channel, process data words
MODULES = [
    ("1 PD", "F0", False, 1),
    ("2 PD", "F1", False, 2),
    ("3 PD", "F2", False, 3),
    ("6 PD", "00F5", False, 6),
    ("10 PD", "00F9", False, 10),
    ("Param + 1 PD", "F3F0", True, 1),
    ("Param + 2 PD", "F3F1", True, 2),
    ("Param + 3 PD", "F3F2", True, 3),
    ("Param + 6 PD", "F3F5", True, 6),
    ("Param + 10 PD", "F3F9", True, 10),
    # the manual's universal-module sizes (4.1), offered as whole configurations too
    ("4 PD", "00F3", False, 4),
    ("5 PD", "00F4", False, 5),
    ("7 PD", "00F6", False, 7),
    ("8 PD", "00F7", False, 8),
    ("9 PD", "00F8", False, 9),
    ("Param + 4 PD", "F3F3", True, 4),
    ("Param + 5 PD", "F3F4", True, 5),
    ("Param + 7 PD", "F3F6", True, 7),
    ("Param + 8 PD", "F3F7", True, 8),
    ("Param + 9 PD", "F3F8", True, 9),
]

# Universal-module forms (manual 4.1) the GSD's modules do not spell: (hex, out = in bytes)
UNIVERSAL_OK = [
    ("F3", 8),      # 4 PD alone: also used by test_pyprofibus_interop.py (SD3 data exchange)
    ("F7", 16),     # 8 PD as one identifier, no empty slot
    ("B7F4", 18),   # parameter channel as 8 consistent I/O bytes + 5 PD
]
# Configurations the card must refuse: (hex, why)
REFUSED = [
    ("F3E2D1", "parameter channel + 3 PD out + 2 PD in: unequal lengths"),
    ("E2D1", "3 words out, 2 words in: unequal lengths (P090 0PD)"),
    ("72", "3 I/O words without consistency over the whole length"),
    ("FA", "11 PD words: more than 10"),
]

# From the reference board's measured worst reply (63.8 us with margin, never below 15 bit
# times); no 12 Mbit/s on that board, so no MaxTsdr_12M (pyprofibus answers None).
MAXTSDR = {9600: 15, 19200: 15, 45450: 15, 93750: 15, 187500: 15, 500000: 32,
           1500000: 96, 3000000: 192, 6000000: 383, 12000000: None}
BAUD_KEYS = ["9.6_supp", "19.2_supp", "45.45_supp", "93.75_supp", "187.5_supp", "500_supp",
             "1.5M_supp", "3M_supp", "6M_supp", "12M_supp"]

COMMON_FIELDS = {
    "Vendor_Name": "SEW-EURODRIVE",
    "Ident_Number": IDENT,
    "Protocol_Ident": 0,
    "Station_Type": 0,
    "Auto_Baud_supp": True,
    "Set_Slave_Add_supp": False,
    "Freeze_Mode_supp": True,
    "Sync_Mode_supp": True,
    "Modular_Station": True,
    "Max_Module": 1,  # every module is a whole configuration: two would be refused
    "Max_Input_Len": 28,
    "Max_Output_Len": 28,
    "Max_Data_Len": 56,
    "Max_Diag_Data_Len": 8,
    "Min_Slave_Intervall": 1,
    "User_Prm_Data_Len": 9,
}

FILES = {
    "SEW_6003.GSD": {"GSD_Revision": 1, "Model_Name": "MOVIDRIVE+DFP21", "dpv1": False},
    "SEWA6003.GSD": {"GSD_Revision": 3, "Model_Name": "MOVIDRIVE DFP21B/MCH (DP-V1)",
                     "dpv1": True},
}

# Keys of GSD revision 3 pyprofibus does not parse: read from the file text.
DPV1_KEYS = {
    "DPV1_Slave": 1,
    "C1_Read_Write_supp": 1,
    "C1_Max_Data_Len": 240,
    "C1_Response_Timeout": 100,
    "C2_Read_Write_supp": 1,
    "C2_Max_Data_Len": 240,
    "C2_Response_Timeout": 100,
    "C2_Max_Count_Channels": 2,
    "Max_Initiate_PDU_Length": 52,
    "DPV1_Data_Types": 0,
    "WD_Base_1ms_supp": 1,
}


def raw_keys(text):
    """key = value pairs of the #Profibus_DP section, comments removed (enough for plain keys)."""
    keys = {}
    in_section = False
    for line in text.splitlines():
        if not in_section:
            in_section = line.strip() == "#Profibus_DP"
            continue
        line = line.split(";", 1)[0].strip()
        m = re.match(r"^([A-Za-z0-9_.]+)\s*=\s*(\S.*)$", line)
        if m:
            keys[m.group(1)] = m.group(2).strip()
    return keys


def cfg_bytes_of(gsd):
    """The Chk_Cfg payload pyprofibus builds for the modules configured in gsd."""
    return b"".join(bytes(e.getDU()) for e in gsd.getCfgDataElements())


def check_file(c, gsd_dir, name, info, GsdInterp):
    path = os.path.join(gsd_dir, name)
    tag = name + ": "
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as e:
        c.check(False, tag + "readable", str(e))
        return None
    c.check(all(b < 0x80 for b in raw), tag + "ASCII only")
    lines = raw.split(b"\n")
    c.check(raw.endswith(b"\r\n") and all(l.endswith(b"\r") for l in lines[:-1]),
            tag + "CRLF line ends")
    c.check(b"\n#Profibus_DP\r\n" in raw, tag + "a line exactly '#Profibus_DP'")

    try:
        gsd = GsdInterp.fromFile(path)
    except Exception as e:  # GsdError and whatever else a broken file causes
        c.check(False, tag + "pyprofibus GsdInterp.fromFile loads it", repr(e))
        return None
    c.check(True, tag + "pyprofibus GsdInterp.fromFile loads it")

    c.equal(gsd.getIdentNumber(), IDENT, tag + "ident number")
    for key, want in COMMON_FIELDS.items():
        c.equal(gsd.getField(key), want, tag + key)
    c.equal(gsd.getField("GSD_Revision"), info["GSD_Revision"], tag + "GSD_Revision")
    c.equal(gsd.getField("Model_Name"), info["Model_Name"], tag + "Model_Name")
    c.equal(bool(gsd.isDPV1()), info["dpv1"], tag + "DPV1_Slave as pyprofibus sees it")
    c.equal([k for k in BAUD_KEYS if gsd.getField(k) is not True], ["12M_supp"],
            tag + "every baud rate but 12 Mbit/s supported")
    c.equal({b: gsd.getMaxTSDR(b) for b in MAXTSDR}, MAXTSDR, tag + "MaxTsdr table")

    mods = [(m.name, bytes(m.configBytes).hex().upper()) for m in gsd.getField("Module", [])]
    c.equal(mods, [(n, h) for n, h, _, _ in MODULES],
            tag + "modules: exactly the twenty configurations with their cfg bytes")
    for mname, hexcfg, _, _ in MODULES:
        gsd.clearConfiguredModules()
        try:
            gsd.setConfiguredModule(mname)
            got = cfg_bytes_of(gsd).hex().upper()
        except Exception as e:
            got = repr(e)
        c.equal(got, hexcfg, tag + "module '%s' selected by name gives Chk_Cfg %s"
                % (mname, hexcfg))
    gsd.clearConfiguredModules()

    c.equal(bytes(gsd.getUserPrmData()).hex(" "), USER_PRM.hex(" "),
            tag + "User_Prm_Data built by pyprofibus")

    keys = raw_keys(raw.decode("ascii", "replace"))
    if info["dpv1"]:
        for key, want in DPV1_KEYS.items():
            got = keys.get(key)
            c.equal(int(got, 0) if got is not None else None, want, tag + key)
        # What a DP-V1 master sends: DPV1_Enable set in the first byte, the rest unchanged.
        prm = bytes(gsd.getUserPrmData(dp1PrmMask=bytearray((0xFF, 0xFF, 0xFF)),
                                       dp1PrmSet=bytearray((0x80, 0x00, 0x00))))
        c.equal(prm.hex(" "), "80" + USER_PRM.hex(" ")[2:],
                tag + "User_Prm_Data with the DP-V1 override 80 00 00")
    else:
        c.check(keys.get("DPV1_Slave", "0") == "0", tag + "no DPV1_Slave in the DP-V0 file")
    # I&M (call service on index 255) exists with DP-V1 only: the DP-V1 file announces it, the
    # DP-V0 file cannot (a DP-V0 master has no way to reach it).
    if info["dpv1"]:
        c.equal(keys.get("Ident_Maintenance_supp"), "1", tag + "Ident_Maintenance_supp = 1")
    else:
        c.check("Ident_Maintenance_supp" not in keys, tag + "no Ident_Maintenance_supp")
    return gsd


def run_check_cfg(dfp_sim, hexcfg):
    try:
        p = subprocess.run([dfp_sim, "check-cfg", hexcfg], capture_output=True, text=True,
                           timeout=10)
    except (OSError, subprocess.TimeoutExpired) as e:
        return None, repr(e)
    return p.returncode, (p.stdout + p.stderr).strip()


def check_card(c, dfp_sim):
    expected = [(h, (8 if param else 0) + 2 * words) for _, h, param, words in MODULES]
    for hexcfg, nbytes in expected + UNIVERSAL_OK:
        rc, out = run_check_cfg(dfp_sim, hexcfg)
        what = "dfp-sim check-cfg %s: accepted, %d bytes out and in" % (hexcfg, nbytes)
        m = re.search(r"(\d+) bytes out, (\d+) bytes in", out)
        lengths = (int(m.group(1)), int(m.group(2))) if m else None
        c.check(rc == 0 and lengths == (nbytes, nbytes) and "accepted" in out, what,
                "exit %r, output %r" % (rc, out))
    # Why Max_Module is 1: two of these modules side by side are never a configuration.
    for first in ("F0", "00F5", "F3F2"):
        for second in ("F0", "00F3", "F3F9"):
            rc, out = run_check_cfg(dfp_sim, first + second)
            c.check(rc == 1, "dfp-sim check-cfg %s%s: two modules refused" % (first, second),
                    "exit %r, output %r" % (rc, out))
    for hexcfg, why in REFUSED:
        rc, out = run_check_cfg(dfp_sim, hexcfg)
        c.check(rc == 1, "dfp-sim check-cfg %s: refused (%s)" % (hexcfg, why),
                "exit %r, output %r" % (rc, out))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--gsd-dir", required=True)
    ap.add_argument("--dfp-sim", help="the dfp-sim program; without it the card is not asked")
    args = ap.parse_args()

    try:
        from pyprofibus.gsd.interp import GsdInterp
    except ImportError as e:
        print("SKIP: pyprofibus is not installed for %s (%s); pip install pyprofibus, or point "
              "the CMake cache variable DFP_PYTHON at an interpreter that has it"
              % (sys.executable, e))
        return SKIP

    c = Checker()
    for name, info in FILES.items():
        check_file(c, args.gsd_dir, name, info, GsdInterp)
    if args.dfp_sim:
        check_card(c, args.dfp_sim)
    else:
        print("NOTE: no --dfp-sim given: the card's acceptance of the configurations "
              "was not checked")
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
