#!/usr/bin/env bash
# dfp-sim line: a virtual RS-485 segment of PTY ports. Exact bytes to every other port and none
# back to the writer; two talkers at once garbled, counted and told, and the line fine after it;
# --timing spreads a write over its characters' time; dfp-sim master and slave on two ports
# reach Data_Exchange; an emulated card inside the line (--card) serves a master on a port; the
# capture has both directions; the line's own master and one on a port share the token ring;
# bad command lines exit 2 with one line.
sim=$1
py=${2:-python3}
here=$(dirname "$0")
. "$here/../cli/lib.sh"
with_tmp

# start_line OUT ARGS...: dfp-sim line --dir $tmp/l ARGS in the background ($line) until its
# ports are listed on OUT.
start_line() {
  local out=$1; shift
  mkdir -p "$tmp/l"
  "$sim" line --dir "$tmp/l" "$@" >"$out" 2>"$out.err" &
  line=$!; pids+=($line)
  for _ in $(seq 50); do grep -q "Ctrl-C ends it" "$out" 2>/dev/null && return 0; sleep 0.1; done
  bad "line did not start: $(cat "$out" "$out.err")"; return 1
}
stop_line() { # stop_line: SIGINT, exit 0, links gone
  kill -INT "$line"; wait "$line"; local rc=$?
  [ "$rc" = 0 ] && ok || bad "line exit $rc on SIGINT"
  if compgen -G "$tmp/l/port*" >/dev/null; then bad "links left: $(ls "$tmp/l")"; else ok; fi
}

# 1. Exact bytes: port1 writes, port2 and port3 read exactly that, port1 nothing.
start_line "$tmp/a.out" --ports 3 || exit 1
expect_in "the ports are listed" "$tmp/l/port3" "$(head -3 "$tmp/a.out")"
[[ $(readlink "$tmp/l/port1") == /dev/pts/[0-9]* ]] && ok || bad "port1 is no link to a PTY"
want=$("$py" -c 'print(bytes((i * 37 + 11) & 0xFF for i in range(64)).hex())')
got=$("$py" "$here/line_probe.py" exact "$tmp/l")
expect_in "port2 reads the 64 octets" "port2 $want" "$got"
expect_in "port3 reads the 64 octets" "port3 $want" "$got"
expect_in "the writer hears nothing" "port1 -" "$got"
stop_line
expect_in "figures: port1 sent" "port1  sent 64 octets in 1 writes, received 0, dropped 0, collisions 0" "$(cat "$tmp/a.out")"
expect_in "figures: port3 received" "port3  sent 0 octets in 0 writes, received 64" "$(cat "$tmp/a.out")"

# Never blocking: port3, which nobody opens, drops what does not fit in its PTY (counted), while
# port2 reads all of a long stream.
start_line "$tmp/f.out" --ports 3 || exit 1
expect_in "port2 reads all 200000 octets" "port2 200000 same" "$("$py" "$here/line_probe.py" flood "$tmp/l")"
stop_line
dropped=$(sed -n 's/^  port3 .* dropped \([0-9]*\),.*/\1/p' "$tmp/f.out")
[ "${dropped:-0}" -gt 0 ] && ok || bad "port3 (never opened) dropped ${dropped:-nothing}: $(cat "$tmp/f.out")"

# 2. A collision: port2 talks 20 ms into port1's 100 octets (115 ms at 9600 bit/s). port3 gets
# 100 octets with 20 garbled ones (0x68 AND 0x10 = 0x00) where they overlapped; port2 hears the
# 80 of port1's that came after its own, and the 8 of the next write, which comes through
# untouched; the collision is counted and told.
start_line "$tmp/c.out" --ports 3 --baud 9600 --timing || exit 1
got=$("$py" "$here/line_probe.py" collide "$tmp/l")
first=$(sed -n 1p <<<"$got" | cut -d' ' -f2)
[ "${#first}" = 200 ] && ok || bad "port3 got ${#first} hex digits during the collision, not 200: $first"
[[ $first =~ ^(68)+(00){20}(68)+$ ]] && ok || bad "not 68..., 20 x 00, 68...: $first"
expect_in "after the collision the line carries a write exactly" "port3 0102030405060708" "$got"
stop_line
expect_in "collision told on stderr" "port1, port2 talked at once, 20 octets garbled" "$(cat "$tmp/c.out.err")"
expect_in "collision counted" "dfp-sim line: 1 collision" "$(cat "$tmp/c.out")"
expect_in "port2's collision" "port2  sent 20 octets in 1 writes, received 88, dropped 0, collisions 1" "$(cat "$tmp/c.out")"

# 3. --timing at 9600 bit/s: 100 octets take 115 ms to reach the reader; without it, at once.
start_line "$tmp/t.out" --ports 2 --baud 9600 --timing || exit 1
read -r _ first _ last _ n < <("$py" "$here/line_probe.py" spread "$tmp/l")
[ "$n" = 100 ] && ok || bad "--timing: $n octets arrived"
awk -v f="$first" -v l="$last" 'BEGIN { exit !(l - f >= 80) }' && ok || bad "--timing: spread $first..$last ms, expected >= 80 ms"
stop_line
start_line "$tmp/u.out" --ports 2 --baud 9600 || exit 1
read -r _ first _ last _ n < <("$py" "$here/line_probe.py" spread "$tmp/l")
[ "$n" = 100 ] && ok || bad "no --timing: $n octets arrived"
awk -v f="$first" -v l="$last" 'BEGIN { exit !(l - f < 40) }' && ok || bad "no --timing: spread $first..$last ms, expected at once"
stop_line

# 4. Two external programs: dfp-sim slave on port2, dfp-sim master on port1, through the line,
# which captures both directions.
start_line "$tmp/m.out" --ports 2 --capture "$tmp/m.txt" || exit 1
"$sim" slave --port "$tmp/l/port2" --address 5 --inverter none --baud 19200 >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3
expect_exit 0 "master and slave through the line" -- timeout 30 "$sim" master --port "$tmp/l/port1" \
  --address 5 --config F3F2 --baud 19200 --cycles 50 --outputs 0000000000000000000605DC0000
expect_in "inputs echo the outputs" "last inputs 0000000000000000000605DC0000" "$out"
kill -INT "$slave"; wait "$slave"
expect_in "slave reached data exchange" "Wait_Cfg -> Data_Exch" "$(cat "$tmp/slave.out")"
stop_line
expect_in "no collision between master and slave" "dfp-sim line: 0 collisions" "$(cat "$tmp/m.out")"
# 6. The capture: Data_Exchange requests (SD2, DA 05, SA 02) and replies (DA 02, SA 05).
req=$(grep -c " 68 11 11 68 05 02 " "$tmp/m.txt"); rsp=$(grep -c " 68 11 11 68 02 05 " "$tmp/m.txt")
[ "$req" -ge 50 ] && [ "$rsp" -ge 50 ] && ok || bad "capture: $req requests, $rsp replies: $(head "$tmp/m.txt")"

# 5. An emulated card inside the line, a master on port1; the capture has the card's replies.
start_line "$tmp/k.out" --ports 1 --card 5 --capture "$tmp/k.txt" || exit 1
expect_exit 0 "master and the line's card" -- timeout 30 "$sim" master --port "$tmp/l/port1" \
  --address 5 --config F3F2 --baud 19200 --cycles 50 --outputs 0000000000000000000605DC0000
expect_in "the master exchanged data" "slave 5 in data exchange, 50 cycles" "$out"
stop_line
expect_in "the card reached data exchange" "Wait_Cfg -> Data_Exch" "$(cat "$tmp/k.out")"
req=$(grep -c "RX 68 11 11 68 05 02 " "$tmp/k.txt"); rsp=$(grep -c "TX 68 11 11 68 02 05 " "$tmp/k.txt")
[ "$req" -ge 50 ] && [ "$rsp" -ge 50 ] && ok || bad "card capture: $req requests, $rsp replies"
# The replay engine reads it and the card it runs answers every request as the line's card did.
expect_exit 0 "the card's capture replays" -- "$sim" replay --check "$tmp/k.txt"

# 8. One line, two external programs and the in-memory bus at once, in one token ring: the
# line's own master 3 (inside, on the in-memory bus) owns dfp-sim slave 7 on port2; dfp-sim
# master 2 on port1 owns the line's card 5. Same bus parameters everywhere (HSA 7, G 1: short
# GAP rounds).
ring=(--hsa 7 --gap-factor 1)
start_line "$tmp/r.out" --ports 2 --card 5 --master 3 --master-slaves 7 "${ring[@]}" \
  --capture "$tmp/r.txt" || exit 1
"$sim" slave --port "$tmp/l/port2" --address 7 --baud 19200 --inverter none >"$tmp/s7.out" 2>&1 &
s7=$!; pids+=($s7)
expect_exit 0 "master 2 in the ring with the line's master 3" -- timeout 60 "$sim" master \
  --port "$tmp/l/port1" --address 5 --config F3F2 --baud 19200 --cycles 100 --timeout 50 "${ring[@]}"
expect_in "master 2 done" "slave 5 in data exchange, 100 cycles" "$out"
expect_in "master 2 saw master 3 in the ring" "token ring: master 3 is in the ring" "$out"
kill -INT "$s7"; wait "$s7"
stop_line
# Whoever times out first (TTO: 1 s for 2, 1.2 s for 3, from each one's start) claims the token
# and lets the other in through its GAP.
if grep -q "token ring: GAP: station 2 answers: master ready" "$tmp/r.out" ||
   grep -q "token ring: GAP: station 3 answers: master ready" <<<"$out"; then ok
else bad "neither master let the other in: $out $(cat "$tmp/r.out")"; fi
expect_in "the line's master saw master 2 in the ring" "token ring: master 2 is in the ring" "$(cat "$tmp/r.out")"
expect_in "the line's master had 7 in data exchange" "slave 7 is in data exchange" "$(cat "$tmp/r.out")"
expect_in "no collision in the ring" "dfp-sim line: 0 collisions" "$(cat "$tmp/r.out")"
expect_in "slave 7 in data exchange with master 3" "Set_Prm from master 3 accepted" "$(cat "$tmp/s7.out")"
# The token went both ways: 3 to 2 and 2 to 3.
t32=$(grep -c " DC 02 03$" "$tmp/r.txt"); t23=$(grep -c " DC 03 02$" "$tmp/r.txt")
[ "$t32" -ge 100 ] && [ "$t23" -ge 100 ] && ok || bad "tokens 3->2: $t32, 2->3: $t23"

# 7. Bad command lines: exit 2, one line.
mkdir -p "$tmp/bad"; touch "$tmp/bad/port1"
for args in "" "--dir $tmp/nodir" "--dir $tmp/bad" "--dir $tmp/l --ports 0" \
            "--dir $tmp/l --ports 17" "--dir $tmp/l --baud 1234" "--dir $tmp/l --card 126" \
            "--dir $tmp/l --card 5 --card 5" "--dir $tmp/l --bogus" \
            "--dir $tmp/l --master 3" "--dir $tmp/l --master-slaves 5" \
            "--dir $tmp/l --master 3 --master-slaves 3" "--dir $tmp/l --master 3 --master-slaves 5 --tsl 5" \
            "--dir $tmp/l --tsl 2000" "--dir $tmp/l --card 5 --master 5 --master-slaves 6" \
            "--dir $tmp/l --master 40 --master-slaves 5"; do
  # shellcheck disable=SC2086
  expect_exit 2 "line $args" -- "$sim" line $args
  [ "$(wc -l <<<"$out")" = 1 ] && ok || bad "line $args: not one line: $out"
done
[ -f "$tmp/bad/port1" ] && ok || bad "a regular file at DIR/port1 was touched"

finish
