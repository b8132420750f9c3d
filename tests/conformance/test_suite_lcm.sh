#!/usr/bin/env bash
# The suite against `dfp-sim slave` on an LCM segment (--bus lcm:CHANNEL): every case PASS or
# NOT APPLICABLE (timing is not measurable on a segment, 12M not claimed). udpm on loopback needs
# a multicast route, so the test runs in a private network namespace (tests/lcm/netns.sh) on a
# group of its own.
sim=$1
root=$2
. "$root/tests/lcm/netns.sh"
. "$root/tests/cli/lib.sh"
with_tmp
v1="$root/firmware/gsd/SEWA6003.GSD"
url="udpm://239.255.76.92:7692?ttl=0"

"$sim" slave --bus lcm:SUITE --lcm-url "$url" --address 4 --inverter none >"$tmp/lcm.out" 2>&1 &
pids+=($!)
sleep 0.5
out=$(timeout 300 "$sim" conformance --bus lcm:SUITE --lcm-url "$url" --address 4 --gsd "$v1" 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "an LCM segment: exit $rc"$'\n'"$(grep -A4 '^FAIL' <<<"$out" | head -20)"$'\n'"slave: $(tail -5 "$tmp/lcm.out")"
expect_in "an LCM segment" "summary: 63 cases, 58 PASS, 0 FAIL, 5 NOT APPLICABLE" "$out"
expect_in "the segment named as the medium" "medium:  lcm:SUITE" "$out"
finish
