"""dfp-lcm-view: a live console view of what dfp-sim publishes over LCM
(sim_host/lcm_bridge/README.md): one line per telegram, per parameter service and per card state,
a status line per station, a summary at the end. Decodes through the classes lcm-gen makes of the
project's .lcm files (lcm_types.py); names the telegrams' services with fdl_text.py.
"""

import argparse
import datetime
import os
import select
import shutil
import signal
import struct
import sys
import time
import unicodedata

from . import fdl_text, lcm_types

LCM_DEFAULT = "udpm://239.255.76.67:7667?ttl=0"   # LCM's own default URL (lcm 1.5)
QUEUE_CAPACITY = 4096   # LCM's default of 30 drops messages while a slow terminal scrolls
DIRECTIONS = {1: "TX", 2: "RX"}
UART_ERRORS = ((1, "parity"), (2, "framing"), (4, "overrun"))

DESCRIPTION = """\
Live view of dfp-sim's LCM traffic (dfp-sim demo|slave|master --lcm URL, --bus lcm:CHANNEL):
every telegram with its time, the publishing station and direction, start delimiter, DA, SA,
FC, service and octets; every parameter service; the state of each card. Messages of other
types on the channels are counted, not shown."""

EPILOG = """\
telegram line:  TIME CHANNEL STATION TX|RX SD DA n SA n FC xx SERVICE OCTETS [! FAULT]
  STATION is the publishing station (a card's telemetry: the card; a segment channel: the
  sender); a reply is named after the last request to its sender ("Data_Exchange reply").
state line:     TIME CHANNEL ADDRESS state DP_STATE, BAUD, LEDs, P090, PO/PI words, then the
  station's counts: Data_Exchange telegrams it sent (a slave's replies, a master's requests)
  and telegrams with UART errors or a damaged frame.

exit status: 0 ended by --count, --duration or Ctrl-C/SIGTERM; 1 --duration ran out before
--count messages arrived, or LCM failed while running; 2 bad option, bad --lcm-url, no .lcm
files in --lcm-types.

examples:
  dfp-lcm-view --lcm-url 'udpm://239.255.76.67:7667?ttl=0'
  dfp-lcm-view --channel DFP_CARD_STATE --status log --duration 10
  dfp-lcm-view --channel SEG --no-telegrams --summary 5      # a virtual segment's stations"""


def _positive_int(text):
    try:
        n = int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError("not a whole number: %r" % text) from None
    if n < 1:
        raise argparse.ArgumentTypeError("must be 1 or more, not %d" % n)
    return n


def _positive_seconds(text):
    try:
        s = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("not a number of seconds: %r" % text) from None
    if not s > 0 or s == float("inf"):
        raise argparse.ArgumentTypeError("must be more than 0 seconds, not %s" % text)
    return s


def parse_args(argv):
    p = argparse.ArgumentParser(prog="dfp-lcm-view", description=DESCRIPTION, epilog=EPILOG,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--lcm-url", metavar="URL",
                   help="LCM URL (default: $LCM_DEFAULT_URL, else " + LCM_DEFAULT + ")")
    p.add_argument("--channel", metavar="REGEX", action="append",
                   help="subscribe to the channels matching REGEX (LCM's syntax, the whole "
                        "name must match); repeatable; default: every channel")
    p.add_argument("--no-telegrams", action="store_true",
                   help="no telegram lines (they are still counted)")
    p.add_argument("--status", choices=("auto", "line", "log"), default="auto",
                   help="line: one status line, rewritten in place; log: a line per card "
                        "state message; auto (default): line on a terminal, else log")
    p.add_argument("--summary", metavar="S", type=_positive_seconds,
                   help="also print the per-station summary every S seconds")
    p.add_argument("--count", metavar="N", type=_positive_int,
                   help="end after N messages of the project's types")
    p.add_argument("--duration", metavar="S", type=_positive_seconds,
                   help="end after S seconds")
    p.add_argument("--lcm-types", metavar="DIR",
                   help="the project's .lcm files (default: $DFP_LCM_TYPES, else "
                        "sim_host/lcm_bridge/dfp_lcm of this checkout)")
    return p.parse_args(argv)


# ---- text ----------------------------------------------------------------------------------

# Unicode categories shown escaped besides C0, DEL and C1 (which are Cc): format characters
# (bidirectional overrides that reorder what follows, zero-width ones), line and paragraph
# separators, and lone surrogates.
_ESCAPED_CATEGORIES = frozenset(("Cc", "Cf", "Zl", "Zp", "Cs"))


def _escape_char(c):
    o = ord(c)
    if o < 0x20 or 0x7F <= o <= 0x9F:
        return "\\x%02x" % o
    if o > 0x9F and unicodedata.category(c) in _ESCAPED_CATEGORIES:
        return "\\u{%04x}" % o
    return c


def visible(text):
    """text with every control character shown as \\xNN or \\u{NNNN}. Strings from the wire
    (channel names, card states, parameter texts) reach the terminal only through this: a
    sender could otherwise clear the screen, fake lines (CR, LF) or, with OSC 52, write the
    clipboard."""
    if text.isprintable():
        return text
    return "".join(_escape_char(c) for c in text)


def time_text(utime):
    """Local clock time of a message's utime (µs since the epoch), to the millisecond."""
    try:
        t = datetime.datetime.fromtimestamp(utime / 1e6)
    except (OverflowError, OSError, ValueError):
        return "utime %d" % utime
    return t.strftime("%H:%M:%S.%f")[:-3]


def baud_text(baud):
    if baud <= 0:
        return "searching"
    for unit, name in ((1_000_000, "Mbit/s"), (1000, "kbit/s")):
        if baud >= unit:
            return "%g %s" % (baud / unit, name)
    return "%d bit/s" % baud


def _opt(value, width):
    return ("-" if value is None else str(value)).rjust(width)


def telegram_line(channel, msg, frame, service):
    data = bytes(msg.data)
    faults = [name for bit, name in UART_ERRORS if msg.error_flags & bit]
    if frame.fault:
        faults.append(frame.fault)
    if msg.length != len(data):
        faults.append("length field %d, %d octets" % (msg.length, len(data)))
    fc = "--" if frame.fc is None else "%02X" % frame.fc
    line = "%s %-14s %3s %s %-3s DA %s SA %s FC %s  %-20s %s" % (
        time_text(msg.utime), channel, "-" if msg.station < 0 else msg.station,
        DIRECTIONS.get(msg.direction, "--"), frame.sd, _opt(frame.da, 3), _opt(frame.sa, 3),
        fc, service, fdl_text.hex_octets(data))
    return line + ("  ! " + ", ".join(faults) if faults else "")


def _words(values, n):
    return " ".join("%04X" % (v & 0xFFFF) for v in list(values)[:max(n, 0)]) or "-"


def param_line(channel, msg):
    result = "ok" if msg.ok else "refused: " + msg.result_text
    return "%s %-14s %3d param %s %s index %d.%d value %d %s" % (
        time_text(msg.utime), channel, msg.address, msg.path, msg.service, msg.index,
        msg.subindex, msg.value, result)


def api_line(channel, msg):
    """An event of a dfp-sim's control API (the audit of a request, a limit)."""
    return "%s %-14s     api %s %s: %s" % (time_text(msg.utime), channel, msg.level, msg.kind,
                                           msg.text)


# ---- per station ---------------------------------------------------------------------------

class Station:
    """What is known of one FDL address: its last card state and, per telegram channel, the
    telegrams it published. The same frame can arrive twice (a slave on a segment with --lcm
    publishes it on the segment channel and on DFP_TELEGRAM), so the counts shown are the
    highest of one channel, never a sum over channels."""

    def __init__(self, address):
        self.address = address
        self.state = None
        self._counts = {}   # channel -> [telegrams, Data_Exchange sent, errors]

    def count(self, channel, dx_sent, error):
        c = self._counts.setdefault(channel, [0, 0, 0])
        c[0] += 1
        c[1] += 1 if dx_sent else 0
        c[2] += 1 if error else 0

    def counts(self):
        cs = self._counts.values()
        return tuple(max((c[i] for c in cs), default=0) for i in range(3))

    def state_text(self, short=False):
        s = self.state
        if s is None:
            return "no card state"
        if short:
            return "%s %s RUN %s BF %s" % (s.dp_state, baud_text(s.baud), s.led_run,
                                           s.led_bus_fault)
        return "%s, %s, RUN %s, BUS FAULT %s, P090 %s, PO %s, PI %s" % (
            s.dp_state, baud_text(s.baud), s.led_run, s.led_bus_fault, s.p090_pd_config,
            _words(s.po, s.pd_words), _words(s.pi, s.pd_words))

    def counts_text(self):
        telegrams, dx, errors = self.counts()
        return "%d telegrams, Data_Exchange sent %d, errors %d" % (telegrams, dx, errors)


# ---- the viewer ----------------------------------------------------------------------------

class Viewer:
    """Turns LCM messages into lines on out. status_line: keep one status line at the bottom,
    rewritten in place (a terminal), instead of a line per card state."""

    def __init__(self, types, out, telegrams=True, status_line=False):
        self.types = types
        self.out = out
        self.show_telegrams = telegrams
        self.status_line = status_line
        self.stations = {}
        self.tracker = fdl_text.ServiceTracker()
        self.handlers = {
            types["telegram_t"]._get_packed_fingerprint(): (types["telegram_t"], self.telegram),
            types["card_state_t"]._get_packed_fingerprint(): (types["card_state_t"], self.state),
            types["param_service_t"]._get_packed_fingerprint():
                (types["param_service_t"], self.param),
        }
        if "api_event_t" in types:  # a checkout's .lcm files from before it are still read
            self.handlers[types["api_event_t"]._get_packed_fingerprint()] = \
                (types["api_event_t"], self.api_event)
        self.counts = {"telegram": 0, "state": 0, "param": 0, "api": 0, "undecodable": 0,
                       "other": 0}
        self.other_channels = set()
        self._status_shown = False
        self._drawn_at = 0.0
        self._dirty = False

    @property
    def messages(self):
        """Messages of the project's types so far."""
        return (self.counts["telegram"] + self.counts["state"] + self.counts["param"] +
                self.counts["api"])

    def station(self, address):
        if address not in self.stations:
            self.stations[address] = Station(address)
        return self.stations[address]

    def on_message(self, channel, data):
        """LCM's handler: the fingerprint (the first 8 octets) says which type it is."""
        kind = self.handlers.get(bytes(data[:8]))
        if kind is None:
            self.counts["other"] += 1
            self.other_channels.add(channel)
            return
        cls, handler = kind
        try:
            msg = cls.decode(data)
        except (ValueError, EOFError, UnicodeError, IndexError, TypeError, OverflowError,
                struct.error):
            self.counts["undecodable"] += 1
            return
        handler(channel, msg)

    def telegram(self, channel, msg):
        self.counts["telegram"] += 1
        frame = fdl_text.parse(msg.data)
        tx = msg.direction == 1
        service = self.tracker.name(channel, frame, msg.station, tx)
        if msg.station >= 0:
            error = msg.error_flags != 0 or bool(frame.fault) or msg.length != len(msg.data)
            self.station(msg.station).count(channel, tx and service.startswith("Data_Exchange"),
                                            error)
        if self.show_telegrams:
            self.emit(telegram_line(channel, msg, frame, service))
        else:
            self._dirty = True
            self.tick()

    def state(self, channel, msg):
        self.counts["state"] += 1
        st = self.station(msg.address)
        st.state = msg
        if self.status_line:
            self._dirty = True
            self.tick()
        else:
            self.emit("%s %-14s %3d state %s; %s" % (time_text(msg.utime), channel, msg.address,
                                                      st.state_text(), st.counts_text()))

    def param(self, channel, msg):
        self.counts["param"] += 1
        self.emit(param_line(channel, msg))

    def api_event(self, channel, msg):
        self.counts["api"] += 1
        self.emit(api_line(channel, msg))

    # -- output --

    def status_text(self):
        parts = []
        for addr in sorted(self.stations):
            st = self.stations[addr]
            telegrams, dx, errors = st.counts()
            parts.append("%d: %s DX %d err %d" % (addr, st.state_text(short=True)
                                                  if st.state else "%d tg" % telegrams,
                                                  dx, errors))
        return " | ".join(parts) or "no station yet"

    def tick(self):
        """Redraws a status line that changed, at most ten times a second (a terminal that
        rewrites a line a thousand times a second only flickers)."""
        if self.status_line and self._dirty and time.monotonic() - self._drawn_at >= 0.1:
            self.redraw()

    def redraw(self):
        self._dirty = False
        self._drawn_at = time.monotonic()
        width = shutil.get_terminal_size((100, 24)).columns
        self.out.write("\r\x1b[K" + visible(self.status_text())[:max(width - 1, 10)])
        self.out.flush()
        self._status_shown = True

    def clear_status(self):
        if self._status_shown:
            self.out.write("\r\x1b[K")
            self._status_shown = False

    def emit(self, line):
        """Every line but the status line and the summary is written here, escaped once."""
        self.clear_status()
        self.out.write(visible(line) + "\n")
        if self.status_line:
            self.redraw()
        else:
            self.out.flush()

    def summary_lines(self, seconds):
        c = self.counts
        lines = ["summary: %d messages in %.1f s (%d telegrams, %d card states, %d parameter "
                 "services, %d API events); %d undecodable, %d of other types%s"
                 % (self.messages, seconds, c["telegram"], c["state"], c["param"], c["api"],
                    c["undecodable"], c["other"],
                    " (%s)" % ", ".join(sorted(self.other_channels)) if c["other"] else "")]
        for addr in sorted(self.stations):
            st = self.stations[addr]
            lines.append("station %d: %s; %s" % (addr, st.state_text(), st.counts_text()))
        return lines

    def print_summary(self, seconds):
        self.clear_status()
        for line in self.summary_lines(seconds):
            self.out.write(visible(line) + "\n")
        if self.status_line:
            self.redraw()
        self.out.flush()


# ---- main ----------------------------------------------------------------------------------

def _fail(code, message):
    print("dfp-lcm-view: " + message, file=sys.stderr)
    return code


def _open_lcm(url):
    import lcm
    try:
        return lcm.LCM(url) if url else lcm.LCM()
    except (RuntimeError, OSError, ValueError):
        return None


def _loop(lc, viewer, args, stop):
    """Handles messages until --count, --duration or a signal; True when --count was the end
    or was not asked for."""
    start = time.monotonic()
    deadline = start + args.duration if args.duration else None
    next_summary = start + args.summary if args.summary else None
    while not stop:
        if args.count and viewer.messages >= args.count:
            return True
        now = time.monotonic()
        if deadline is not None and now >= deadline:
            return not args.count
        if next_summary is not None and now >= next_summary:
            viewer.print_summary(now - start)
            next_summary += args.summary
        wait = 0.1 if deadline is None else min(0.1, deadline - now)
        # select() rather than lc.handle_timeout(): a signal interrupts LCM's own wait with an
        # error indistinguishable from a real one, Python's select() resumes after the handler.
        readable, _, _ = select.select([lc], [], [], wait)
        if readable:
            try:
                lc.handle()
            except OSError:
                if not stop:
                    raise
        viewer.tick()
    return True


def run(args, out=None):
    out = out or sys.stdout
    try:
        types = lcm_types.load(args.lcm_types)
    except lcm_types.LcmTypesError as e:
        return _fail(2 if e.usage else 1, str(e))
    url = args.lcm_url or os.environ.get("LCM_DEFAULT_URL") or ""
    lc = _open_lcm(url)
    if lc is None:
        return _fail(2, "cannot open LCM URL '%s' (LCM's reason is above); e.g. "
                        "udpm://239.255.76.67:7667?ttl=0" % url)
    status_line = args.status == "line" or (args.status == "auto" and out.isatty())
    viewer = Viewer(types, out, telegrams=not args.no_telegrams, status_line=status_line)
    channels = args.channel or [".*"]
    for ch in channels:
        sub = lc.subscribe(ch, viewer.on_message)
        if sub is None:
            return _fail(2, "bad --channel %r: not a regular expression LCM can use (its "
                            "reason is above)" % ch)
        sub.set_queue_capacity(QUEUE_CAPACITY)
    stop = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(True))
    print("dfp-lcm-view: listening on %s, channels %s" % (url or LCM_DEFAULT,
                                                          ", ".join(channels)),
          file=sys.stderr, flush=True)
    start = time.monotonic()
    try:
        complete = _loop(lc, viewer, args, stop)
    except OSError as e:
        viewer.status_line = False
        viewer.print_summary(time.monotonic() - start)
        return _fail(1, "LCM failed: %s" % e)
    viewer.status_line = False   # the summary is the last word: no status line after it
    viewer.print_summary(time.monotonic() - start)
    if not complete:
        return _fail(1, "only %d of %d messages within %g s" % (viewer.messages, args.count,
                                                                 args.duration))
    return 0


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        import lcm  # noqa: F401  (the module, before anything else needs it)
    except ImportError:
        return _fail(1, "the Python module lcm is missing: pip install lcm (make deps-python "
                        "puts it into build/venv)")
    try:
        return run(args)
    except BrokenPipeError:
        # The reader went away (| head): nothing more to say, and nothing to say it to.
        sys.stdout = open(os.devnull, "w")
        return 0


if __name__ == "__main__":
    sys.exit(main())
