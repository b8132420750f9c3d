"""HTTP client of dfp-sim's control API (docs/api.md). Standard library only."""

import http.client
import json
import os
import ssl
import urllib.error
import urllib.parse
import urllib.request
from dataclasses import dataclass

from .errors import ApiError, AuthError, DfpSimError, ParamError, TlsError

API = "/api/v1"
# The paths of a master parameter service (docs/api.md, POST /api/v1/master/param).
PARAM_VIAS = ("channel", "ds47", "c2")
# The master's phase names for a slave in cyclic data exchange.
DATA_EXCH_PHASES = ("DATA_EXCH", "Data_Exchange")


@dataclass(frozen=True)
class ParamResult:
    """A positive parameter answer: `text` is what a MOVITOOLS user reads ("3 (FIELDBUS)")."""

    p_number: str
    index: int
    name: str
    value: object
    text: str

    @classmethod
    def from_answer(cls, answer):
        return cls(p_number=answer.get("p_number"), index=answer.get("index"),
                   name=answer.get("name"), value=answer.get("value"), text=answer.get("text"))

    def __str__(self):
        return "%s %s = %s" % (self.p_number, self.name, self.text)


def _param_ref(p):
    """P-number ("P100"), index (8461 or "8461") or name, as the API takes it."""
    if isinstance(p, bool) or not isinstance(p, (str, int)):
        raise TypeError("a parameter is a P-number ('P100'), an index (8461) or a name, not %r"
                        % (p,))
    return str(p)


TOKEN_ENV = "DFP_SIM_TOKEN"


class Client:
    """One running dfp-sim with `--http`, e.g. Client("http://127.0.0.1:8080", token=T).

    `token` (the operator or viewer token dfp-sim printed at start, or gave it by
    --http-token-file) goes as `Authorization: Bearer` on every request, the event stream
    included; None takes $DFP_SIM_TOKEN, "" sends none (for a server started with
    --http-no-auth). An https URL verifies the server's certificate against `cafile` (a PEM
    file: the self-signed certificate itself, or its CA), or the system's store without it.

    Every call is one HTTP request; nothing is cached, so properties always show the state the
    simulation published last (at most 50 ms old in wall-clock modes).
    """

    def __init__(self, base_url, timeout=10.0, token=None, cafile=None):
        if "://" not in base_url:
            base_url = "http://" + base_url
        self.base_url = base_url.rstrip("/")
        # A parameter service through the master answers within 5 s or with 504: longer here.
        self.timeout = timeout
        self.token = os.environ.get(TOKEN_ENV, "") if token is None else str(token)
        self.cafile = None if cafile is None else os.fspath(cafile)
        self._ssl = None
        if urllib.parse.urlsplit(self.base_url).scheme == "https":
            self._ssl = ssl.create_default_context(cafile=self.cafile)

    def __repr__(self):
        return "Client(%r)" % self.base_url

    # ---- plumbing --------------------------------------------------------------------------

    def _headers(self, accept):
        headers = {"Accept": accept}
        if self.token:
            headers["Authorization"] = "Bearer " + self.token
        return headers

    def request(self, method, path, body=None, timeout=None):
        """One request; returns the decoded JSON answer. HTTP errors raise ApiError (401:
        AuthError), a certificate that does not verify TlsError."""
        url = self.base_url + path
        data = None
        headers = self._headers("application/json")
        if method not in ("GET", "HEAD"):
            # the server takes a state-changing request only as JSON, body or not (415)
            headers["Content-Type"] = "application/json"
        if body is not None:
            data = json.dumps(body).encode("utf-8")
        req = urllib.request.Request(url, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(req, timeout=timeout or self.timeout,
                                        context=self._ssl) as rsp:
                raw = rsp.read()
        except urllib.error.HTTPError as e:
            raise _http_error(e.code, e.read(), e.reason, method, path) from None
        except urllib.error.URLError as e:
            if isinstance(e.reason, ssl.SSLError):
                raise TlsError(self.base_url, e.reason) from None
            raise
        if not raw:
            return None
        try:
            return json.loads(raw.decode("utf-8"))
        except ValueError:
            raise DfpSimError("%s %s: the answer is not JSON: %r"
                              % (method, path, raw[:200])) from None

    def get(self, path, **query):
        q = {k: v for k, v in query.items() if v is not None}
        if q:
            path += "?" + urllib.parse.urlencode(q)
        return self.request("GET", path)

    def post(self, path, body=None):
        return _checked(self.request("POST", path, {} if body is None else body), "POST", path)

    def put(self, path, body):
        return _checked(self.request("PUT", path, body), "PUT", path)

    # ---- reading ---------------------------------------------------------------------------

    def state(self):
        """GET /api/v1/state: the whole simulation as a dict."""
        return self.get(API + "/state")

    def card(self, address):
        """The card with this PROFIBUS address (as its DIP switches set it at power-up)."""
        return Card(self, address)

    def cards(self):
        return [Card(self, c["address"]) for c in self.state()["cards"]]

    def master(self):
        """The built-in DP master of `dfp-sim master` or `demo`."""
        return Master(self)

    def params(self, q=None):
        """GET /api/v1/params?q=...: the parameter table, filtered by P-number, index or name."""
        return self.get(API + "/params", q=q)

    def log(self, since=0, limit=None):
        """GET /api/v1/log: the held log events with seq >= since, oldest first."""
        return self.get(API + "/log", since=since, limit=limit)

    def events(self, last_event_id=None, timeout=None):
        """The live Server-Sent Events stream /api/v1/events, as a generator of dicts.

        Each item is {"event": "log"|"state"|..., "data": <parsed JSON, or the text if it is
        not JSON>, "id": <the last event id seen, or None>}. `last_event_id` asks the server to
        replay the held log events after that seq first. `timeout` (default: the client's) is
        the longest wait for the next bytes; the server sends a state event every 100 ms, so
        a silent stream raises TimeoutError. Close the generator (or leave the for loop) to
        drop the connection.
        """
        parts = urllib.parse.urlsplit(self.base_url)
        if parts.scheme == "https":
            conn = http.client.HTTPSConnection(parts.hostname, parts.port,
                                               timeout=timeout or self.timeout,
                                               context=self._ssl)
        else:
            conn = http.client.HTTPConnection(parts.hostname, parts.port,
                                              timeout=timeout or self.timeout)
        path = parts.path + API + "/events"
        headers = self._headers("text/event-stream")
        headers["Cache-Control"] = "no-cache"
        if last_event_id is not None:
            headers["Last-Event-ID"] = str(last_event_id)
        try:
            try:
                conn.request("GET", path, headers=headers)
            except ssl.SSLError as e:
                raise TlsError(self.base_url, e) from None
            rsp = conn.getresponse()
            if rsp.status != 200:
                raise _http_error(rsp.status, rsp.read(), rsp.reason, "GET", path)
            yield from parse_sse(rsp)
        finally:
            conn.close()


def parse_sse(stream):
    """Server-Sent Events from a binary file-like object (the WHATWG rules that matter here).

    Blank line = dispatch; `:` starts a comment; `data:` lines are joined with "\\n"; one
    space after the colon is dropped; an event without data is not dispatched; `id` persists
    across events.
    """
    event, data, last_id = "", [], None
    while True:
        line = stream.readline()
        if not line:
            return  # the server closed the stream
        line = line.decode("utf-8", errors="replace").rstrip("\r\n")
        if line == "":
            if data:
                text = "\n".join(data)
                try:
                    parsed = json.loads(text)
                except ValueError:
                    parsed = text
                yield {"event": event or "message", "data": parsed, "id": last_id}
            event, data = "", []
            continue
        if line.startswith(":"):
            continue
        field, sep, value = line.partition(":")
        if sep and value.startswith(" "):
            value = value[1:]
        if field == "event":
            event = value
        elif field == "data":
            data.append(value)
        elif field == "id":
            if "\0" not in value:
                last_id = value
        # "retry" and unknown fields: ignored


def _http_error(status, raw, reason, method, path):
    cls = AuthError if status == 401 else ApiError
    return cls(status, _error_text(raw, reason), method, path)


def _error_text(raw, fallback):
    try:
        doc = json.loads(raw.decode("utf-8"))
        if isinstance(doc, dict) and "error" in doc:
            return str(doc["error"])
    except (ValueError, UnicodeDecodeError):
        pass
    text = raw.decode("utf-8", errors="replace").strip()
    return text.splitlines()[0] if text else str(fallback)


def _checked(answer, method, path):
    """An action answer: {"ok": true, ...}; {"ok": false, "error": ...} raises ApiError."""
    if isinstance(answer, dict) and answer.get("ok") is False:
        raise ApiError(200, str(answer.get("error", "ok: false")), method, path)
    return answer


class Card:
    """One DFP21B card (and the drive behind it). Properties read the API every time."""

    def __init__(self, client, address):
        self.client = client
        self.address = int(address)
        self._path = "%s/cards/%d" % (API, self.address)

    def __repr__(self):
        return "Card(%r, %d)" % (self.client.base_url, self.address)

    def state(self):
        """GET /api/v1/cards/{a}: one consistent snapshot of everything below, as a dict."""
        return self.client.get(self._path)

    def _drive(self):
        d = self.state().get("drive")
        if d is None:
            raise DfpSimError("card %d has no drive (dfp-sim runs with --inverter none)"
                              % self.address)
        return d

    # ---- the card ----------------------------------------------------------------------------

    @property
    def dp(self):
        """The DP slave: state, baud, baud_state, master, watchdog_ms, config, diag."""
        return self.state()["dp"]

    @property
    def dp_state(self):
        """"Wait_Prm", "Wait_Cfg" or "Data_Exch"."""
        return self.dp["state"]

    @property
    def baud(self):
        """The baud rate found (None while searching)."""
        return self.dp["baud"]

    @property
    def baud_state(self):
        return self.dp["baud_state"]

    @property
    def master_address(self):
        """The master that has locked the card, or None."""
        return self.dp["master"]

    @property
    def watchdog_ms(self):
        return self.dp["watchdog_ms"]

    @property
    def config(self):
        return self.dp["config"]

    @property
    def diag(self):
        return self.dp["diag"]

    @property
    def leds(self):
        """{"run": ..., "bus_fault": ..., ...}: "off", "on" or "blink"."""
        return self.state()["leds"]

    @property
    def run_led(self):
        return self.leds["run"]

    @property
    def bus_fault_led(self):
        return self.leds["bus_fault"]

    @property
    def cable(self):
        return self.state()["cable"]

    @property
    def on_bus(self):
        return self.state()["on_bus"]

    @property
    def dip(self):
        return self.state()["dip"]

    @property
    def monitor(self):
        """P090 .. P099 and P819 as the card shows them ("po"/"pi": the PD words)."""
        return self.state()["monitor"]

    @property
    def dpv1(self):
        return self.state()["dpv1"]

    @property
    def nvm(self):
        return self.state()["nvm"]

    # ---- the drive -------------------------------------------------------------------------

    @property
    def drive(self):
        """The drive's part of the snapshot as a dict (DfpSimError without a drive)."""
        return self._drive()

    @property
    def control_word(self):
        return self._drive()["control_word"]

    @property
    def control_text(self):
        return self._drive()["control_text"]

    @property
    def status_word(self):
        return self._drive()["status_word"]

    @property
    def status_text(self):
        return self._drive()["status_text"]

    @property
    def enabled(self):
        return self._drive()["enabled"]

    @property
    def fault(self):
        """The drive's fault number, 0 = no fault."""
        return self._drive()["fault"]

    @property
    def fault_name(self):
        return self._drive()["fault_name"]

    @property
    def speed_setpoint_rpm(self):
        return self._drive()["speed_setpoint_rpm"]

    @property
    def speed_actual_rpm(self):
        return self._drive()["speed_actual_rpm"]

    @property
    def current_pct(self):
        return self._drive()["current_pct"]

    @property
    def ramp_up_ms(self):
        return self._drive()["ramp_up_ms"]

    @property
    def ramp_down_ms(self):
        return self._drive()["ramp_down_ms"]

    @property
    def inputs(self):
        """The drive's digital inputs, e.g. {"DI00": True} (True = +24 V)."""
        return self._drive()["inputs"]

    # ---- actions -----------------------------------------------------------------------------

    def set_input(self, name, value):
        """Drive terminal, e.g. set_input("DI00", False): /CONTROLLER INHIBIT active."""
        return self.client.post(self._path + "/inputs", {str(name): bool(value)})

    def inject_fault(self, number):
        """The drive raises fault `number` (1..255) as if it had detected it."""
        return self.client.post(self._path + "/fault", {"fault": int(number)})

    def pull_cable(self):
        """The card's PROFIBUS connector pulled: it hears and sends nothing."""
        return self.client.post(self._path + "/cable", {"connected": False})

    def plug_cable(self):
        return self.client.post(self._path + "/cable", {"connected": True})

    def power_cycle(self):
        """The card (not the drive) restarts: baud search, DIP switches read again."""
        return self.client.post(self._path + "/power-cycle", {})

    def set_dip(self, address):
        """DIP switches for the next power-up (0..127). The card keeps its address until then."""
        return self.client.post(self._path + "/dip", {"address": int(address)})

    def read_param(self, p):
        """Reads a drive parameter directly (not over the bus) -> ParamResult."""
        path = "%s/params/%s" % (self._path, urllib.parse.quote(_param_ref(p), safe=""))
        return ParamResult.from_answer(_param_answer(self.client.request("GET", path),
                                                     "GET", path))

    def write_param(self, p, value, volatile=False):
        """Writes a drive parameter directly, with the drive's own checks -> ParamResult.

        `value` is a number or an enumeration text ("FIELDBUS"). A refusal by the drive raises
        ParamError (status 400) with the MOVILINK error text.
        """
        path = "%s/params/%s" % (self._path, urllib.parse.quote(_param_ref(p), safe=""))
        body = {"value": value}
        if volatile:
            body["volatile"] = True
        try:
            answer = self.client.request("PUT", path, body)
        except ApiError as e:
            if e.status == 400 and "MOVILINK" in e.message:
                raise ParamError(e.status, e.message, {"p_number": _param_ref(p)},
                                 "PUT", path) from None
            raise
        return ParamResult.from_answer(_param_answer(answer, "PUT", path))


def _param_answer(answer, method, path):
    if not isinstance(answer, dict):
        raise DfpSimError("%s %s: unexpected answer %r" % (method, path, answer))
    if answer.get("ok") is False:
        raise ParamError(200, str(answer.get("error", "refused")), answer, method, path)
    return answer


class Master:
    """The built-in class-1 DP master (the PLC) of `dfp-sim master` or `demo`."""

    def __init__(self, client):
        self.client = client

    def __repr__(self):
        return "Master(%r)" % self.client.base_url

    def state(self):
        """The master's part of GET /api/v1/state."""
        m = self.client.state().get("master")
        if m is None:
            raise DfpSimError("%s has no DP master (dfp-sim slave?)" % self.client.base_url)
        return m

    @property
    def address(self):
        return self.state()["address"]

    @property
    def running(self):
        return self.state()["running"]

    @property
    def baud(self):
        return self.state()["baud"]

    @property
    def slaves(self):
        return self.state()["slaves"]

    def slave(self, address):
        """The master's view of one slave: phase, cycles, po, pi, outputs, inputs, diag."""
        for s in self.state()["slaves"]:
            if s["address"] == address:
                return s
        raise DfpSimError("the master has no slave %d" % address)

    def phase(self, slave):
        """The master's start-up phase for this slave, e.g. "Set_Prm", "Data_Exchange"."""
        return self.slave(slave)["phase"]

    def in_data_exchange(self, slave):
        """True while the master exchanges data with this slave (its phase is data exchange;
        docs/api.md spells it "DATA_EXCH", dfp-sim's master log "Data_Exchange")."""
        return self.phase(slave) in DATA_EXCH_PHASES

    def po(self, slave):
        """The PO words the master sends (after the parameter channel, if any)."""
        return self.slave(slave)["po"]

    def pi(self, slave):
        """The PI words the master received last."""
        return self.slave(slave)["pi"]

    def cycles(self, slave):
        return self.slave(slave)["cycles"]

    # ---- actions -----------------------------------------------------------------------------

    def run(self):
        """PLC RUN: the master starts the slaves up again."""
        return self.client.post(API + "/master/run", {"running": True})

    def stop(self):
        """PLC STOP: the master stops sending; the card's watchdog expires."""
        return self.client.post(API + "/master/run", {"running": False})

    def set_po(self, slave, words):
        """The PO words from now on, e.g. set_po(4, [0x0006, 1500]); words not given stay."""
        words = [int(w) for w in words]
        return self.client.post("%s/master/slaves/%d/outputs" % (API, slave), {"po": words})

    def set_outputs(self, slave, hex_image):
        """The whole output image (parameter channel included) as hex."""
        return self.client.post("%s/master/slaves/%d/outputs" % (API, slave),
                                {"hex": str(hex_image)})

    def _param(self, body):
        path = API + "/master/param"
        return ParamResult.from_answer(
            _param_answer(self.client.request("POST", path, body), "POST", path))

    def read_param(self, slave, p, via="channel"):
        """A read service while cyclic exchange goes on -> ParamResult.

        `via` (one of PARAM_VIAS): "channel" (cyclic 8-octet MOVILINK channel), "ds47" (DP-V1
        class-1 data set 47) or "c2" (data set 47 over a class-2 connection the master opens
        for the service and aborts after it). A refusal raises ParamError with the MOVILINK
        text; a class-2 connection that does not open raises ApiError 502; no answer within
        5 s raises ApiError 504.
        """
        return self._param({"slave": int(slave), "op": "read", "param": _param_ref(p),
                            "via": _via(via)})

    def write_param(self, slave, p, value, via="channel", volatile=False):
        """A write service (non-volatile unless volatile=True) -> ParamResult."""
        return self._param({"slave": int(slave), "op": "write", "param": _param_ref(p),
                            "value": value, "via": _via(via), "volatile": bool(volatile)})


def _via(via):
    if via not in PARAM_VIAS:
        raise ValueError("via %r: use one of %s" % (via, ", ".join(PARAM_VIAS)))
    return via
