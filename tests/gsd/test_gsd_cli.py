#!/usr/bin/env python3
"""dfp-sim gsd FILE: the lines it prints for the project's GSD files and a feature file, the
problems of an inconsistent file with their lines (exit 1), and exit 2 with its one-line error
for a file that cannot be read or parsed and for a bad command line.

usage: test_gsd_cli.py DFP_SIM GSD_DIR TESTS_GSD_DIR

Prints one line per check and "N passed, M failed"; exit 0 when all passed, 1 otherwise.
"""

import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "interop"))
from checker import Checker  # noqa: E402  (tests/interop/checker.py)


def run(dfp_sim, *args):
    r = subprocess.run([dfp_sim, "gsd", *args], capture_output=True, text=True, timeout=30)
    return r.returncode, r.stdout.splitlines(), r.stderr.strip()


def has_lines(c, out, lines, what):
    for line in lines:
        c.check(line in out, "%s: prints %r" % (what, line), "\n".join(out))


def own_files(c, dfp_sim, gsd_dir):
    sew = os.path.join(gsd_dir, "SEW_6003.GSD")
    rc, out, err = run(dfp_sim, sew)
    c.equal((rc, err), (0, ""), "SEW_6003.GSD: exit 0, nothing on stderr")
    has_lines(c, out, [
        "ident 0x6003, modular station (at most 1 module), inputs <= 28, outputs <= 28, "
        "data <= 56, diagnosis <= 8, user parameters <= 9 octets",
        "rates, auto baud (MaxTsdr in bit times): 9.6 15, 19.2 15, 45.45 15, 93.75 15, "
        "187.5 15, 500 32, 1.5M 96, 3M 192, 6M 383",
        "modules (20):",
        "  \"6 PD\" 00 F5: 12 in, 12 out",
        "  \"Param + 10 PD\" F3 F9: 28 in, 28 out",
        "user parameters by default (9 octets): 00 00 00 06 81 00 00 01 01",
        "  octet 8: 1 \"Diagnostic alarm\" Unsigned8 default 1 (Off), 0-1",
        "DP-V1: no keys (DP-V0)",
        "consistent: no problems",
    ], "SEW_6003.GSD")
    rc, out, _ = run(dfp_sim, os.path.join(gsd_dir, "SEWA6003.GSD"))
    c.equal(rc, 0, "SEWA6003.GSD: exit 0")
    has_lines(c, out, [
        "DP-V1: DPV1_Slave 1, C1_Read_Write_supp 1, C1_Max_Data_Len 240, C1_Response_Timeout "
        "100, C2_Read_Write_supp 1, C2_Max_Data_Len 240, C2_Response_Timeout 100, "
        "C2_Max_Count_Channels 2, Max_Initiate_PDU_Length 52, DPV1_Data_Types 0, "
        "WD_Base_1ms_supp 1",
    ], "SEWA6003.GSD")
    rc, out, _ = run(dfp_sim, sew, "--json")
    doc = json.loads("\n".join(out))
    c.equal((rc, doc["ident"], doc["user_prm"], len(doc["modules"]), doc["problem_count"]),
            (0, 0x6003, "000000068100000101", 20, 0), "SEW_6003.GSD --json")


def features(c, dfp_sim, tests_dir):
    path = os.path.join(tests_dir, "good", "features.gsd")
    rc, out, _ = run(dfp_sim, path, "--module", "8 DI", "--module", "special")
    c.equal(rc, 0, "features.gsd: exit 0")
    has_lines(c, out, [
        "rates (MaxTsdr in bit times): 9.6 60, 19.2 60, 500 100, 12M 800",
        "  \"8 DI\" 10: 1 in, 0 out, 2 parameter octets",
        "  \"special\" 40 83: 4 in, 0 out",
        "user parameters by default with the modules given (8 octets): "
        "00 00 00 31 12 34 AA 01",
        "  octet 3: 11 \"Speed\" BitArea(4-6) default 3 (Fast), one of 0, 1, 3, 5",
        "  octet 4: 12 \"Limit\" Unsigned16 default 4660, 0-40000",
        "  octet 1 of \"8 DI\": 10 \"Low bit\" Bit(0) default 1, 0-1",
    ], "features.gsd")


def inconsistent(c, dfp_sim, tests_dir):
    path = os.path.join(tests_dir, "bad", "inconsistent.gsd")
    rc, out, err = run(dfp_sim, path)
    c.equal((rc, err), (1, ""), "inconsistent.gsd: exit 1")
    c.equal(out[-5:], [
        "4 problems:",
        "  %s:14: 1.5M_supp = 1 without MaxTsdr_1.5M" % path,
        "  %s:22: module \"8 words in\": 16 input octets, Max_Input_Len is 4" % path,
        "  %s:22: module \"8 words in\": 16 data octets, Max_Data_Len is 8" % path,
        "  %s:20: C1_Read_Write_supp without DPV1_Slave = 1" % path,
    ], "inconsistent.gsd: the problems with their lines")
    has_lines(c, out, ["ignored: line 21: Vendor_Specific_Thing (not a keyword this reader "
                       "knows)"], "inconsistent.gsd")
    rc, out, _ = run(dfp_sim, path, "--json")
    doc = json.loads("\n".join(out))
    c.equal((rc, doc["problem_count"], doc["problems"][0]["line"], doc["ignored"]),
            (1, 4, 14, [{"line": 21, "keyword": "Vendor_Specific_Thing"}]),
            "inconsistent.gsd --json")


def errors(c, dfp_sim, gsd_dir, tests_dir):
    bad = os.path.join(tests_dir, "bad")
    sew = os.path.join(gsd_dir, "SEW_6003.GSD")
    cases = [
        ([os.path.join(bad, "out_of_range.gsd")],
         "dfp-sim: %s:3: Ident_Number: 65536 is out of range 0..65535"
         % os.path.join(bad, "out_of_range.gsd")),
        ([os.path.join(bad, "unterminated_module.gsd")],
         "dfp-sim: %s:6: Module inside the Module of line 5 (no EndModule before it)"
         % os.path.join(bad, "unterminated_module.gsd")),
        ([os.path.join(bad, "none.gsd")],
         "dfp-sim: %s: No such file or directory" % os.path.join(bad, "none.gsd")),
        ([], "dfp-sim: gsd needs a file: dfp-sim gsd FILE [--json] [--module NAME]..."),
        ([sew, sew], "dfp-sim: gsd takes one FILE; '%s' is a second" % sew),
        ([sew, "--bogus"], "dfp-sim: gsd: unknown option '--bogus' (see dfp-sim --help)"),
        ([sew, "--module", "11 PD"], "dfp-sim: gsd: no module \"11 PD\" in %s" % sew),
    ]
    for args, message in cases:
        rc, out, err = run(dfp_sim, *args)
        c.equal((rc, out, err), (2, [], message), "gsd %s: exit 2, one line" % " ".join(args))


def main():
    if len(sys.argv) != 4:
        print(__doc__)
        return 2
    dfp_sim, gsd_dir, tests_dir = sys.argv[1:]
    c = Checker()
    own_files(c, dfp_sim, gsd_dir)
    features(c, dfp_sim, tests_dir)
    inconsistent(c, dfp_sim, tests_dir)
    errors(c, dfp_sim, gsd_dir, tests_dir)
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
