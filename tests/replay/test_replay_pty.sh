#!/usr/bin/env bash
# Captures taken on a PTY (dfp-sim slave and dfp-sim param/master over a socat PTY pair, with
# --capture and an LCM log) replay as MATCH without flags: the replay recognises the relaxed
# timing (answers later than any line allows), replays at 12 Mbit/s with the card at its rate and
# the inverter answering at once as in dfp-sim slave, and says so in the text and JSON reports.
# --timing, --baud and --inverter-delay still win.
sim=$1
. "$(dirname "$0")/../cli/lib.sh"
with_tmp

# ---- the slave's capture: a parameter service through the channel, then 100 cycles -----------
pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 --capture "$tmp/slave.pcap" \
  --lcm "file://$tmp/slave.lcm?mode=w" >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "param read over the PTY" -- timeout 30 "$sim" param --port "$tmp/b" --address 4 read P000
expect_exit 0 "master over the PTY" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3F2 --baud 19200 --cycles 100 --outputs 0000000000000000000605DC0000
kill -INT "$slave"; wait "$slave"
# ---- the master's capture, against a fresh slave --------------------------------------------
pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 >"$tmp/slave2.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "master with --capture" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3F2 --baud 19200 --cycles 100 --capture "$tmp/master.pcap"
kill -INT "$slave"; wait "$slave"

# ---- replayed without flags ------------------------------------------------------------------
expect_exit 0 "the slave's capture" -- "$sim" replay "$tmp/slave.pcap" --check --report json "$tmp/slave.json"
expect_in "relaxed inferred and why" "  timing    relaxed (inferred: a tty/PTY capture: " "$out"
expect_in "why: too late for a line" "ms after their request began, too late for a line at " "$out"
expect_in "12 Mbit/s" "  bus       12 Mbit/s (relaxed timing: every record at its recorded time on the fastest rate" "$out"
expect_in "the card at its rate" "fixed at the bus rate (relaxed timing: the card on the tty had its rate)" "$out"
expect_in "the inverter at once" "inverter: emulated MOVIDRIVE, 0 us per parameter service (relaxed timing: as in dfp-sim slave)" "$out"
expect_in "slave capture: match" "result: MATCH: all" "$out"
answers=$(sed -n 's/.*tty\/PTY capture: \([0-9]*\) of \([0-9]*\) answers.*/\1 \2/p' <<<"$out")
read -r late all <<<"$answers"
if [ -n "$all" ] && [ "$all" -gt 100 ] && [ $((2 * late)) -gt "$all" ]; then ok
else bad "relaxed judged on '$answers' answers"; fi
python3 - "$tmp/slave.json" >"$tmp/json.txt" 2>&1 <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
i = j["inferred"]
print(j["verdict"], i["timing"]["mode"], i["timing"]["inferred"], i["rate"]["baud"],
      i["rate"]["inferred"], i["fixed_baud"]["value"], i["fixed_baud"]["inferred"],
      i["inverter_delay"]["us"], i["inverter_delay"]["inferred"], j["card"]["baud"])
print(i["timing"]["source"])
PY
expect_in "JSON: what was inferred" "MATCH relaxed True 12000000 True True True 0 True 12000000" "$(cat "$tmp/json.txt")"
expect_in "JSON: why" "a tty/PTY capture: $late of $all answers of station 4 begin" "$(cat "$tmp/json.txt")"

# The LCM log of the same session records the nominal rate with every telegram: at 19.2 kbit/s
# the answers begin before their requests could have ended.
expect_exit 0 "the slave's LCM log" -- "$sim" replay "$tmp/slave.lcm" --check
expect_in "LCM: judged at the recorded rate" "too late for a line at 19.2 kbit/s (the rate the capture records) or before the request could have ended" "$out"
expect_in "LCM: the recorded rate overridden" "it overrides the capture's own rate, 19.2 kbit/s, for every record" "$out"
expect_in "LCM: match" "result: MATCH: all" "$out"

expect_exit 0 "the master's capture" -- "$sim" replay "$tmp/master.pcap" --check
expect_in "master capture: relaxed" "  timing    relaxed (inferred: a tty/PTY capture: " "$out"
expect_in "master capture: match" "result: MATCH: all" "$out"

# ---- explicit flags win ----------------------------------------------------------------------
# As a line's capture: the lowest rate the timing allows and the default inverter time of 3 ms
# (the parameter service's answer then usually comes a cycle later than recorded: not asserted,
# the PTY's pace varies).
"$sim" replay "$tmp/slave.pcap" --check --timing line >"$tmp/line.out" 2>&1
out=$(cat "$tmp/line.out")
expect_in "line as given" "  timing    line (given with --timing)" "$out"
expect_in "line: the rate from the timing" "(the capture records no rate; the lowest rate its timing allows" "$out"
expect_in "line: the default inverter" "(inferred: the capture's first request to it, record 1, is answered: the card had its rate before the capture began); inverter: emulated MOVIDRIVE"$'\n' "$out"$'\n'
# --baud and --inverter-delay given: used as given, the rest still from the relaxed timing.
expect_exit 0 "--baud 6M --inverter-delay 0" -- "$sim" replay "$tmp/slave.pcap" --check --baud 6M --inverter-delay 0
expect_in "rate as given" "  bus       6 Mbit/s (given with --baud)" "$out"
expect_in "delay as given" "0 us per parameter service (given with --inverter-delay)" "$out"
expect_in "still relaxed" "  timing    relaxed (inferred: a tty/PTY capture: " "$out"
finish
