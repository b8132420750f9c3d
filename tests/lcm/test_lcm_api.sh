#!/usr/bin/env bash
# The control API's own events in the LCM telemetry (docs/api.md "Security", the audit): `dfp-sim
# demo --http --lcm file://LOG` audits an accepted action and three refused requests; each is an
# api_event_t on DFP_API with exactly the level, kind and text GET /api/v1/log gives, and a line
# of the terminal log. Then a burst of 400 refusals: the terminal shows or counts every one, and
# DFP_API carries those shown. A file:// log needs no network.
# Usage: test_lcm_api.sh DFP_SIM PYTHON
sim=$1
py=$2
. "$(dirname "$0")/../cli/lib.sh"
with_tmp
token=lcm-api-test-token-0123456789
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
url=http://127.0.0.1:$port
bearer=(-H "Authorization: Bearer $token")
DFP_SIM_TOKEN=$token "$sim" demo --http "$port" --lcm "file://$tmp/api.lcm?mode=w" \
  >"$tmp/demo.out" 2>"$tmp/demo.err" &
pid=$!
pids+=("$pid")
# Past the demo's scenes (2.5 s at wall-clock speed with --http): an action taken during them
# would make its checks fail.
for _ in $(seq 150); do
  curl -s --max-time 2 "${bearer[@]}" "$url/api/v1/state" |
    python3 -c 'import json,sys; sys.exit(0 if json.load(sys.stdin)["t_us"] > 2500000 else 1)' \
    2>/dev/null && break
  sleep 0.1
done

post() { curl -s --max-time 5 -o /dev/null -w '%{http_code}' -X POST "$@"; }
expect_in "an operator's STOP" 200 "$(post "${bearer[@]}" -H 'Content-Type: application/json' -d '{"running": false}' "$url/api/v1/master/run")"
expect_in "a cross-site simple POST" 415 "$(post "${bearer[@]}" -H 'Content-Type: text/plain' -d '{"running": true}' "$url/api/v1/master/run")"
expect_in "no token" 401 "$(post -H 'Content-Type: application/json' -d '{"running": true}' "$url/api/v1/master/run")"
expect_in "a foreign Origin" 403 "$(post "${bearer[@]}" -H 'Content-Type: application/json' -H 'Origin: http://evil.example' -d '{"running": true}' "$url/api/v1/master/run")"
sleep 0.3 # the loop passes the API's events on at its next turn (every 20 ms)
curl -s --max-time 5 "${bearer[@]}" "$url/api/v1/log?since=0&limit=4096" >"$tmp/log.json"
# A burst of 400 refusals (no token, on 4 keep-alive connections): the loop passes on at most
# 32 per turn and counts the rest in a line; nothing is lost from the count.
python3 - "$port" <<'PY'
import http.client, sys, threading
def burst():
    c = http.client.HTTPConnection("127.0.0.1", int(sys.argv[1]), timeout=5)
    for _ in range(100):
        c.request("GET", "/api/v1/state")
        c.getresponse().read()
threads = [threading.Thread(target=burst) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
PY
sleep 0.3
curl -s --max-time 5 "${bearer[@]}" "$url/api/v1/log?since=0&limit=4096" >"$tmp/log_all.json"
kill -INT "$pid"; wait "$pid"; rc=$?
[ "$rc" = 0 ] && ok || bad "the demo ended with exit $rc: $(cat "$tmp/demo.err")"

"$py" - "$tmp/log.json" >"$tmp/api_log.txt" <<'PY'
import json, sys
for e in json.load(open(sys.argv[1])):
    if e["source"] == "http":
        print(e["level"], e["kind"], e["text"])
PY
PYTHONPATH="$(dirname "$0")/../../python" "$py" - "$tmp/api.lcm" >"$tmp/api_lcm.txt" <<'PY'
import sys
import lcm
from dfpsim import lcm_types
api_event_t = lcm_types.load()["api_event_t"]
for e in lcm.EventLog(sys.argv[1], "r"):
    if e.channel == "DFP_API":
        m = api_event_t.decode(e.data)
        print(m.level, m.kind, m.text)
PY
cp "$tmp/api_lcm.txt" "$tmp/api_lcm_all.txt"
head -n "$(wc -l <"$tmp/api_log.txt")" "$tmp/api_lcm_all.txt" >"$tmp/api_lcm.txt"
expect_in "four audit events in the API's log" 4 "$(grep -c ' audit ' "$tmp/api_log.txt")"
if [ -s "$tmp/api_lcm.txt" ] && cmp -s "$tmp/api_log.txt" "$tmp/api_lcm.txt"; then ok; else
  bad "DFP_API differs from the API's log:"$'\n'"$(diff "$tmp/api_log.txt" "$tmp/api_lcm.txt")"; fi
expect_in "the accepted STOP" 'info audit 127.0.0.1:' "$(grep 'POST /api/v1/master/run -> 200' "$tmp/api_lcm.txt")"
expect_in "the refusals at level warn" \
  "warn audit" "$(grep -- '-> 415 Content-Type must be application/json' "$tmp/api_lcm.txt")"
expect_in "the client without a token" " none POST /api/v1/master/run -> 401 a token is needed" "$(cat "$tmp/api_lcm.txt")"
expect_in "the foreign Origin" "-> 403 Origin 'http://evil.example' is not allowed" "$(cat "$tmp/api_lcm.txt")"
if grep -qF "$token" "$tmp/api_lcm.txt"; then bad "the token is on DFP_API"; else ok; fi
# The burst: every refusal in the API's log; the terminal shows some and counts the others, and
# DFP_API carries those it shows.
in_log=$("$py" -c 'import json,sys; print(sum(e["source"] == "http" for e in json.load(open(sys.argv[1]))))' "$tmp/log_all.json")
expect_in "404 events of the API in its log" "x404x" "x${in_log}x"
shown=$(grep -cE '^ *[0-9.]+ ms  http     127\.0\.0\.1:' "$tmp/demo.out")
counted=$(sed -nE 's/.*  http     ([0-9]+) more events of the API not shown here \(over 32 in 20 ms\).*/\1/p' "$tmp/demo.out" | awk '{s += $1} END {print s + 0}')
[ "$((shown + counted))" = "$in_log" ] && ok || bad "terminal: $shown shown + $counted counted, log: $in_log"
on_lcm=$("$py" -c 'import sys; print(sum(1 for _ in open(sys.argv[1])))' "$tmp/api_lcm_all.txt")
[ "$on_lcm" = "$shown" ] && ok || bad "DFP_API carries $on_lcm, the terminal shows $shown"
# The terminal log: one line per event, source "http".
expect_in "each on the terminal" 4 "$(grep -cE '^ *[0-9.]+ ms  http     127\.0\.0\.1:[0-9]+ (operator|none) POST /api/v1/master/run -> ' "$tmp/demo.out")"
finish
