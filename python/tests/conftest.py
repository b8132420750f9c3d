"""Options and fixtures of the dfpsim tests.

    pytest python/tests                                    # unit tests; the rest is skipped
    pytest python/tests --dfp-sim build/host/sim_host/dfp_sim/dfp-sim    # everything
    DFP_SIM=build/host/sim_host/dfp_sim/dfp-sim pytest python/tests       # the same

(Name the test directory before --dfp-sim, or write --dfp-sim=PATH: pytest looks for conftest.py
files before it knows this option, and would otherwise take PATH for a test path.)

With --dfp-sim (or $DFP_SIM) the tests that start the real simulator run too. They need socat
for the PTY pair: without it the whole run ends at once with exit 77 (ctest: skipped), or with
exit 1 when --require-tools is given (ctest with DFP_REQUIRE_INTEROP=ON, i.e. `make test`).
"""

import os
import shutil
import sys

import pytest

# Importable without `pip install` too (pyproject.toml's pythonpath does the same for pytest
# run from python/; this covers a rootdir found elsewhere).
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from dfpsim import DfpSim  # noqa: E402

SKIP = 77


def pytest_addoption(parser):
    g = parser.getgroup("dfpsim")
    g.addoption("--dfp-sim", default=os.environ.get("DFP_SIM") or None, metavar="PATH",
                help="the dfp-sim binary for the tests against the real simulator "
                     "(default: $DFP_SIM; without it they are skipped)")
    g.addoption("--require-tools", action="store_true", default=False,
                help="socat missing is a failure (exit 1), not a skip (exit 77)")


def pytest_sessionstart(session):
    config = session.config
    if config.getoption("--dfp-sim") and shutil.which("socat") is None:
        if config.getoption("--require-tools"):
            pytest.exit("socat not found (apt-get install socat): the PTY pair between "
                        "dfp-sim slave and master needs it", returncode=1)
        pytest.exit("SKIP: socat not found (apt-get install socat)", returncode=SKIP)


# ---- steps that build on each other --------------------------------------------------------
# A module marked `pytestmark = pytest.mark.incremental` is a checklist: once a step failed,
# the steps after it are reported as skipped ("previous step failed: ...") instead of failing
# for the same reason again.

def pytest_configure(config):
    config.addinivalue_line("markers", "incremental: later tests in the module depend on "
                                       "the earlier ones")


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    if "incremental" in item.keywords and rep.failed and call.when == "call":
        item.module._dfpsim_failed_step = item.name
    if rep.failed:
        # what dfp-sim (slave, master, socat) printed last, next to the failure
        for name in ("bus", "demo"):
            session = getattr(getattr(item, "funcargs", {}).get(name), "session", None)
            if session is not None:
                for proc, text in session.outputs().items():
                    rep.sections.append(("%s output (last lines)" % proc, text))


def pytest_runtest_setup(item):
    if "incremental" in item.keywords:
        failed = getattr(item.module, "_dfpsim_failed_step", None)
        if failed is not None:
            pytest.skip("previous step failed: %s" % failed)


# ---- fixtures ------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def dfp_sim(request):
    """Path of the real dfp-sim; the test is skipped without --dfp-sim / $DFP_SIM."""
    path = request.config.getoption("--dfp-sim")
    if not path:
        pytest.skip("no --dfp-sim PATH (or $DFP_SIM): the tests against the real simulator "
                    "are left out")
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        pytest.fail("--dfp-sim %s is not an executable file" % path, pytrace=False)
    return os.path.abspath(path)


@pytest.fixture
def demo(dfp_sim):
    """`dfp-sim demo --http PORT`, as a dfpsim.Client; stopped (and its exit code checked)
    after the test."""
    with DfpSim.demo(dfp_sim=dfp_sim) as sim:
        yield sim


@pytest.fixture(scope="module")
def bus(dfp_sim):
    """A card (`dfp-sim slave --address 4`) and a PLC (`dfp-sim master`, Param + 3 PD,
    19200 bit/s) on a PTY pair, shared by the tests of one module (a commissioning session).
    `bus.slave` / `bus.master` are the two processes' Clients."""
    with DfpSim.slave_and_master(address=4, config="F3F2", baud=19200, dfp_sim=dfp_sim) as b:
        yield b
