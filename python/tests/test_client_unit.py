"""The client against a small HTTP server in the test (no dfp-sim needed): request bodies,
error mapping, the SSE parser, wait_until's messages, and DfpSim's process handling (with a
stand-in script for dfp-sim)."""

import io
import json
import os
import sys
import textwrap
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from dfpsim import (ApiError, AuthError, Client, DfpSim, DfpSimError, ParamError, ParamResult,
                    free_port, parse_sse, wait_for, wait_until)


class FakeApi:
    """routes[(METHOD, path)] = (status, body); body: dict/list (JSON) or bytes (raw)."""

    def __init__(self):
        self.routes = {}
        self.requests = []  # (method, path, headers, body or None)
        api = self

        class Handler(BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def log_message(self, *args):
                pass

            def _handle(self):
                n = int(self.headers.get("Content-Length") or 0)
                raw = self.rfile.read(n) if n else b""
                body = json.loads(raw) if raw else None
                api.requests.append((self.command, self.path, dict(self.headers), body))
                status, rsp = api.routes.get((self.command, self.path),
                                             (404, {"error": "no such route: " + self.path}))
                ctype = "application/json"
                if isinstance(rsp, (bytes, str)):
                    data = rsp.encode() if isinstance(rsp, str) else rsp
                    if self.path.endswith("/events"):
                        ctype = "text/event-stream"
                    else:
                        ctype = "text/plain"
                else:
                    data = json.dumps(rsp).encode()
                self.send_response(status)
                self.send_header("Content-Type", ctype)
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            do_GET = do_POST = do_PUT = _handle

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.server.daemon_threads = True
        self.url = "http://127.0.0.1:%d" % self.server.server_address[1]
        self.thread = threading.Thread(target=self.server.serve_forever, args=(0.01,),
                                       daemon=True)
        self.thread.start()

    def close(self):
        self.server.shutdown()
        self.server.server_close()


@pytest.fixture
def api():
    a = FakeApi()
    yield a
    a.close()


@pytest.fixture
def client(api, monkeypatch):
    monkeypatch.delenv("DFP_SIM_TOKEN", raising=False)
    return Client(api.url)


CARD = {
    "address": 4, "cable": True, "on_bus": True, "dip": {"address": 4, "next_address": 4},
    "dp": {"state": "Data_Exch", "baud": 19200, "baud_state": "control", "master": 2,
           "watchdog_ms": 100, "config": "F3F2", "diag": {"hex": "0C00"}},
    "leds": {"run": "on", "bus_fault": "off", "run_pattern": "steady",
             "bus_fault_pattern": "off"},
    "monitor": {"po": [6, 1500, 0], "pi": [1031, 1500, 0]},
    "drive": {"control_word": 6, "status_word": 1031, "enabled": True, "fault": 0,
              "fault_name": "no fault", "speed_setpoint_rpm": 300.0,
              "speed_actual_rpm": 212.4, "current_pct": 11.5, "ramp_up_ms": 2000,
              "ramp_down_ms": 2000, "inputs": {"DI00": True}},
}
P100 = {"ok": True, "p_number": "P100", "index": 8461, "name": "setpoint source", "value": 3,
        "text": "3 (FIELDBUS)"}


# ---- reading -------------------------------------------------------------------------------

def test_card_properties_read_the_card_snapshot(api, client):
    api.routes[("GET", "/api/v1/cards/4")] = (200, CARD)
    card = client.card(4)
    assert card.dp_state == "Data_Exch"
    assert card.baud == 19200
    assert card.master_address == 2
    assert card.watchdog_ms == 100
    assert card.leds["bus_fault"] == "off" and card.bus_fault_led == "off"
    assert card.speed_actual_rpm == 212.4
    assert card.speed_setpoint_rpm == 300.0
    assert card.current_pct == 11.5
    assert card.status_word == 0x0407
    assert (card.fault, card.fault_name) == (0, "no fault")
    assert card.inputs == {"DI00": True}
    # every property is a request of its own: nothing cached
    assert sum(1 for r in api.requests if r[1] == "/api/v1/cards/4") == 13


def test_card_without_drive_says_so(api, client):
    api.routes[("GET", "/api/v1/cards/4")] = (200, dict(CARD, drive=None))
    with pytest.raises(DfpSimError, match="card 4 has no drive"):
        client.card(4).speed_actual_rpm


def test_base_url_without_scheme(api):
    api.routes[("GET", "/api/v1/state")] = (200, {"mode": "slave", "master": None})
    c = Client(api.url[len("http://"):] + "/")
    assert c.state()["mode"] == "slave"


def test_log_and_params_queries(api, client):
    api.routes[("GET", "/api/v1/log?since=17")] = (200, [{"seq": 17, "text": "x"}])
    api.routes[("GET", "/api/v1/log?since=0&limit=5")] = (200, [])
    api.routes[("GET", "/api/v1/params?q=ramp+t11")] = (200, [{"p_number": "P130"}])
    assert client.log(since=17) == [{"seq": 17, "text": "x"}]
    assert client.log(limit=5) == []
    assert client.params("ramp t11") == [{"p_number": "P130"}]


def test_master_view_of_a_slave(api, client):
    api.routes[("GET", "/api/v1/state")] = (200, {"master": {
        "address": 2, "running": True, "baud": 19200,
        "slaves": [{"address": 4, "phase": "DATA_EXCH", "cycles": 9, "po": [6, 1500, 0],
                    "pi": [1031, 1500, 0]}]}})
    m = client.master()
    assert m.phase(4) == "DATA_EXCH"
    assert m.in_data_exchange(4) is True
    assert m.po(4) == [6, 1500, 0]
    assert m.pi(4) == [1031, 1500, 0]
    assert m.running is True
    with pytest.raises(DfpSimError, match="no slave 5"):
        m.phase(5)
    api.routes[("GET", "/api/v1/state")] = (200, {"master": None})
    with pytest.raises(DfpSimError, match="has no DP master"):
        m.phase(4)


# ---- actions: what goes on the wire --------------------------------------------------------

def test_action_bodies(api, client):
    ok = (200, {"ok": True})
    for path in ("/api/v1/cards/4/inputs", "/api/v1/cards/4/fault", "/api/v1/cards/4/cable",
                 "/api/v1/cards/4/power-cycle", "/api/v1/cards/4/dip", "/api/v1/master/run",
                 "/api/v1/master/slaves/4/outputs"):
        api.routes[("POST", path)] = ok
    card, m = client.card(4), client.master()
    card.set_input("DI00", False)
    card.inject_fault(14)
    card.pull_cable()
    card.plug_cable()
    card.power_cycle()
    card.set_dip(5)
    m.stop()
    m.run()
    m.set_po(4, [0x0006, 1500])
    m.set_outputs(4, "00" * 8 + "000605DC0000")
    sent = [(r[1].rsplit("/", 1)[1], r[3]) for r in api.requests]
    assert sent == [
        ("inputs", {"DI00": False}),
        ("fault", {"fault": 14}),
        ("cable", {"connected": False}),
        ("cable", {"connected": True}),
        ("power-cycle", {}),
        ("dip", {"address": 5}),
        ("run", {"running": False}),
        ("run", {"running": True}),
        ("outputs", {"po": [6, 1500]}),
        ("outputs", {"hex": "0000000000000000000605DC0000"}),
    ]
    assert all(r[0] == "POST" and r[2]["Content-Type"] == "application/json"
               for r in api.requests)


def test_a_state_changing_request_without_body_is_still_json(api, client):
    api.routes[("POST", "/api/v1/logout")] = (200, {"ok": True})
    client.request("POST", "/api/v1/logout")
    method, _, headers, body = api.requests[-1]
    assert (method, headers["Content-Type"], body) == ("POST", "application/json", None)
    api.routes[("GET", "/api/v1/state")] = (200, {"mode": "demo"})
    client.state()
    assert "Content-Type" not in api.requests[-1][2]


# ---- the token -----------------------------------------------------------------------------

def test_token_goes_as_bearer_on_every_request_and_the_stream(api, monkeypatch):
    monkeypatch.delenv("DFP_SIM_TOKEN", raising=False)
    api.routes[("GET", "/api/v1/state")] = (200, {"mode": "demo"})
    api.routes[("POST", "/api/v1/master/run")] = (200, {"ok": True})
    api.routes[("GET", "/api/v1/events")] = (200, SSE)
    c = Client(api.url, token="op-token-0123456789")
    c.state()
    c.master().stop()
    assert next(c.events())["event"] == "log"
    assert [r[2].get("Authorization") for r in api.requests] == \
        ["Bearer op-token-0123456789"] * 3
    assert "op-token" not in repr(c)


def test_token_from_the_environment_and_none(api, monkeypatch):
    api.routes[("GET", "/api/v1/state")] = (200, {"mode": "demo"})
    monkeypatch.setenv("DFP_SIM_TOKEN", "env-token-0123456789")
    Client(api.url).state()
    assert api.requests[-1][2]["Authorization"] == "Bearer env-token-0123456789"
    Client(api.url, token="given-token-0123456").state()   # an argument wins
    assert api.requests[-1][2]["Authorization"] == "Bearer given-token-0123456"
    Client(api.url, token="").state()                      # "": no token at all
    assert "Authorization" not in api.requests[-1][2]
    monkeypatch.delenv("DFP_SIM_TOKEN")
    Client(api.url).state()
    assert "Authorization" not in api.requests[-1][2]


NEED_TOKEN = ("a token is needed: open the URL dfp-sim printed at start, or send "
              "Authorization: Bearer TOKEN")


def test_401_is_an_auth_error_with_the_servers_text(api, client):
    api.routes[("GET", "/api/v1/state")] = (401, {"error": NEED_TOKEN})
    with pytest.raises(AuthError) as e:
        client.state()
    assert (e.value.status, e.value.message) == (401, NEED_TOKEN)
    assert isinstance(e.value, ApiError)
    api.routes[("GET", "/api/v1/events")] = (401, {"error": NEED_TOKEN})
    with pytest.raises(AuthError, match="a token is needed"):
        next(client.events())


def test_card_parameter_access(api, client):
    api.routes[("GET", "/api/v1/cards/4/params/P100")] = (200, P100)
    api.routes[("GET", "/api/v1/cards/4/params/setpoint%20source")] = (200, P100)
    api.routes[("PUT", "/api/v1/cards/4/params/8461")] = (200, P100)
    card = client.card(4)
    r = card.read_param("P100")
    assert r == ParamResult("P100", 8461, "setpoint source", 3, "3 (FIELDBUS)")
    assert str(r) == "P100 setpoint source = 3 (FIELDBUS)"
    assert card.read_param("setpoint source").text == "3 (FIELDBUS)"
    assert card.write_param(8461, "FIELDBUS", volatile=True).value == 3
    assert api.requests[-1][3] == {"value": "FIELDBUS", "volatile": True}


def test_master_parameter_service(api, client):
    api.routes[("POST", "/api/v1/master/param")] = (200, P100)
    m = client.master()
    assert m.read_param(4, "P100").text == "3 (FIELDBUS)"
    assert api.requests[-1][3] == {"slave": 4, "op": "read", "param": "P100", "via": "channel"}
    m.write_param(4, "P100", "FIELDBUS", via="ds47")
    assert api.requests[-1][3] == {"slave": 4, "op": "write", "param": "P100",
                                   "value": "FIELDBUS", "via": "ds47", "volatile": False}
    m.read_param(5, 8489, via="c2")
    assert api.requests[-1][3] == {"slave": 5, "op": "read", "param": "8489", "via": "c2"}
    m.write_param(5, "P160", 2250, via="c2", volatile=True)
    assert api.requests[-1][3] == {"slave": 5, "op": "write", "param": "P160", "value": 2250,
                                   "via": "c2", "volatile": True}


def test_master_parameter_service_unknown_via_is_refused_before_sending(api, client):
    sent = len(api.requests)
    with pytest.raises(ValueError, match="via 'class2': use one of channel, ds47, c2"):
        client.master().read_param(4, "P100", via="class2")
    assert len(api.requests) == sent


# ---- errors --------------------------------------------------------------------------------

def test_400_is_an_api_error_with_the_servers_text(api, client):
    api.routes[("POST", "/api/v1/cards/4/inputs")] = (
        400, {"error": "unknown input 'DI07' (the emulation models DI00)"})
    with pytest.raises(ApiError) as e:
        client.card(4).set_input("DI07", True)
    assert e.value.status == 400
    assert e.value.message == "unknown input 'DI07' (the emulation models DI00)"
    assert e.value.method == "POST" and e.value.path == "/api/v1/cards/4/inputs"
    assert not isinstance(e.value, ParamError)


@pytest.mark.parametrize("status, message", [
    (403, "read-only server (dfp-sim replay)"),
    (403, "this needs the operator role; this client is a viewer"),
    (415, "Content-Type must be application/json"),
    (404, "no card with address 9"),
    (405, "method not allowed"),
    (409, "no master in dfp-sim slave"),
    (504, "no answer to the parameter service within 5 s"),
])
def test_every_error_status_keeps_its_message(api, client, status, message):
    api.routes[("POST", "/api/v1/master/run")] = (status, {"error": message})
    with pytest.raises(ApiError) as e:
        client.master().stop()
    assert (e.value.status, e.value.message) == (status, message)
    assert message in str(e.value)


def test_error_without_json_body(api, client):
    api.routes[("GET", "/api/v1/state")] = (502, b"Bad Gateway\nfrom a proxy")
    with pytest.raises(ApiError) as e:
        client.state()
    assert (e.value.status, e.value.message) == (502, "Bad Gateway")


def test_refused_master_service_is_a_param_error(api, client):
    api.routes[("POST", "/api/v1/master/param")] = (200, {
        "ok": False, "error": "MOVILINK error: class 8, additional code 0x1C: controller "
                              "inhibit required", "p_number": "P100"})
    with pytest.raises(ParamError) as e:
        client.master().write_param(4, "P100", "FIELDBUS")
    assert e.value.status == 200
    assert e.value.message == ("MOVILINK error: class 8, additional code 0x1C: controller "
                               "inhibit required")
    assert e.value.p_number == "P100"
    assert isinstance(e.value, ApiError)


def test_refused_direct_write_is_a_param_error(api, client):
    api.routes[("PUT", "/api/v1/cards/4/params/P130")] = (
        400, {"error": "MOVILINK error: class 8, additional code 0x15: value too high"})
    with pytest.raises(ParamError) as e:
        client.card(4).write_param("P130", 99999999)
    assert (e.value.status, e.value.p_number) == (400, "P130")
    assert e.value.message.endswith("value too high")


def test_other_400_on_a_direct_write_stays_an_api_error(api, client):
    api.routes[("PUT", "/api/v1/cards/4/params/P100")] = (400, {"error": "value: expected a "
                                                                        "number or a text"})
    with pytest.raises(ApiError) as e:
        client.card(4).write_param("P100", [1])
    assert not isinstance(e.value, ParamError)


def test_action_answering_ok_false_raises(api, client):
    api.routes[("POST", "/api/v1/cards/4/fault")] = (200, {"ok": False, "error": "no drive"})
    with pytest.raises(ApiError, match="no drive"):
        client.card(4).inject_fault(1)


def test_connection_refused_is_an_oserror():
    port = free_port()
    with pytest.raises(OSError):
        Client("http://127.0.0.1:%d" % port, timeout=1).state()


# ---- Server-Sent Events --------------------------------------------------------------------

SSE = (
    b": a comment the parser skips\n"
    b"retry: 1000\n"
    b"\n"
    b"event: log\n"
    b"id: 1042\n"
    b'data: {"seq":1042,"kind":"dp_state","text":"Wait_Cfg -> Data_Exch (master 2)"}\n'
    b"\n"
    b"event: state\r\n"
    b'data: {"t_us": 5,\r\n'
    b'data:  "mode": "demo"}\r\n'
    b": comment inside an event\r\n"
    b"\r\n"
    b"event: nothing\n"
    b"\n"
    b"data:no space after the colon\n"
    b"data\n"
    b"\n"
    b"event: log\n"
    b"data: {\"seq\": 1043}\n"
    b"id\n"
    b"\n"
    b"data: the stream ends before this blank line"
)

EXPECTED = [
    {"event": "log", "id": "1042",
     "data": {"seq": 1042, "kind": "dp_state", "text": "Wait_Cfg -> Data_Exch (master 2)"}},
    {"event": "state", "id": "1042", "data": {"t_us": 5, "mode": "demo"}},
    {"event": "message", "id": "1042", "data": "no space after the colon\n"},
    {"event": "log", "id": "", "data": {"seq": 1043}},
]


def test_sse_parser():
    assert list(parse_sse(io.BytesIO(SSE))) == EXPECTED


def test_events_stream(api, client):
    api.routes[("GET", "/api/v1/events")] = (200, SSE)
    assert list(client.events()) == EXPECTED
    assert api.requests[-1][2]["Accept"] == "text/event-stream"
    assert "Last-Event-ID" not in api.requests[-1][2]


def test_events_resume_after_an_id(api, client):
    api.routes[("GET", "/api/v1/events")] = (200, SSE)
    events = client.events(last_event_id=1041)
    assert next(events)["id"] == "1042"
    events.close()
    assert api.requests[-1][2]["Last-Event-ID"] == "1041"


def test_events_error_status(api, client):
    api.routes[("GET", "/api/v1/events")] = (403, {"error": "too many streams"})
    with pytest.raises(ApiError) as e:
        next(client.events())
    assert (e.value.status, e.value.message) == (403, "too many streams")


# ---- wait_until / wait_for -----------------------------------------------------------------

def test_wait_until_returns_the_true_value():
    values = iter([0, 0, 0, 7])
    assert wait_until(lambda: next(values), timeout=1, interval=0.001) == 7


def test_wait_until_timeout_names_what_and_the_last_value():
    t0 = time.monotonic()
    with pytest.raises(TimeoutError) as e:
        wait_until(lambda: None, timeout=0.2, interval=0.05, what="Data_Exch at card 4")
    assert 0.2 <= time.monotonic() - t0 < 1.0
    msg = str(e.value)
    assert "after 0.2 s" in msg
    assert "waiting for Data_Exch at card 4" in msg
    assert msg.endswith("last value seen: None")


def test_wait_until_default_what_is_the_function_name():
    def drive_ready():
        return False
    with pytest.raises(TimeoutError, match="waiting for drive_ready .*last value seen: False"):
        wait_until(drive_ready, timeout=0.05)


def test_wait_until_against_a_card(api, client):
    api.routes[("GET", "/api/v1/cards/4")] = (200, CARD)
    drive = client.card(4)
    with pytest.raises(TimeoutError, match=r"speed >= 299\.5 rpm .*last value seen: False"):
        wait_until(lambda: drive.speed_actual_rpm >= 299.5, timeout=0.1, what="speed >= 299.5 rpm")
    with pytest.raises(TimeoutError, match=r"last value seen: 212\.4$"):
        wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm >= 299.5, timeout=0.1,
                 what="speed >= 299.5 rpm")
    assert wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm > 200) == 212.4


def test_wait_until_checks_once_more_at_the_deadline():
    t_end = time.monotonic() + 0.1
    # true only from the deadline on; a poll interval far beyond it must not hide that
    assert wait_until(lambda: time.monotonic() >= t_end, timeout=0.1, interval=10) is True


def test_wait_until_does_not_swallow_errors():
    with pytest.raises(ZeroDivisionError):
        wait_until(lambda: 1 / 0, timeout=1)


# ---- DfpSim with a stand-in for dfp-sim ----------------------------------------------------

FAKE_SIM = textwrap.dedent("""\
    #!%s
    # stand-in for dfp-sim: serves /api/v1/state on --http; SIGINT ends it with $FAKE_RC
    import json, os, signal, sys, threading
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
    args = sys.argv[1:]
    host, _, port = args[args.index("--http") + 1].rpartition(":")
    if os.environ.get("FAKE_DIE"):
        print("fake: dying at start-up", file=sys.stderr)
        sys.exit(3)
    class H(BaseHTTPRequestHandler):
        def log_message(self, *a):
            pass
        def do_GET(self):
            # as dfp-sim: the token from the environment, and nothing without it
            ok = self.headers.get("Authorization") == "Bearer " + os.environ["DFP_SIM_TOKEN"]
            b = json.dumps({"mode": args[0], "argv": args, "token": os.environ["DFP_SIM_TOKEN"]}
                           if ok else {"error": "a token is needed"}).encode()
            self.send_response(200 if ok else 401)
            self.send_header("Content-Length", str(len(b)))
            self.end_headers()
            self.wfile.write(b)
    srv = ThreadingHTTPServer((host, int(port)), H)
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *a: stop.set())
    if os.environ.get("FAKE_IGNORE_SIGINT"):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    print("fake dfp-sim", args[0], "on", port, flush=True)
    stop.wait()
    sys.exit(int(os.environ.get("FAKE_RC", "0")))
    """) % sys.executable


@pytest.fixture
def fake_sim(tmp_path):
    p = tmp_path / "dfp-sim"
    p.write_text(FAKE_SIM)
    p.chmod(0o755)
    return str(p)


def test_demo_starts_waits_and_stops(fake_sim, monkeypatch):
    monkeypatch.setenv("DFP_SIM", fake_sim)
    with DfpSim.demo() as sim:
        st = sim.state()
        assert st["mode"] == "demo"
        assert st["argv"][1] == "--http" and st["argv"][2].startswith("127.0.0.1:")
        assert sim.base_url.endswith(":" + st["argv"][2].rsplit(":", 1)[1])


def test_each_start_gets_its_own_token_and_the_client_sends_it(fake_sim, monkeypatch):
    monkeypatch.setenv("DFP_SIM_TOKEN", "the-callers-own-token")
    with DfpSim.demo(dfp_sim=fake_sim) as a, DfpSim.demo(dfp_sim=fake_sim) as b:
        ta, tb = a.state()["token"], b.state()["token"]
    assert ta == a.token and tb == b.token
    assert ta != tb and "the-callers-own-token" not in (ta, tb)
    assert len(ta) == 43   # secrets.token_urlsafe(32): 32 octets in base64url
    assert all(ch.isalnum() or ch in "-_" for ch in ta)


def test_demo_given_port(fake_sim):
    port = free_port()
    with DfpSim.demo(http_port=port, dfp_sim=fake_sim) as sim:
        assert sim.base_url == "http://127.0.0.1:%d" % port


def test_nonzero_exit_code_raises_unless_told_otherwise(fake_sim, monkeypatch):
    monkeypatch.setenv("FAKE_RC", "1")
    with pytest.raises(DfpSimError, match="exit 1 on SIGINT"):
        with DfpSim.demo(dfp_sim=fake_sim):
            pass
    with DfpSim.demo(dfp_sim=fake_sim, check_exit=False):
        pass


def test_a_failing_body_is_not_masked_by_the_exit_code(fake_sim, monkeypatch):
    monkeypatch.setenv("FAKE_RC", "1")
    with pytest.raises(KeyError) as e:
        with DfpSim.demo(dfp_sim=fake_sim):
            raise KeyError("the test's own failure")
    assert any("exit 1 on SIGINT" in n for n in e.value.__notes__)


def test_process_that_ignores_sigint_is_killed(fake_sim, monkeypatch):
    monkeypatch.setenv("FAKE_IGNORE_SIGINT", "1")
    t0 = time.monotonic()
    with pytest.raises(DfpSimError, match="killed after 1 s"):
        with DfpSim.demo(dfp_sim=fake_sim, stop_timeout=1.0):
            pass
    assert time.monotonic() - t0 < 5


def test_start_up_failure_shows_the_output(fake_sim, monkeypatch):
    monkeypatch.setenv("FAKE_DIE", "1")
    with pytest.raises(DfpSimError, match="(?s)exited with 3 before its API answered.*"
                                          "dying at start-up"):
        with DfpSim.demo(dfp_sim=fake_sim):
            pass


def test_missing_binary(monkeypatch, tmp_path):
    monkeypatch.delenv("DFP_SIM", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(DfpSimError, match=r"\$DFP_SIM"):
        DfpSim.demo()
    with pytest.raises(DfpSimError, match="not an executable"):
        DfpSim.demo(dfp_sim=os.path.join(str(tmp_path), "nothing"))
