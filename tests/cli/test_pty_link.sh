#!/usr/bin/env bash
# dfp-sim slave --pty LINK: the card makes its own PTY pair (no socat) and LINK points at the
# slave side. dfp-sim master on LINK gets what it gets over socat's pair (test_pty_master_slave),
# two masters one after the other find the card still there (it holds the slave side itself),
# a line of cards answers on it, the link goes on SIGTERM and after --duration, an old link is
# replaced, and a bad --pty is refused with its reason.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

# start_pty LINK ARGS...: dfp-sim slave --pty LINK in the background ($slave), until LINK points
# at a PTY.
start_pty() {
  local link=$1; shift
  "$sim" slave --pty "$link" "$@" >"$tmp/slave.out" 2>&1 &
  slave=$!; pids+=($slave)
  for _ in $(seq 50); do [[ $(readlink "$link") == /dev/pts/[0-9]* ]] && return 0; sleep 0.1; done
  bad "no link $link: $(cat "$tmp/slave.out")"; return 1
}
       END { print n + 0 }' "$1"
}

start_pty "$tmp/link" --inverter none --address 4 --baud 1.5M || exit 1
target=$(readlink "$tmp/link")
case "$target" in /dev/pts/*) ok ;; *) bad "link points at '$target', not a /dev/pts device" ;; esac
expect_in "the start line names the PTY and the link" \
  "dfp-sim slave: DFP21B on its own PTY $target (masters open $tmp/link), DIP address 4, fixed 1.5 Mbit/s" \
  "$(cat "$tmp/slave.out")"
expect_exit 0 "master runs 50 cycles at 1.5 Mbit/s on the link" -- timeout 30 "$sim" master \
  --port "$tmp/link" --address 4 --config F3F2 --baud 1.5M --cycles 50 \
  --outputs 0000000000000000000605DC0000 --capture "$tmp/n.txt"
expect_in "inputs echo the outputs" "last inputs 0000000000000000000605DC0000" "$out"
n=$(dx_cycles "$tmp/n.txt")
[ "$n" = 53 ] && ok || bad "Data_Exchange requests for --cycles 50: $n, expected 53 (50 + 3 leaving)"
# The first master closed the link; the card holds the slave side, so it saw no hang-up and the
# next master starts it up again on the same link.
expect_exit 0 "a second master on the same link" -- timeout 30 "$sim" master --port "$tmp/link" \
  --address 4 --config F3F2 --baud 1.5M --cycles 20 --outputs 00000000000000001234A5A55A5A
expect_in "second master: inputs echo the outputs" "last inputs 00000000000000001234A5A55A5A" "$out"
if kill -0 "$slave" 2>/dev/null; then ok; else bad "the card ended when the first master closed the link"; fi
kill -TERM "$slave"; wait "$slave"; rc=$?
[ "$rc" = 0 ] && ok || bad "slave exit $rc on SIGTERM"
if [ -e "$tmp/link" ] || [ -L "$tmp/link" ]; then bad "link left behind after SIGTERM"; else ok; fi
slave_out=$(cat "$tmp/slave.out")
expect_in "the card reached data exchange" "Wait_Cfg -> Data_Exch" "$slave_out"
expect_in "the card stopped on the signal" "stopping (signal); card 4 state" "$slave_out"
if grep -qE "hang-up|EIO|Input/output error" <<<"$slave_out"; then bad "hang-up seen: $slave_out"; else ok; fi

# A line of cards and the other slave options (capture, --duration) on the card's own pair; a
# stale link (its target gone) is replaced, and --duration removes the link too.
ln -s /dev/pts/does-not-exist "$tmp/line"
start_pty "$tmp/line" --inverter none --address 4-6 --baud 19200 --duration 10 \
  --capture "$tmp/line.pcap" || exit 1
expect_exit 0 "master polls three cards on the link" -- timeout 30 "$sim" master --port "$tmp/line" \
  --address 4-6 --config F3F2 --baud 19200 --cycles 10 --quiet
kill -INT "$slave"; wait "$slave"; rc=$?
[ "$rc" = 0 ] && ok || bad "line: slave exit $rc on SIGINT"
if [ -L "$tmp/line" ]; then bad "line: link left behind"; else ok; fi
for a in 4 5 6; do expect_in "card $a in data exchange" "card $a   Wait_Cfg -> Data_Exch" "$(cat "$tmp/slave.out")"; done
size=$(stat -c %s "$tmp/line.pcap")
[ "$size" -gt 1000 ] && ok || bad "capture only $size bytes"
expect_exit 0 "--duration 1 ends by itself" -- timeout 10 "$sim" slave --pty "$tmp/dur" --duration 1 --quiet
if [ -L "$tmp/dur" ]; then bad "--duration: link left behind"; else ok; fi

# Bad uses: refused before anything is made, with the reason.
expect_exit 2 "--pty with --port" -- "$sim" slave --pty "$tmp/x" --port /dev/null
[ "$out" = "dfp-sim: slave: --pty LINK makes the card's own PTY pair: it excludes --port and --bus" ] &&
  ok || bad "--pty with --port: $out"
expect_exit 2 "--pty with --bus" -- "$sim" slave --pty "$tmp/x" --bus lcm:seg
expect_in "--pty with --bus says so" "it excludes --port and --bus" "$out"
echo keep >"$tmp/file"
expect_exit 2 "--pty on a regular file" -- "$sim" slave --pty "$tmp/file"
[ "$out" = "dfp-sim: slave: --pty '$tmp/file' exists and is a regular file, not a symbolic link: refused (give a path that does not exist yet, or an old link to replace)" ] &&
  ok || bad "--pty on a file: $out"
[ "$(cat "$tmp/file")" = keep ] && ok || bad "the file was touched"
expect_exit 2 "--pty on a directory" -- "$sim" slave --pty "$tmp"
expect_in "--pty on a directory says so" "exists and is a directory, not a symbolic link" "$out"
expect_exit 1 "--pty in a directory that does not exist" -- "$sim" slave --pty "$tmp/no/such/link"
expect_in "--pty in a missing directory: the link" \
  "dfp-sim: slave: --pty: cannot make the link $tmp/no/such/link -> /dev/pts/" "$out"
expect_in "--pty in a missing directory: the reason" ": No such file or directory" "$out"
expect_exit 2 "--pty without a value" -- "$sim" slave --pty
expect_exit 2 "no medium names --pty" -- "$sim" slave
expect_in "no medium names --pty" "or --pty LINK (a PTY pair of the card's own)" "$out"
finish
