#!/usr/bin/env bash
# Bad command lines, missing devices and unwritable files: one clear line, non-zero exit.
sim=$1
. "$(dirname "$0")/lib.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

expect_exit 2 "no arguments" -- "$sim"
expect_in "no arguments prints usage" "usage: dfp-sim" "$out"
expect_exit 0 "--help" -- "$sim" --help
expect_exit 2 "unknown command" -- "$sim" fly
expect_in "unknown command named" "unknown command 'fly'" "$out"
expect_exit 2 "slave without port" -- "$sim" slave
expect_in "slave without port says so" "--port DEV is required" "$out"
expect_exit 1 "slave on a missing device" -- "$sim" slave --port /dev/does-not-exist
expect_in "missing device named" "cannot open /dev/does-not-exist" "$out"
expect_exit 2 "address out of range" -- "$sim" slave --port /dev/null --address 200
expect_in "address range named" "--address: '200' is not a number from 0 to 127" "$out"
expect_exit 2 "baud not a PROFIBUS rate" -- "$sim" slave --port /dev/null --baud 115200
expect_in "baud message" "is not a PROFIBUS rate" "$out"
expect_exit 2 "option without value" -- "$sim" slave --port
expect_in "missing value named" "option --port needs a value" "$out"
expect_exit 2 "unknown option" -- "$sim" slave --port /dev/null --colour
expect_exit 2 "master without config" -- "$sim" master --port /dev/null --address 4
expect_exit 2 "master bad hex" -- "$sim" master --port /dev/null --address 4 --config F3G2
expect_in "bad hex named" "--config: 'F3G2' is not a sequence of hex octets" "$out"
expect_exit 2 "master odd hex digits" -- "$sim" master --port /dev/null --address 4 --config F3F
# Bus parameters of the token ring: the table's ranges, the rules between them, the own address.
m4=(master --port /dev/null --address 4 --config F3F2)
expect_exit 2 "unknown bus profile" -- "$sim" "${m4[@]}" --bus-profile fast
[ "$out" = "dfp-sim: --bus-profile: 'fast' is not dp or usb" ] && ok || bad "profile: $out"
expect_exit 2 "slot time below range" -- "$sim" "${m4[@]}" --tsl 5
[ "$out" = "dfp-sim: --tsl: '5' is not a number from 37 to 16777215" ] && ok || bad "tsl: $out"
expect_exit 2 "min TSDR above max TSDR" -- "$sim" "${m4[@]}" --min-tsdr 70 --max-tsdr 60
[ "$out" = "dfp-sim: master: bus parameters: min TSDR must not exceed max TSDR" ] && ok ||
  bad "tsdr: $out"
expect_exit 2 "time-out beyond the timers" -- "$sim" "${m4[@]}" --baud 9600 --tsl 80000
expect_in "time-out rule named" "must each stay below 2147 s at this rate" "$out"
expect_exit 2 "own address above HSA" -- "$sim" "${m4[@]}" --master-address 40
[ "$out" = "dfp-sim: master: --master-address 40: address 40 is above HSA 31: no master's GAP maintenance asks it, so it could join no ring (give --hsa 40 or more, as every master of the segment)" ] &&
  ok || bad "hsa: $out"
expect_exit 2 "param above HSA too" -- "$sim" param --port /dev/null --address 4 --hsa 1 read P100
expect_in "param's own address named" "--master-address 2: address 2 is above HSA 1" "$out"
expect_exit 1 "master on a missing device" -- "$sim" master --port /nonexistent/tty --address 4 --config F2
expect_exit 1 "demo capture into a missing directory" -- "$sim" demo --capture /nonexistent/dir/x.pcap
expect_in "capture path named" "cannot write capture file /nonexistent/dir/x.pcap" "$out"
expect_exit 2 "demo unknown option" -- "$sim" demo --fast
expect_exit 0 "check-cfg of Param + 3 PD" -- "$sim" check-cfg F3F2
expect_in "check-cfg lengths" "F3F2: accepted, param channel + 3 PD, 14 bytes out, 14 bytes in" "$out"
expect_exit 0 "check-cfg of 10 PD" -- "$sim" check-cfg "00 F9"
expect_exit 1 "check-cfg of unequal lengths" -- "$sim" check-cfg F3E2D1
expect_in "check-cfg unequal reason" "14 bytes out but 12 in" "$out"
expect_exit 2 "check-cfg without argument" -- "$sim" check-cfg
finish
