# dfp-sim replay --http (docs/replay.md): a capture replayed at its own pace (--speed real) with
# the read-only control API beside it. The API shows the card under test in Data_Exch with its
# address and mode "replay", read_only true; every action (a card's inputs, a parameter write,
# the master) answers 403; the replay's report is unchanged by the server.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
export DFP_SIM_TOKEN=cli-test-token-0123456789 # the operator's: even it may not act on a replay
auth=(-H "Authorization: Bearer $DFP_SIM_TOKEN")
get() { curl -s --max-time 5 "${auth[@]}" "http://127.0.0.1:$1$2"; }
post() { curl -s --max-time 10 -o "$tmp/body" -w '%{http_code}' -X "${4:-POST}" "${auth[@]}" -H 'Content-Type: application/json' -d "$3" "http://127.0.0.1:$1$2"; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }

# About 5 s of bus time: 2500 Data_Exchange cycles of 2 ms.
expect_exit 0 "record the capture" -- "$sim" record --cycles 2500 --param-every 0 --capture "$tmp/long.pcap"
port=$(free_port)
"$sim" replay "$tmp/long.pcap" --check --speed real --http "$port" >"$tmp/replay.out" 2>"$tmp/replay.err" &
replay=$!; pids+=($replay)

card_dx() { get "$port" /api/v1/state | json 'd["cards"][0]["dp"]["state"] == "Data_Exch"'; }
seen=no
for _ in $(seq 40); do [ "$(card_dx 2>/dev/null)" = True ] && { seen=yes; break; }; sleep 0.1; done
if [ $seen = yes ]; then ok; else bad "the card never showed Data_Exch: $(get "$port" /api/v1/state)"; fi
st=$(get "$port" /api/v1/state)
expect_in "mode replay, read-only" "replay True 1 4" \
  "$(json '" ".join(str(x) for x in [d["mode"], d["read_only"], len(d["cards"]), d["cards"][0]["address"]])' <<<"$st")"
code=$(post "$port" /api/v1/cards/4/inputs '{"di00":false}')
expect_in "a card action is refused" '403 {"error":"this server is read-only"}' "$code $(cat "$tmp/body")"
code=$(post "$port" /api/v1/cards/4/params/P100 '{"value":3}' PUT)
expect_in "a parameter write is refused" '403 {"error":"this server is read-only"}' "$code $(cat "$tmp/body")"
code=$(post "$port" /api/v1/master/run '{"running":false}')
expect_in "a master action is refused" '403 {"error":"this server is read-only"}' "$code $(cat "$tmp/body")"
if kill -0 $replay 2>/dev/null; then ok; else bad "the replay ended before the API was asked (too fast?)"; fi

wait $replay; rc=$?
if [ $rc = 0 ]; then ok; else bad "replay exit $rc: $(cat "$tmp/replay.out" "$tmp/replay.err")"; fi
expect_in "the check still matches" "result: MATCH: all 2527 replies match" "$(cat "$tmp/replay.out")"
expect_in "the server said where it listens" "(read-only)" "$(cat "$tmp/replay.out" "$tmp/replay.err")"
finish
