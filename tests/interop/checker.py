"""Pass/fail counting shared by the interop tests; the closing line is "N passed, M failed"."""


class Checker:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, ok, what, detail=""):
        if ok:
            self.passed += 1
            print("PASS %s" % what)
        else:
            self.failed += 1
            print("FAIL %s%s" % (what, (": " + detail) if detail else ""))
        return ok

    def equal(self, actual, expected, what):
        return self.check(actual == expected, what,
                          "got %r, expected %r" % (actual, expected))


def pyprofibus_main(doc, body):
    """The common frame of the pyprofibus tests: options --dfp-sim, --gsd-dir, --baud,
    --verbose; exit 77 (a ctest skip) without pyprofibus, pyserial or socat; body(checker,
    pyprofibus, args) runs the checks; prints the time and "N passed, M failed"."""
    import argparse
    import os
    import shutil
    import sys
    import time

    ap = argparse.ArgumentParser(description=doc.split("\n")[0])
    ap.add_argument("--dfp-sim", required=True)
    ap.add_argument("--gsd-dir", required=True)
    ap.add_argument("--baud", type=int, default=19200)
    ap.add_argument("--verbose", action="store_true", help="print the logs even on success")
    args = ap.parse_args()

    try:
        import pyprofibus
        import pyprofibus.phy_serial  # noqa: F401 (needs pyserial)
    except ImportError as e:
        print("SKIP: pyprofibus/pyserial not installed for %s (%s); pip install pyprofibus "
              "pyserial, or point the CMake cache variable DFP_PYTHON at an interpreter that "
              "has them" % (sys.executable, e))
        return 77
    if shutil.which("socat") is None:
        print("SKIP: socat not found (apt-get install socat)")
        return 77
    if not os.access(args.dfp_sim, os.X_OK):
        print("FAIL dfp-sim not executable: %s" % args.dfp_sim)
        print("0 passed, 1 failed")
        return 1

    c = Checker()
    t0 = time.monotonic()
    body(c, pyprofibus, args)
    print("     total %.2f s" % (time.monotonic() - t0))
    print("%d passed, %d failed" % (c.passed, c.failed))
    return 0 if c.failed == 0 else 1
