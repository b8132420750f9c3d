"""dfp-sim monitor's full-screen view (docs/monitor.md "The terminal view") on a port of
`dfp-sim line` (master 2, DFP21B cards 5 and 6), run on a PTY of 30 x 110 as a person would run
it in a terminal, its output read through a small terminal model (cursor positioning, erase,
attributes, the alternate screen, scrolling) so the test sees the screen the person sees:
the header with the source and the rate, the ring, one row per station with its state and
master; Down Down Enter: station 6's details; e: the events; q: exit 0 with the terminal
given back (main screen, the PTY's settings as before); Ctrl-C the same. Then the line ends
under a running monitor: it says the port hung up, on the main screen where it stays
readable, and exits 1 with the terminal given back as well.

Usage: test_monitor_top.py DFP_SIM   (the last line is "N passed, M failed")
"""
import codecs
import fcntl
import os
import re
import select
import signal
import struct
import subprocess
import sys
import tempfile
import termios
import time

ROWS, COLS = 30, 110
SHOW_S = 15       # the line's master and its cards on the screen
KEY_S = 5         # a key's effect on the screen
EXIT_S = 5        # the monitor gone after q or the hang-up


class Screen:
    """The part of an xterm the monitor's view and its summary use."""

    def __init__(self, rows, cols):
        self.rows, self.cols = rows, cols
        self.main = self._blank()
        self.alt_buf = self._blank()
        self.alt = False
        self.x = self.y = 0
        self.saved = (0, 0)
        self.attr = ""          # the SGR in force: "" or a set of "1", "4", "7"
        self.cursor_shown = True
        self.raw = b""
        self._dec = codecs.getincrementaldecoder("utf-8")("replace")
        self._esc = ""          # an escape sequence not yet complete

    def _blank(self):
        return [[(" ", "") for _ in range(self.cols)] for _ in range(self.rows)]

    @property
    def buf(self):
        return self.alt_buf if self.alt else self.main

    def line(self, r):
        return "".join(c for c, _ in self.buf[r]).rstrip()

    def lines(self):
        return [self.line(r) for r in range(self.rows)]

    def text(self):
        return "\n".join(self.lines())

    def reversed_rows(self):
        return [r for r in range(self.rows) if any("7" in a for _, a in self.buf[r])]

    def feed(self, data):
        self.raw += data
        for ch in self._dec.decode(data):
            if self._esc:
                self._esc += ch
                if self._esc_done():
                    seq, self._esc = self._esc, ""
                    self._escape(seq)
            elif ch == "\x1b":
                self._esc = ch
            else:
                self._char(ch)

    def _esc_done(self):
        s = self._esc
        if len(s) < 2:
            return False
        if s[1] != "[":
            return True                 # ESC and one character
        return len(s) > 2 and "@" <= s[-1] <= "~"

    def _newline(self):
        if self.y == self.rows - 1:
            self.buf.pop(0)
            self.buf.append([(" ", "") for _ in range(self.cols)])
        else:
            self.y += 1

    def _char(self, ch):
        if ch == "\r":
            self.x = 0
        elif ch == "\n":
            self._newline()
        elif ch == "\b":
            self.x = max(0, self.x - 1)
        elif ch >= " ":
            if self.x >= self.cols:     # the pending wrap of a full line
                self.x = 0
                self._newline()
            self.buf[self.y][self.x] = (ch, self.attr)
            self.x += 1

    def _escape(self, seq):
        if seq[1] != "[":
            return
        final, body = seq[-1], seq[2:-1]
        private = body.startswith("?")
        nums = [int(n) if n.isdigit() else 0 for n in body.lstrip("?").split(";")] if body else []
        if private and final in "hl":
            on = final == "h"
            for n in nums:
                if n == 1049 and on != self.alt:
                    if on:
                        self.saved = (self.x, self.y)
                        self.alt_buf = self._blank()
                        self.alt = True
                    else:
                        self.alt = False
                        self.x, self.y = self.saved
                elif n == 25:
                    self.cursor_shown = on
        elif final == "H":
            r = (nums[0] if nums and nums[0] else 1) - 1
            c = (nums[1] if len(nums) > 1 and nums[1] else 1) - 1
            self.y, self.x = min(r, self.rows - 1), min(c, self.cols - 1)
        elif final == "J" and nums and nums[0] == 2:
            for r in range(self.rows):
                self.buf[r] = [(" ", "") for _ in range(self.cols)]
        elif final == "K":
            for c in range(self.x, self.cols):
                self.buf[self.y][c] = (" ", "")
        elif final == "m":
            codes = set(str(n) for n in (nums or [0]))
            self.attr = "" if codes <= {"0"} else "".join(sorted(codes - {"0"}))


passed = failed = 0


def ok():
    global passed
    passed += 1


def bad(msg):
    global failed
    failed += 1
    print("FAIL: " + msg, file=sys.stderr)


def check(cond, what, screen=None):
    if cond:
        ok()
    else:
        bad(what + ("" if screen is None else ":\n" + screen.text()))
    return cond


class Monitor:
    """dfp-sim monitor ARGS with a PTY of ROWS x COLS as its terminal (stdin, stdout, stderr and
    controlling terminal), its output fed to a Screen."""

    def __init__(self, sim, args):
        self.master, self.slave = os.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", ROWS, COLS, 0, 0))
        self.before = termios.tcgetattr(self.slave)
        self.screen = Screen(ROWS, COLS)

        def own_terminal():
            os.setsid()
            fcntl.ioctl(0, termios.TIOCSCTTY, 0)
        self.proc = subprocess.Popen([sim, "monitor"] + args, stdin=self.slave,
                                     stdout=self.slave, stderr=self.slave,
                                     preexec_fn=own_terminal, close_fds=True)

    def read(self, timeout):
        """What the monitor wrote within timeout s (less when it ended)."""
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                return
            r, _, _ = select.select([self.master], [], [], min(left, 0.05))
            if r:
                try:
                    data = os.read(self.master, 65536)
                except OSError:
                    return
                self.screen.feed(data)
            elif self.proc.poll() is not None:
                return

    def until(self, cond, timeout):
        """Reads until cond(screen) holds; its last value."""
        end = time.monotonic() + timeout
        while True:
            got = cond(self.screen)
            if got or time.monotonic() >= end:
                return got
            self.read(0.1)

    def key(self, data):
        os.write(self.master, data)

    def wait(self, timeout):
        end = time.monotonic() + timeout
        while self.proc.poll() is None and time.monotonic() < end:
            self.read(0.05)
        self.read(0.2)             # what it wrote last
        return self.proc.poll()

    def settings_restored(self):
        return termios.tcgetattr(self.slave) == self.before

    def close(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master)
        os.close(self.slave)


def start_line(sim, tmp, name):
    d = os.path.join(tmp, name)
    os.mkdir(d)
    out = open(os.path.join(tmp, name + ".out"), "w+")
    line = subprocess.Popen([sim, "line", "--dir", d, "--ports", "2", "--baud", "187500",
                             "--card", "5", "--card", "6", "--master", "2",
                             "--master-slaves", "5,6", "--quiet"],
                            stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    end = time.monotonic() + 10
    while time.monotonic() < end and line.poll() is None:
        out.seek(0)
        if "Ctrl-C ends it" in out.read():
            return line, os.path.join(d, "port1")
        time.sleep(0.05)
    out.seek(0)
    raise SystemExit("dfp-sim line did not start: " + out.read())


ROW = re.compile(r"^[! ]\s*(\d+) (\S+)\s+(\S+(?: ring)?)\s+(\S+)")


def rows(screen):
    """address -> (role, state, master) of the station table's rows."""
    got = {}
    for ln in screen.lines()[3:]:
        m = ROW.match(ln)
        if not m:
            break
        got[int(m.group(1))] = (m.group(2), m.group(3), m.group(4))
    return got


def line_and_cards_shown(s):
    r = rows(s)
    return (r.get(2, ("",))[0] == "master" and r.get(2)[1] in ("holder", "in ring") and
            r.get(5) == ("slave", "Data_Exch", "2") and r.get(6) == ("slave", "Data_Exch", "2"))


def test_keys_and_quit(sim, tmp):
    line, port = start_line(sim, tmp, "l1")
    mon = Monitor(sim, ["--port", port, "--baud", "187500"])
    try:
        s = mon.screen
        check(mon.until(line_and_cards_shown, SHOW_S),
              "the table shows master 2, slaves 5 and 6 in Data_Exch with master 2", s)
        check(s.alt, "the view is on the alternate screen")
        check(not s.cursor_shown, "the cursor is hidden while the view is shown")
        head = s.line(0)
        check(head.startswith(port + "  187.5 kbit/s  up "), "the header names the port and "
              "the rate: " + head)
        check(head.endswith("? help  q quit"), "the header shows the keys: " + head)
        check(mon.until(lambda sc: re.search(r"  ring 2  holder 2$", sc.line(1)), KEY_S),
              "the second line shows the ring of master 2", s)
        check(s.line(2).split() == ["ADR", "ROLE", "STATE", "MSTR", "IDENT", "DXmean", "DXmax",
                                    "TSDRus", "REQ", "REP", "MISS", "DIAG"],
              "the table's heading: " + s.line(2))
        check([int(ROW.match(s.line(r)).group(1)) for r in (3, 4, 5)] == [2, 5, 6],
              "one row per station by address", s)
        check(s.reversed_rows() == [3], "the first station is selected (reversed)", s)
        check(" n/m " in s.line(4), "TSDR not measurable on a PTY: " + s.line(4))

        mon.key(b"\x1b[B")
        mon.key(b"\x1b[B")
        check(mon.until(lambda sc: sc.reversed_rows() == [5], KEY_S),
              "Down Down selects the third row (station 6)", s)
        mon.key(b"\r")
        check(mon.until(lambda sc: sc.line(6).startswith("station 6: slave, Data_Exch (e: "),
                        KEY_S), "Enter: station 6's details in the pane", s)
        details = "\n".join(s.lines()[7:])
        check("heard first at " in details, "the details say when 6 was heard", s)
        check("data exchange " in details, "the details have 6's Data_Exchange figures", s)

        mon.key(b"e")
        check(mon.until(lambda sc: sc.line(6).startswith("events, newest first: "), KEY_S),
              "e: the events pane", s)
        events = s.lines()[7:]
        check(any(ln.endswith("slave 5 in data exchange with master 2") for ln in events),
              "the events pane has slave 5 entering data exchange", s)
        check(any(ln.endswith("slave 6 in data exchange with master 2") for ln in events),
              "and slave 6", s)

        mon.key(b"q")
        rc = mon.wait(EXIT_S)
        check(rc == 0, "q: the monitor exits 0 (exit %s)" % rc, s)
        check(b"\x1b[?1049l" in s.raw, "the alternate screen is left")
        check(not s.alt and s.cursor_shown, "main screen and cursor back", s)
        check(mon.settings_restored(), "the PTY's settings are what they were before")
        check(re.search(r"^monitor %s: [0-9.]+ s, \d+ telegrams" % re.escape(port), s.text(),
                        re.M), "the summary on the main screen", s)
    finally:
        mon.close()

    # Ctrl-C on the terminal (SIGINT from the PTY's line discipline) ends it the same way.
    mon = Monitor(sim, ["--port", port, "--baud", "187500"])
    try:
        s = mon.screen
        check(mon.until(line_and_cards_shown, SHOW_S), "a second view shows the line", s)
        mon.key(b"\x03")
        rc = mon.wait(EXIT_S)
        check(rc == 0, "Ctrl-C: the monitor exits 0 (exit %s)" % rc, s)
        check(not s.alt and s.cursor_shown, "Ctrl-C: main screen and cursor back", s)
        check(mon.settings_restored(), "Ctrl-C: the PTY's settings are what they were before")
    finally:
        mon.close()
        line.send_signal(signal.SIGINT)
        line.wait()


def test_line_gone(sim, tmp):
    line, port = start_line(sim, tmp, "l2")
    mon = Monitor(sim, ["--port", port, "--baud", "187500"])
    try:
        s = mon.screen
        check(mon.until(line_and_cards_shown, SHOW_S), "the view shows the line", s)
        line.send_signal(signal.SIGTERM)   # the line closes its PTYs: the port hangs up
        line.wait()
        rc = mon.wait(EXIT_S)
        check(rc == 1, "the port hung up: the monitor exits 1 (exit %s)" % rc, s)
        check(not s.alt and s.cursor_shown, "main screen and cursor back", s)
        check(mon.settings_restored(), "the PTY's settings are what they were before")
        check(re.search(r"^monitor: %s: hang-up" % re.escape(port), s.text(), re.M),
              "the hang-up is told on the main screen", s)
    finally:
        mon.close()
        if line.poll() is None:
            line.kill()
            line.wait()


def main():
    sim = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="dfp-mon-top-") as tmp:
        test_keys_and_quit(sim, tmp)
        test_line_gone(sim, tmp)
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
