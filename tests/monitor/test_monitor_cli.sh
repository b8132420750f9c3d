#!/usr/bin/env bash
# dfp-sim monitor end to end: a capture of the simulated bus read offline (the live list, the
# events, the JSON and JUnit reports, the exit status of the checks), its pcapng record read
# back, the monitor on a port of dfp-sim line with a master and two cards inside (the ring, the
# cards in Data_Exch, garbage on the line counted and the line followed after it), and bad
# command lines with their messages.
sim=$1
py=${2:-python3}
here=$(dirname "$0")
. "$here/../cli/lib.sh"
with_tmp

# json FILE EXPR: the Python expression over the document d, printed.
json() { "$py" -c 'import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$@"; }
station() { echo "[s for s in d['stations'] if s['address'] == $1][0]"; }

# 1. A capture of the simulated bus: master 2 with cards 4 and 5, a second master 3, faults
# (a watchdog expiry, a wrong configuration).
"$sim" record --capture "$tmp/r.pcap" --cycles 200 --faults --foreign >/dev/null 2>&1 ||
  bad "record failed"
expect_exit 0 "offline monitor with reports" -- "$sim" monitor "$tmp/r.pcap" --timing \
  --report json "$tmp/r.json" --report junit "$tmp/r.xml" --pcapng "$tmp/r.pcapng"
expect_in "summary: telegrams" "monitor $tmp/r.pcap:" "$out"
expect_in "summary: slave 4's row" "   4 passive -    Data_Exch      2  6003" "$out"
expect_in "ring members" "[2, 3]" "$(json "$tmp/r.json" "d['ring']['members']")"
for a in 4 5; do
  expect_in "slave $a in Data_Exch with master 2, ident 0x6003" "Data_Exch 2 0x6003" \
    "$(json "$tmp/r.json" "' '.join(str(($(station $a))['dp'][k]) for k in ('state','master','ident'))")"
  expect_in "slave $a: 0 missing, 0 repeats, 0 garbled" "0 0 0" \
    "$(json "$tmp/r.json" "' '.join(str(($(station $a))[k]) for k in ('missing','repeats_received','garbled'))")"
  expect_in "slave $a: TSDR measured" "True" "$(json "$tmp/r.json" "($(station $a))['tsdr_us']['n'] > 0")"
done
events=$(json "$tmp/r.json" "'\n'.join(e['type'] + ' ' + str(e['station']) + ' ' + e['text'] for e in d['events']['last'])")
expect_in "the wrong configuration: 4 leaves data exchange" "dx_leave 4 slave 4 left data exchange: new Set_Prm from master 2" "$events"
expect_in "the wrong configuration: Cfg_Fault" "prm_fault 4 slave 4 refused its configuration (Cfg_Fault)" "$events"
expect_in "the watchdog: 5 leaves data exchange" "dx_leave 5 slave 5 left data exchange: its watchdog (100 ms) expired" "$events"
expect_in "the watchdog: 4 too" "dx_leave 4 slave 4 left data exchange: its watchdog (100 ms) expired" "$events"
expect_in "master 3 joins the ring" "ring_enter 3 master 3 is in the token ring (passes to 2)" "$events"
expect_in "JUnit: no failure" 'failures="0"' "$(head -3 "$tmp/r.xml")"
expect_in "JUnit: slave 4's case" 'classname="dfp-sim monitor" name="4 data exchange"' "$(cat "$tmp/r.xml")"
# The pcapng record of the same run holds every telegram: read back, the same counts.
expect_exit 0 "the pcapng record read back" -- "$sim" monitor "$tmp/r.pcapng" --timing --report json "$tmp/p.json"
same=$(json "$tmp/p.json" "d['line']['telegrams']")
expect_in "the pcapng record has every telegram" "$(json "$tmp/r.json" "d['line']['telegrams']")" "$same"
# --gsd: the card's GSD gives the MaxTsdr at 1.5 Mbit/s its answers are judged against.
gsd="$here/../../firmware/gsd/SEW_6003.GSD"
want=$(sed -n 's/^MaxTsdr_1\.5M *= *\([0-9]*\).*/\1/Ip' "$gsd" | head -1)
expect_exit 0 "--gsd" -- "$sim" monitor "$tmp/r.pcap" --timing --gsd "$gsd" --report json "$tmp/g.json"
expect_in "--gsd: slave 4's max TSDR is the GSD's ($want)" "$want 0" \
  "$(json "$tmp/g.json" "' '.join(str(x) for x in (($(station 4))['dp']['max_tsdr_bits'], ($(station 4))['tsdr_over_max']))")"
expect_exit 2 "--gsd: a missing file" -- "$sim" monitor "$tmp/r.pcap" --gsd "$tmp/none.gsd"
expect_in "--gsd: a missing file: the message" "monitor: --gsd $tmp/none.gsd" "$out"
# A slave that is expected but never heard fails the check: exit 1, the case says so.
expect_exit 1 "--expect 9 (never heard)" -- "$sim" monitor "$tmp/r.pcap" --expect 9 --report junit "$tmp/e.xml"
expect_in "JUnit: 9 never heard" 'classname="dfp-sim monitor" name="9 data exchange"' "$(cat "$tmp/e.xml")"
expect_in "JUnit: one failure" 'failures="1"' "$(head -3 "$tmp/e.xml")"
expect_in "JUnit: why" '<failure message="slave 9 never heard">' "$(cat "$tmp/e.xml")"

# 2. Live, on a port of the line: the line's master 2 with cards 5 and 6.
mkdir -p "$tmp/l"
"$sim" line --dir "$tmp/l" --ports 2 --baud 187500 --card 5 --card 6 --master 2 \
  --master-slaves 5,6 --quiet >"$tmp/line.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do grep -q "Ctrl-C ends it" "$tmp/line.out" 2>/dev/null && break; sleep 0.1; done
"$sim" monitor --port "$tmp/l/port1" --baud 187500 --seconds 4 --view log \
  --report json "$tmp/live.json" >"$tmp/live.out" 2>&1 &
mon=$!
sleep 2
# Garbage on the line from port2: counted as garbled, and the monitor follows the line after it.
"$py" -c 'import os,sys; fd=os.open(sys.argv[1], os.O_WRONLY); os.write(fd, bytes([0x68,0x33,0x44,0x99,0x00,0x10,0x77])); os.close(fd)' "$tmp/l/port2"
wait "$mon"; rc=$?
[ "$rc" = 0 ] && ok || bad "live monitor exit $rc: $(cat "$tmp/live.out")"
expect_in "live: ring of master 2" "[2]" "$(json "$tmp/live.json" "d['ring']['members']")"
for a in 5 6; do
  expect_in "live: slave $a in Data_Exch with master 2" "Data_Exch 2" \
    "$(json "$tmp/live.json" "' '.join(str(($(station $a))['dp'][k]) for k in ('state','master'))")"
done
expect_in "live: the garbage counted" "True" "$(json "$tmp/live.json" "d['line']['garbled'] >= 1")"
expect_in "live: telegrams after the garbage" "True" \
  "$(json "$tmp/live.json" "($(station 5))['last_s'] > 3.0")"
expect_in "live: TSDR not measurable without --timing" "None" "$(json "$tmp/live.json" "($(station 5))['tsdr_us']")"

# --http on the live source: GET /api/v1/bus is this monitor's document (with the token only),
# its events are in the API's log as kind "bus".
token=abcdefghijklmnop0123
port=$((20000 + RANDOM % 20000))
DFP_SIM_TOKEN=$token "$sim" monitor --port "$tmp/l/port1" --baud 187500 --seconds 6 --view none \
  --http "$port" >"$tmp/http.out" 2>&1 &
mon=$!
got=
for _ in $(seq 40); do
  sleep 0.25
  got=$(curl -s -H "Authorization: Bearer $token" "http://127.0.0.1:$port/api/v1/bus") || continue
  "$py" -c 'import json,sys; d=json.loads(sys.argv[1]); sys.exit(0 if any(s["address"] == 5 and s["dp"] and s["dp"]["state"] == "Data_Exch" for s in d["stations"]) else 1)' "$got" 2>/dev/null && break
done
"$py" -c 'import json,sys; d=json.loads(sys.argv[1]); print(d["monitor"]["source"], d["ring"]["members"], [(s["address"], s["dp"]["state"]) for s in d["stations"] if s["dp"]])' "$got" >"$tmp/http.doc" 2>&1
expect_in "--http: the bus document" "$tmp/l/port1 [2] [(5, 'Data_Exch'), (6, 'Data_Exch')]" "$(cat "$tmp/http.doc")"
expect_in "--http: no token, no document" "401" "$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$port/api/v1/bus")"
expect_in "--http: the bus events in the log" '"source":"station 5","level":"info","kind":"bus","text":"station 5 heard for the first time (passive)"' \
  "$(curl -s -H "Authorization: Bearer $token" "http://127.0.0.1:$port/api/v1/log")"
expect_in "--http: read-only" "403" "$(curl -s -o /dev/null -w '%{http_code}' -X POST -H "Authorization: Bearer $token" -H 'Content-Type: application/json' -d '{"running":false}' "http://127.0.0.1:$port/api/v1/master/run")"
wait "$mon"
expect_in "--http: the run ends by itself" "monitor $tmp/l/port1:" "$(cat "$tmp/http.out")"
expect_exit 2 "--http with a file" -- "$sim" monitor "$tmp/r.pcap" --http 0

# 3. Bad command lines: exit 2 with one line; a missing file: exit 1.
expect_exit 2 "no source" -- "$sim" monitor
expect_in "no source: the message" "monitor: where does it listen? (--port DEV, --bus lcm:CHANNEL or a capture FILE)" "$out"
expect_exit 2 "two sources" -- "$sim" monitor "$tmp/r.pcap" --port /dev/null
expect_in "two sources: the message" "one source at a time" "$out"
expect_exit 2 "two files" -- "$sim" monitor "$tmp/r.pcap" "$tmp/p.json"
expect_exit 2 "--seconds with a file" -- "$sim" monitor "$tmp/r.pcap" --seconds 3
expect_exit 2 "--view top with a file" -- "$sim" monitor "$tmp/r.pcap" --view top
expect_exit 2 "--view word" -- "$sim" monitor "$tmp/r.pcap" --view graph
expect_in "--view word: the message" "monitor: --view 'graph': use top, log or none" "$out"
expect_exit 2 "--report kind" -- "$sim" monitor "$tmp/r.pcap" --report xml "$tmp/x"
expect_in "--report kind: the message" "monitor: --report 'xml': use json FILE or junit FILE" "$out"
expect_exit 2 "--report without a file" -- "$sim" monitor "$tmp/r.pcap" --report json
expect_exit 2 "--report onto the capture" -- "$sim" monitor "$tmp/r.pcap" --report json "$tmp/r.pcap"
expect_exit 2 "--report into no directory" -- "$sim" monitor "$tmp/r.pcap" --report json "$tmp/none/r.json"
expect_in "--report into no directory: said at the start, with the file" "monitor: --report json $tmp/none/r.json: cannot write it: No such file or directory" "$out"
expect_exit 2 "--report onto a directory" -- "$sim" monitor "$tmp/r.pcap" --report junit "$tmp"
expect_in "--report onto a directory: the message" "monitor: --report junit $tmp: cannot write it: it is a directory" "$out"
expect_exit 2 "--expect out of range" -- "$sim" monitor "$tmp/r.pcap" --expect 200
expect_exit 1 "a missing capture" -- "$sim" monitor "$tmp/none.pcap"
expect_in "a missing capture: the message" "monitor: " "$out"
expect_exit 2 "--view top without a terminal" -- "$sim" monitor --port "$tmp/l/port1" --view top --seconds 1
expect_in "--view top without a terminal: the message" "monitor: --view top:" "$out"
ln -s "$tmp/target" "$tmp/link.json"
expect_exit 2 "a report through a symbolic link" -- "$sim" monitor "$tmp/r.pcap" --report json "$tmp/link.json"
expect_in "a report through a symbolic link: the message" "is a symbolic link: refused" "$out"
[ ! -e "$tmp/target" ] && ok || bad "the link's target was written"
finish
