#!/usr/bin/env bash
# Reply-path instruction counts on the target: the -qemu-sbus image single-stepped by QEMU with
# an instruction trace, driven by dfp-sim (DP-V0 start-up + Data_Exchange, C1 and C2 reads, a
# 19-parameter C2 read, a 28-octet Data_Exchange, an FCB repeat).
# usage: measure_reply_path.sh IMAGE_DIR DFP_SIM OUT_DIR
set -eu
img=$1/dfp21b-stm32f405-qemu-sbus.elf
sim=$2
out=$3
mkdir -p "$out"
rm -f "$out"/trace.log "$out"/*.pcap "$out"/qemu.log
timeout 300 qemu-system-arm -M netduinoplus2 -nographic -monitor none \
  -semihosting-config enable=on,target=native -serial pty -singlestep -d exec,nochain \
  -D "$out/trace.log" -kernel "$img" >> "$out/qemu.log" 2>&1 & # append: semihosting writes through its own offset
qpid=$!
for _ in $(seq 100); do pts=$(grep -o '/dev/pts/[0-9]*' "$out/qemu.log" || true); [ -n "$pts" ] && break; sleep 0.1; done
exec 9<>"$pts"
timeout 60 "$sim" master --port "$pts" --address 4 --config F3F2 --cycles 10 \
  --outputs 00000000000000001234ABCD5678 --capture "$out/1.pcap" > /dev/null
timeout 60 "$sim" param --port "$pts" --address 4 --via movilink --capture "$out/2.pcap" read 8300
timeout 60 "$sim" param --port "$pts" --address 4 --via c2 --capture "$out/3.pcap" read 8300
# the largest data set 47 request: 19 parameters, parsed and answered by the main loop
timeout 120 "$sim" param --port "$pts" --address 4 --via c2 --timeout 100 --capture "$out/4.pcap" \
  read $(printf '8300 %.0s' $(seq 19)) > /dev/null
# the longest Data_Exchange the card takes: parameter channel + 10 process data words, 28 octets
timeout 60 "$sim" master --port "$pts" --address 4 --config F3F9 --cycles 10 \
  --outputs "$(printf '00%.0s' $(seq 8))$(printf '1234%.0s' $(seq 10))" --capture "$out/5.pcap" \
  > /dev/null
# an FCB repeat: master 5 reads the diagnosis (first frame, then a new one), then repeats that
# request with the same FCB as if our reply had been lost; the card answers it from its cache
for fc_fcs in 6D:F0 5D:E0 5D:E0; do
  printf "\x68\x05\x05\x68\x84\x85\x${fc_fcs%:*}\x3C\x3E\x${fc_fcs#*:}\x16" > "$pts"
  sleep 1
done
exec 9>&-
# The image prints its summary and exits by semihosting after its silence timeout; QEMU does not
# always leave then (seen under load: it sat until the outer timeout), so stop it once the
# summary is out. SIGTERM lets it flush the trace.
for _ in $(seq 600); do
  kill -0 $qpid 2>/dev/null || break
  if grep -q "dfp21b-qemu:" "$out/qemu.log"; then sleep 2; kill $qpid 2>/dev/null; break; fi
  sleep 0.1
done
wait $qpid || true
grep -q "dfp21b-qemu:" "$out/qemu.log" || { echo "measure_reply_path: the image printed no summary" >&2; exit 1; }
python3 "$(dirname "$0")/../../firmware/board/stm32f405/tools/reply_path_count.py" \
  --card "$1/dfp21b-stm32f405.elf" "$img" \
  "$out/trace.log" "$out/1.pcap" "$out/2.pcap" "$out/3.pcap" "$out/4.pcap" "$out/5.pcap"
