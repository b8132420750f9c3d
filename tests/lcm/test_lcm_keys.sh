#!/usr/bin/env bash
# Keyed LCM segments (dfp-sim --bus lcm:CH --key FILE, sim_host/lcm_bridge/README.md "Keyed
# segments"): a keyed slave and master reach Data_Exchange; a process without the key cannot take
# the card over: unsigned telegrams, telegrams signed with another key or for another channel,
# and a recording of signed ones played back are dropped and counted by reason, and the card
# never hears them (its capture stays empty, its state Wait_Prm). The same plain telegrams do
# take over a plain segment's card (the attack this guards against). A plain segment refuses a
# real drive (--inverter can:), and bad key files are refused. udpm on loopback needs a
# multicast route: a private network namespace.
# Usage: test_lcm_keys.sh DFP_SIM LCM_SEG_INJECT
sim=$1
inject=$2
. "$(dirname "$0")/netns.sh"
. "$(dirname "$0")/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
trap 'exit 1' INT TERM
url="udpm://239.255.76.76:7676?ttl=0"
newkey() { (umask 077; head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' >"$1"); }
newkey "$tmp/k1"
newkey "$tmp/k2"

# The PLC's own start-up and a Data_Exchange with its address (2) to the card at 4: Set_Prm
# (watchdog on), Chk_Cfg F3 F2, and PO1 0006 PO2 0BB8 (enable, 3000 rpm).
set_prm=6815156884825D3D3E88010A0B6003000000000681000001006716
chk_cfg=6807076884827D3E3EF3F2E416
dx=6811116804027D000000000000000000060BB800004C16
attack=("$set_prm" "$chk_cfg" "$dx")

# start_slave NAME [OPTIONS...]: the card at 4, 19.2 kbit/s, capture NAME.txt, output NAME.out.
start_slave() {
  local name=$1; shift
  "$sim" slave --bus lcm:SEG --lcm-url "$url" --address 4 --baud 19200 --inverter none \
    --capture "$tmp/$name.txt" --capture-format text "$@" >"$tmp/$name.out" 2>&1 &
  slave=$!; pids+=($slave)
  for _ in $(seq 100); do [ -s "$tmp/$name.out" ] && break; sleep 0.1; done
  sleep 0.3 # subscribed: its first line comes after the segment opened
}
stop_slave() { # stop_slave NAME: SIGINT, exit 0; $sout = its output
  kill -INT "$slave"
  if wait "$slave"; then ok; else bad "$1: slave exit $?"; fi
  pids=()
  sout=$(cat "$tmp/$1.out")
}
heard() { grep -c ' RX ' "$tmp/$1.txt"; } # telegrams the card heard (its text capture)
no_takeover() { # no_takeover NAME: the card heard nothing and stayed in Wait_Prm
  expect_in "$1: no Set_Prm accepted" "card 4 state Wait_Prm" "$sout"
  if grep -qF "Set_Prm from master" <<<"$sout"; then bad "$1: the card took a Set_Prm"; else ok; fi
  local n; n=$(heard "$1")
  if [ "$n" = 0 ]; then ok; else bad "$1: the card heard $n telegrams"; fi
}
totals() { echo "segment SEG (keyed): $1 telegrams taken, $2 dropped ($3)"; }

# ---- the attack on a plain segment: any process takes the card over ----
start_slave plain
expect_exit 0 "plain telegrams published" -- "$inject" "$url" SEG plain "${attack[@]}"
sleep 0.3
stop_slave plain
expect_in "plain: the PLC's address takes the card" "Set_Prm from master 2 accepted" "$sout"
expect_in "plain: into Data_Exchange" "Wait_Cfg -> Data_Exch" "$sout"
expect_in "plain: the card heard the PO words" "0000000000000000060BB80000" "$(tr -d ' ' <"$tmp/plain.txt")"
if [ "$(heard plain)" = 3 ]; then ok; else bad "plain: the card heard $(heard plain) telegrams, not 3"; fi

# ---- unsigned on a keyed segment ----
start_slave unsigned --key "$tmp/k1"
expect_exit 0 "unsigned telegrams published" -- "$inject" "$url" SEG plain "${attack[@]}"
expect_in "three of them" "published 3" "$out"
sleep 0.3
stop_slave unsigned
no_takeover unsigned
expect_in "unsigned: the first drop logged" \
  "segment SEG: dropped a telegram: unsigned, station 2, source id" "$sout"
expect_in "unsigned: counted" "$(totals 0 3 "unsigned 3, signed 0, bad signature 0, stale 0, replayed 0, senders full 0, malformed 0")" "$sout"

# ---- signed with another key; signed with the key for another channel ----
start_slave wrongkey --key "$tmp/k1"
expect_exit 0 "telegrams signed with another key" -- "$inject" "$url" SEG "sign:$tmp/k2" "${attack[@]}"
expect_exit 0 "telegrams signed for channel OTHER" -- "$inject" "$url" SEG "sign:$tmp/k1:OTHER" \
  "${attack[@]}"
sleep 0.3
stop_slave wrongkey
no_takeover wrongkey
expect_in "wrong key, other channel: bad signatures" "$(totals 0 6 "unsigned 0, signed 0, bad signature 6, stale 0, replayed 0, senders full 0, malformed 0")" "$sout"

# ---- a recording played back: at once (replayed), and after the window (stale) ----
start_slave replay --key "$tmp/k1"
expect_exit 0 "signed with the key: a station of the segment" -- "$inject" "$url" SEG \
  "sign:$tmp/k1" --save "$tmp/rec.bin" "${attack[@]}"
sleep 0.3
expect_exit 0 "the recording played back at once" -- "$inject" "$url" SEG "replay:$tmp/rec.bin"
expect_in "all of it" "published 3" "$out"
sleep 2.2
expect_exit 0 "the recording played back after 2 s" -- "$inject" "$url" SEG "replay:$tmp/rec.bin"
sleep 0.3
stop_slave replay
expect_in "replay: the key holder takes the card" "Set_Prm from master 2 accepted" "$sout"
expect_in "replay: counted" "$(totals 3 6 "unsigned 0, signed 0, bad signature 0, stale 3, replayed 3, senders full 0, malformed 0")" "$sout"
# A slave started after the recording (it has never seen the sender) takes none of it either.
start_slave fresh --key "$tmp/k1"
expect_exit 0 "the recording played to a fresh slave" -- "$inject" "$url" SEG "replay:$tmp/rec.bin"
sleep 0.3
stop_slave fresh
no_takeover fresh
expect_in "fresh: stale" "$(totals 0 3 "unsigned 0, signed 0, bad signature 0, stale 3, replayed 0, senders full 0, malformed 0")" "$sout"

# ---- keyed master and slave; a master with another key; a plain slave hears no keyed one ----
start_slave keyed --key "$tmp/k1"
expect_exit 1 "a master with another key cannot take the card" -- timeout 30 "$sim" master \
  --bus lcm:SEG --lcm-url "$url" --address 4 --config F3F2 --cycles 5 --timeout 2 --key "$tmp/k2"
expect_exit 0 "keyed master and slave exchange data" -- timeout 30 "$sim" master --bus lcm:SEG \
  --lcm-url "$url" --address 4 --config F3F2 --cycles 20 --key "$tmp/k1" \
  --outputs 0000000000000000000605DC0000
expect_in "echoed inputs" "last inputs 0000000000000000000605DC0000" "$out"
expect_in "the master's totals" "segment SEG (keyed): " "$out"
expect_in "the master dropped nothing" "dropped (unsigned 0, signed 0, bad signature 0, stale 0, replayed 0, senders full 0, malformed 0)" "$out"
stop_slave keyed
expect_in "keyed: Data_Exchange" "Wait_Cfg -> Data_Exch" "$sout"
expect_in "keyed: only the first master's Set_Prm" "Set_Prm from master 2 accepted" "$sout"
bad_sig=$(grep -o 'dropped (unsigned 0, signed 0, bad signature [0-9]*, stale 0, replayed 0, senders full 0, malformed 0)' <<<"$sout" | grep -o 'bad signature [0-9]*')
if [ -n "$bad_sig" ] && [ "$bad_sig" != "bad signature 0" ]; then ok; else
  bad "keyed: the other key's telegrams are not all bad signatures:"$'\n'"$(tail -2 <<<"$sout")"; fi

start_slave unkeyed
expect_exit 0 "signed telegrams to a slave without key" -- "$inject" "$url" SEG "sign:$tmp/k1" \
  "${attack[@]}"
sleep 0.3
stop_slave unkeyed
no_takeover unkeyed
expect_in "unkeyed: counted as signed" "segment SEG: 0 telegrams taken, 3 dropped (unsigned 0, signed 3, bad signature 0, stale 0, replayed 0, senders full 0, malformed 0)" "$sout"

# ---- the command line ----
expect_exit 2 "a plain segment with a real drive" -- "$sim" slave --bus lcm:SEG --inverter can:vcan0
expect_in "says why and how" "slave: --bus lcm: without --key lets any process on the LCM group drive the real MOVIDRIVE on vcan0; give --key FILE" "$out"
expect_exit 2 "... with its SBus address" -- "$sim" slave --bus lcm:SEG --inverter can:can1:5
expect_in "names the interface" "drive the real MOVIDRIVE on can1; give --key FILE" "$out"
expect_exit 2 "a missing key file" -- "$sim" slave --bus lcm:SEG --key "$tmp/nosuch"
expect_in "says so" "slave: --key $tmp/nosuch: No such file or directory" "$out"
(umask 077; printf '0123456789abcdef0123456789abcdef01234567\n' >"$tmp/short")
expect_exit 2 "a short key" -- "$sim" master --bus lcm:SEG --address 4 --config F3F2 --key "$tmp/short"
expect_in "counts the digits" "master: --key $tmp/short: 40 hex digits, a key is 64 (32 octets)" "$out"
(umask 077; printf '%s\n' "$(cat "$tmp/k1" | tr '0-9' 'g')" >"$tmp/nothex")
expect_exit 2 "a key that is not hex" -- "$sim" param --bus lcm:SEG --address 4 --key "$tmp/nothex" read 8300
expect_in "says where" "param: --key $tmp/nothex: not hex digits on one line (character" "$out"
(umask 077; { cat "$tmp/k1"; echo; cat "$tmp/k1"; echo; } >"$tmp/twolines")
expect_exit 2 "two lines" -- "$sim" slave --bus lcm:SEG --key "$tmp/twolines"
expect_in "not one line" "not hex digits on one line (character 65)" "$out"
cp "$tmp/k1" "$tmp/open"; chmod 644 "$tmp/open"
expect_exit 2 "a world-readable key" -- "$sim" slave --bus lcm:SEG --key "$tmp/open"
expect_in "as ssh does" "slave: --key $tmp/open: readable by others than its owner (mode 0644): chmod 600 $tmp/open" "$out"
chmod 640 "$tmp/open"
expect_exit 2 "a group-readable key" -- "$sim" slave --bus lcm:SEG --key "$tmp/open"
expect_in "mode named" "(mode 0640)" "$out"
expect_exit 2 "a directory" -- "$sim" slave --bus lcm:SEG --key "$tmp"
expect_in "not a file" "slave: --key $tmp: not a regular file" "$out"
expect_exit 2 "--key without --bus" -- "$sim" slave --port /dev/null --key "$tmp/k1"
expect_in "belongs to --bus" "slave: --key belongs to --bus lcm:CHANNEL" "$out"
finish
