#!/usr/bin/env bash
# dfp-sim monitor --seconds beyond 71 minutes (4295 s: more microseconds than the 32-bit
# hal_time_us_t holds) ends when it should. The clock runs 4096 times as fast (clock_fast.so),
# so 5000 s take about 1.2 s; a monitor that cannot count past the wrap runs on until the
# timeout kills it.
sim=$1
fast=$2
here=$(dirname "$0")
. "$here/../cli/lib.sh"
with_tmp

mkdir -p "$tmp/l"
"$sim" line --dir "$tmp/l" --ports 1 --baud 187500 --quiet >"$tmp/line.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do grep -q "Ctrl-C ends it" "$tmp/line.out" 2>/dev/null && break; sleep 0.1; done
# Under AddressSanitizer the preloaded clock comes before ASan's runtime in the library list,
# which ASan refuses unless told that this order is meant.
asan="${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0"
expect_exit 0 "--seconds 5000 on a clock 4096 times as fast" -- timeout 30 \
  env ASAN_OPTIONS="$asan" LD_PRELOAD="$fast" \
  "$sim" monitor --port "$tmp/l/port1" --baud 187500 --seconds 5000 --view none
expect_in "--seconds 5000: the summary" "monitor $tmp/l/port1:" "$out"
finish
