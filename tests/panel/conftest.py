"""Options and tool checks for the front panel's browser test (test_panel.py).

Run by ctest as
    python -m pytest -q tests/panel/test_panel.py --dfp-sim PATH --out DIR [--require-tools]
Without selenium, chromium or chromedriver the whole session exits 77 (ctest: skipped), or fails
when --require-tools is given (CMake passes it with DFP_REQUIRE_INTEROP=ON, as `make test` does).
"""
import importlib.util
import os
import shutil

import pytest

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
CHROMEDRIVER_NAMES = ("chromedriver",)
SKIP = 77


def pytest_addoption(parser):
    group = parser.getgroup("panel", "DFP21B front panel test")
    group.addoption("--dfp-sim", dest="dfp_sim", default=None,
                    help="the dfp-sim program (started as `dfp-sim demo --http PORT`)")
    group.addoption("--out", "--screenshot", dest="out", default=None,
                    help="directory for panel.png and dfp-sim's output (default: a temporary one)")
    group.addoption("--require-tools", dest="require_tools", action="store_true", default=False,
                    help="fail instead of exiting 77 when chromium, chromedriver or selenium are missing")


def find_program(names, env):
    """The first of names on PATH (or /usr/bin, /usr/lib/chromium for Debian's layout), or the
    path in the environment variable env."""
    if os.environ.get(env):
        p = os.environ[env]
        return p if os.access(p, os.X_OK) else None
    for n in names:
        p = shutil.which(n)
        if p:
            return p
    for d in ("/usr/bin", "/usr/lib/chromium"):
        for n in names:
            p = os.path.join(d, n)
            if os.access(p, os.X_OK):
                return p
    return None


def missing_tools():
    missing = []
    if importlib.util.find_spec("selenium") is None:
        missing.append("selenium (pip install selenium, or `make deps-python`)")
    if find_program(CHROMIUM_NAMES, "DFP_CHROMIUM") is None:
        missing.append("chromium (apt-get install chromium)")
    if find_program(CHROMEDRIVER_NAMES, "DFP_CHROMEDRIVER") is None:
        missing.append("chromedriver (apt-get install chromium-driver)")
    return missing


def pytest_configure(config):
    if config.getoption("help", default=False) or config.getoption("collectonly", default=False):
        return
    if not config.getoption("dfp_sim"):
        raise pytest.UsageError("--dfp-sim PATH is required")
    missing = missing_tools()
    if missing:
        msg = "panel test: missing " + ", ".join(missing)
        if config.getoption("require_tools"):
            pytest.exit(msg + " (required: DFP_REQUIRE_INTEROP=ON)", returncode=1)
        pytest.exit(msg + ": skipped", returncode=SKIP)
