#!/usr/bin/env bash
# dfp-sim monitor on a virtual segment over LCM (docs/monitor.md; sim_host/lcm_bridge/README.md):
# a `dfp-sim slave` at 5 and a `dfp-sim master` at 2 start up while the monitor listens: its live
# list has master 2 in the ring and slave 5 in Data_Exch with master 2, ident 0x6003, its
# diagnosis and the DFP21B's PD configuration. A monitor at another rate than the segment's hears
# every telegram garbled, as on a real line, and says why. On a keyed segment (--key) the monitor
# with the key hears the traffic; one without it takes no telegram (0 in its report) and says
# that it dropped signed ones. udpm on loopback needs a multicast route: a private network
# namespace (exit 77 where none can be made), so parallel tests never hear each other.
# Usage: test_monitor_lcm.sh DFP_SIM PYTHON
sim=$1
py=${2:-python3}
here=$(dirname "$0")
. "$here/../lcm/netns.sh"
. "$here/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
url="udpm://239.255.76.90:7690?ttl=0"

# json FILE EXPR: the Python expression over the report d (s(A): station A), printed; a tuple's
# items separated by spaces.
json() {
  "$py" -c 'import json,sys
d = json.load(open(sys.argv[1]))
s = lambda a: next(x for x in d["stations"] if x["address"] == a)
v = eval(sys.argv[2])
print(" ".join(str(x) for x in v) if isinstance(v, tuple) else v)' "$@"
}

# monitor NAME ARGS...: a monitor for 6 s in the background, its report NAME.json.
mons=()
monitor() {
  local name=$1; shift
  "$sim" monitor --bus lcm:SEG --lcm-url "$url" --seconds 6 --view log \
    --report json "$tmp/$name.json" "$@" >"$tmp/$name.out" 2>&1 &
  mons+=("$!:$name")
}
# stations ARGS...: slave 5 and master 2 (F3 F2: Param + 3 PD) at 19.2 kbit/s, after the monitors
# subscribed; they run until wait_monitors ends them.
stations() {
  sleep 0.5
  "$sim" slave --bus lcm:SEG --lcm-url "$url" --address 5 --baud 19200 --inverter none "$@" \
    >"$tmp/slave.out" 2>&1 &
  pids+=($!)
  for _ in $(seq 50); do [ -s "$tmp/slave.out" ] && break; sleep 0.1; done
  "$sim" master --bus lcm:SEG --lcm-url "$url" --master-address 2 --address 5 --config F3F2 \
    --baud 19200 --cycles 0 "$@" >"$tmp/master.out" 2>&1 &
  pids+=($!)
}
# wait_monitors: each monitor's exit status 0 (every DP slave it heard in data exchange), then
# the master and the slave stopped.
wait_monitors() {
  local m rc
  for m in "${mons[@]}"; do
    wait "${m%%:*}"; rc=$?
    [ "$rc" = 0 ] && ok || bad "monitor ${m#*:}: exit $rc:"$'\n'"$(cat "$tmp/${m#*:}.out")"
  done
  mons=()
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done
  wait "${pids[@]}" 2>/dev/null
  pids=()
}
# sees_the_line NAME: its report has the ring and the card in data exchange.
sees_the_line() {
  local f="$tmp/$1.json"
  expect_in "$1: the source" "lcm:SEG 19200" \
    "$(json "$f" "d['monitor']['source'], d['monitor']['baud']")"
  expect_in "$1: ring of master 2" "[2] active True" \
    "$(json "$f" "d['ring']['members'], s(2)['role'], s(2)['in_ring']")"
  expect_in "$1: slave 5 in Data_Exch with master 2, ident 0x6003" "passive Data_Exch 2 0x6003" \
    "$(json "$f" "s(5)['role'], s(5)['dp']['state'], s(5)['dp']['master'], s(5)['dp']['ident']")"
  expect_in "$1: slave 5's diagnosis" "WD_On | Master_Add 2, ident 0x6003" \
    "$(json "$f" "s(5)['dp']['diag_text']")"
  expect_in "$1: the DFP21B's PD configuration" "3PD + PARAM True" \
    "$(json "$f" "s(5)['dp']['dfp21b']['pd_config'], s(5)['dp']['dfp21b']['param_channel']")"
  expect_in "$1: nothing garbled, nothing missing" "0 0 0" \
    "$(json "$f" "d['line']['garbled'], d['line']['unanswered'], s(5)['missing']")"
  expect_in "$1: no TSDR measured on LCM" "None False" \
    "$(json "$f" "s(5)['tsdr_us'], d['monitor']['timing']")"
  expect_in "$1: the event" "slave 5 in data exchange with master 2" "$(cat "$tmp/$1.out")"
}

# ---- a plain segment: a monitor at the segment's rate, and one at its default (1.5M) ----
monitor plain --baud 19200
monitor default_rate
stations
wait_monitors
sees_the_line plain
expect_in "master: in data exchange" "slave 5 is in data exchange" "$(cat "$tmp/master.out")"
expect_in "at 1.5M: nothing but garbled octets" "0 [] True" \
  "$(json "$tmp/default_rate.json" "d['line']['telegrams'], d['stations'], d['line']['garbled']>0")"
expect_in "at 1.5M: says why" "monitor: segment SEG: every telegram heard was sent at a rate other\
 than --baud 1.5 Mbit/s (heard garbled): give the segment's rate" "$(cat "$tmp/default_rate.out")"
if grep -q "other than --baud" "$tmp/plain.out"; then bad "plain: told of another rate"; else ok; fi

# ---- a keyed segment: the monitor with the key hears it, the one without it nothing ----
(umask 077; head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$tmp/k1")
monitor keyed --baud 19200 --key "$tmp/k1"
monitor nokey --baud 19200
stations --key "$tmp/k1"
wait_monitors
sees_the_line keyed
expect_in "keyed: the segment's totals" "segment SEG (keyed): " "$(cat "$tmp/keyed.out")"
expect_in "keyed: nothing dropped" "dropped (unsigned 0, signed 0, bad signature 0, stale 0,\
 replayed 0, senders full 0, malformed 0)" "$(cat "$tmp/keyed.out")"
expect_in "without the key: 0 telegrams, no station" "0 0 []" \
  "$(json "$tmp/nokey.json" "d['line']['telegrams'], d['line']['garbled'], d['stations']")"
expect_in "without the key: the summary" "monitor lcm:SEG: " \
  "$(grep -F ' 0 telegrams, 0 tokens, 0 garbled' "$tmp/nokey.out")"
expect_in "without the key: says it dropped signed telegrams" \
  "segment SEG: dropped a telegram: signed" "$(cat "$tmp/nokey.out")"
n=$(sed -n 's/.*SEG: 0 telegrams taken, [0-9]* dropped (unsigned 0, signed \([0-9]*\),.*/\1/p' \
  "$tmp/nokey.out")
if [ -n "$n" ] && [ "$n" -gt 0 ]; then ok; else
  bad "without the key: its totals do not count signed drops:"$'\n'"$(cat "$tmp/nokey.out")"; fi
finish
