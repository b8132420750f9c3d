#!/usr/bin/env bash
# Hostile datagrams on an LCM segment (sim_host/lcm_bridge/README.md, "Who can reach a segment"):
# the two datagrams that crash an LCM 1.3.1 subscriber (lcm_hostile_datagrams.py) reach a slave
# and a master running on the segment; both stay up and the master still brings the slave to
# Data_Exchange afterwards. udpm on loopback needs a multicast route: a private namespace.
# Usage: test_lcm_datagrams.sh DFP_SIM PYTHON
sim=$1
python=$2
. "$(dirname "$0")/netns.sh"
. "$(dirname "$0")/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
trap 'exit 1' INT TERM
group=239.255.76.74
port=7674
url="udpm://$group:$port?ttl=0"

"$sim" slave --bus lcm:SEG --lcm-url "$url" --address 5 --inverter none >"$tmp/slave.out" 2>&1 &
slave=$!; pids+=($slave)
for _ in $(seq 100); do [ -s "$tmp/slave.out" ] && break; sleep 0.1; done

expect_exit 0 "the hostile datagrams go out" -- "$python" "$(dirname "$0")/lcm_hostile_datagrams.py" \
  "$group" "$port" SEG
expect_in "both datagrams sent" "sent 2 datagrams" "$out"
sleep 0.5
if kill -0 "$slave" 2>/dev/null; then ok; else
  wait "$slave"; bad "the slave died (exit $?):"$'\n'"$(tail -3 "$tmp/slave.out")"; fi

# A master that hears them too, while it runs; then the slave must still serve it.
( sleep 0.3; "$python" "$(dirname "$0")/lcm_hostile_datagrams.py" "$group" "$port" SEG \
    >/dev/null ) &
expect_exit 0 "a master still reaches Data_Exchange with the slave" -- \
  timeout 60 "$sim" master --bus lcm:SEG --lcm-url "$url" --address 5 --config F3F2 --baud 19200 \
  --cycles 20 --timeout 30
expect_in "master done" "done: slave 5 in data exchange" "$out"
if kill -0 "$slave" 2>/dev/null; then ok; else bad "the slave died during the master's run"; fi
kill -INT "$slave"
if wait "$slave"; then ok; else bad "the slave did not exit 0 on SIGINT"; fi
pids=()
expect_in "the slave served the master" "Wait_Cfg -> Data_Exch" "$(cat "$tmp/slave.out")"
finish
