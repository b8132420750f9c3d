#!/usr/bin/env bash
# The Timing and DP-V1 groups of dfp-sim conformance: against the card in process at every rate
# the DP-V1 GSD's cases all pass (timing.rates_unclaimed NOT APPLICABLE: no 12M in the GSD); with
# the DP-V0 GSD every DP-V1 case is NOT APPLICABLE; on a PTY (dfp-sim slave) the DP-V1 cases pass
# and the timing ones are NOT APPLICABLE (no timing, no rate).
sim=$1
root=$2
. "$root/tests/cli/lib.sh"
with_tmp
v1="$root/firmware/gsd/SEWA6003.GSD"
v0="$root/firmware/gsd/SEW_6003.GSD"

# expect_rates DESCRIPTION SUMMARY OUTPUT: SUMMARY after each of the nine rates the card runs.
expect_rates() {
  local n=0
  for b in "9.6 kbit/s" "19.2 kbit/s" "45.45 kbit/s" "93.75 kbit/s" "187.5 kbit/s" \
           "500 kbit/s" "1.5 Mbit/s" "3 Mbit/s" "6 Mbit/s"; do
    grep -qxF -- "$b: $2" <<<"$3" && n=$((n + 1))
  done
  if [ "$n" = 9 ]; then ok; else bad "$1: '$2' at $n of 9 rates:"$'\n'"$3"; fi
}

out=$(timeout 120 "$sim" conformance --card --address 4 --gsd "$v1" --only dpv1. --baud all 2>&1)
expect_rates "DP-V1 GSD, card in process" "12 cases, 12 PASS, 0 FAIL, 0 NOT APPLICABLE" "$out"
out=$(timeout 120 "$sim" conformance --card --address 4 --gsd "$v1" --only timing. --baud all 2>&1)
expect_rates "timing, card in process" "4 cases, 3 PASS, 0 FAIL, 1 NOT APPLICABLE" "$out"
expect_in "unclaimed rates named" \
  "rates the GSD does not claim are not tested: 12M" "$out"
out=$(timeout 60 "$sim" conformance --card --address 4 --gsd "$v0" --only dpv1. 2>&1)
expect_in "DP-V0 GSD: DP-V1 not applicable" \
  "summary: 12 cases, 0 PASS, 0 FAIL, 12 NOT APPLICABLE" "$out"

"$sim" slave --pty "$tmp/link" --address 4 >"$tmp/slave.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ $(readlink "$tmp/link") == /dev/pts/[0-9]* ]] && break; sleep 0.1; done
out=$(timeout 120 "$sim" conformance --port "$tmp/link" --address 4 --gsd "$v1" --only dpv1. 2>&1)
expect_in "DP-V1 on a PTY" "summary: 12 cases, 12 PASS, 0 FAIL, 0 NOT APPLICABLE" "$out"
out=$(timeout 60 "$sim" conformance --port "$tmp/link" --address 4 --gsd "$v1" --only timing. 2>&1)
expect_in "timing on a PTY" "summary: 4 cases, 0 PASS, 0 FAIL, 4 NOT APPLICABLE" "$out"
expect_in "TSDR not measurable on a PTY" "does not time answers to the bit" "$out"
finish
