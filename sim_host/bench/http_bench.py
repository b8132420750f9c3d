#!/usr/bin/env python3
"""What HTTP clients can do to the bus (docs/performance.md, "The control API under load").

Starts dfp-sim slave (one card, address 4) and dfp-sim master over a PTY pair made by socat,
the master setting a 10 ms DP watchdog (time base 1 ms), both with --http. Then:
  flood      N worker processes send requests to the card's API for a fixed time (GET state,
             GET log?limit=4096, a POST the loop refuses with 409, and event streams); prints the
             request count, the rate and the card's watchdog expiries during the flood (from its
             log, "DP watchdog expired"), and its state at the end.
  slowloris  opens N connections to the master's API from 127.0.0.2 (and further addresses with
             --addresses), each sending one octet every 2 s, then times a STOP (POST
             /api/v1/master/run {"running": false}) from 127.0.0.1; prints the time, and how many
             of the slow connections the server closed and when.
Output: one "key=value" line per figure. DFP_SIM_TOKEN (else a token of its own) goes to
dfp-sim in its environment and to the server as "Authorization: Bearer" with every request.
Usage: http_bench.py DFP_SIM [--part flood|slowloris|both] [--seconds S] [--workers N] [--pause-ms MS]
                     [--conns N] [--addresses K] [--hold S] [--nice N] [--rt PRIO]
"""
import argparse
import http.client
import json
import multiprocessing
import os
import re
import secrets
import socket
import subprocess
import sys
import tempfile
import threading
import time

WATCHDOG_PRM = ["--watchdog", "100", "--prm", "040000068100000100"]  # 10 x 1 ms (WD_Base_1ms)
# The API needs a credential (docs/api.md, "Security"): dfp-sim gets this token in its
# environment and every request sends it.
TOKEN = os.environ.get("DFP_SIM_TOKEN") or secrets.token_urlsafe(32)
os.environ["DFP_SIM_TOKEN"] = TOKEN


def headers(extra=None):
    h = {"Content-Type": "application/json"}
    if TOKEN:
        h["Authorization"] = "Bearer " + TOKEN
    h.update(extra or {})
    return h


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def request(port, method, path, body=None, source="127.0.0.1", timeout=10.0):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout, source_address=(source, 0))
    try:
        c.request(method, path, body=body, headers=headers())
        r = c.getresponse()
        return r.status, r.read()
    finally:
        c.close()


class Rig:
    """socat, the card (slave) and the master, in a temporary directory."""

    def __init__(self, sim, nice, rt):
        self.prefix = ["chrt", "-f", str(rt)] if rt else ["nice", "-n", str(nice)] if nice else []
        self.dir = tempfile.mkdtemp(prefix="dfp-http-bench.")
        self.procs = []
        a, b = os.path.join(self.dir, "a"), os.path.join(self.dir, "b")
        self.spawn([*self.prefix, "socat", f"pty,raw,echo=0,link={a}",
                    f"pty,raw,echo=0,link={b}"], "socat")
        for _ in range(50):
            if os.path.exists(a) and os.path.exists(b):
                break
            time.sleep(0.1)
        self.card_port, self.master_port = free_port(), free_port()
        self.spawn([*self.prefix, sim, "slave", "--port", a, "--address", "4", "--http",
                    str(self.card_port)], "slave")
        self.spawn([*self.prefix, sim, "master", "--port", b, "--address", "4", "--config", "F3F2",
                    "--baud", "1.5M", "--cycles", "0", *WATCHDOG_PRM, "--http",
                    str(self.master_port)], "master")

    def spawn(self, argv, name):
        out = open(os.path.join(self.dir, name + ".out"), "wb")
        self.procs.append(subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT))

    def card(self):
        status, body = request(self.card_port, "GET", "/api/v1/state")
        return json.loads(body)["cards"][0]["dp"] if status == 200 else {}

    def wait_data_exchange(self, limit_s=20.0):
        end = time.monotonic() + limit_s
        while time.monotonic() < end:
            try:
                dp = self.card()
                if dp.get("state") == "Data_Exch" and dp.get("watchdog_ms") == 10:
                    return True
            except OSError:
                pass
            time.sleep(0.1)
        return False

    def expiries(self):
        with open(os.path.join(self.dir, "slave.out"), "rb") as f:
            return len(re.findall(rb"DP watchdog expired", f.read()))

    def close(self):
        for p in reversed(self.procs):
            p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()


# ---- flood -----------------------------------------------------------------------------------

REQUESTS = [("GET", "/api/v1/state", None), ("GET", "/api/v1/log?limit=4096", None),
            ("POST", "/api/v1/master/run", b'{"running": false}')]  # the card's loop: 409


def flood_worker(args):
    port, source, until, kind, pause_s, client_nice = args
    # The flood's clients stand for other machines: on this one they must not take the CPU from
    # the processes under test, or the figure would be the load generator's, not the server's.
    os.nice(client_nice)
    if kind == "events":
        return stream_worker(port, source, until)
    n, conn = 0, None
    while time.time() < until:
        method, path, body = REQUESTS[n % len(REQUESTS)]
        try:
            if conn is None:
                conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10,
                                                  source_address=(source, 0))
            conn.request(method, path, body=body, headers=headers())
            conn.getresponse().read()
            n += 1
            if pause_s > 0:
                time.sleep(pause_s)
        except (OSError, http.client.HTTPException):
            conn = None
            time.sleep(0.01)
    return n


def stream_worker(port, source, until):
    n = 0
    while time.time() < until:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2, source_address=(source, 0))
            auth = f"Authorization: Bearer {TOKEN}\r\n" if TOKEN else ""
            s.sendall(f"GET /api/v1/events HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n{auth}\r\n"
                      .encode())
            n += 1
            while time.time() < until and s.recv(65536):
                pass
            s.close()
        except OSError:
            time.sleep(0.01)
    return n


def flood(rig, seconds, workers, pause_s, client_nice):
    before = rig.expiries()
    until = time.time() + seconds
    # Each worker from an address of its own, so the per-address limit does not turn them away.
    jobs = [(rig.card_port, f"127.0.0.{10 + i}", until, "requests", pause_s, client_nice)
            for i in range(workers)]
    jobs += [(rig.card_port, f"127.0.0.{10 + i}", until, "events", 0, client_nice)
             for i in range(2)]
    t0 = time.monotonic()
    with multiprocessing.Pool(len(jobs)) as pool:
        counts = pool.map(flood_worker, jobs)
    spent = time.monotonic() - t0
    requests = sum(counts[:workers])
    print(f"flood_seconds={spent:.1f}")
    print(f"flood_workers={workers}")
    print(f"flood_requests={requests}")
    print(f"flood_rate_per_s={requests / spent:.0f}")
    print(f"flood_watchdog_expiries={rig.expiries() - before}")
    print(f"flood_card_state={rig.card().get('state')}")


# ---- slow-loris ------------------------------------------------------------------------------

def slowloris(rig, conns, addresses, hold_s):
    text = f"GET /api/v1/state HTTP/1.1\r\nHost: 127.0.0.1:{rig.master_port}\r\n" + \
           "X-Padding: " + "a" * 4000 + "\r\n\r\n"
    socks, closed_at, lock = [], {}, threading.Lock()
    t_open = time.monotonic()
    for i in range(conns):
        s = socket.socket()
        s.bind((f"127.0.0.{2 + i % addresses}", 0))
        s.settimeout(2)
        try:
            s.connect(("127.0.0.1", rig.master_port))
            socks.append(s)
        except OSError:
            closed_at[i] = 0.0
            s.close()

    stop = threading.Event()

    def drip():
        k = 0
        while not stop.is_set():
            for i, s in enumerate(socks):
                if i in closed_at:
                    continue
                try:
                    s.send(text[k % len(text)].encode())
                    s.setblocking(False)
                    try:
                        gone = s.recv(4096) == b""
                    except BlockingIOError:
                        gone = False
                    s.setblocking(True)
                except OSError:
                    gone = True
                if gone:
                    with lock:
                        closed_at[i] = time.monotonic() - t_open
            k += 1
            stop.wait(2.0)

    th = threading.Thread(target=drip, daemon=True)
    th.start()
    time.sleep(3.0)  # every connection has sent something and waits for more
    t0 = time.monotonic()
    try:
        status, _ = request(rig.master_port, "POST", "/api/v1/master/run",
                            b'{"running": false}', timeout=30)
    except OSError:
        status = 0
    stop_s = time.monotonic() - t0
    time.sleep(max(0.0, hold_s - (time.monotonic() - t_open)))
    stop.set()
    th.join()
    with lock:
        times = sorted(closed_at.values())
    for s in socks:
        s.close()
    print(f"slowloris_conns={conns}")
    print(f"slowloris_addresses={addresses}")
    print(f"stop_status={status}")
    print(f"stop_seconds={stop_s:.3f}")
    print(f"slowloris_closed={len(times)}")
    print(f"slowloris_open_after_{hold_s:.0f}s={conns - len(times)}")
    print(f"slowloris_last_closed_s={times[-1] if times else -1:.1f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sim")
    ap.add_argument("--part", choices=["flood", "slowloris", "both"], default="both")
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--workers", type=int, default=8)
    ap.add_argument("--pause-ms", type=float, default=0.0,
                    help="each flood worker waits this long between two requests")
    ap.add_argument("--conns", type=int, default=70)
    ap.add_argument("--addresses", type=int, default=1)
    ap.add_argument("--hold", type=float, default=16.0)
    ap.add_argument("--client-nice", type=int, default=19,
                    help="the flood's clients run at this nice value (default 19: they stand for "
                    "other machines; 0 lets them compete with dfp-sim for the CPU)")
    ap.add_argument("--nice", type=int, default=0,
                    help="run dfp-sim with this nice value (e.g. -10 as root: other load on the "
                         "machine then disturbs the loops less; the request threads still go "
                         "to +10)")
    ap.add_argument("--rt", type=int, default=0,
                    help="run socat and dfp-sim with SCHED_FIFO at this priority (chrt; root or "
                         "RLIMIT_RTPRIO); the request threads drop it")
    o = ap.parse_args()
    if not os.access(o.sim, os.X_OK):
        print(f"http_bench: {o.sim} is not an executable", file=sys.stderr)
        return 2
    rig = Rig(o.sim, o.nice, o.rt)
    try:
        # A STOP needs a running master only; the 10 ms watchdog matters for the flood.
        if o.part != "slowloris" and not rig.wait_data_exchange():
            print(f"http_bench: the card did not reach Data_Exch with a 10 ms watchdog "
                  f"(logs in {rig.dir})", file=sys.stderr)
            return 1
        print(f"logs={rig.dir}")
        if o.part in ("flood", "both"):
            quiet = rig.expiries()
            time.sleep(2.0)
            print(f"quiet_watchdog_expiries_2s={rig.expiries() - quiet}")
            flood(rig, o.seconds, o.workers, o.pause_ms / 1000.0, o.client_nice)
        if o.part in ("slowloris", "both"):
            rig.wait_data_exchange(5.0)
            slowloris(rig, o.conns, o.addresses, o.hold)
    finally:
        rig.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
