#!/usr/bin/env bash
# make demo's job: the timeline shows each scene's expected outcome, and --capture writes pcap.
sim=$1
. "$(dirname "$0")/lib.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

expect_exit 0 "demo runs to the end" -- "$sim" demo --capture "$tmp/demo.pcap"
expect_in "baud found" "baud rate found: 1.5 Mbit/s (P092)" "$out"
expect_in "parameterised" "Set_Prm from master 2 accepted; watchdog 100 ms (P819)" "$out"
expect_in "data exchange" "Wait_Cfg -> Data_Exch" "$out"
expect_in "firmware through the parameter channel" "read index 8300 (P076 firmware) -> 823947913 (0x311C7289)" "$out"
expect_in "P100 written" "write P100 setpoint source = 3 FIELDBUS -> done" "$out"
expect_in "limit enforced" "maximum speed = 99000 rpm -> error: class 8, additional code 0x15: value too high" "$out"
expect_in "PO data enabled" "after P100/P101: PI1 status 0206" "$out"
expect_in "ramped to speed" "at speed: PI1 status 0407 (enabled, ready, PO enabled, unit status 4) PI2 300.0 rpm" "$out"
expect_in "monitor PO" "P094..P096 PO1..PO3    0006 05DC 0000 hex" "$out"
expect_in "fault after timeout" "FAULT, fault 28) PI2   0.0 rpm" "$out"
expect_in "external diagnosis" "Ext_Diag WD_On | Master_Add 2, ident 0x6003, ext 02 1C" "$out"
expect_in "fault reset" "after the reset: PI1 status 0407" "$out"
expect_in "watchdog" "DP watchdog expired (100 ms without the master)" "$out"
expect_in "bus fault lit after watchdog" "LED BUS FAULT on" "$out"
expect_in "cfg fault" "Chk_Cfg refused -> Cfg_Fault; P090 = 0PD" "$out"
expect_in "master sees Cfg_Fault" "diagnosis: Station_Not_Ready Cfg_Fault Prm_Req" "$out"
expect_in "monitor 0PD" "P090 PD configuration  0PD" "$out"
expect_in "verdict" "result: every scene behaved as the manual describes" "$out"
# pcap: global header with link type 257, first record = the master's claim of the token (a
# token to itself, DC 02 02: 3 octets), the third its first FDL status request.
hdr=$(od -An -tx1 -N24 "$tmp/demo.pcap" | tr -d ' \n')
if [ "$hdr" = "d4c3b2a1020004000000000000000000ffff000001010000" ]; then ok; else bad "pcap header $hdr"; fi
first=$(od -An -tx1 -j40 -N3 "$tmp/demo.pcap" | tr -d ' \n')
if [ "$first" = "dc0202" ]; then ok; else bad "first telegram $first"; fi
third=$(od -An -tx1 -j$((40 + 3 + 16 + 3 + 16)) -N6 "$tmp/demo.pcap" | tr -d ' \n')
if [ "$third" = "100402494f16" ]; then ok; else bad "third telegram $third"; fi
count=$(grep -o "capture: [0-9]* telegrams" <<<"$out" | grep -o "[0-9]*")
if [ "${count:-0}" -gt 100 ]; then ok; else bad "telegram count $count"; fi
finish
