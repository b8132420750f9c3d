#!/usr/bin/env bash
# dfp-sim param as a master on a virtual segment over LCM (--bus lcm:CHANNEL): against
# `dfp-sim slave --bus lcm:...` it reads P100 by name on every path, writes a value by name and
# reads it back by another path, reads I&M0, times out on an address nobody has, is refused by
# the card's diagnosis while a PLC owns it (class 2 still works), and refuses
# --port with --bus, --lcm-url without --bus and a bad channel (exit 2). udpm on loopback needs a
# multicast route, so the test runs in a private network namespace (tests/lcm/netns.sh).
sim=$1
. "$(dirname "$0")/../lcm/netns.sh"
. "$(dirname "$0")/lib.sh"
with_tmp
url="udpm://239.255.76.74:7674?ttl=0"

"$sim" slave --bus lcm:PARAM --lcm-url "$url" --address 4 >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.5

# Every master of the segment with the same bus parameters, as next to a real PLC; HSA 7 and
# G 1 keep GAP maintenance short, so a master beside the PLC is let into its ring within a
# second (each silent address costs a slot time, 100 ms on a segment).
ring=(--hsa 7 --gap-factor 1)
param() { "$sim" param --bus lcm:PARAM --lcm-url "$url" --address 4 --timeout 10 "${ring[@]}" "$@"; }

for via in channel movilink profidrive c2; do
  expect_exit 0 "read P100 via $via" -- param read P100 --via "$via"
  [ "$out" = "read 8461 via $via: P100 setpoint source = 0 (BIPOL./FIX.SETPT)" ] && ok ||
    bad "read P100 via $via: $out"
done
expect_exit 0 "write P100 FIELDBUS by name" -- param write "setpoint source" FIELDBUS --via movilink
[ "$out" = "write 8461 = 3 via movilink: ok (P100 setpoint source = 3 (FIELDBUS))" ] && ok ||
  bad "write P100: $out"
expect_exit 0 "read back via c2" -- param read P100 --via c2
[ "$out" = "read 8461 via c2: P100 setpoint source = 3 (FIELDBUS)" ] && ok || bad "read back: $out"
expect_exit 0 "im0 on the segment" -- param im0
expect_in "im0 serial" "  serial number      DFP-SIM-004" "$out"
expect_exit 1 "nobody at 5 on the segment" -- "$sim" param --bus lcm:PARAM --lcm-url "$url" --address 5 --timeout 1 read P100 --via movilink
[ "$out" = "read 8461 via movilink: error timeout: no result within 1 s: slave 5 did not reach data exchange (phase FDL status)" ] &&
  ok || bad "timeout on the segment: $out"

# A PLC (class-1 master 1) owns the card: the card refuses another class-1 master through its
# diagnosis (Master_Add 1), never with RS, and the timeout says so; class 2 still works.
"$sim" master --bus lcm:PARAM --lcm-url "$url" --address 4 --config F3F2 --master-address 1 \
  --cycles 0 "${ring[@]}" >"$tmp/plc.out" 2>&1 &
plc=$!; pids+=($plc)
for _ in $(seq 50); do grep -q "slave 4 is in data exchange" "$tmp/plc.out" && break; sleep 0.1; done
expect_in "PLC in data exchange" "slave 4 is in data exchange" "$(cat "$tmp/plc.out")"
expect_exit 1 "class 1 beside the PLC" -- param --timeout 5 read P100 --via movilink
# The start-up goes on one telegram per token visit: the timeout finds it in any phase, with the
# reason of the last attempt.
[[ "$out" =~ ^"read 8461 via movilink: error timeout: no result within 5 s: slave 4 did not reach data exchange (phase "[^\)]*"slave is locked by master 1)"$ ]] &&
  ok || bad "class 1 beside the PLC: $out"
expect_exit 1 "a second master beside the PLC" -- "$sim" master --bus lcm:PARAM --lcm-url "$url" \
  --address 4 --config F3F2 --master-address 3 --cycles 5 --timeout 5 --quiet "${ring[@]}"
[[ "$(tail -n 1 <<<"$out")" =~ ^"dfp-sim: master: slave 4 did not complete 5 Data_Exchange cycles (timeout; reached 0, phase "[^\)]*"slave is locked by master 1)"$ ]] &&
  ok || bad "second master: $out"
expect_exit 0 "class 2 beside the PLC" -- param read P100 --via c2 --master-address 3
kill -INT "$plc"; wait "$plc"; rc=$?
[ "$rc" = 0 ] && ok || bad "PLC exit $rc"
expect_in "PLC kept data exchange" "stopped: outputs cleared" "$(cat "$tmp/plc.out")"
if grep -q "RS:" "$tmp/plc.out"; then bad "the PLC saw RS: $(cat "$tmp/plc.out")"; else ok; fi

expect_exit 2 "--port and --bus" -- "$sim" param --port /dev/null --bus lcm:PARAM --address 4 read P100
[ "$out" = "dfp-sim: param: --port and --bus exclude each other" ] && ok || bad "--port and --bus: $out"
expect_exit 2 "--lcm-url without --bus" -- "$sim" param --port /dev/null --lcm-url "$url" --address 4 read P100
[ "$out" = "dfp-sim: param: --lcm-url belongs to --bus lcm:CHANNEL" ] && ok || bad "--lcm-url: $out"
expect_exit 2 "bad channel" -- "$sim" param --bus can:X --address 4 read P100
[ "$out" = "dfp-sim: param: --bus 'can:X': use lcm:CHANNEL (1..63 of A-Z a-z 0-9 _ . -)" ] && ok ||
  bad "bad channel: $out"

kill -INT "$slave"; wait "$slave"
expect_in "slave on the segment" "DFP21B on LCM segment PARAM ($url)" "$(cat "$tmp/slave.out")"
finish
