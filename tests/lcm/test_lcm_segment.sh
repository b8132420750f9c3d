#!/usr/bin/env bash
# A virtual PROFIBUS segment over LCM: 32 `dfp-sim slave --bus lcm:SEG` processes (addresses
# 3..34) and one `dfp-sim master --bus lcm:SEG --address 3-34` bring every slave to
# Data_Exchange and run 50 cycles each. udpm on loopback needs a multicast route: the test runs
# in a private network namespace (unshare -n) so it never touches the machine's routes.
# Prints the figures docs/performance.md quotes (start-up time, cycles/s, CPU).
# Usage: test_lcm_segment.sh DFP_SIM [BAUD] [SLOT_MS] [SLAVES]
sim=$1
baud=${2:-19200}
slot_ms=${3:-100}
nslaves=${4:-32}
. "$(dirname "$0")/netns.sh"
. "$(dirname "$0")/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

url="udpm://239.255.76.70:7670?ttl=0"
first=3
last=$((first + nslaves - 1))
for a in $(seq $first $last); do
  "$sim" slave --bus lcm:SEG --lcm-url "$url" --address "$a" --inverter none \
    >"$tmp/slave$a.out" 2>&1 &
  pids+=($!)
done
# Every slave is listening once it printed its first line.
for _ in $(seq 100); do
  n=0
  for a in $(seq $first $last); do [ -s "$tmp/slave$a.out" ] && n=$((n + 1)); done
  [ "$n" = "$nslaves" ] && break
  sleep 0.1
done
if [ "$n" = "$nslaves" ]; then ok; else bad "only $n of $nslaves slaves started"; fi

t0=$(date +%s%N)
timeout 300 "$sim" master --bus lcm:SEG --lcm-url "$url" --address "$first-$last" --config F3F2 \
  --baud "$baud" --tsl "$((baud * slot_ms / 1000))" --cycles 50 --timeout 240 --outputs 0000000000000000000605DC0000 \
  >"$tmp/master.out" 2>&1
rc=$?
t1=$(date +%s%N)
master_out=$(cat "$tmp/master.out")
if [ "$rc" = 0 ]; then ok; else bad "master exit $rc:"$'\n'"$(tail -5 "$tmp/master.out")"; fi
expect_in "master saw every slave in data exchange" "all $nslaves slaves in data exchange" "$master_out"
expect_in "master done" "done: $nslaves slaves in data exchange" "$master_out"

for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done
stopped=0
for p in "${pids[@]}"; do
  if wait "$p"; then stopped=$((stopped + 1)); fi
done
pids=()
if [ "$stopped" = "$nslaves" ]; then ok; else bad "only $stopped of $nslaves slaves exited 0 on SIGINT"; fi
reached=0
for a in $(seq $first $last); do
  out=$(cat "$tmp/slave$a.out")
  if grep -qF "Wait_Cfg -> Data_Exch" <<<"$out" && grep -qF "DIP address $a," <<<"$out"; then
    reached=$((reached + 1))
  else
    bad "slave $a never reached Data_Exch:"$'\n'"$(tail -3 "$tmp/slave$a.out")"
  fi
done
if [ "$reached" = "$nslaves" ]; then ok; fi

# Figures: start-up and rates as the master measured them, wall time, CPU of all processes.
times >"$tmp/times" # not in a pipe: a subshell would report its own (empty) children
read -r cu cs < <(tr 'ms' '  ' <"$tmp/times" | awk 'NR==2 {print $1*60+$2, $3*60+$4}')
echo "figures: $nslaves slaves at $baud, slot time $slot_ms ms: $(grep -o 'all reached data exchange.*' "$tmp/master.out")"
echo "figures: master run $(( (t1 - t0) / 1000000 )) ms wall; CPU of all ${nslaves}+1 processes:" \
     "user ${cu}s system ${cs}s on $(nproc) CPUs"
finish
