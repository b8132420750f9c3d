# Slow-loris against the control API (docs/api.md, "Limits"): 70 connections from 127.0.0.2
# (then from 127.0.0.2..10), each sending one octet every 2 s, do not lock out the operator at
# 127.0.0.1: a STOP of the master answers 200 within 5 s, and every slow connection is closed
# once its 10 s to deliver a whole request are up (at most 8 per address are accepted at all,
# and at most 16 wait for a request at once). The card and the master run
# over a PTY pair (sim_host/bench/http_bench.py, which also gives the figures).
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp
bench="$(dirname "$0")/../../sim_host/bench/http_bench.py"

# The API needs a token (docs/api.md, "Security"): http_bench.py gives dfp-sim one in its
# environment (DFP_SIM_TOKEN) and sends it with every request.

# From one address (the per-address limit) and from 9 (the limit of connections waiting for a
# request: slow clients from many addresses push out each other, not the operator).
for addresses in 1 9; do
  out=$(timeout 120 python3 "$bench" "$sim" --part slowloris --conns 70 --addresses "$addresses" \
        --hold 16 2>"$tmp/err") || { bad "http_bench.py failed: $(cat "$tmp/err")"; finish; exit 1; }
  val() { sed -n "s/^$1=//p" <<<"$out"; }
  [ "$(val stop_status)" = 200 ] && ok || bad "$addresses addresses: STOP answered $(val stop_status), not 200"
  python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < 5.0 else 1)" "$(val stop_seconds)" \
    && ok || bad "$addresses addresses: STOP took $(val stop_seconds) s (bound 5 s)"
  [ "$(val slowloris_open_after_16s)" = 0 ] && ok || bad "$addresses addresses: every slow connection closed within 16 s: $(val slowloris_open_after_16s)"
  # 10 s after its acceptance, found by the client within its 2 s between octets; from 9
  # addresses the last ones wait in the listen backlog until older ones are pushed out.
  bound=$([ "$addresses" = 1 ] && echo 14 || echo 16)
  python3 -c "import sys; sys.exit(0 if 0 <= float(sys.argv[1]) < float(sys.argv[2]) else 1)" \
    "$(val slowloris_last_closed_s)" "$bound" && ok || bad "$addresses addresses: last slow connection closed at $(val slowloris_last_closed_s) s (bound $bound s)"
done

# The log names a connection the limit closed when it never had a request answered (a slow
# client), not a browser's keep-alive connection that idles after its answer: both are closed
# 10 s after their last answer or their opening.
export DFP_SIM_TOKEN=slowloris-test-token-0123456789
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
"$sim" demo --http "$port" >"$tmp/demo.out" 2>"$tmp/demo.err" &
pids+=($!)
for _ in $(seq 100); do
  curl -s --max-time 2 -H "Authorization: Bearer $DFP_SIM_TOKEN" "http://127.0.0.1:$port/api/v1/state" >/dev/null && break
  sleep 0.1
done
timeout 60 python3 - "$port" "$DFP_SIM_TOKEN" >"$tmp/kinds" <<'PY'
import json, socket, sys, threading, time
port, token = int(sys.argv[1]), sys.argv[2]
ports = {}
def closed_after(s, t0):
    try:
        while s.recv(4096):
            pass
    except OSError:
        pass
    return time.time() - t0
def keep_alive():
    s = socket.create_connection(("127.0.0.1", port), timeout=20)
    ports["keep-alive"] = s.getsockname()[1]
    s.sendall(b"GET /api/v1/session HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
    t0 = time.time()
    s.settimeout(20)
    ports["keep-alive closed"] = closed_after(s, t0) > 9
def slow():
    s = socket.create_connection(("127.0.0.1", port), timeout=20)
    ports["slow"] = s.getsockname()[1]
    t0 = time.time()
    s.sendall(b"GET /api/v1/state HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ")
    s.settimeout(2)  # one octet every 2 s, until the server closes (EOF or reset)
    try:
        while time.time() - t0 < 15:
            try:
                if not s.recv(4096):
                    break
            except socket.timeout:
                s.sendall(b"a")
    except OSError:
        pass
    ports["slow closed"] = time.time() - t0 < 14
threads = [threading.Thread(target=f) for f in (keep_alive, slow)]
for t in threads:
    t.start()
for t in threads:
    t.join()
time.sleep(0.5)
import urllib.request
req = urllib.request.Request("http://127.0.0.1:%d/api/v1/log?since=0&limit=4096" % port,
                             headers={"Authorization": "Bearer " + token})
log = json.load(urllib.request.urlopen(req, timeout=5))
limits = [e["text"] for e in log if e["kind"] == "limit"]
print("keep-alive closed after 9 s:", ports["keep-alive closed"])
print("slow closed within 14 s:", ports["slow closed"])
print("limit events:", len(limits))
print("names the slow one:", any(":%d closed" % ports["slow"] in t for t in limits))
print("names the keep-alive one:", any(":%d closed" % ports["keep-alive"] in t for t in limits))
PY
kinds=$(cat "$tmp/kinds")
expect_in "the idle keep-alive connection is closed" "keep-alive closed after 9 s: True" "$kinds"
expect_in "the slow one is closed" "slow closed within 14 s: True" "$kinds"
expect_in "one limit event" "limit events: 1" "$kinds"
expect_in "it names the slow connection" "names the slow one: True" "$kinds"
expect_in "not the keep-alive one" "names the keep-alive one: False" "$kinds"
finish
