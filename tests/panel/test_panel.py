"""The web front panel (sim_host/http/www) in a real browser against a running `dfp-sim demo`.

Starts `dfp-sim demo --http PORT` with a known operator and viewer token ($DFP_SIM_TOKEN,
$DFP_SIM_VIEWER_TOKEN), waits for the end of the demo's timeline (card in Data_Exch, drive at
300 rpm), opens the panel in headless chromium through selenium as `/?token=TOKEN` (the URL
dfp-sim prints) and checks that it shows what GET /api/v1/state says, that its DI00 switch
inhibits the drive, that a bad request answers 400 without harming the simulation, the login
(form, wrong token, the token gone from the address, the HttpOnly cookie, log out, a 401
bringing the form back, the viewer's disabled controls), that a page of another origin can
neither act (no-cors fetch, sendBeacon, a form) nor frame the panel, the bus page (the bus
monitor's live list and a station's details), and that SIGINT ends dfp-sim with exit status 0. The tool checks and the command-line options are in conftest.py.
"""
import json
import os
import re
import signal
import socket
import subprocess
import tempfile
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

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

TOKEN = "panel-test-operator-0123456789abcdef"
VIEWER_TOKEN = "panel-test-viewer-0123456789abcdef"

PANEL_IDS = ("led-run", "led-bus-fault", "dp-state", "card-address", "speed-actual",
             "speed-setpoint", "current", "fault-name", "status-text", "di00", "cable",
             "power-cycle", "master-run", "log", "plot", "param-search", "param-results",
             "conn-status")


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def http(base, method, path, body=None, timeout=5, token=TOKEN):
    """(status, parsed JSON body or None) for one request with the token (Bearer); HTTP errors
    are returned, not raised."""
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method)
    if data is not None:
        req.add_header("Content-Type", "application/json")
    if token:
        req.add_header("Authorization", "Bearer " + token)
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


def start_demo(exe, port, log_path, args=()):
    """`dfp-sim demo --http PORT ARGS` with the test's tokens -> (Sim, True once its API
    answers, False if it ended or did not answer within STARTUP_S)."""
    logf = open(log_path, "w")
    env = dict(os.environ, DFP_SIM_TOKEN=TOKEN, DFP_SIM_VIEWER_TOKEN=VIEWER_TOKEN)
    proc = subprocess.Popen([exe, "demo", "--http", str(port)] + list(args), stdout=logf,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=env)
    logf.close()
    s = Sim(proc, "http://127.0.0.1:%d" % port, log_path)
    deadline = time.monotonic() + STARTUP_S
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            status, _ = http(s.base, "GET", "/api/v1/state", timeout=2)
            if status == 200:
                return s, True
        except OSError:
            pass
        time.sleep(0.1)
    return s, False


@pytest.fixture(scope="module")
def sim(pytestconfig, out_dir):
    exe = pytestconfig.getoption("dfp_sim")
    log_path = os.path.join(out_dir, "dfp-sim.log")
    proc = None
    for _attempt in range(3):  # the port picked may be taken between bind() and dfp-sim's
        port = free_port()
        s, up = start_demo(exe, port, log_path)
        proc = s.proc
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


def panel_shown(drv):
    """The panel (not the login form) connected to the stream and showing a card."""
    return (drv.execute_script("return document.body.dataset.view") == "panel" and
            page_text(drv, "conn-status") == "connected" and
            page_text(drv, "dp-state") not in ("", "–"))


def login_shown(drv):
    return (drv.execute_script("return document.body.dataset.view") == "login" and
            drv.find_element(By.ID, "login-token").is_displayed())


def open_with_token(drv, base, token):
    """The URL dfp-sim prints at start, in a browser without a session."""
    drv.get(base + "/")
    drv.delete_all_cookies()
    drv.get(base + "/?token=" + urllib.parse.quote(token, safe=""))
    wait_for(lambda: panel_shown(drv), PAGE_S, "the panel connected and showing a card")


def open_logged_out(drv, base):
    drv.get(base + "/")
    drv.delete_all_cookies()
    drv.get(base + "/")
    wait_for(lambda: login_shown(drv), PAGE_S, "the login form")


def log_in_with_the_form(drv, token):
    field = drv.find_element(By.ID, "login-token")
    field.clear()
    field.send_keys(token)
    drv.find_element(By.ID, "login-button").click()


def session_cookie(drv):
    return next((c for c in drv.get_cookies() if c["name"] == "dfp_session"), None)


def page_fetch(drv, method, path, body=None):
    """(status, text) of a fetch the panel's own page makes (same origin: its cookie)."""
    return drv.execute_async_script("""
        const [method, path, body, done] = arguments;
        const opt = {method: method, credentials: 'same-origin', headers: {}};
        if (method !== 'GET') { opt.headers['Content-Type'] = 'application/json'; opt.body = body; }
        fetch(path, opt).then(async (r) => done([r.status, await r.text()]),
                              (e) => done([0, String(e)]));
    """, method, path, None if body is None else json.dumps(body))


@pytest.fixture(scope="module")
def page(sim, browser):
    open_with_token(browser, sim.base, TOKEN)
    return browser


def test_page_has_its_elements(page):
    for eid in PANEL_IDS:
        assert page.find_elements(By.ID, eid), "no element with id %r on the panel" % eid
    assert page.find_element(By.ID, "plot").tag_name == "canvas"
    for eid in ("led-run", "led-bus-fault"):
        assert page.find_element(By.ID, eid).get_attribute("data-mode") in ("off", "on", "blink")
    assert page.find_element(By.ID, "di00").is_enabled(), "controls disabled for the operator"
    assert not page.find_element(By.ID, "ro-badge").is_displayed()
    assert page.find_element(By.ID, "logout").is_displayed()
    assert not page.find_element(By.ID, "login").is_displayed()


def test_token_is_gone_from_the_address_and_the_cookie_is_httponly(sim, page):
    href = page.execute_script("return location.href")
    assert href == sim.base + "/", href
    assert TOKEN not in page.current_url
    cookie = session_cookie(page)
    assert cookie is not None, page.get_cookies()
    assert cookie["httpOnly"] is True and cookie.get("sameSite") == "Strict", cookie
    assert cookie["value"] and TOKEN not in cookie["value"]
    # the page's scripts cannot read it (nor could an injected one)
    assert "dfp_session" not in page.execute_script("return document.cookie")


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


def bus_station(doc, address):
    return next((st for st in doc["stations"] if st["address"] == address), None)


def bus_row(drv, address, cls):
    return drv.find_element(By.CSS_SELECTOR, "#bus-st-%d .%s" % (address, cls)).text.strip()


def bus_detail(drv, key):
    rows = drv.find_elements(By.CSS_SELECTOR, '#bus-detail tr[data-key="%s"] td' % key)
    return rows[0].text.strip() if rows else None


def test_bus_page_shows_the_live_list_and_a_station(sim, page):
    """The bus page against GET /api/v1/bus: the demo's master and its card in the live list,
    the card's details on a click, the bus events from the stream; back to the card after."""
    card = first_card(get_state(sim.base))["address"]
    master = get_state(sim.base)["master"]["address"]

    def card_in_dx():
        status, doc = http(sim.base, "GET", "/api/v1/bus")
        st = bus_station(doc, card) if status == 200 else None
        return st is not None and st["dp"] and st["dp"]["state"] == "Data_Exch" and doc
    doc = wait_for(card_in_dx, PAGE_S, "the monitor's card in Data_Exch")
    assert bus_station(doc, card)["dp"]["ident"] == "0x6003"
    assert bus_station(doc, card)["dp"]["master"] == master
    assert bus_station(doc, master)["role"] == "active"
    assert master in doc["ring"]["members"]
    try:
        page.find_element(By.ID, "tab-bus").click()
        assert page.execute_script("return document.body.dataset.page") == "bus"
        assert page.find_element(By.ID, "bus-page").is_displayed()
        assert not page.find_element(By.ID, "layout").is_displayed()

        def listed():
            return (bus_row(page, card, "c-state") == "Data_Exch" and
                    bus_row(page, card, "c-ident") == "0x6003" and
                    bus_row(page, card, "c-master") == str(master) and
                    bus_row(page, master, "c-role").startswith("active") and
                    page.find_element(By.ID, "bus-st-%d" % card).get_attribute("data-warn")
                    != "now")
        wait_for(listed, PAGE_S, "the live list with master %d and card %d" % (master, card))
        page.find_element(By.ID, "bus-st-%d" % master).click()
        wait_for(lambda: page_text(page, "bus-sel") == str(master), PAGE_S, "the master's details")
        assert bus_detail(page, "state") is None, "a master has no DP slave details"
        page.find_element(By.ID, "bus-st-%d" % card).click()
        wait_for(lambda: page_text(page, "bus-sel") == str(card), PAGE_S, "the card's details")
        assert bus_detail(page, "state") == "Data_Exch"
        assert bus_detail(page, "ident") == "0x6003"
        assert bus_detail(page, "master") == str(master)
        assert bus_detail(page, "configuration (Chk_Cfg)") == bus_station(doc, card)["dp"]["cfg"]
        assert bus_detail(page, "diagnosis") not in (None, "", "–")
        assert bus_detail(page, "PD configuration") not in (None, "", "–"), "no DFP21B names"
        assert page.find_elements(By.CSS_SELECTOR, "#bus-stations tr.sel#bus-st-%d" % card)
        events = [e.text for e in page.find_elements(By.CSS_SELECTOR, "#bus-events li")]
        assert any("data exchange" in t for t in events), events
        assert all(li.get_attribute("data-kind") == "bus"
                   for li in page.find_elements(By.CSS_SELECTOR, "#bus-events li"))
        assert page.execute_script("return location.hash") == "#bus"
        assert not js_errors(page), js_errors(page)
    finally:
        page.find_element(By.ID, "tab-card-%d" % card).click()
    assert page.execute_script("return document.body.dataset.page") == "cards"
    assert page.find_element(By.ID, "layout").is_displayed()
    assert page.execute_script("return location.hash") == ""


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


# ---- another origin ------------------------------------------------------------------------
# The attacker's pages are served from 127.0.0.1 on another port: another origin but the same
# site, so the browser sends the panel's SameSite=Strict cookie along with their requests and
# only the server's own checks (Origin, Content-Type) stand in the way.

ATTACK_PAGE = """<!DOCTYPE html><html><head><title>attacker</title></head><body>
<iframe name="sink"></iframe>
<form id="f" method="POST" action="%(panel)s/api/v1/master/run" enctype="text/plain"
      target="sink"><input name='{"running": false, "x": "' value='"}'></form>
<script>
(async () => {
  const url = '%(panel)s/api/v1/master/run';
  const body = '{"running": false}';
  try {
    await fetch(url, {method: 'POST', mode: 'no-cors', body: body, credentials: 'include'});
  } catch (e) { /* refused or not: the server's log tells */ }
  navigator.sendBeacon(url, body);
  document.getElementById('f').submit();
  document.title = 'sent';
})();
</script></body></html>"""

FRAME_PAGE = """<!DOCTYPE html><html><head><title>decoy</title></head><body>
<iframe id="victim" src="%(panel)s/" width="900" height="600"></iframe>
<script>
document.getElementById('victim').addEventListener('load', () => { document.title = 'framed'; });
</script></body></html>"""


@pytest.fixture(scope="module")
def attacker(sim):
    """Base URL of a server of another origin with /attack.html and /frame.html."""
    pages = {"/attack.html": ATTACK_PAGE % {"panel": sim.base},
             "/frame.html": FRAME_PAGE % {"panel": sim.base}}

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

        def do_GET(self):
            body = pages.get(self.path, "not here").encode()
            self.send_response(200 if self.path in pages else 404)
            self.send_header("Content-Type", "text/html; charset=utf-8")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    srv = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    srv.daemon_threads = True
    t = threading.Thread(target=srv.serve_forever, args=(0.05,), daemon=True)
    t.start()
    try:
        yield "http://127.0.0.1:%d" % srv.server_address[1]
    finally:
        srv.shutdown()
        srv.server_close()


def refused_run_requests(base):
    """Audit lines of refused POSTs of /api/v1/master/run (docs/api.md, "Audit")."""
    status, log = http(base, "GET", "/api/v1/log?since=0")
    assert status == 200, status
    return [e["text"] for e in log if e.get("kind") == "audit" and
            "POST /api/v1/master/run" in e.get("text", "") and
            re.search(r"-> 4\d\d", e.get("text", ""))]


def test_another_origin_cannot_act(sim, page, attacker):
    assert get_state(sim.base)["master"]["running"] is True
    assert session_cookie(page) is not None, "the browser holds no session to abuse"
    before = len(refused_run_requests(sim.base))
    page.get(attacker + "/attack.html")
    wait_for(lambda: page.title == "sent", PAGE_S, "the attack page's requests sent")
    # fetch, beacon and form all reach dfp-sim: refused there, or the master stops
    wait_for(lambda: (len(refused_run_requests(sim.base)) - before >= 3 or
                      not get_state(sim.base)["master"]["running"]), PAGE_S,
             "three refused POSTs of /api/v1/master/run in the log, or the master stopped")
    st = get_state(sim.base)
    assert st["master"]["running"] is True, "a page of another origin stopped the master"
    assert len(refused_run_requests(sim.base)) - before >= 3
    assert first_card(st)["dp"]["state"] == "Data_Exch"
    page.get_log("browser")  # the attack page's own console lines are not the panel's


def test_the_panel_refuses_to_be_framed(sim, page, attacker):
    page.get(attacker + "/frame.html")
    wait_for(lambda: page.title == "framed", PAGE_S, "the decoy's frame loaded")
    page.switch_to.frame(page.find_element(By.ID, "victim"))
    try:
        found = [eid for eid in ("topbar", "login", "layout", "di00", "master-run")
                 if page.find_elements(By.ID, eid)]
    finally:
        page.switch_to.default_content()
    assert found == [], "the panel rendered inside another origin's frame: %s" % found
    page.get_log("browser")


# ---- login, log out, the viewer ------------------------------------------------------------

def test_without_token_the_login_form_and_no_state(sim, browser):
    open_logged_out(browser, sim.base)
    assert not browser.find_element(By.ID, "layout").is_displayed()
    assert not browser.find_element(By.ID, "login-error").is_displayed()
    assert browser.find_element(By.ID, "login-token").get_attribute("type") == "password"
    shown = browser.execute_script("return document.getElementById('dp-state').textContent")
    assert shown == "–", shown
    asked = browser.execute_script(
        "return performance.getEntriesByType('resource').map((e) => e.name)")
    assert not [u for u in asked if re.search(r"/api/v1/(state|events|log|params)", u)], asked
    assert session_cookie(browser) is None


def test_a_wrong_token_in_the_form_stays_on_the_form(sim, browser):
    open_logged_out(browser, sim.base)
    log_in_with_the_form(browser, "not-the-token-0123456789")
    wait_for(lambda: browser.find_element(By.ID, "login-error").is_displayed(), PAGE_S,
             "the login form's error line")
    assert "401" in page_text(browser, "login-error")
    assert login_shown(browser)
    assert not browser.find_element(By.ID, "layout").is_displayed()
    assert session_cookie(browser) is None


def test_the_right_token_in_the_form_opens_the_panel(sim, browser):
    open_logged_out(browser, sim.base)
    log_in_with_the_form(browser, TOKEN)
    wait_for(lambda: panel_shown(browser), PAGE_S, "the panel after the form's login")
    assert browser.find_element(By.ID, "di00").is_enabled()
    assert TOKEN not in browser.current_url
    assert browser.find_element(By.ID, "login-token").get_attribute("value") == ""


def test_a_401_brings_the_login_form_back(sim, browser):
    """The session gone (as when dfp-sim was started again): the next call answers 401."""
    open_with_token(browser, sim.base, TOKEN)
    browser.delete_cookie("dfp_session")
    browser.find_element(By.ID, "param-search").send_keys("P13")
    wait_for(lambda: login_shown(browser), PAGE_S, "the login form after a 401")
    assert "log in again" in page_text(browser, "login-error")
    log_in_with_the_form(browser, TOKEN)
    wait_for(lambda: panel_shown(browser), PAGE_S, "the panel and its stream after logging in")


def test_log_out(sim, browser):
    open_with_token(browser, sim.base, TOKEN)
    browser.find_element(By.ID, "logout").click()
    wait_for(lambda: login_shown(browser), PAGE_S, "the login form after Log out")
    # the event stream closed, not left to retry against 401s
    assert browser.execute_script("return es === null && "
                                  "document.getElementById('conn-status').textContent") == \
        "logged out"
    cookie = session_cookie(browser)
    assert cookie is None or cookie["value"] == "", cookie
    status, _ = page_fetch(browser, "GET", "api/v1/state")
    assert status == 401
    assert get_state(sim.base)["master"]["running"] is True


def test_viewer_sees_the_panel_with_every_action_disabled(sim, browser):
    open_with_token(browser, sim.base, VIEWER_TOKEN)
    badge = browser.find_element(By.ID, "ro-badge")
    assert badge.is_displayed() and badge.text.strip() == "read-only (viewer)"
    controls = browser.find_elements(By.CSS_SELECTOR, ".ctl")
    assert len(controls) > 20, len(controls)
    enabled = [c.get_attribute("id") or c.tag_name for c in controls if c.is_enabled()]
    assert enabled == [], "action controls enabled for a viewer: %s" % enabled
    assert browser.find_element(By.ID, "logout").is_displayed()
    # the server, not only the page, holds the viewer to reading
    status, text = page_fetch(browser, "POST", "api/v1/master/run", {"running": False})
    assert status == 403, (status, text)
    assert json.loads(text) == {"error": "this needs the operator role; this client is a viewer"}
    assert get_state(sim.base)["master"]["running"] is True
    assert not js_errors(browser), js_errors(browser)


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


def stop(s):
    s.proc.send_signal(signal.SIGINT)
    try:
        return s.proc.wait(timeout=SIGINT_S)
    except subprocess.TimeoutExpired:
        s.proc.kill()
        s.proc.wait()
        return None


def test_a_restarted_dfp_sim_brings_the_login_form_back(pytestconfig, sim, browser, out_dir):
    """dfp-sim started again behind the same address (the sessions died with the old one): the
    open panel's stream gets 401, the login form comes back, and after logging in the panel
    and its stream carry on."""
    assert sim.proc.poll() is not None, "the first dfp-sim still runs"
    assert browser.execute_script("return document.body.dataset.view") == "panel"
    port = int(sim.base.rsplit(":", 1)[1])
    again, up = start_demo(pytestconfig.getoption("dfp_sim"), port,
                           os.path.join(out_dir, "dfp-sim-again.log"))
    try:
        assert up, "dfp-sim did not start again on port %d:\n%s" % (port, again.output_tail())
        wait_for(lambda: login_shown(browser), PAGE_S, "the login form after the restart")
        assert "log in again" in page_text(browser, "login-error")
        log_in_with_the_form(browser, TOKEN)
        wait_for(lambda: panel_shown(browser), PAGE_S, "the panel and its stream again")
        assert browser.find_element(By.ID, "di00").is_enabled()
    finally:
        stop(again)


def test_no_auth_opens_the_panel_without_login(pytestconfig, browser, out_dir):
    """--http-no-auth (loopback only): every browser is operator, no form, no Log out."""
    nolog, up = start_demo(pytestconfig.getoption("dfp_sim"), free_port(),
                           os.path.join(out_dir, "dfp-sim-no-auth.log"), ["--http-no-auth"])
    try:
        assert up, "dfp-sim --http-no-auth did not start:\n" + nolog.output_tail()
        browser.delete_all_cookies()
        browser.get(nolog.base + "/")
        wait_for(lambda: panel_shown(browser), PAGE_S, "the panel without a login")
        assert browser.find_element(By.ID, "di00").is_enabled()
        assert not browser.find_element(By.ID, "logout").is_displayed()
        assert session_cookie(browser) is None
        assert not js_errors(browser), js_errors(browser)
    finally:
        stop(nolog)
