#!/usr/bin/env bash
# dfp-sim param against dfp-sim slave (emulated MOVIDRIVE) over a socat PTY pair: read 8300 by
# every path, writes read back by another path, several indices in one data set 47 request (each
# result in its place, one request on the wire), --volatile, a value above the maximum (exit 1
# and the error text), I&M0 by class 1 and class 2, --json parsed by python3, a slave that does
# not answer, and bad command lines (exit 2, one line on stderr, nothing on stdout).
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3

param() { "$sim" param --port "$tmp/b" --address 4 --timeout 10 "$@"; }
# json_get JSON KEY: the value as Python prints it (True/False for booleans).
json_get() { python3 -c 'import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])' "$1" "$2"; }

# Firmware version 8300 by each path.
for via in channel movilink profidrive c2; do
  expect_exit 0 "read 8300 via $via" -- param read 8300 --via "$via"
  expect_in "8300 via $via" "read 8300 via $via: P076 firmware basic unit = 823947913 (0x311C7289)" "$out"
done
expect_exit 0 "read without --via is the cyclic channel" -- param read 8300
expect_in "default path" "read 8300 via channel: P076 firmware basic unit = 823947913" "$out"

# JSON, one object, parsed.
expect_exit 0 "read 8300 --json" -- param read 8300 --via movilink --json
if [ "$(printf '%s\n' "$out" | wc -l)" = 1 ]; then ok; else bad "--json printed more than one line: $out"; fi
[ "$(json_get "$out" value)" = 823947913 ] && ok || bad "json value: $out"
[ "$(json_get "$out" hex)" = 0x311C7289 ] && ok || bad "json hex: $out"
[ "$(json_get "$out" ok)" = True ] && ok || bad "json ok: $out"
[ "$(json_get "$out" via)" = movilink ] && ok || bad "json via: $out"
[ "$(json_get "$out" index)" = 8300 ] && ok || bad "json index: $out"

# Writes, each read back by another path (P160 n11 = 8489, IPOS H0 = 11000).
expect_exit 0 "write 8489 via profidrive (id 0x02)" -- param write 8489 1500 --via profidrive
expect_in "write ok" "write 8489 = 1500 via profidrive: ok" "$out"
expect_exit 0 "read back via c2" -- param read 8489 --via c2
expect_in "read back 1500" "read 8489 via c2: P160 internal setpoint n11 = 1.500 rpm (raw 1500, 0x000005DC)" "$out"
expect_exit 0 "write 8489 via c2" -- param write 8489 2250 --via c2 --json
[ "$(json_get "$out" ok)" = True ] && ok || bad "c2 write json: $out"
expect_exit 0 "read back via channel" -- param read 8489
expect_in "read back 2250" "read 8489 via channel: P160 internal setpoint n11 = 2.250 rpm (raw 2250," "$out"
expect_exit 0 "write 8489 via channel" -- param write 8489 3000 --via channel
expect_exit 0 "read back via movilink" -- param read 8489 --via movilink
expect_in "read back 3000" "read 8489 via movilink: P160 internal setpoint n11 = 3.000 rpm (raw 3000," "$out"
# Back-to-back masters on the cyclic channel: the card keeps its handshake across masters, each
# new one must toggle relative to the reply it sees (dp_master_param_sync), or nothing runs.
expect_exit 0 "second write via channel" -- param write 8489 4000
expect_exit 0 "read back via channel again" -- param read 8489
expect_in "read back 4000" "read 8489 via channel: P160 internal setpoint n11 = 4.000 rpm (raw 4000," "$out"
expect_exit 0 "third write via channel" -- param write 8489 3000
expect_exit 0 "read back via channel once more" -- param read 8489
expect_in "read back 3000 again" "read 8489 via channel: P160 internal setpoint n11 = 3.000 rpm (raw 3000," "$out"
expect_exit 0 "write volatile H0 via movilink" -- param write 11000 -7 --via movilink --volatile
expect_in "volatile write" "write volatile 11000 = -7 via movilink: ok" "$out"
expect_exit 0 "read H0 via profidrive" -- param read 11000 --via profidrive --json
[ "$(json_get "$out" value)" = -7 ] && ok || bad "H0 = -7: $out"
[ "$(json_get "$out" hex)" = 0xFFFFFFF9 ] && ok || bad "H0 hex: $out"
expect_exit 0 "write volatile H0 via channel" -- param write 11000 0x1234 --volatile
expect_exit 0 "read H0 via c2" -- param read 11000 --via c2
expect_in "H0 = 0x1234" "read 11000 via c2: 4660 (0x00001234)" "$out"

# Several indices in one data set 47 request: one line per parameter in the order asked; a
# refused one fails alone (exit 1), the others keep their values.
expect_exit 1 "read 4 indices via movilink, one illegal" -- param read 8300 11000 1 8489 --via movilink
want=$'read 8300 via movilink: P076 firmware basic unit = 823947913 (0x311C7289)\nread 11000 via movilink: 4660 (0x00001234)
read 1 via movilink: error 0x0810: class 8, additional code 0x10: illegal parameter index
read 8489 via movilink: P160 internal setpoint n11 = 3.000 rpm (raw 3000, 0x00000BB8)'
[ "$out" = "$want" ] && ok || bad "4-index read: got
$out"
expect_exit 0 "read 2 indices via c2" -- param read 8489 11000 --via c2
[ "$out" = $'read 8489 via c2: P160 internal setpoint n11 = 3.000 rpm (raw 3000, 0x00000BB8)\nread 11000 via c2: 4660 (0x00001234)' ] && ok || bad "2-index c2 read: $out"
expect_exit 0 "read 3 indices via profidrive --json" -- param read 11000 8300 8489 --via profidrive --json
if [ "$(printf '%s\n' "$out" | wc -l)" = 3 ]; then ok; else bad "--json: not 3 lines: $out"; fi
[ "$(json_get "$(sed -n 2p <<<"$out")" index)" = 8300 ] && ok || bad "json line 2 index: $out"
[ "$(json_get "$(sed -n 3p <<<"$out")" value)" = 3000 ] && ok || bad "json line 3 value: $out"
expect_exit 1 "read 2 indices via c2 --json, the second illegal" -- param read 8300 1 --via c2 --json
[ "$(json_get "$(sed -n 1p <<<"$out")" ok)" = True ] && ok || bad "json line 1 ok: $out"
[ "$(json_get "$(sed -n 2p <<<"$out")" ok)" = False ] && ok || bad "json line 2 not ok: $out"
[ "$(json_get "$(sed -n 2p <<<"$out")" error)" = 0x0810 ] && ok || bad "json line 2 error: $out"
# 19 distinct indices (the most one request carries), H5 set first so that a shifted result shows:
# each answer in its place, and all of them through one data set 47 write on the wire.
expect_exit 0 "write volatile H5 = 55" -- param write 11005 55 --via movilink --volatile
nineteen="8300 8489 11000 $(seq -s ' ' 11001 11016)"
expect_exit 0 "read 19 indices via c2" -- param read $nineteen --via c2 --capture "$tmp/19.pcap"
want="read 8300 via c2: P076 firmware basic unit = 823947913 (0x311C7289)
read 8489 via c2: P160 internal setpoint n11 = 3.000 rpm (raw 3000, 0x00000BB8)
read 11000 via c2: 4660 (0x00001234)"
for i in $(seq 11001 11016); do
  v=0; [ "$i" = 11005 ] && v=55
  want="$want
read $i via c2: $v (0x$(printf '%08X' $v))"
done
[ "$out" = "$want" ] && ok || bad "19 results: got
$out"
writes=$(python3 - "$tmp/19.pcap" <<'PY'
import struct, sys
d = open(sys.argv[1], "rb").read()
o, n = 24, []
while o + 16 <= len(d):
    cl = struct.unpack("<I", d[o + 8:o + 12])[0]
    r = d[o + 16:o + 16 + cl]
    o += 16 + cl
    # SD2 to station 4 with SAPs, DP-V1 Write (0x5F) of index 47
    if len(r) > 11 and r[0] == 0x68 and r[4] == 0x84 and r[9] == 0x5F and r[11] == 47:
        n.append(len(r))
print(" ".join(map(str, n)))
PY
)
[ "$writes" = 133 ] && ok || bad "data set 47 writes on the wire (octets each): '$writes', expected one of 133"

# A value above P302's maximum: exit 1 and the meaning, by every path.
expect_exit 1 "P302 = 99000000 via movilink" -- param write 8517 99000000 --via movilink --volatile
expect_in "MOVILINK error text" "error 0x0815: class 8, additional code 0x15: value too high" "$out"
expect_exit 1 "P302 = 99000000 via channel" -- param write 8517 99000000
expect_in "channel error text" "error 0x0815: class 8, additional code 0x15: value too high" "$out"
expect_exit 1 "P302 = 99000000 via profidrive" -- param write 8517 99000000 --via profidrive --json
[ "$(json_get "$out" ok)" = False ] && ok || bad "json ok false: $out"
[ "$(json_get "$out" error)" = 0x0002 ] && ok || bad "PROFIdrive error 0x0002: $out"
expect_in "PROFIdrive text" "low or high limit exceeded" "$out"
expect_exit 1 "P302 = 99000000 via c2" -- param write 8517 99000000 --via c2 --json
[ "$(json_get "$out" error)" = 0x0815 ] && ok || bad "c2 error 0x0815: $out"
expect_exit 1 "index 1 does not exist" -- param read 1 --via movilink
expect_in "illegal index" "error 0x0810: class 8, additional code 0x10: illegal parameter index" "$out"

# I&M0 by class 1 and class 2; without --via it goes through movilink and says so.
expect_exit 0 "im0 (class 1)" -- param im0
[ "$(head -n 1 <<<"$out")" = "im0 via movilink:" ] && ok || bad "im0 without --via names its path: $out"
expect_in "im0 manufacturer" "manufacturer id    0x010A" "$out"
expect_in "im0 order id" "order id           824 240 2" "$out"
expect_in "im0 serial" "serial number      DFP-SIM-004" "$out"
expect_exit 0 "im0 via c2 --json" -- param im0 --via c2 --json
[ "$(json_get "$out" manufacturer)" = 0x010A ] && ok || bad "im0 manufacturer: $out"
[ "$(json_get "$out" manufacturer_id)" = 266 ] && ok || bad "im0 manufacturer_id: $out"
[ "$(json_get "$out" order_id)" = "824 240 2" ] && ok || bad "im0 order_id: $out"
[ "$(json_get "$out" im_supported)" = 0x001E ] && ok || bad "im0 im_supported: $out"
[ "$(json_get "$out" via)" = c2 ] && ok || bad "im0 via c2: $out"
expect_exit 0 "im0 --json without --via" -- param im0 --json
[ "$(json_get "$out" via)" = movilink ] && ok || bad "im0 default path in JSON: $out"
expect_exit 0 "im0 via profidrive" -- param im0 --via profidrive
expect_in "im0 via profidrive" "serial number      DFP-SIM-004" "$out"
[ "$(head -n 1 <<<"$out")" = "im0 via profidrive:" ] && ok || bad "im0 via profidrive: $out"

# Nobody at address 5: exit 1 within the timeout, with the reason (for each index asked).
expect_exit 1 "no slave at 5, two indices" -- "$sim" param --port "$tmp/b" --address 5 --timeout 1 read 8300 8301 --via movilink
want="read 8300 via movilink: error timeout: no result within 1 s: slave 5 did not reach data exchange (phase FDL status)
read 8301 via movilink: error timeout: no result within 1 s: slave 5 did not reach data exchange (phase FDL status)"
[ "$out" = "$want" ] && ok || bad "timeout for both indices: $out"
expect_exit 1 "no slave at 5 (class 1)" -- "$sim" param --port "$tmp/b" --address 5 --timeout 1 read 8300 --via movilink
expect_in "class-1 timeout text" "error timeout: no result within 1 s: slave 5 did not reach data exchange" "$out"
expect_exit 1 "no slave at 5 (class 2)" -- "$sim" param --port "$tmp/b" --address 5 --timeout 2 read 8300 --via c2 --json
expect_in "class-2 no answer" '"text":"Initiate (resource manager): no answer from slave 5"' "$out"

# Bad command lines: exit 2, one line on stderr, nothing on stdout.
usage() { # usage DESCRIPTION NEEDLE ARGS...
  local what=$1 needle=$2; shift 2
  "$sim" param "$@" >"$tmp/o" 2>"$tmp/e"; local rc=$?
  if [ "$rc" = 2 ]; then ok; else bad "$what: exit $rc, expected 2"; fi
  if [ ! -s "$tmp/o" ] && [ "$(wc -l <"$tmp/e")" = 1 ]; then ok; else bad "$what: output $(cat "$tmp/o" "$tmp/e")"; fi
  expect_in "$what" "$needle" "$(cat "$tmp/e")"
}
P=(--port "$tmp/b" --address 4)
usage "no operation" "say what to do" "${P[@]}"
usage "no port" "--port DEV and --address N are required" read 8300
usage "read without index" "read takes the parameter INDEX" "${P[@]}" read
usage "20 indices" "a read takes up to 19 indices" "${P[@]}" read $nineteen 8300 --via c2
usage "2 indices via channel" "the cyclic channel carries one service at a time" "${P[@]}" read 8300 8301
usage "bad second index" "'x' matches 11 parameters" "${P[@]}" read 8300 x --via c2
usage "index too big" "'70000' is not a number from 0 to 65535" "${P[@]}" read 70000
usage "write without value" "write takes two arguments" "${P[@]}" write 8489
usage "value not a number" "VALUE 'x12' is not a number for P160" "${P[@]}" write 8489 x12
usage "unknown path" "--via 'usb'" "${P[@]}" read 8300 --via usb
usage "volatile on read" "--volatile belongs to write" "${P[@]}" read 8300 --volatile
usage "volatile via profidrive" "--volatile works with --via movilink or channel" "${P[@]}" write 8489 1 --via profidrive --volatile
usage "im0 via channel" "dfp-sim: param: im0 needs DP-V1, which --via channel does not use: leave --via out (im0 then uses movilink) or give --via movilink, profidrive or c2" "${P[@]}" --via channel im0
usage "unknown operation" "unknown operation 'frob'" "${P[@]}" frob 1
usage "unknown option" "unknown option '--fast'" "${P[@]}" read 8300 --fast
usage "bad baud" "--baud" "${P[@]}" read 8300 --baud 1234

kill -INT "$slave"; wait "$slave"
slave_out=$(cat "$tmp/slave.out")
expect_in "slave saw DP-V1 parameterisation" "Data_Exch" "$slave_out"
finish
