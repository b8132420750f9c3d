#!/usr/bin/env bash
# dfp-sim master drives dfp-sim slave over a PTY pair made by socat: start-up, 100 cycles,
# the PO words come back as PI words; an address above 125 keeps the card off the bus; the master
# leaves with Global_Control Clear_Data and acknowledges a drive fault with --reset-fault.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

pty_pair || exit 1
"$sim" slave --inverter none --port "$tmp/a" --address 4 --baud 19200 --capture "$tmp/slave.pcap" >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "master reaches 100 cycles" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3F2 --baud 19200 --cycles 100 --outputs 0000000000000000000605DC0000
expect_in "inputs echo the outputs" "last inputs 0000000000000000000605DC0000" "$out"
kill -INT "$slave"; wait "$slave"; rc=$?
if [ "$rc" = 0 ]; then ok; else bad "slave exit $rc on SIGINT"; fi
slave_out=$(cat "$tmp/slave.out")
expect_in "slave reached data exchange" "Wait_Cfg -> Data_Exch" "$slave_out"
expect_in "slave LED off in data exchange" "LED BUS FAULT off" "$slave_out"
expect_in "slave stops cleanly" "stopping (signal)" "$slave_out"
size=$(stat -c %s "$tmp/slave.pcap")
if [ "$size" -gt 1000 ]; then ok; else bad "slave capture only $size bytes"; fi

# --cycles N is N Data_Exchange cycles and then the 3 of leaving, no more: the run ends at the
# reply that completes them (it used to end at the next 20 ms slice, several cycles later).
pty_pair || exit 1
"$sim" slave --inverter none --port "$tmp/a" --address 4 --baud 1.5M --quiet >/dev/null 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "master runs 50 cycles at 1.5 Mbit/s" -- timeout 30 "$sim" master --port "$tmp/b" \
  --address 4 --config F3F2 --baud 1.5M --cycles 50 --quiet --capture "$tmp/n.txt"
dx=$(dx_cycles "$tmp/n.txt")
[ "$dx" = 53 ] && ok || bad "Data_Exchange requests for --cycles 50: $dx, expected 53 (50 + 3 leaving)"
kill -INT "$slave"; wait "$slave"

# 8 octets each way: the master sends SD3 requests, the card answers SD2.
pty_pair || exit 1
"$sim" slave --inverter none --port "$tmp/a" --baud 19200 >"$tmp/slave2.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "4 PD (8 bytes, SD3)" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3 --baud 19200 --cycles 20 --outputs 1122334455667788 --capture "$tmp/m2.pcap"
expect_in "SD3 inputs" "last inputs 1122334455667788" "$out"
# The capture holds SD3 requests (start delimiter A2) and SD2 replies with 8 input octets.
m2=$(od -An -tx1 -v "$tmp/m2.pcap" | tr -s ' \n' ' ')
if grep -q " a2 04 02 " <<<"$m2"; then ok; else bad "no SD3 request in capture"; fi
if grep -q " 68 0b 0b 68 02 04 08 " <<<"$m2"; then ok; else bad "no SD2 reply of 8 octets in capture"; fi
if ! grep -q " a2 02 04 " <<<"$m2"; then ok; else bad "an SD3 reply in capture"; fi
kill -INT "$slave"; wait "$slave"

# Address 126: the card stays off the bus, RUN blinks, the master gets no answer.
pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 126 --baud 19200 >"$tmp/slave3.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 1 "no answer from address 126" -- "$sim" master --port "$tmp/b" --address 125 \
  --config F2 --baud 19200 --cycles 1 --timeout 2
kill -INT "$slave"; wait "$slave"
slave_out=$(cat "$tmp/slave3.out")
expect_in "RUN blinks" "LED RUN       blink" "$slave_out"
expect_in "off the bus" "stays off the bus" "$slave_out"
# The master leaves like a PLC going to STOP: Global_Control Clear_Data and zero outputs, so the
# drive is inhibited before the watchdog expires; F28 then follows (P831). --reset-fault at the
# next start acknowledges it with control word bit 6.
pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 >"$tmp/slave4.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "P101 = FIELDBUS" -- "$sim" param --port "$tmp/b" --address 4 write P101 FIELDBUS
# param left the card in data exchange; the next master joins the bus only after the lost-token
# time-out (6 + 2 x 2 slot times = 1 s), so the card's watchdog runs out first: that F28 belongs
# to param; the master acknowledges it (--reset-fault) and the order below is checked on what
# follows it.
for _ in $(seq 50); do grep -q "fault F28" "$tmp/slave4.out" && break; sleep 0.1; done
base=$(wc -l <"$tmp/slave4.out")
expect_exit 0 "master enables the drive, then stops" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3F2 --baud 19200 --cycles 30 --outputs 0000000000000000000605DC0000 --reset-fault
expect_in "Clear_Data announced" "master   going to STOP: Global_Control Clear_Data, outputs zero for 3 cycles" "$out"
expect_in "Clear_Data sent" "master   Global_Control 0x02 to group 0x00 (broadcast)" "$out"
expect_in "master left cleanly" "master   stopped: outputs cleared, leaving the bus" "$out"
for _ in $(seq 50); do tail -n +$((base + 1)) "$tmp/slave4.out" | grep -q "fault F28 fieldbus timeout$" && break; sleep 0.1; done
after=$(tail -n +$((base + 1)) "$tmp/slave4.out")
gc=$(grep -n "card     Global_Control 0x02 from master 2" <<<"$after" | head -1 | cut -d: -f1)
inh=$(grep -n "drive 4  inhibited: output stage off" <<<"$after" | head -1 | cut -d: -f1)
f28=$(grep -n "drive 4  fault F28 fieldbus timeout$" <<<"$after" | head -1 | cut -d: -f1)
if [ -n "$gc" ] && [ -n "$inh" ] && [ -n "$f28" ] && [ "$gc" -lt "$inh" ] && [ "$inh" -lt "$f28" ]; then ok
else bad "Clear_Data ($gc), inhibit ($inh), F28 ($f28) not in that order: $(cat "$tmp/slave4.out")"; fi
expect_exit 0 "master --reset-fault" -- timeout 30 "$sim" master --port "$tmp/b" --address 4 \
  --config F3F2 --baud 19200 --cycles 30 --reset-fault
expect_in "reset set" "master   slave 4: fault reset, control word 0040 (bit 6 set)" "$out"
expect_in "reset cleared" "master   slave 4: fault reset done, control word 0000" "$out"
sleep 0.2
expect_in "the drive reset F28" "drive 4  fault F28 fieldbus timeout reset" "$(cat "$tmp/slave4.out")"
expect_exit 2 "--reset-fault needs a DFP21B configuration" -- "$sim" master --port "$tmp/b" --address 4 \
  --config F3E2D1 --reset-fault
[ "$out" = "dfp-sim: master: --reset-fault needs a configuration the DFP21B accepts (its PO1 is the drive's control word)" ] &&
  ok || bad "--reset-fault usage: $out"
kill -INT "$slave"; wait "$slave"
finish
