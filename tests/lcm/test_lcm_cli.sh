#!/usr/bin/env bash
# dfp-sim and LCM from the command line: `dfp-sim demo --lcm udpm://...` recorded by lcm-logger
# holds the same telegrams as the demo's own pcap (octets, order, relative times), the card's
# frames marked TX; the log reads back as a capture (convert, replay --check); damaged logs end
# with the event and byte; bad --bus/--lcm-url/--address options are usage errors. udpm on
# loopback needs a multicast route, so the test runs in a private network namespace.
sim=$1
channels=$2 # lcm_log_channels: events per channel of a log
lcm_logger=$3
. "$(dirname "$0")/netns.sh"
. "$(dirname "$0")/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
trap 'exit 1' INT TERM
url="udpm://239.255.76.72:7672?ttl=0"

# ---- demo --lcm, recorded by lcm-logger ----
# lcm-logger says "Opening log file" before it subscribes; the exact counts below need every
# message, so give it a generous moment on a loaded machine. The demo publishes its 3 924
# messages in a burst: with the default socket buffer (rmem_default, ~200 datagrams) a logger
# that the other tests' load holds off loses datagrams in the kernel, so it asks for 4 MB
# (LCM's recv_buf_size, capped by net.core.rmem_max).
start_logger() { # start_logger LOG OUT
  "$lcm_logger" --lcm-url="$url&recv_buf_size=4194304" --force "$1" >"$2" 2>&1 &
  logger=$!; pids+=($logger)
  for _ in $(seq 100); do grep -q "Opening log file" "$2" 2>/dev/null && break; sleep 0.1; done
  sleep 1
}
start_logger "$tmp/demo.lcm" "$tmp/logger.out"
expect_exit 0 "demo --lcm" -- "$sim" demo --lcm "$url" --capture "$tmp/demo.pcap"
expect_in "demo reports what it published" "3920 messages published to $url" "$out"
sleep 0.3
kill -INT "$logger"; wait "$logger"
if [ -s "$tmp/demo.lcm" ]; then ok; else bad "lcm-logger wrote nothing"; fi

expect_exit 0 "the log converts as a capture" -- "$sim" convert "$tmp/demo.lcm" "$tmp/lcm.txt"
expect_in "every telegram is in the log" "(lcm) -> $tmp/lcm.txt (text): 3880 records" "$out"
expect_exit 0 "the pcap converts" -- "$sim" convert "$tmp/demo.pcap" "$tmp/pcap.txt"
# Same octets in the same order, same times relative to the first telegram (µs).
rel() { awk '{split($1, t, "."); if (NR == 1) {s0 = t[1]; f0 = t[2]}
              us = (t[1] - s0) * 1000000 + (t[2] - f0) / 1000; $1 = ""; $2 = ""; print us, $0}' "$1"; }
if diff <(rel "$tmp/lcm.txt") <(rel "$tmp/pcap.txt") >"$tmp/diff" 2>&1; then ok; else
  bad "LCM log and pcap differ:"$'\n'"$(head -5 "$tmp/diff")"; fi
# The card's frames are TX, the master's RX (as the card sees the bus).
tx_sc=$(grep -c ' TX E5$' "$tmp/lcm.txt")
rx_sc=$(grep -c ' RX E5$' "$tmp/lcm.txt")
rx_req=$(grep -c ' RX 10 04 02 ' "$tmp/lcm.txt")
tx_req=$(grep -c ' TX 10 04 02 ' "$tmp/lcm.txt")
if [ "$tx_sc" -gt 0 ] && [ "$rx_sc" = 0 ] && [ "$rx_req" -gt 0 ] && [ "$tx_req" = 0 ]; then ok; else
  bad "directions: SC $tx_sc TX / $rx_sc RX, requests to 4 $rx_req RX / $tx_req TX"; fi
expect_exit 0 "replay --check of the LCM log" -- "$sim" replay "$tmp/demo.lcm" --check
expect_in "every reply matches" "MATCH: all 646 replies match" "$out"
# Card state and parameter services went to their own channels. The demo runs in simulated
# time, so the counts are the same every run: 5 services of its own plus the card's status
# polls (diagnostic alarm on), and the state at most every 100 ms of simulated time.
expect_exit 0 "channels of the demo log" -- "$channels" "$tmp/demo.lcm"
expect_in "every telegram" "DFP_TELEGRAM 3880" "$out"
expect_in "parameter services" "DFP_PARAM 24" "$out"
expect_in "card states" "DFP_CARD_STATE 16" "$out"

# ---- damaged logs ----
size=$(stat -c %s "$tmp/demo.lcm")
head -c $((size - 30)) "$tmp/demo.lcm" >"$tmp/cut.lcm"
expect_exit 1 "a truncated log" -- "$sim" convert "$tmp/cut.lcm" "$tmp/cut.txt"
expect_in "truncation named with event and byte" "truncated event" "$out"
expect_in "position given" "at byte" "$out"
{ head -c 200 "$tmp/demo.lcm"; printf 'garbage!'; tail -c +201 "$tmp/demo.lcm"; } >"$tmp/garbage.lcm"
expect_exit 1 "garbage inside a log" -- "$sim" convert "$tmp/garbage.lcm" "$tmp/g.txt"
expect_in "garbage found" "bad sync word" "$out"
head -c 5000 /dev/urandom >"$tmp/noise.bin"
expect_exit 1 "noise read as LCM" -- "$sim" convert "$tmp/noise.bin" "$tmp/n.txt" --in-format lcm
expect_in "noise: first event" "event 1 at byte 0: bad sync word" "$out"
expect_exit 1 "replay of a truncated log" -- "$sim" replay "$tmp/cut.lcm" --check

# ---- command-line errors ----
expect_exit 2 "--port and --bus" -- "$sim" slave --port /dev/null --bus lcm:X
expect_in "says so" "--port and --bus exclude each other" "$out"
expect_exit 2 "--bus not lcm:" -- "$sim" slave --bus tcp:X
expect_in "says how" "use lcm:CHANNEL" "$out"
expect_exit 2 "--lcm-url without --bus" -- "$sim" slave --port /dev/null --lcm-url "$url"
expect_exit 2 "master: address range backwards" -- "$sim" master --bus lcm:X --address 9-3 --config F3F2
expect_in "says how" "use addresses 0..125 as N, N-M or a comma list" "$out"
expect_exit 2 "master: address twice" -- "$sim" master --bus lcm:X --address 3,4,3 --config F3F2
expect_in "names it" "address 3 is given twice" "$out"
expect_exit 2 "master: 33 slaves" -- "$sim" master --bus lcm:X --address 1-33 --config F3F2
expect_in "limit named" "more than 32 slaves" "$out"
# A namespace without the multicast route: LCM cannot open udpm, the command says why.
expect_exit 1 "udpm without a multicast route" -- unshare -n "$sim" slave --bus lcm:X --duration 1
expect_in "names the route" "udpm needs a multicast route, e.g. ip route add 239.0.0.0/8 dev lo" "$out"
expect_exit 1 "an LCM URL that does not open" -- "$sim" demo --lcm "nosuch://x"
expect_in "reason" "cannot open LCM URL 'nosuch://x'" "$out"

# ---- slave --lcm on a segment: card state and telemetry next to the bus ----
# A fixed rate, so that the card hears every frame on the segment without errors.
"$sim" slave --bus lcm:SEG1 --lcm-url "$url" --address 5 --baud 19200 --inverter none --lcm "$url" \
  --capture "$tmp/slave.pcap" >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
start_logger "$tmp/slave.lcm" "$tmp/logger2.out"
expect_exit 0 "master on the segment" -- timeout 30 "$sim" master --bus lcm:SEG1 --lcm-url "$url" \
  --address 5 --config F3F2 --cycles 20 --outputs 0000000000000000000605DC0000
expect_in "echoed inputs" "last inputs 0000000000000000000605DC0000" "$out"
sleep 0.3
kill -INT "$slave"; wait "$slave"; rc=$?
if [ "$rc" = 0 ]; then ok; else bad "slave exit $rc"; fi
kill -INT "$logger"; wait "$logger"
expect_in "slave published" "messages published to $url" "$(cat "$tmp/slave.out")"
# The segment channel SEG1 holds each frame once (its sender's TX); DFP_TELEGRAM the card's view.
expect_exit 0 "the log of segment and telemetry reads" -- "$sim" convert "$tmp/slave.lcm" "$tmp/slave.txt"
"$channels" "$tmp/slave.lcm" >"$tmp/slave.channels"
seg=$(awk '$1 == "SEG1" {print $2}' "$tmp/slave.channels")
tel=$(awk '$1 == "DFP_TELEGRAM" {print $2}' "$tmp/slave.channels")
st=$(awk '$1 == "DFP_CARD_STATE" {print $2}' "$tmp/slave.channels")
if [ "${seg:-0}" -ge 40 ] && [ "$tel" = "$seg" ] && [ "${st:-0}" -ge 2 ]; then ok; else
  bad "segment frames $seg, telemetry telegrams $tel, card states $st"; fi
# --capture on the segment has the same telegrams as the telemetry.
expect_exit 0 "the slave's capture on the segment" -- "$sim" convert "$tmp/slave.pcap" "$tmp/sp.txt"
expect_in "as many as published" "(text): $tel records" "$out"
# The log replays: the card's telemetry alone (the reader says so; SEG1 repeats the same frames
# from their senders), each request before the reply it got.
expect_exit 0 "the segment log replays against the card" -- "$sim" replay "$tmp/slave.lcm" --check \
  --fixed-baud --inverter none
expect_in "the telemetry channel, said" "source    LCM log: read channel DFP_TELEGRAM (the card's telemetry); not read: SEG1" "$out"
expect_in "every reply matches" "MATCH: all" "$out"
expect_exit 0 "the segment channel alone" -- "$sim" convert "$tmp/slave.lcm" "$tmp/seg1.txt" --channel SEG1
expect_in "its frames" "(text): $seg records" "$out"
expect_exit 2 "a channel without telegrams" -- "$sim" convert "$tmp/slave.lcm" "$tmp/x.txt" --channel DFP_PARAM
expect_in "names the ones there are" "no telegram_t on LCM channel 'DFP_PARAM' (channels with telegrams: " "$out"
# ---- replay --lcm: the replay's telemetry carries the capture's times ----
golden="$(dirname "$0")/../replay/golden/param_channel.pcap"
expect_exit 0 "replay --check --lcm into an LCM log" -- "$sim" replay "$golden" --check \
  --lcm "file://$tmp/replay.lcm?mode=w"
expect_in "replay still matches" "MATCH: all 227 replies match" "$out"
expect_in "replay reports what it published" "lcm: 452 messages published" "$out"
"$channels" "$tmp/replay.lcm" >"$tmp/replay.channels"
# 227 records put on the bus + 205 telegrams of the card; the services that reached the
# emulated inverter (the refusals the card answers itself are not services); states <= 100 ms.
expect_in "every telegram on the replay bus" "DFP_TELEGRAM 432" "$(cat "$tmp/replay.channels")"
expect_in "the parameter services" "DFP_PARAM 15" "$(cat "$tmp/replay.channels")"
expect_in "card states" "DFP_CARD_STATE 5" "$(cat "$tmp/replay.channels")"
"$sim" convert "$tmp/replay.lcm" "$tmp/replay.txt" --quiet
"$sim" convert "$golden" "$tmp/golden.txt" --quiet
# Same times and octets as the capture (the card's answers are its own, identical here), with
# the card's telegrams TX and the capture's RX.
if diff <(awk '{$2 = ""; print}' "$tmp/replay.txt") <(awk '{$2 = ""; print}' "$tmp/golden.txt") \
   >"$tmp/rdiff"; then ok; else bad "replay telemetry differs from the capture: $(head -3 "$tmp/rdiff")"; fi
expect_in "the card's first answer is TX, at its capture time" \
  "1704067200.060420000 TX 10 02 04 00 06 16" "$(grep -m1 ' TX ' "$tmp/replay.txt")"
expect_exit 0 "the replay's LCM log replays itself" -- "$sim" replay "$tmp/replay.lcm" --check
expect_in "and matches" "MATCH: all 227 replies match" "$out"
expect_exit 1 "replay --lcm to a bad URL" -- "$sim" replay "$golden" --lcm "nosuch://x"
finish
