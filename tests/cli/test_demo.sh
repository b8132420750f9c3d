#!/usr/bin/env bash
# make demo's job: the timeline shows each scene's expected outcome, and --capture writes pcap.
sim=$1
. "$(dirname "$0")/lib.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

expect_exit 0 "demo runs to the end" -- "$sim" demo --capture "$tmp/demo.pcap"
expect_in "baud found" "baud rate found: 1.5 Mbit/s (P092)" "$out"
expect_in "parameterised" "Set_Prm from master 2 accepted; watchdog 100 ms (P819)" "$out"
expect_in "data exchange" "Wait_Cfg -> Data_Exch" "$out"
expect_in "loopback PI" "P097..P099 PI1..PI3    0006 05DC 0000 hex" "$out"
expect_in "watchdog" "DP watchdog expired (100 ms without the master)" "$out"
expect_in "bus fault lit after watchdog" "LED BUS FAULT on" "$out"
expect_in "cfg fault" "Chk_Cfg refused -> Cfg_Fault; P090 = 0PD" "$out"
expect_in "master sees Cfg_Fault" "diagnosis: Station_Not_Ready Cfg_Fault Prm_Req" "$out"
expect_in "monitor 0PD" "P090 PD configuration  0PD" "$out"
expect_in "verdict" "result: every scene behaved as the manual describes" "$out"
# pcap: global header with link type 257, first record = the master's first FDL status request.
hdr=$(od -An -tx1 -N24 "$tmp/demo.pcap" | tr -d ' \n')
if [ "$hdr" = "d4c3b2a1020004000000000000000000ffff000001010000" ]; then ok; else bad "pcap header $hdr"; fi
first=$(od -An -tx1 -j40 -N6 "$tmp/demo.pcap" | tr -d ' \n')
if [ "$first" = "100402494f16" ]; then ok; else bad "first telegram $first"; fi
count=$(grep -o "capture: [0-9]* telegrams" <<<"$out" | grep -o "[0-9]*")
if [ "${count:-0}" -gt 100 ]; then ok; else bad "telegram count $count"; fi
finish
