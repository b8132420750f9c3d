"""The panel's bus page (docs/monitor.md "The bus page") showing `dfp-sim monitor --http` on a
port of `dfp-sim line` (master 2, DFP21B cards 5 and 6), in headless chromium through selenium.

The monitor joins the line before its master starts the cards (the master waits a lost-token
time-out first), so it sees their start-up: their ident and diagnosis. The page, opened with the
token as a bookmark of the bus page (/?token=T#bus), must show the live list (master 2 in the
ring, 5 and 6 in Data_Exch with master 2, ident 0x6003), on a click on 5 its details (the
diagnosis decoded, the DFP21B's names) and the bus events ("slave 5 in data exchange with
master 2"); and it must send nothing but GETs after logging in (chromium's own record of the
requests, and the server's audit, which logs every request that acts). SIGINT ends the monitor
with exit status 0 (every slave in data exchange).

Usage: test_monitor_panel.py DFP_SIM [--require-tools]   (the last line is "N passed, M failed")
Without selenium, chromium or chromedriver it exits 77 (ctest: skipped), or 1 with
--require-tools, as the panel's own test does (tests/panel/conftest.py).
"""
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "panel"))
try:
    from conftest import (CHROMEDRIVER_NAMES, CHROMIUM_NAMES, SKIP,  # noqa: E402
                          find_program, missing_tools)
except ImportError as e:  # the panel's conftest.py needs pytest
    print("monitor_panel: %s (make deps-python): %s" % (e, "failed" if "--require-tools" in
                                                         sys.argv else "skipped"))
    sys.exit(1 if "--require-tools" in sys.argv else 77)

TOKEN = "monitor-panel-test-0123456789abcdef"
START_S = 20      # the monitor's API answering, the cards in its live list
PAGE_S = 15       # the page showing what the API says
ATTEMPTS = 3      # a loaded machine may start the monitor after the cards' start-up

passed = failed = 0


def ok():
    global passed
    passed += 1


def bad(msg):
    global failed
    failed += 1
    print("FAIL: " + msg, file=sys.stderr)


def check(cond, what):
    if cond:
        ok()
    else:
        bad(what)
    return cond


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get(base, path, token=TOKEN):
    req = urllib.request.Request(base + path)
    if token:
        req.add_header("Authorization", "Bearer " + token)
    try:
        with urllib.request.urlopen(req, timeout=3) as r:
            return r.status, json.loads(r.read().decode())
    except urllib.error.HTTPError as e:
        return e.code, None
    except (OSError, ValueError):
        return 0, None


def wait_for(cond, timeout, interval=0.1):
    """cond()'s first true value within timeout s, else its last value."""
    end = time.monotonic() + timeout
    while True:
        try:
            got = cond()
        except Exception:  # noqa: BLE001 (a page between two renders: try again)
            got = None
        if got or time.monotonic() >= end:
            return got
        time.sleep(interval)


def station(doc, address):
    return next((s for s in doc["stations"] if s["address"] == address), None)


class Run:
    """dfp-sim line, and dfp-sim monitor --http on its port1 started as soon as the line is."""

    def __init__(self, sim, tmp, n):
        self.dir = os.path.join(tmp, "l%d" % n)
        os.mkdir(self.dir)
        self.line_out = os.path.join(tmp, "line%d.out" % n)
        self.mon_out = os.path.join(tmp, "monitor%d.out" % n)
        self.line = subprocess.Popen(
            [sim, "line", "--dir", self.dir, "--ports", "2", "--baud", "187500", "--card", "5",
             "--card", "6", "--master", "2", "--master-slaves", "5,6", "--quiet"],
            stdout=open(self.line_out, "w"), stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        self.mon = None
        if not wait_for(lambda: "Ctrl-C ends it" in self.read(self.line_out), 10, 0.02):
            raise SystemExit("dfp-sim line did not start: " + self.read(self.line_out))
        self.port = free_port()
        self.base = "http://127.0.0.1:%d" % self.port
        self.mon = subprocess.Popen(
            [sim, "monitor", "--port", os.path.join(self.dir, "port1"), "--baud", "187500",
             "--view", "none", "--http", str(self.port)],
            stdout=open(self.mon_out, "w"), stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            env=dict(os.environ, DFP_SIM_TOKEN=TOKEN))

    @staticmethod
    def read(path):
        with open(path, errors="replace") as f:
            return f.read()

    def cards_in_dx(self):
        """The bus document once 5 and 6 are in Data_Exch (None before, or when it ended)."""
        if self.mon.poll() is not None:
            return None
        status, doc = get(self.base, "/api/v1/bus")
        if status != 200:
            return None
        st = [station(doc, a) for a in (5, 6)]
        return doc if all(s and s["dp"] and s["dp"]["state"] == "Data_Exch" for s in st) else None

    def stop(self):
        rc = None
        if self.mon is not None and self.mon.poll() is None:
            self.mon.send_signal(signal.SIGINT)
            try:
                rc = self.mon.wait(10)
            except subprocess.TimeoutExpired:
                self.mon.kill()
                self.mon.wait()
        if self.line.poll() is None:
            self.line.send_signal(signal.SIGINT)
            self.line.wait()
        return rc


def start(sim, tmp):
    """A Run whose monitor saw the cards' start-up, and its bus document."""
    for n in range(ATTEMPTS):
        run = Run(sim, tmp, n)
        doc = wait_for(run.cards_in_dx, START_S)
        if doc and station(doc, 5)["dp"]["ident"] == "0x6003":
            return run, doc
        why = ("its start-up missed (a loaded machine): again" if doc else
               "no Data_Exch in the bus document:\n" + run.read(run.mon_out))
        run.stop()
        if not doc:
            raise SystemExit("dfp-sim monitor --http: " + why)
        print("monitor_panel: attempt %d: %s" % (n + 1, why))
    raise SystemExit("the monitor missed the cards' start-up %d times" % ATTEMPTS)


def browser():
    os.environ.setdefault("SE_OFFLINE", "true")
    os.environ.setdefault("SE_AVOID_STATS", "true")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1400,1000", "--no-first-run", "--disable-extensions"):
        opts.add_argument(a)
    opts.binary_location = find_program(CHROMIUM_NAMES, "DFP_CHROMIUM")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    service = Service(executable_path=find_program(CHROMEDRIVER_NAMES, "DFP_CHROMEDRIVER"))
    drv = webdriver.Chrome(service=service, options=opts)
    drv.set_page_load_timeout(PAGE_S)
    return drv


def requests_made(drv):
    """(method, URL) of every request the page sent, from chromium's DevTools record."""
    got = []
    for entry in drv.get_log("performance"):
        msg = json.loads(entry["message"])["message"]
        if msg.get("method") == "Network.requestWillBeSent":
            req = msg["params"]["request"]
            got.append((req["method"], req["url"]))
    return got


def check_page(drv, run, doc):
    from selenium.webdriver.common.by import By

    def cell(address, cls):
        return drv.find_element(By.CSS_SELECTOR, "#bus-st-%d .%s" % (address, cls)).text.strip()

    def detail(key):
        tds = drv.find_elements(By.CSS_SELECTOR, '#bus-detail tr[data-key="%s"] td' % key)
        return tds[0].text.strip() if tds else None

    drv.get(run.base + "/?token=" + TOKEN + "#bus")
    check(wait_for(lambda: drv.execute_script("return document.body.dataset.view") == "panel",
                   PAGE_S), "the token in the address logs in")
    check(drv.execute_script("return document.body.dataset.page") == "bus" and
          drv.find_element(By.ID, "bus-page").is_displayed(), "#bus opens the bus page")
    check(drv.execute_script("return location.search") == "", "the token is gone from the address")

    def listed():
        return (cell(2, "c-role") == "active (ring)" and
                all(cell(a, "c-state") == "Data_Exch" and cell(a, "c-master") == "2" and
                    cell(a, "c-ident") == "0x6003" for a in (5, 6)))
    check(wait_for(listed, PAGE_S), "the live list: master 2 in the ring, 5 and 6 in Data_Exch "
          "with master 2, ident 0x6003")
    info = drv.find_element(By.ID, "bus-info").text
    check(info.startswith(os.path.join(run.dir, "port1") + " · 187.5 kBd · ring 2 · "),
          "the page's line names the port, the rate and the ring: " + info)
    check("TSDR not measurable on this medium" in info, "no TSDR on a PTY: " + info)
    check(drv.find_element(By.ID, "bus-st-5").get_attribute("data-warn") == "",
          "no warning on slave 5")

    drv.find_element(By.ID, "bus-st-5").click()
    check(wait_for(lambda: drv.find_element(By.ID, "bus-sel").text.strip() == "5", PAGE_S),
          "a click on 5 shows its details")
    want = station(doc, 5)["dp"]
    check(want["diag_text"] == "WD_On | Master_Add 2, ident 0x6003",
          "the document's diagnosis of 5: %r" % want["diag_text"])
    shown = {k: detail(k) for k in ("state", "master", "ident", "diagnosis", "diagnosis octets",
                                    "configuration (Chk_Cfg)", "PD configuration",
                                    "parameter channel", "control word", "status word")}
    check(shown["state"] == "Data_Exch" and shown["master"] == "2" and shown["ident"] == "0x6003",
          "5's details: state, master, ident: %r" % shown)
    check(shown["diagnosis"] == want["diag_text"], "5's diagnosis decoded: %r" % shown)
    check(shown["diagnosis octets"] == "000C00026003", "5's diagnosis octets: %r" % shown)
    check(shown["configuration (Chk_Cfg)"] == want["cfg"], "5's Chk_Cfg: %r" % shown)
    check(shown["PD configuration"] == "3PD + PARAM", "the DFP21B's PD configuration: %r" % shown)
    check(shown["parameter channel"] == "yes (8 octets before the PD)",
          "the DFP21B's parameter channel: %r" % shown)
    d = want["dfp21b"]
    check((shown["control word"] or "").startswith(d["control_word"] + " ") and
          (shown["status word"] or "").startswith(d["status_word"] + " "),
          "the DFP21B's control and status word: %r" % shown)

    def events():
        return [li.text for li in drv.find_elements(By.CSS_SELECTOR, "#bus-events li")]
    check(wait_for(lambda: any(t.endswith("slave 5 in data exchange with master 2")
                               for t in events()), PAGE_S),
          "the bus events have 5 entering data exchange: %r" % events())
    errors = [e for e in drv.get_log("browser")
              if e.get("level") == "SEVERE" and e.get("source") != "network"]
    check(not errors, "no error in the page: %r" % errors)

    time.sleep(2.5)  # a few of the page's polls more
    made = requests_made(drv)
    others = [r for r in made if r[0] != "GET" and r != ("POST", run.base + "/api/v1/login")]
    check(("POST", run.base + "/api/v1/login") in made,
          "the record holds the login's POST (it sees more than GETs): %r" % made)
    check(not others, "the page sent nothing but GETs after its login: %r" % others)
    check(sum(1 for r in made if r[1] == run.base + "/api/v1/bus") >= 2,
          "the page read GET /api/v1/bus: %r" % made)


def main():
    sim = sys.argv[1]
    missing = missing_tools()
    if missing:
        msg = "monitor_panel: missing " + ", ".join(missing)
        if "--require-tools" in sys.argv[2:]:
            print(msg + " (required: DFP_REQUIRE_INTEROP=ON)")
            return 1
        print(msg + ": skipped")
        return SKIP
    with tempfile.TemporaryDirectory(prefix="dfp-mon-panel-") as tmp:
        run, doc = start(sim, tmp)
        drv = None
        try:
            drv = browser()
            check_page(drv, run, doc)
        finally:
            if drv is not None:
                drv.quit()
            rc = run.stop()
        out = run.read(run.mon_out)
        check(rc == 0, "SIGINT: the monitor exits 0 (exit %s):\n%s" % (rc, out))
        audit = [ln for ln in out.splitlines() if " http " in ln]
        check(len(audit) == 1 and audit[0].endswith(" login operator -> 200"),
              "the server's audit: the login and no action: %r" % audit)
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
