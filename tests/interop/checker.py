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
