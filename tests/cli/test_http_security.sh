# The control API's security (docs/api.md "Security") against the real program, attack by attack:
# cross-site "simple" POSTs, foreign Origins, DNS rebinding (a foreign Host), framing and sniffing
# headers on every kind of answer, no or a wrong token, the viewer role, the login cookie, a token
# in an API URL, --http-no-auth, TLS with a right and a wrong CA, the start-up URL with its
# token, and the audit events of actions and refusals. Each asserts exact statuses and bodies.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

token=cli-test-token-0123456789
viewer=cli-viewer-token-9876543210
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
as_json=(-H 'Content-Type: application/json')
# start_demo NAME URL ARGS...: dfp-sim demo with ARGS (environment as the caller set it), stdout
# and stderr in $tmp/NAME.out and .err; returns once the demo's timeline (1.8 s) is over: its PO
# words and RUN state then stay as they are unless a client changes them.
start_demo() {
  local name=$1 base=$2; shift 2
  "$sim" demo "$@" >"$tmp/$name.out" 2>"$tmp/$name.err" &
  pids+=($!)
  for _ in $(seq 150); do
    [ "$(curl -s --max-time 2 "${bearer[@]}" "$base/api/v1/state" | json 'd["t_us"] > 2500000' 2>/dev/null)" = True ] && return 0
    sleep 0.1
  done
  bad "$name did not come up: $(cat "$tmp/$name.err")"; return 1
}

port=$(free_port)
url=http://127.0.0.1:$port
DFP_SIM_TOKEN=$token DFP_SIM_VIEWER_TOKEN=$viewer start_demo main "$url" --http "$port" \
  --http-allow-host rig.example || { finish; exit 1; }
master() { call "${bearer[@]}" "$url/api/v1/state" | cut -d' ' -f2- | json '[d["master"]["running"], d["master"]["slaves"][0]["po"]]'; }
# expect_master DESCRIPTION WANTED: the master's RUN state and PO words, once an accepted action
# reached the published state (within 3 s), or at once for one that must have changed nothing.
expect_master() {
  local got
  for _ in $(seq 30); do got=$(master); [ "$got" = "$2" ] && break; sleep 0.1; done
  if [ "$got" = "$2" ]; then ok; else bad "$1: $got, expected $2"; fi
}
expect_master "the demo's master runs with PO words 6 1500 0" "[True, [6, 1500, 0]]"

# The start-up lines: the URL to open with each token, on stderr only.
expect_in "the operator's URL" "dfp-sim: control panel at $url/?token=$token" "$(cat "$tmp/main.err")"
expect_in "the viewer's URL" "dfp-sim: read-only panel at $url/?token=$viewer" "$(cat "$tmp/main.err")"
if grep -qF "$token" "$tmp/main.out"; then bad "the token is in the log on stdout"; else ok; fi

# Cross-site "simple" POSTs (what a page of any site may send without asking), even with the
# token: 415, and neither the PO words nor the RUN state change.
po='{"po":[6,3000,0]}'
unsupported='415 {"error":"Content-Type must be application/json"}'
expect_in "text/plain POST" "$unsupported" \
  "$(call "${bearer[@]}" -H 'Content-Type: text/plain' -d "$po" "$url/api/v1/master/slaves/4/outputs")"
expect_in "form POST" "$unsupported" \
  "$(call "${bearer[@]}" -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "multipart POST" "$unsupported" \
  "$(call "${bearer[@]}" -F 'running=false' "$url/api/v1/master/run")"
expect_in "a POST without a Content-Type" "$unsupported" \
  "$(call "${bearer[@]}" -X POST "$url/api/v1/master/run")"
expect_in "a JSON Content-Type in other case with a charset passes that check" '400 {"error":"the body must be a JSON object (it is empty)"}' \
  "$(call "${bearer[@]}" -H 'Content-Type: Application/JSON; charset=utf-8' -X POST "$url/api/v1/master/run")"
sleep 0.5 # an accepted action would show within 0.1 s
expect_in "nothing changed" "[True, [6, 1500, 0]]" "$(master)"

# Origins: a foreign one and "null" are refused (403) before anything else; the server's own
# is accepted.
expect_in "a foreign Origin" "403 {\"error\":\"Origin 'http://evil.example' is not allowed\"}" \
  "$(call "${bearer[@]}" "${as_json[@]}" -H 'Origin: http://evil.example' -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "a foreign Origin with text/plain" "403 {\"error\":\"Origin 'http://evil.example' is not allowed\"}" \
  "$(call "${bearer[@]}" -H 'Content-Type: text/plain' -H 'Origin: http://evil.example' -d "$po" "$url/api/v1/master/slaves/4/outputs")"
expect_in "Origin null" "403 {\"error\":\"Origin 'null' is not allowed\"}" \
  "$(call "${bearer[@]}" "${as_json[@]}" -H 'Origin: null' -d '{"running":false}' "$url/api/v1/master/run")"
sleep 0.5
expect_in "still nothing changed" "[True, [6, 1500, 0]]" "$(master)"
expect_in "the same origin" '200 {"ok":true}' \
  "$(call "${bearer[@]}" "${as_json[@]}" -H "Origin: $url" -d '{"po":[6,1200,0]}' "$url/api/v1/master/slaves/4/outputs")"
expect_master "the PO words set" "[True, [6, 1200, 0]]"

# DNS rebinding: a name of the attacker's that points at 127.0.0.1 is no IP address, localhost
# or --http-allow-host name; refused for the API and the panel's files alike.
evil="403 {\"error\":\"Host 'evil.example' is not allowed; start dfp-sim with --http-allow-host evil.example to allow it\"}"
expect_in "a foreign Host reads no state" "$evil" "$(call "${bearer[@]}" -H 'Host: evil.example' "$url/api/v1/state")"
expect_in "a foreign Host with a port gets no panel" "$evil" "$(call -H "Host: evil.example:$port" "$url/")"
expect_in "an --http-allow-host name is answered" "200" "$(call "${bearer[@]}" -H "Host: RIG.example:$port" "$url/api/v1/state" | cut -c1-3)"
expect_in "localhost is answered" "200" "$(call "${bearer[@]}" -H "Host: localhost:$port" "$url/api/v1/state" | cut -c1-3)"
expect_in "an IPv6 literal is answered" "200" "$(call "${bearer[@]}" -H "Host: [::1]:$port" "$url/api/v1/state" | cut -c1-3)"

# Every answer carries the anti-framing, anti-sniffing and CSP headers: a file, JSON, an error
# and the event stream.
csp="Content-Security-Policy: default-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'"
check_headers() { # check_headers WHAT
  expect_in "$1: CSP" "$csp" "$(header Content-Security-Policy)"
  expect_in "$1: X-Frame-Options" "X-Frame-Options: DENY" "$(header X-Frame-Options)"
  expect_in "$1: nosniff" "X-Content-Type-Options: nosniff" "$(header X-Content-Type-Options)"
  expect_in "$1: Referrer-Policy" "Referrer-Policy: no-referrer" "$(header Referrer-Policy)"
}
expect_in "the panel's page" "200" "$(call "$url/" | cut -c1-3)"
check_headers "the panel's page"
expect_in "a JSON answer" "200" "$(call "${bearer[@]}" "$url/api/v1/state" | cut -c1-3)"
check_headers "a JSON answer"
expect_in "and it is not cached" "Cache-Control: no-store" "$(header Cache-Control)"
expect_in "an error" "404" "$(call "$url/no-such-file" | cut -c1-3)"
check_headers "an error"
curl -s -N --max-time 1 -D "$tmp/head" -o /dev/null "${bearer[@]}" "$url/api/v1/events"
expect_in "the event stream" "Content-Type: text/event-stream" "$(header Content-Type)"
check_headers "the event stream"

# Credentials: none, a wrong one, a token in the URL of an API request: 401 with a challenge.
need='401 {"error":"a token is needed: open the URL dfp-sim printed at start, or send Authorization: Bearer TOKEN"}'
expect_in "no token" "$need" "$(call "$url/api/v1/state")"
expect_in "the challenge" 'WWW-Authenticate: Bearer realm="dfp-sim"' "$(header WWW-Authenticate)"
check_headers "a 401"
expect_in "no token for an action" "$need" "$(call "${as_json[@]}" -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "a wrong token" "$need" "$(call -H "Authorization: Bearer ${token}x" "$url/api/v1/state")"
expect_in "a wrong token of the same length" "$need" "$(call -H "Authorization: Bearer ${token%?}x" "$url/api/v1/state")"
expect_in "?token= in an API URL" "$need" "$(call "$url/api/v1/state?token=$token")"
expect_in "the event stream needs one too" "$need" "$(call "$url/api/v1/events")"
expect_in "the right token" '200 {"t_us":' "$(call "${bearer[@]}" "$url/api/v1/state")"
panel=$(call "$url/?token=$token")
expect_in "the opened URL serves the panel" "200 " "${panel:0:4}"
expect_in "its page" "<html" "$panel"
expect_in "nothing changed without a token" "[True, [6, 1200, 0]]" "$(master)"

# The viewer reads and watches, and may not act.
vbearer=(-H "Authorization: Bearer $viewer")
expect_in "the viewer reads the state" '200 {"t_us":' "$(call "${vbearer[@]}" "$url/api/v1/state")"
expect_in "the viewer reads a parameter" '200 {"ok":true,"p_number":"P100"' "$(call "${vbearer[@]}" "$url/api/v1/cards/4/params/P100")"
viewer_no='403 {"error":"this needs the operator role; this client is a viewer"}'
expect_in "the viewer may not stop the PLC" "$viewer_no" \
  "$(call "${vbearer[@]}" "${as_json[@]}" -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "nor write a parameter" "$viewer_no" \
  "$(call "${vbearer[@]}" "${as_json[@]}" -X PUT -d '{"value":1000}' "$url/api/v1/cards/4/params/P130")"
sleep 0.5
expect_in "the viewer changed nothing" "[True, [6, 1200, 0]]" "$(master)"
expect_in "session of a viewer" '200 {"auth":true,"role":"viewer"}' "$(call "${vbearer[@]}" "$url/api/v1/session")"
expect_in "session without a credential" '200 {"auth":true,"role":null}' "$(call "$url/api/v1/session")"

# The panel's login: a cookie (HttpOnly, SameSite=Strict) that works for reads and for actions
# of the same origin, until logout forgets it.
expect_in "a wrong login" "$need" "$(call "${as_json[@]}" -d '{"token":"not-the-token-at-all"}' "$url/api/v1/login")"
if [ -z "$(header Set-Cookie)" ]; then ok; else bad "a wrong login set $(header Set-Cookie)"; fi
expect_in "the operator's login" '200 {"role":"operator"}' \
  "$(call "${as_json[@]}" -H "Origin: $url" -d "{\"token\":\"$token\"}" "$url/api/v1/login")"
cookie=$(header Set-Cookie)
if [[ $cookie =~ ^Set-Cookie:\ dfp_session=[A-Za-z0-9_-]{43}\;\ Path=/\;\ HttpOnly\;\ SameSite=Strict$ ]]; then ok; else bad "the cookie: '$cookie'"; fi
session=$(sed -E 's/^Set-Cookie: (dfp_session=[^;]*);.*/\1/' <<<"$cookie")
jar=(-H "Cookie: $session")
expect_in "the cookie reads" '200 {"t_us":' "$(call "${jar[@]}" "$url/api/v1/state")"
expect_in "session with the cookie" '200 {"auth":true,"role":"operator"}' "$(call "${jar[@]}" "$url/api/v1/session")"
expect_in "the cookie acts (same origin)" '200 {"ok":true}' \
  "$(call "${jar[@]}" "${as_json[@]}" -H "Origin: $url" -d '{"po":[6,900,0]}' "$url/api/v1/master/slaves/4/outputs")"
expect_master "the cookie's action done" "[True, [6, 900, 0]]"
expect_in "the cookie from a foreign page" "403 {\"error\":\"Origin 'http://evil.example' is not allowed\"}" \
  "$(call "${jar[@]}" "${as_json[@]}" -H 'Origin: http://evil.example' -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "the viewer's login" '200 {"role":"viewer"}' "$(call "${as_json[@]}" -d "{\"token\":\"$viewer\"}" "$url/api/v1/login")"
vjar=(-H "Cookie: $(header Set-Cookie | sed -E 's/^Set-Cookie: (dfp_session=[^;]*);.*/\1/')")
expect_in "a viewer's cookie may not act" "$viewer_no" \
  "$(call "${vjar[@]}" "${as_json[@]}" -d '{"running":false}' "$url/api/v1/master/run")"
# Each role has half of the 64 sessions: 64 logins with the viewer token push out the oldest
# viewer sessions, never the operator's.
for _ in $(seq 64); do
  curl -s --max-time 5 -o /dev/null "${as_json[@]}" -d "{\"token\":\"$viewer\"}" "$url/api/v1/login"
done
expect_in "the operator's session outlives 64 viewer logins" '200 {"auth":true,"role":"operator"}' \
  "$(call "${jar[@]}" "$url/api/v1/session")"
expect_in "the first viewer session made room" '200 {"auth":true,"role":null}' \
  "$(call "${vjar[@]}" "$url/api/v1/session")"
expect_in "logout" '200 {"ok":true}' "$(call "${jar[@]}" "${as_json[@]}" -X POST "$url/api/v1/logout")"
expect_in "logout clears the cookie" "Set-Cookie: dfp_session=; Path=/; Max-Age=0; HttpOnly; SameSite=Strict" "$(header Set-Cookie)"
expect_in "the cookie no longer works" "$need" "$(call "${jar[@]}" "$url/api/v1/state")"
expect_in "the RUN state is what the operator left" "[True, [6, 900, 0]]" "$(master)"

# Request headers as RFC 9112 3.2 and RFC 9110 7.2 have them: one Host, and only a port after
# its name; a JSON Content-Type with nothing but parameters after it.
raw() { # raw REQUEST-HEAD: the status line of the answer to it (no body)
  python3 - "$port" "$1" <<'PY'
import socket, sys
s = socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=5)
s.sendall(sys.argv[2].encode().replace(b"|", b"\r\n") + b"\r\n\r\n")
print(s.recv(4096).split(b"\r\n")[0].decode())
PY
}
expect_in "two Host headers" "HTTP/1.1 400" \
  "$(raw "GET /api/v1/state HTTP/1.1|Host: 127.0.0.1|Host: evil.example|Authorization: Bearer $token")"
expect_in "two Host headers, the other order" "HTTP/1.1 400" \
  "$(raw "GET /api/v1/state HTTP/1.1|Host: evil.example|Host: 127.0.0.1|Authorization: Bearer $token")"
expect_in "no port but words after the name" "400 {\"error\":\"Host 'localhost:evil' is not NAME[:PORT]\"}" \
  "$(call "${bearer[@]}" -H 'Host: localhost:evil' "$url/api/v1/state")"
expect_in "a name after an IPv6 literal" "400 {\"error\":\"Host '[::1]evil.example' is not NAME[:PORT]\"}" \
  "$(call "${bearer[@]}" -H 'Host: [::1]evil.example' "$url/api/v1/state")"
expect_in "an empty port is a port" '200 {"t_us":' "$(call "${bearer[@]}" -H 'Host: localhost:' "$url/api/v1/state")"
expect_in "words after application/json" "415 {\"error\":\"Content-Type must be application/json\"}" \
  "$(call "${bearer[@]}" -H 'Content-Type: application/json garbage' -d '{"running":false}' "$url/api/v1/master/run")"
expect_in "application/json with a charset" '200 {"ok":true}' \
  "$(call "${bearer[@]}" -H 'Content-Type: application/json ; charset=utf-8' -d '{"running":true}' "$url/api/v1/master/run")"
# A path and a body key hold a newline and ESC: the action's error repeats them, the audit
# line does not carry them.
call "${bearer[@]}" "${as_json[@]}" -d '{}' "$url/api/v1/cards/4/x%0A%1b%5b2Jfake%20line" >/dev/null
call "${bearer[@]}" "${as_json[@]}" -d '{"a\nb\u001b[31m":1}' "$url/api/v1/master/run" >/dev/null
# A wrong token at /api/v1/session: its answer tells, so it is logged like any refusal.
call -H "Authorization: Bearer not-the-token-at-all" "$url/api/v1/session" >/dev/null

# The audit: actions and refusals in the log with the client's address, role, method, path
# and status; logins without the token.
log=$(call "${bearer[@]}" "$url/api/v1/log?since=0&limit=4096" | cut -d' ' -f2-)
audit=$(json '"\n".join(e["level"] + " " + e["text"] for e in d if e["source"] == "http" and e["kind"] == "audit")' <<<"$log")
audit_has() { # audit_has DESCRIPTION REGEX
  if grep -qE -- "$2" <<<"$audit"; then ok; else bad "audit: $1: /$2/ not in:"$'\n'"$audit"; fi
}
audit_has "the operator's action" '^info 127\.0\.0\.1:[0-9]+ operator POST /api/v1/master/slaves/4/outputs -> 200$'
audit_has "a refused simple POST" '^warn 127\.0\.0\.1:[0-9]+ operator POST /api/v1/master/run -> 415 Content-Type must be application/json$'
audit_has "a foreign Host" "^warn 127\.0\.0\.1:[0-9]+ operator GET /api/v1/state -> 403 Host 'evil.example' is not allowed"
audit_has "no token" '^warn 127\.0\.0\.1:[0-9]+ none GET /api/v1/state -> 401 a token is needed'
audit_has "the viewer refused" '^warn 127\.0\.0\.1:[0-9]+ viewer POST /api/v1/master/run -> 403 this needs the operator role; this client is a viewer$'
audit_has "a login" '^info 127\.0\.0\.1:[0-9]+ login operator -> 200$'
audit_has "a wrong login" '^warn 127\.0\.0\.1:[0-9]+ login -> 401$'
audit_has "a logout" '^info 127\.0\.0\.1:[0-9]+ logout operator -> 200$'
audit_has "a wrong token at /session" '^warn 127\.0\.0\.1:[0-9]+ none GET /api/v1/session -> 200 a wrong credential$'
audit_has "the path's newline and ESC as ?" "^warn 127\.0\.0\.1:[0-9]+ operator POST /api/v1/cards/4/x\?\?\[2Jfake line -> 404 no action 'x\?\?\[2Jfake line'"
audit_has "the body key's too" '^warn 127\.0\.0\.1:[0-9]+ operator POST /api/v1/master/run -> 400 .*a\?b\?\[31m'
ctl_events=$(json 'sum(1 for e in d if e["source"] == "http" and any(c in e["text"] for c in "\n\r\x1b"))' <<<"$log")
[ "$ctl_events" = 0 ] && ok || bad "$ctl_events audit texts hold a newline, CR or ESC"
for t in "$token" "$viewer" "not-the-token-at-all"; do
  if grep -qF -- "$t" <<<"$log"; then bad "a token is in the log: $t"; else ok; fi
done

# --http-no-auth: refused off loopback; on loopback every client acts without a token, and the
# other checks stay.
expect_exit 2 "--http-no-auth on 0.0.0.0" -- timeout 10 "$sim" demo --http 0.0.0.0:0 --http-no-auth
expect_in "says why" "dfp-sim: --http-no-auth: refused on 0.0.0.0, which is not a loopback address (127.0.0.0/8, ::1)" "$out"
nport=$(free_port)
nurl=http://127.0.0.1:$nport
start_demo noauth "$nurl" --http "$nport" --http-no-auth || { finish; exit 1; }
expect_in "no token in its URL" "dfp-sim: control panel at $nurl/"$'\n' "$(cat "$tmp/noauth.err")"$'\n'
expect_in "an action without a token" '200 {"ok":true}' "$(call "${as_json[@]}" -d '{"running":false}' "$nurl/api/v1/master/run")"
# The state is published at most 20 ms after the action: look for up to 3 s.
for _ in $(seq 30); do
  running=$(curl -s "$nurl/api/v1/state" | json 'd["master"]["running"]')
  [ "$running" = False ] && break
  sleep 0.1
done
expect_in "done" "False" "$running"
expect_in "session says no auth" '200 {"auth":false,"role":"operator"}' "$(call "$nurl/api/v1/session")"
expect_in "login needs nothing" '200 {"role":"operator"}' "$(call "${as_json[@]}" -d '{}' "$nurl/api/v1/login")"
expect_in "still no simple POST" "$unsupported" "$(call -d '{"running":true}' "$nurl/api/v1/master/run")"
expect_in "still no foreign Host" "403" "$(call -H 'Host: evil.example' "$nurl/api/v1/state" | cut -c1-3)"

# Bad options: one line and exit 2.
mkdir "$tmp/tls" && cd "$tmp/tls" || exit 1
mkcert() { # mkcert NAME: a self-signed certificate for localhost and 127.0.0.1
  openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:P-256 -nodes -subj /CN=localhost \
    -addext subjectAltName=DNS:localhost,IP:127.0.0.1 -days 2 -keyout "$1.key" -out "$1.pem" 2>/dev/null
}
mkcert rig && mkcert other || bad "openssl could not make the test certificates"
expect_exit 2 "--http-cert without --http-key" -- timeout 10 "$sim" demo --http 0 --http-cert rig.pem
expect_in "says so" "dfp-sim: --http-cert and --http-key go together: give both or neither" "$out"
expect_exit 2 "a certificate that is no PEM" -- timeout 10 "$sim" demo --http 0 --http-cert /dev/null --http-key rig.key
expect_in "names it" "dfp-sim: --http-cert '/dev/null': not a PEM file" "$out"
expect_exit 2 "a key that does not match" -- timeout 10 "$sim" demo --http 0 --http-cert rig.pem --http-key other.key
expect_in "says the HTTPS server did not start" "the HTTPS server did not start on 127.0.0.1" "$out"
printf 'short\n' >short.token
expect_exit 2 "a token file with a short token" -- timeout 10 "$sim" demo --http 0 --http-token-file short.token
expect_in "names the file" "dfp-sim: --http-token-file 'short.token': the first line must be the token, 16..256 printable ASCII characters without spaces" "$out"
expect_exit 2 "a short DFP_SIM_TOKEN" -- env DFP_SIM_TOKEN=short timeout 10 "$sim" demo --http 0
expect_in "names the variable" "dfp-sim: DFP_SIM_TOKEN: the token must be 16..256" "$out"

# TLS, with the token dfp-sim makes itself: the printed https URL carries it; curl trusting the
# test CA gets the panel and, with that token, the API; another CA fails the verification; plain
# HTTP gets no answer.
tport=$(free_port)
env -u DFP_SIM_TOKEN "$sim" demo --http "$tport" --http-cert rig.pem --http-key rig.key \
  >"$tmp/tls.out" 2>"$tmp/tls.err" &
pids+=($!)
for _ in $(seq 150); do grep -q "control panel at" "$tmp/tls.err" && break; sleep 0.1; done
line=$(grep "control panel at" "$tmp/tls.err")
if [[ $line =~ ^dfp-sim:\ control\ panel\ at\ https://127\.0\.0\.1:$tport/\?token=([A-Za-z0-9_-]{43})$ ]]; then
  ok; made=${BASH_REMATCH[1]}
else
  bad "the https URL with a made token: '$line'"; made=none
fi
panel=$(call --cacert rig.pem "https://127.0.0.1:$tport/?token=$made")
expect_in "the printed URL opens the panel over https" "200 " "${panel:0:4}"
expect_in "its page" "<html" "$panel"
expect_in "the made token works" '200 {"t_us":' "$(call --cacert rig.pem -H "Authorization: Bearer $made" "https://localhost:$tport/api/v1/state")"
expect_in "the cookie is Secure over TLS" "; HttpOnly; SameSite=Strict; Secure" \
  "$(call --cacert rig.pem "${as_json[@]}" -d "{\"token\":\"$made\"}" "https://127.0.0.1:$tport/api/v1/login" >/dev/null; header Set-Cookie)"
expect_exit 60 "another CA: the certificate does not verify" -- curl -s --max-time 5 --cacert other.pem "https://127.0.0.1:$tport/"
code=$(curl -s --max-time 5 -o /dev/null -w '%{http_code}' "http://127.0.0.1:$tport/api/v1/session"); rc=$?
if [ "$rc" != 0 ] && [ "$code" = 000 ]; then ok; else bad "plain HTTP to the TLS port: curl exit $rc, status $code"; fi
finish
