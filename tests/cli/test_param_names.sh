#!/usr/bin/env bash
# dfp-sim param with parameter names (movidrive_names.h) against dfp-sim slave over a socat PTY
# pair: read by P-number, by name and by index all name the parameter and show its value as text;
# write takes an enumeration text and a value in the unit; --json carries p_number, name and
# text beside the raw value; IPOS variables as Hn; an unknown or ambiguous name is a bad command
# line (exit 2, the one-line reason on stderr, nothing on stdout).
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

pty_pair || exit 1
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
sleep 0.3

param() { "$sim" param --port "$tmp/b" --address 4 --timeout 10 "$@"; }
json_get() { python3 -c 'import json,sys; print(json.loads(sys.argv[1])[sys.argv[2]])' "$1" "$2"; }
eq() { if [ "$2" = "$3" ]; then ok; else bad "$1: got '$2', expected '$3'"; fi; }

# Reads: P-number, name, index, hex index; P100 starts at 0 (BIPOL./FIX.SETPT).
expect_exit 0 "read P100" -- param read P100
eq "read P100" "$out" "read 8461 via channel: P100 setpoint source = 0 (BIPOL./FIX.SETPT)"
expect_exit 0 "write P100 FIELDBUS" -- param write P100 FIELDBUS
eq "write P100 FIELDBUS" "$out" "write 8461 = 3 via channel: ok (P100 setpoint source = 3 (FIELDBUS))"
expect_exit 0 "read \"setpoint source\"" -- param read "setpoint source" --via movilink
eq "read by name" "$out" "read 8461 via movilink: P100 setpoint source = 3 (FIELDBUS)"
expect_exit 0 "read p100 0x210D 8461 by data set 47" -- param read p100 0x210D 8461 --via c2
eq "three spellings, one parameter" "$out" "read 8461 via c2: P100 setpoint source = 3 (FIELDBUS)
read 8461 via c2: P100 setpoint source = 3 (FIELDBUS)
read 8461 via c2: P100 setpoint source = 3 (FIELDBUS)"
expect_exit 0 "write fieldbus (any case) via profidrive" -- param write p100 fieldbus --via profidrive

# Units: P000 speed (0.001 rpm), P130 ramp (ms), P160 written as "300.5", P076 no unit.
expect_exit 0 "read speed" -- param read P000
eq "P000" "$out" "read 8318 via channel: P000 speed = 0.000 rpm (raw 0, 0x00000000)"
expect_exit 0 "write P160 300.5" -- param write P160 300.5 --via movilink
eq "P160 written" "$out" "write 8489 = 300500 via movilink: ok (P160 internal setpoint n11 = 300.500 rpm (raw 300500, 0x000495D4))"
expect_exit 0 "write P160 \"250 rpm\"" -- param write P160 "250 rpm" --via c2
expect_exit 0 "read P160 P130 P076" -- param read P160 "ramp t11 up cw" P076 --via movilink
eq "units" "$out" "read 8489 via movilink: P160 internal setpoint n11 = 250.000 rpm (raw 250000, 0x0003D090)
read 8470 via movilink: P130 ramp t11 UP CW = 2000 ms (raw 2000, 0x000007D0)
read 8300 via movilink: P076 firmware basic unit = 823947913 (0x311C7289)"

# IPOS variables by Hn; an index the table lacks still goes to the drive (which refuses it).
expect_exit 0 "write H12" -- param write H12 -42 --via movilink --volatile
eq "H12 write" "$out" "write volatile 11012 = -42 via movilink: ok"
expect_exit 0 "read h12 --json" -- param read h12 --via c2 --json
eq "H12 index" "$(json_get "$out" index)" 11012
eq "H12 p_number" "$(json_get "$out" p_number)" H12
eq "H12 value" "$(json_get "$out" value)" -42
expect_exit 1 "read 1 (not in the table)" -- param read 1 --via movilink
expect_in "index 1 refused by the drive" "read 1 via movilink: error 0x0810" "$out"

# --json: the raw value and every earlier key, plus p_number, name, text.
expect_exit 0 "read P100 --json" -- param read P100 --via movilink --json
for kv in op=read index=8461 p_number=P100 "name=setpoint source" via=movilink ok=True value=3 \
          hex=0x00000003 "text=3 (FIELDBUS)"; do
  eq "json ${kv%%=*}" "$(json_get "$out" "${kv%%=*}")" "${kv#*=}"
done
expect_exit 0 "write P160 --json" -- param write "internal setpoint n11" 1.5 --via profidrive --json
for kv in op=write index=8489 p_number=P160 "name=internal setpoint n11" value=1500 \
          "text=1.500 rpm" ok=True volatile=False; do
  eq "write json ${kv%%=*}" "$(json_get "$out" "${kv%%=*}")" "${kv#*=}"
done
expect_exit 1 "refused write --json keeps the error text" -- param write P302 99000000 --via c2 --json
eq "refused: p_number" "$(json_get "$out" p_number)" P302
eq "refused: error" "$(json_get "$out" error)" 0x0815
expect_in "refused: text is the error" '"text":"class 8, additional code 0x15: value too high"' "$out"

# Bad names and values: exit 2, one line on stderr, nothing on stdout.
usage() { # usage DESCRIPTION EXPECTED-STDERR ARGS...
  local what=$1 want=$2; shift 2
  "$sim" param --port "$tmp/b" --address 4 "$@" >"$tmp/o" 2>"$tmp/e"; local rc=$?
  eq "$what: exit status" "$rc" 2
  if [ ! -s "$tmp/o" ]; then ok; else bad "$what: stdout $(cat "$tmp/o")"; fi
  eq "$what: stderr" "$(cat "$tmp/e")" "$want"
}
usage "unknown P-number" "dfp-sim: param: no parameter 'P999'" read P999
usage "unknown name" "dfp-sim: param: no parameter 'warp drive'" read "warp drive"
usage "unknown name among others" "dfp-sim: param: no parameter 'warp drive'" read P100 "warp drive" --via c2
usage "ambiguous name" "dfp-sim: param: 'fieldbus timeout' matches 2 parameters: P819 fieldbus timeout delay, P831 response FIELDBUS TIMEOUT" read "fieldbus timeout"
usage "IPOS variable out of range" "dfp-sim: param: 'H512' is not an IPOS variable (H0..H511)" read H512
usage "unknown enumeration text" "dfp-sim: param: VALUE 'BUS' is not a value of P100 setpoint source: BIPOL./FIX.SETPT, UNIPOL/FIX.SETPT, RS-485, FIELDBUS, MOTOR POT, ... or a number" write P100 BUS
usage "too many decimals" "dfp-sim: param: VALUE '1.0005' has more than 3 decimals for rpm" write P160 1.0005
usage "unknown name on write" "dfp-sim: param: no parameter 'P9'" write P9 1

kill -INT "$slave"; wait "$slave"
finish
