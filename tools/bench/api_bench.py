#!/usr/bin/env python3
"""Benchmark of the control API (docs/performance.md, "The control API"): prints figures, asserts
nothing. A card (dfp-sim slave) and the built-in master (dfp-sim master --cycles 0) on a PTY pair
at 19.2 kbit/s, both with --http. Measures

  1. GET /api/v1/state latency on the slave (N sequential requests: median, p99, max);
  2. the SSE event stream: state events per second seen by one client;
  3. the master's Data_Exchange cycle rate over a window with no client, with 10 clients
     streaming /api/v1/events from the slave and the master, and with one more client polling
     /state back to back, so a reader can see what the panel costs the bus.

    tools/bench/api_bench.py [--dfp-sim PATH] [--requests N] [--window S]
"""
import argparse
import json
import os
import secrets
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

# The API needs a credential (docs/api.md, "Security"): both processes get this token.
TOKEN = secrets.token_urlsafe(32)
os.environ["DFP_SIM_TOKEN"] = TOKEN


def api_request(port, path):
    return urllib.request.Request(f"http://127.0.0.1:{port}{path}",
                                  headers={"Authorization": "Bearer " + TOKEN})


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def get(port, path, timeout=5):
    with urllib.request.urlopen(api_request(port, path), timeout=timeout) as r:
        return json.loads(r.read())


def wait(pred, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            if pred():
                return
        except OSError:
            pass
        time.sleep(0.05)
    sys.exit(f"api_bench: {what} not reached within {timeout} s")


def cycles(port):
    return sum(s["cycles"] for s in get(port, "/api/v1/state")["master"]["slaves"])


def cycle_rate(port, window):
    c0, t0 = cycles(port), time.monotonic()
    time.sleep(window)
    c1, t1 = cycles(port), time.monotonic()
    return (c1 - c0) / (t1 - t0)


def stream(port, stop, counter):
    try:
        with urllib.request.urlopen(api_request(port, "/api/v1/events"), timeout=5) as r:
            while not stop.is_set():
                line = r.readline()
                if not line:
                    return
                if line.startswith(b"event: state"):
                    counter[0] += 1
    except OSError:
        pass


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dfp-sim", default=os.environ.get(
        "DFP_SIM", "build/host/sim_host/dfp_sim/dfp-sim"))
    ap.add_argument("--requests", type=int, default=1000)
    ap.add_argument("--window", type=float, default=5.0)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp()
    pa, pb = os.path.join(tmp, "a"), os.path.join(tmp, "b")
    procs = [subprocess.Popen(["socat", f"pty,raw,echo=0,link={pa}", f"pty,raw,echo=0,link={pb}"])]
    try:
        wait(lambda: os.path.exists(pa) and os.path.exists(pb), 5, "the PTY pair")
        ps, pm = free_port(), free_port()
        procs.append(subprocess.Popen([a.dfp_sim, "slave", "--port", pa, "--address", "4",
                                       "--baud", "19200", "--quiet", "--http", str(ps)],
                                      stdout=subprocess.DEVNULL))
        procs.append(subprocess.Popen([a.dfp_sim, "master", "--port", pb, "--address", "4",
                                       "--config", "F3F2", "--baud", "19200", "--cycles", "0",
                                       "--quiet", "--http", str(pm)], stdout=subprocess.DEVNULL))
        wait(lambda: get(pm, "/api/v1/state")["master"]["slaves"][0]["phase"] == "DATA_EXCH",
             15, "data exchange")
        lat = []
        for _ in range(a.requests):
            t = time.perf_counter()
            get(ps, "/api/v1/state")
            lat.append((time.perf_counter() - t) * 1e3)
        lat.sort()
        print(f"GET /api/v1/state (slave, {a.requests} sequential requests): median "
              f"{statistics.median(lat):.2f} ms, p99 {lat[int(0.99 * len(lat)) - 1]:.2f} ms, "
              f"max {lat[-1]:.2f} ms")
        quiet = cycle_rate(pm, a.window)
        stop = threading.Event()
        counters = [[0] for _ in range(10)]
        threads = [threading.Thread(target=stream, args=(ps if k % 2 else pm, stop, counters[k]),
                                    daemon=True) for k in range(10)]
        for t in threads:
            t.start()
        polls = [0]

        def poll():
            while not stop.is_set():
                get(ps, "/api/v1/state")
                polls[0] += 1

        poller = threading.Thread(target=poll, daemon=True)
        time.sleep(1.0)
        c_before = [c[0] for c in counters]
        t0 = time.monotonic()
        streaming = cycle_rate(pm, a.window)
        span = time.monotonic() - t0
        rates = [(c[0] - b) / span for c, b in zip(counters, c_before)]
        poller.start()
        busy = cycle_rate(pm, a.window)
        stop.set()
        print(f"event stream: {min(rates):.1f}..{max(rates):.1f} state events/s per client "
              f"(10 clients)")
        print(f"master Data_Exchange cycles/s at 19.2 kbit/s: {quiet:.1f} without clients, "
              f"{streaming:.1f} with 10 streaming clients "
              f"({100.0 * (streaming - quiet) / quiet:+.1f} %), {busy:.1f} with one more client "
              f"polling /state back to back ({polls[0] / a.window:.0f} requests/s, "
              f"{100.0 * (busy - quiet) / quiet:+.1f} %)")
    finally:
        for p in reversed(procs):
            p.send_signal(signal.SIGINT)
        for p in procs:
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()


if __name__ == "__main__":
    main()
