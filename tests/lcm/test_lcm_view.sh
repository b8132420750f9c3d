#!/usr/bin/env bash
# dfp-lcm-view (python/dfpsim/lcm_view.py), the console viewer `make deps-python` installs into
# the venv beside DFP_PYTHON, against `dfp-sim demo --lcm udpm://...`: three viewers at once see
# every message of the demo; the telegram lines carry the octets of the demo's own capture, in
# order, with the right station, direction, addresses and services; the state lines and the
# status line show the card in Data_Exch; --channel, --no-telegrams, --count, --duration,
# SIGINT and the option errors (exit 2). udpm on loopback needs a multicast route: a private
# network namespace.
# Usage: test_lcm_view.sh DFP_SIM PYTHON
sim=$1
view="$(dirname "$2")/dfp-lcm-view"
. "$(dirname "$0")/netns.sh"
. "$(dirname "$0")/../cli/lib.sh"
if [ ! -x "$view" ]; then
  echo "no $view: make deps-python (pip install -e ./python) installs it"
  echo "0 passed, 1 failed"
  exit 1
fi
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
trap 'exit 1' INT TERM
url="udpm://239.255.76.76:7676?ttl=0"
wait_listening() { # wait_listening STDERR_FILE: the viewer has subscribed
  for _ in $(seq 100); do grep -q "listening on" "$1" 2>/dev/null && return 0; sleep 0.1; done
  return 1
}

# ---- three viewers on one demo ----
# The demo publishes 3920 messages (tests/lcm/test_lcm_cli.sh counts them with lcm-logger):
# 3880 telegrams, 16 card states, 24 parameter services.
LCM_DEFAULT_URL="$url" "$view" --count 3920 --duration 60 >"$tmp/all.out" 2>"$tmp/all.err" &
all=$!; pids+=($all)
"$view" --lcm-url "$url" --channel DFP_CARD_STATE --no-telegrams --count 16 --duration 60 \
  >"$tmp/state.out" 2>"$tmp/state.err" &
state=$!; pids+=($state)
"$view" --lcm-url "$url" --status line --no-telegrams --count 3920 --duration 60 \
  >"$tmp/line.out" 2>"$tmp/line.err" &
line=$!; pids+=($line)
for f in all state line; do
  if wait_listening "$tmp/$f.err"; then ok; else bad "viewer '$f' did not start: $(cat "$tmp/$f.err")"; fi
done
expect_exit 0 "demo --lcm" -- "$sim" demo --lcm "$url" --capture "$tmp/demo.txt"
for p in all state line; do
  if wait "${!p}"; then ok; else bad "viewer '$p' exit $?: $(cat "$tmp/$p.err")"; fi
done
pids=()

all_out=$(cat "$tmp/all.out")
expect_in "\$LCM_DEFAULT_URL is the default URL" "listening on $url, channels .*" "$(cat "$tmp/all.err")"
expect_in "every message arrived" \
  "summary: 3920 messages in" "$all_out"
expect_in "counted by type" \
  "(3880 telegrams, 16 card states, 24 parameter services, 0 API events); 0 undecodable" "$all_out"
# Every telegram line holds the octets of the demo's own capture, in the same order.
grep ' DFP_TELEGRAM ' "$tmp/all.out" | grep -oE '( [0-9A-F]{2})+$' | sed 's/^ //' >"$tmp/view.hex"
cut -d' ' -f3- "$tmp/demo.txt" >"$tmp/demo.hex"
if [ "$(wc -l <"$tmp/demo.hex")" -gt 1000 ] && diff "$tmp/view.hex" "$tmp/demo.hex" >"$tmp/diff"; then ok; else
  bad "telegram octets differ from the capture:"$'\n'"$(head -6 "$tmp/diff")"; fi
# The master (2) asks the card (4), the card answers; the card publishes both (RX, TX).
dx_req=$(grep -cE ' DFP_TELEGRAM +4 RX SD2 DA +4 SA +2 FC [57]D  Data_Exchange +68 11 11 68 04 02 [57]D ' "$tmp/all.out")
dx_rsp=$(grep -cE ' DFP_TELEGRAM +4 TX SD2 DA +2 SA +4 FC 08  Data_Exchange reply +68 11 11 68 02 04 08 ' "$tmp/all.out")
if [ "$dx_req" -gt 100 ] && [ "$dx_rsp" -gt 100 ]; then ok; else
  bad "Data_Exchange lines: $dx_req requests 4 <- 2, $dx_rsp replies 4 -> 2"; fi
expect_in "Set_Prm with its SAPs" "RX SD2 DA   4 SA   2 FC 5D  Set_Prm              68 15 15 68 84 82 5D 3D 3E " "$all_out"
expect_in "an SC named after its request" "TX SC  DA   - SA   - FC --  Chk_Cfg reply        E5" "$all_out"
expect_in "Slave_Diag answer (SD2, 8 DU octets)" "TX SD2 DA   2 SA   4 FC 08  Slave_Diag reply     68 0B 0B 68 82 84 08 3E 3C " "$all_out"
expect_in "FDL_Status during the baud search" "RX SD1 DA   4 SA   2 FC 49  FDL_Status           10 04 02 49 4F 16" "$all_out"
expect_in "a parameter service" "param channel write index 8461.0 value 3 ok" "$all_out"
expect_in "a state line in Data_Exch" \
  "DFP_CARD_STATE   4 state Data_Exch, 1.5 Mbit/s, RUN on, BUS FAULT off, P090 3PD + PARAM" "$all_out"
expect_in "the watchdog's Wait_Prm" "DFP_CARD_STATE   4 state Wait_Prm, 1.5 Mbit/s, RUN on, BUS FAULT on" "$all_out"
# The station summary counts the card's Data_Exchange replies: as many as its reply lines
# (SD2 with DL or DH, SC).
dx_sent=$(grep -cE ' DFP_TELEGRAM +4 TX .*  Data_Exchange reply ' "$tmp/all.out")
expect_in "station summary" \
  "station 4: Data_Exch, 1.5 Mbit/s, RUN on, BUS FAULT off, P090 3PD + PARAM, PO 0006 05DC 0000, PI 0407 05DC 0154; 3880 telegrams, Data_Exchange sent $dx_sent, errors 0" \
  "$all_out"

state_out=$(cat "$tmp/state.out")
if ! grep -q ' DFP_TELEGRAM \| DFP_PARAM ' "$tmp/state.out"; then ok; else
  bad "--channel DFP_CARD_STATE --no-telegrams printed other lines"; fi
n=$(grep -c ' DFP_CARD_STATE   4 state ' "$tmp/state.out")
if [ "$n" = 16 ]; then ok; else bad "16 state lines expected, $n"; fi
expect_in "only the state channel" \
  "summary: 16 messages in" "$state_out"
expect_in "only states counted" "(0 telegrams, 16 card states, 0 parameter services, 0 API events)" "$state_out"
expect_in "state in Data_Exch" "state Data_Exch, 1.5 Mbit/s" "$state_out"

# --status line: the line rewritten in place (CR, erase line), no telegram lines, then the summary.
line_out=$(cat "$tmp/line.out")
expect_in "status line in Data_Exch" $'\r\e[K4: Data_Exch 1.5 Mbit/s RUN on BF off DX ' "$line_out"
if ! grep -q ' DFP_TELEGRAM ' "$tmp/line.out"; then ok; else bad "--no-telegrams printed telegrams"; fi
expect_in "summary after the status line" $'\r\e[Ksummary: 3920 messages' "$line_out"

# ---- ending by itself, by signal ----
expect_exit 0 "--duration alone: nothing to wait for" -- "$view" --lcm-url "$url" --duration 0.3
expect_in "an empty summary" "summary: 0 messages in " "$out"
expect_exit 1 "--count not reached within --duration" -- "$view" --lcm-url "$url" --count 5 --duration 0.3
expect_in "says so" "only 0 of 5 messages within 0.3 s" "$out"
"$view" --lcm-url "$url" >"$tmp/int.out" 2>"$tmp/int.err" &
v=$!; pids+=($v)
wait_listening "$tmp/int.err"
kill -INT "$v"
if wait "$v"; then ok; else bad "SIGINT: exit $?, expected 0"; fi
pids=()
expect_in "SIGINT ends with the summary" "summary: 0 messages" "$(cat "$tmp/int.out")"

# ---- usage errors: exit 2 with the reason ----
expect_exit 0 "--help" -- "$view" --help
expect_in "--help explains the exit status" "exit status: 0 ended by --count" "$out"
expect_exit 2 "unknown option" -- "$view" --bogus
expect_in "names it" "unrecognized arguments: --bogus" "$out"
expect_exit 2 "--count 0" -- "$view" --count 0
expect_in "says why" "argument --count: must be 1 or more, not 0" "$out"
expect_exit 2 "--duration not a number" -- "$view" --duration soon
expect_in "says why" "argument --duration: not a number of seconds: 'soon'" "$out"
expect_exit 2 "--status unknown" -- "$view" --status loud
expect_exit 2 "bad URL" -- "$view" --lcm-url bogus://x --duration 1
expect_in "names the URL" "cannot open LCM URL 'bogus://x'" "$out"
expect_in "with LCM's reason" 'LCM provider "bogus" not found' "$out"
expect_exit 2 "bad channel regex" -- "$view" --lcm-url "$url" --channel '(' --duration 1
expect_in "names the channel" "bad --channel '('" "$out"
expect_exit 2 "no .lcm files" -- "$view" --lcm-types "$tmp" --duration 1
expect_in "names the files" "no telegram_t.lcm, card_state_t.lcm, param_service_t.lcm in $tmp" "$out"
finish
