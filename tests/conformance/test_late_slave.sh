#!/usr/bin/env bash
# A slave whose every answer comes 150 ms late, after the tester's 100 ms slot time (a loaded
# host, an emulator): dfp-sim slave on a PTY behind late_relay.py. The tester takes each late
# answer as the answer to its retry of the same request and lets the answers to the other sends
# go unheard, so no answer passes for the next request's: the start-up and the ident case PASS
# as on a prompt slave. Answers later than the third send's slot time: the case fails on silence,
# and no answer is taken for another request's.
sim=$1
root=$2
. "$root/tests/cli/lib.sh"
with_tmp
v1="$root/firmware/gsd/SEWA6003.GSD"

# relay SLAVE_LINK DELAY: starts the relay, sets $port to the tester's side.
relay() {
  rm -f "$tmp/port"
  python3 "$root/tests/conformance/late_relay.py" "$1" "$2" "$tmp/port" &
  pids+=($!)
  for _ in $(seq 50); do [ -s "$tmp/port" ] && break; sleep 0.1; done
  port=$(cat "$tmp/port")
}

"$sim" slave --pty "$tmp/link" --address 4 --inverter none >"$tmp/slave.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ $(readlink "$tmp/link") == /dev/pts/[0-9]* ]] && break; sleep 0.1; done
relay "$tmp/link" 0.15
out=$(timeout 300 "$sim" conformance --port "$port" --address 4 --gsd "$v1" \
        --only gsd.ident 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "answers 150 ms late: exit $rc"$'\n'"$(grep -A4 '^FAIL' <<<"$out" | head -20)"
expect_in "answers 150 ms late" "summary: 1 case, 1 PASS, 0 FAIL, 0 NOT APPLICABLE" "$out"
out=$(timeout 300 "$sim" conformance --port "$port" --address 4 --gsd "$v1" \
        --only dp.start_up 2>&1)
expect_in "answers 150 ms late: the start-up" "summary: 1 case, 1 PASS, 0 FAIL" "$out"

# 400 ms: after the third send's slot time
kill "${pids[-1]}"
relay "$tmp/link" 0.4
expect_exit 1 "answers 400 ms late" -- timeout 300 "$sim" conformance --port "$port" --address 4 \
  --gsd "$v1" --only gsd.ident
# found (every answer is the DUT's), then every request of the case unanswered: silence, never a
# late answer taken for another request's
expect_in "answers 400 ms late: no answer, not another's" \
  "start-up: Slave_Diag: expected DL with SAPs 62/60 and 6 or more octets, got silence" "$out"
finish
