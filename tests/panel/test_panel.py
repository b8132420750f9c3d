"""The web front panel (sim_host/http/www) in a real browser against a running `dfp-sim demo`.

Starts `dfp-sim demo --http PORT`, waits for the end of the demo's timeline (card in Data_Exch,
drive at 300 rpm), loads the panel in headless chromium through selenium and checks that it
shows what GET /api/v1/state says, that its DI00 switch inhibits the drive, that a bad request
answers 400 without harming the simulation, and that SIGINT ends dfp-sim with exit status 0.
The tool checks and the command-line options are in conftest.py.
"""
import json
import os
import signal
import socket
import subprocess
import tempfile
import time
import urllib.error
import urllib.request

import pytest

from conftest import CHROMEDRIVER_NAMES, CHROMIUM_NAMES, find_program

# selenium must never try to download a browser or a driver (no internet on CI machines).
os.environ.setdefault("SE_OFFLINE", "true")
os.environ.setdefault("SE_AVOID_STATS", "true")

from selenium import webdriver  # noqa: E402  (after the environment above)
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

STARTUP_S = 60        # dfp-sim answering and the demo's timeline over
PAGE_S = 15           # the page loaded and showing the state
DI00_S = 10           # the drive stopped after DI00 off
SIGINT_S = 5          # dfp-sim gone after SIGINT

PANEL_IDS = ("led-run", "led-bus-fault", "dp-state", "card-address", "speed-actual",
             "speed-setpoint", "current", "fault-name", "status-text", "di00", "cable",
             "power-cycle", "master-run", "log", "plot", "param-search", "param-results",
             "conn-status")


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http(base, method, path, body=None, timeout=5):
    """(status, parsed JSON body or None) for one request; HTTP errors are returned, not raised."""
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method)
    if data is not None:
        req.add_header("Content-Type", "application/json")
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            raw, status = r.read(), r.status
    except urllib.error.HTTPError as e:
        raw, status = e.read(), e.code
    try:
        return status, json.loads(raw.decode("utf-8"))
    except ValueError:
        return status, None


def get_state(base):
    status, st = http(base, "GET", "/api/v1/state")
    assert status == 200, "GET /api/v1/state answered %s" % status
    return st


def first_card(st):
    assert st["cards"], "no card in the state"
    return st["cards"][0]


def wait_for(cond, timeout, what, interval=0.1):
    """Calls cond() until it returns something true; fails with what and the last value."""
    deadline = time.monotonic() + timeout
    last = None
    while True:
        try:
            last = cond()
        except AssertionError as e:
            last = e
        if last and not isinstance(last, AssertionError):
            return last
        if time.monotonic() >= deadline:
            pytest.fail("timed out after %s s waiting for %s (last: %r)" % (timeout, what, last))
        time.sleep(interval)


class Sim:
    def __init__(self, proc, base, log_path):
        self.proc, self.base, self.log_path = proc, base, log_path

    def output_tail(self, n=40):
        try:
            with open(self.log_path, "r", errors="replace") as f:
                return "".join(f.readlines()[-n:])
        except OSError:
            return ""


@pytest.fixture(scope="module")
def out_dir(pytestconfig):
    d = pytestconfig.getoption("out") or tempfile.mkdtemp(prefix="dfp-panel-")
    os.makedirs(d, exist_ok=True)
    return d


@pytest.fixture(scope="module")
def sim(pytestconfig, out_dir):
    exe = pytestconfig.getoption("dfp_sim")
    log_path = os.path.join(out_dir, "dfp-sim.log")
    proc = None
    for _attempt in range(3):  # the port picked may be taken between bind() and dfp-sim's
        port = free_port()
        logf = open(log_path, "w")
        proc = subprocess.Popen([exe, "demo", "--http", str(port)], stdout=logf,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        logf.close()
        s = Sim(proc, "http://127.0.0.1:%d" % port, log_path)
        deadline = time.monotonic() + STARTUP_S
        up = False
        while time.monotonic() < deadline and proc.poll() is None:
            try:
                status, _ = http(s.base, "GET", "/api/v1/state", timeout=2)
                if status == 200:
                    up = True
                    break
            except OSError:
                pass
            time.sleep(0.1)
        if up:
            break
        if proc.poll() == 2:  # "port taken": try another one
            continue
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        pytest.fail("dfp-sim demo --http %d did not answer within %s s (exit %s):\n%s"
                    % (port, STARTUP_S, proc.returncode, s.output_tail()))
    else:
        pytest.fail("dfp-sim could not bind a port three times:\n" + s.output_tail())

    def timeline_over():
        st = get_state(s.base)
        c = first_card(st)
        d = c.get("drive") or {}
        return (c["dp"]["state"] == "Data_Exch" and
                (d.get("speed_actual_rpm") or 0) >= 299) and st
    try:
        wait_for(timeline_over, STARTUP_S, "the demo in Data_Exch at 300 rpm")
        yield s
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def browser():
    opts = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1400,1000", "--no-first-run", "--disable-extensions"):
        opts.add_argument(a)
    opts.binary_location = find_program(CHROMIUM_NAMES, "DFP_CHROMIUM")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(executable_path=find_program(CHROMEDRIVER_NAMES, "DFP_CHROMEDRIVER"))
    drv = webdriver.Chrome(service=service, options=opts)
    drv.set_page_load_timeout(PAGE_S)
    try:
        yield drv
    finally:
        drv.quit()


def page_text(drv, eid):
    return drv.find_element(By.ID, eid).text.strip()


def page_number(drv, eid):
    t = page_text(drv, eid)
    try:
        return float(t)
    except ValueError:
        return None


def js_errors(drv):
    """SEVERE console entries that come from the panel's own code (not the network)."""
    return [e for e in drv.get_log("browser")
            if e.get("level") == "SEVERE" and e.get("source") != "network"]


@pytest.fixture(scope="module")
def page(sim, browser):
    browser.get(sim.base + "/")
    wait_for(lambda: page_text(browser, "conn-status") == "connected" and
             page_text(browser, "dp-state") not in ("", "–"), PAGE_S,
             "the panel connected and showing a card")
    return browser


def test_page_has_its_elements(page):
    for eid in PANEL_IDS:
        assert page.find_elements(By.ID, eid), "no element with id %r on the panel" % eid
    assert page.find_element(By.ID, "plot").tag_name == "canvas"
    for eid in ("led-run", "led-bus-fault"):
        assert page.find_element(By.ID, eid).get_attribute("data-mode") in ("off", "on", "blink")
    assert page.find_element(By.ID, "di00").is_enabled(), "controls disabled on a writable server"


def test_page_shows_the_state(sim, page):
    def matches():
        st = get_state(sim.base)
        c = first_card(st)
        d = c["drive"]
        shown = {
            "run": page.find_element(By.ID, "led-run").get_attribute("data-mode"),
            "bus_fault": page.find_element(By.ID, "led-bus-fault").get_attribute("data-mode"),
            "dp": page_text(page, "dp-state"),
            "address": page_text(page, "card-address"),
            "speed": page_number(page, "speed-actual"),
        }
        ok = (shown["run"] == c["leds"]["run"] and shown["bus_fault"] == c["leds"]["bus_fault"] and
              shown["dp"] == c["dp"]["state"] and shown["address"] == str(c["address"]) and
              shown["speed"] is not None and abs(shown["speed"] - d["speed_actual_rpm"]) <= 1.0)
        assert ok, {"page": shown, "api": {"leds": c["leds"], "dp": c["dp"]["state"],
                                           "address": c["address"],
                                           "speed": d["speed_actual_rpm"]}}
        return True
    wait_for(matches, PAGE_S, "the page to match GET /api/v1/state")
    st = get_state(sim.base)
    c = first_card(st)
    assert c["leds"]["run"] == "on" and c["dp"]["state"] == "Data_Exch"
    assert page.find_element(By.ID, "led-run").get_attribute("data-mode") == "on"
    assert page_number(page, "speed-actual") >= 299
    assert page.find_element(By.ID, "di00").is_selected(), "DI00 switch off while DI00 = +24 V"
    assert page.find_elements(By.CSS_SELECTOR, "#log li"), "the log shows no line"
    assert not js_errors(page), js_errors(page)


def test_parameter_service_over_class2(sim, page):
    """The parameter-service box with via c2 shows what a class-1 read through the API gives."""
    status, c1 = http(sim.base, "POST", "/api/v1/master/param",
                      {"slave": 4, "op": "read", "param": "P100", "via": "channel"}, timeout=10)
    assert status == 200 and c1["ok"] is True, (status, c1)
    want = "P100 (8461) %s = %s" % (c1["name"], c1["text"])
    slave = page.find_element(By.ID, "ps-slave")
    slave.clear()
    slave.send_keys("4")
    Select(page.find_element(By.ID, "ps-via")).select_by_value("c2")
    Select(page.find_element(By.ID, "ps-op")).select_by_value("read")
    param = page.find_element(By.ID, "ps-param")
    param.clear()
    param.send_keys("P100")
    page.find_element(By.ID, "ps-send").click()
    wait_for(lambda: page_text(page, "ps-result") not in ("", "…"), PAGE_S,
             "the class-2 service's answer on the panel")
    assert page_text(page, "ps-result") == want
    assert page.find_element(By.ID, "ps-result").get_attribute("data-ok") == "1"
    assert "read P100 via c2: ok" in page_text(page, "status-line")


def test_bad_input_answers_400_and_demo_runs_on(sim):
    status, body = http(sim.base, "POST", "/api/v1/cards/4/inputs", {"DI99": True})
    assert status == 400, (status, body)
    assert isinstance(body, dict) and isinstance(body.get("error"), str) and body["error"], body
    assert sim.proc.poll() is None, "dfp-sim exited after a bad request:\n" + sim.output_tail()
    c = first_card(get_state(sim.base))
    assert c["dp"]["state"] == "Data_Exch"
    assert c["drive"]["inputs"]["DI00"] is True, "a refused request touched the simulation"


def test_di00_off_stops_the_drive(sim, page):
    di00 = page.find_element(By.ID, "di00")
    assert di00.is_selected()
    di00.click()

    def stopped():
        c = first_card(get_state(sim.base))
        speed = page_number(page, "speed-actual")
        assert c["drive"]["inputs"]["DI00"] is False, "API: DI00 still true"
        assert c["drive"]["speed_actual_rpm"] == 0, "API: speed %s" % c["drive"]["speed_actual_rpm"]
        assert speed == 0, "page: speed %r" % page_text(page, "speed-actual")
        return True
    wait_for(stopped, DI00_S, "speed 0 on the page and in the API after DI00 off")
    assert not page.find_element(By.ID, "di00").is_selected()
    assert "error" not in (page.find_element(By.ID, "status-line").get_attribute("data-level") or "")


def test_screenshot(page, out_dir):
    time.sleep(0.5)  # one more state event: the plot shows the ramp down
    path = os.path.join(out_dir, "panel.png")
    if os.path.exists(path):
        os.remove(path)
    h = page.execute_script("return document.documentElement.scrollHeight")
    page.set_window_size(1400, max(1000, min(int(h) + 140, 3000)))
    time.sleep(0.3)
    assert page.save_screenshot(path)
    assert os.path.isfile(path)
    with open(path, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n", "not a PNG: " + path
    assert os.path.getsize(path) > 10000
    assert not js_errors(page), js_errors(page)


def test_sigint_ends_dfp_sim(sim):
    assert sim.proc.poll() is None, "dfp-sim ended early:\n" + sim.output_tail()
    sim.proc.send_signal(signal.SIGINT)
    try:
        rc = sim.proc.wait(timeout=SIGINT_S)
    except subprocess.TimeoutExpired:
        sim.proc.kill()
        sim.proc.wait()
        pytest.fail("dfp-sim still running %s s after SIGINT (a browser was connected)" % SIGINT_S)
    assert rc == 0, "dfp-sim exited %s after SIGINT:\n%s" % (rc, sim.output_tail())
