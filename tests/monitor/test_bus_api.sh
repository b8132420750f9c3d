# GET /api/v1/bus (docs/api.md) against `dfp-sim demo --http`: the same access rules and headers
# as every other route (no or a wrong token 401, a token in the URL 401, a foreign Host 403, the
# viewer may read, no other method), the monitor's document with the demo's master and its card
# in Data_Exch, and the monitor's events in the log and the event stream as kind "bus".
sim=$1
. "$(dirname "$0")/../cli/lib.sh"
with_tmp

token=bus-test-token-0123456789
viewer=bus-viewer-token-9876543210
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
# call CURL-ARGS...: "STATUS BODY"; the answer's headers in $tmp/head.
call() {
  local code
  code=$(curl -s --max-time 5 -D "$tmp/head" -o "$tmp/body" -w '%{http_code}' "$@")
  echo "$code $(cat "$tmp/body")"
}
header() { grep -i "^$1:" "$tmp/head" | tr -d '\r'; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }
bearer=(-H "Authorization: Bearer $token")

port=$(free_port)
url=http://127.0.0.1:$port
DFP_SIM_TOKEN=$token DFP_SIM_VIEWER_TOKEN=$viewer "$sim" demo --http "$port" \
  >"$tmp/demo.out" 2>"$tmp/demo.err" &
pids+=($!)
# The card (4) in Data_Exch with its master (2) as the monitor's document says, once the demo's
# timeline (which takes the card out of data exchange twice) is over.
card_in_dx() {
  curl -s --max-time 2 "${bearer[@]}" "$url/api/v1/state" | json 'd["t_us"] > 2500000' | grep -q True &&
    curl -s --max-time 2 "${bearer[@]}" "$url/api/v1/bus" |
    json '[s["dp"]["state"] for s in d["stations"] if s["address"] == 4 and s["dp"]] == ["Data_Exch"]'
}
up=
for _ in $(seq 200); do [ "$(card_in_dx 2>/dev/null)" = True ] && { up=1; break; }; sleep 0.1; done
if [ -z "$up" ]; then bad "the monitor never showed card 4 in Data_Exch: $(cat "$tmp/demo.err")"; finish; exit 1; fi
ok

# The document.
doc=$(call "${bearer[@]}" "$url/api/v1/bus")
expect_in "200 with the token" "200 {" "$doc"
body=${doc#200 }
expect_in "card 4: Data_Exch, master 2, ident 0x6003, its configuration" \
  "['Data_Exch', 2, '0x6003', 'F3F2', 'passive']" \
  "$(json '[[s["dp"]["state"], s["dp"]["master"], s["dp"]["ident"], s["dp"]["cfg"], s["role"]] for s in d["stations"] if s["address"] == 4][0]' <<<"$body")"
expect_in "master 2: active, in the ring, sends requests" "['active', True, True]" \
  "$(json '[[s["role"], s["in_ring"], s["requests_sent"] > 0] for s in d["stations"] if s["address"] == 2][0]' <<<"$body")"
expect_in "the ring is master 2" "[2]" "$(json 'd["ring"]["members"]' <<<"$body")"
expect_in "the stations heard are 2 and 4" "[2, 4]" "$(json '[s["address"] for s in d["stations"]]' <<<"$body")"
expect_in "the medium and its rate" "in-memory bus 1500000 True" \
  "$(json 'd["monitor"]["source"], d["monitor"]["baud"], d["monitor"]["timing"]' <<<"$body" | tr -d "(),'")"
expect_in "JSON content type" "Content-Type: application/json" "$(header Content-Type)"
for h in "Content-Security-Policy: default-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'" \
         "X-Frame-Options: DENY" "X-Content-Type-Options: nosniff" "Referrer-Policy: no-referrer" \
         "Cache-Control: no-store"; do
  expect_in "header on 200: ${h%%:*}" "$h" "$(header "${h%%:*}")"
done
# Published every 500 ms of the loop: a newer document within 2 s.
t1=$(json 'd["monitor"]["t_s"]' <<<"$body")
sleep 1.2
t2=$(curl -s --max-time 5 "${bearer[@]}" "$url/api/v1/bus" | json 'd["monitor"]["t_s"]')
expect_in "a newer document a second later" "True" "$(python3 -c "print($t2 > $t1)")"

# The access rules of every route.
need='401 {"error":"a token is needed: open the URL dfp-sim printed at start, or send Authorization: Bearer TOKEN"}'
expect_in "no token: 401" "$need" "$(call "$url/api/v1/bus")"
expect_in "with WWW-Authenticate" 'WWW-Authenticate: Bearer realm="dfp-sim"' "$(header WWW-Authenticate)"
expect_in "the 401 has the headers too" "X-Frame-Options: DENY" "$(header X-Frame-Options)"
expect_in "a wrong token: 401" "$need" \
  "$(call -H "Authorization: Bearer not-the-token-0123456789" "$url/api/v1/bus")"
expect_in "a token in the URL: 401" "$need" "$(call "$url/api/v1/bus?token=$token")"
expect_in "a foreign Host: 403" \
  "403 {\"error\":\"Host 'evil.example' is not allowed; start dfp-sim with --http-allow-host evil.example to allow it\"}" \
  "$(call "${bearer[@]}" -H "Host: evil.example" "$url/api/v1/bus")"
expect_in "the viewer reads it" "200 {\"monitor\":" \
  "$(call -H "Authorization: Bearer $viewer" "$url/api/v1/bus")"
expect_in "POST: 405" '405 {"error":"use GET"}' \
  "$(call "${bearer[@]}" -H 'Content-Type: application/json' -d '{}' "$url/api/v1/bus")"
expect_in "a viewer's POST: 403 (an action)" \
  '403 {"error":"this needs the operator role; this client is a viewer"}' \
  "$(call -H "Authorization: Bearer $viewer" -H 'Content-Type: application/json' -d '{}' "$url/api/v1/bus")"
expect_in "the session cookie of a login reads it" "200 {\"monitor\":" \
  "$(curl -s -c "$tmp/jar" -H 'Content-Type: application/json' -d "{\"token\":\"$viewer\"}" "$url/api/v1/login" >/dev/null
     call -b "$tmp/jar" "$url/api/v1/bus")"

# The monitor's events: log kind "bus", source "station N", in the log and the stream.
log=$(curl -s --max-time 5 "${bearer[@]}" "$url/api/v1/log?since=0&limit=4096")
expect_in "card 4 entering data exchange, logged as kind bus" \
  "('station 4', 'info', 'slave 4 in data exchange with master 2')" \
  "$(json '[(e["source"], e["level"], e["text"]) for e in d if e["kind"] == "bus"]' <<<"$log")"
expect_in "master 2 heard first, as kind bus" "('station 2', 'bus')" \
  "$(json '[(e["source"], e["kind"]) for e in d if e["kind"] == "bus"][0]' <<<"$log")"
curl -s --max-time 2 "${bearer[@]}" -H "Last-Event-ID: 0" "$url/api/v1/events" >"$tmp/sse" 2>/dev/null
expect_in "the event stream carries them" '"source":"station 4","level":"info","kind":"bus","text":"slave 4 in data exchange with master 2"' \
  "$(cat "$tmp/sse")"
finish
