#!/usr/bin/env bash
# The whole suite (docs/conformance.md) as make test runs it: against the card in process at
# every rate each GSD claims and against dfp-sim slave on a PTY, every case PASS or NOT
# APPLICABLE, with the exact counts; the JUnit and HTML reports agree with the terminal's; bad
# command lines are refused with exit 2.
sim=$1
root=$2
. "$root/tests/cli/lib.sh"
with_tmp
v1="$root/firmware/gsd/SEWA6003.GSD"
v0="$root/firmware/gsd/SEW_6003.GSD"
rates=("9.6 kbit/s" "19.2 kbit/s" "45.45 kbit/s" "93.75 kbit/s" "187.5 kbit/s" "500 kbit/s"
       "1.5 Mbit/s" "3 Mbit/s" "6 Mbit/s")

# every_rate DESCRIPTION LINE OUTPUT: "<rate>: LINE" for each of the nine rates.
every_rate() {
  local n=0
  for b in "${rates[@]}"; do grep -qxF -- "$b: $2" <<<"$3" && n=$((n + 1)); done
  if [ "$n" = 9 ]; then ok; else bad "$1: '$2' at $n of 9 rates:"$'\n'"$(grep -E '^(FAIL|[0-9])' <<<"$3")"; fi
}
# junit_counts FILE: "tests failures skipped" summed over the testsuites.
junit_counts() {
  python3 -c 'import sys, xml.etree.ElementTree as E
r = E.parse(sys.argv[1]).getroot()
t = [sum(int(s.get(k, 0)) for s in r.iter("testsuite")) for k in ("tests", "failures", "skipped")]
print(*t)' "$1"
}

# ---- the card in process, every rate -------------------------------------------------------
out=$(timeout 300 "$sim" conformance --card --address 4 --gsd "$v1" --baud all \
        --report junit "$tmp/v1.xml" --report html "$tmp/v1.html" 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "DP-V1 GSD, card in process: exit $rc"
# 63 cases: dp.set_prm.user_prm (no ExtUserPrmData) and timing.rates_unclaimed (no 12M) NA
every_rate "DP-V1 GSD, card in process" "63 cases, 61 PASS, 0 FAIL, 2 NOT APPLICABLE" "$out"
expect_in "the total" "summary: 567 cases, 549 PASS, 0 FAIL, 18 NOT APPLICABLE" "$out"
expect_in "the frame form is information" "info:" "$(grep -A3 'fdl.frame_form' <<<"$out")"
got=$(junit_counts "$tmp/v1.xml")
[ "$got" = "567 0 18" ] && ok || bad "JUnit counts: '$got', expected '567 0 18'"
python3 - "$tmp/v1.html" <<'PY' && ok || bad "HTML report: not well-formed or counts differ"
import sys, xml.etree.ElementTree as E
text = open(sys.argv[1], encoding="utf-8").read()
E.fromstring(text.split("\n", 1)[1] if text.startswith("<!DOCTYPE") else text)
assert text.count("dp.watchdog.expiry") >= 9 and "SEW-EURODRIVE" in text and "<script" not in text
PY

out=$(timeout 300 "$sim" conformance --card --address 4 --gsd "$v0" --baud all 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "DP-V0 GSD, card in process: exit $rc"
# the 12 DP-V1 cases NA, user_prm PASS (this GSD has ExtUserPrmData)
every_rate "DP-V0 GSD, card in process" "63 cases, 50 PASS, 0 FAIL, 13 NOT APPLICABLE" "$out"

# ---- dfp-sim slave on a PTY ----------------------------------------------------------------
"$sim" slave --pty "$tmp/link" --address 4 --inverter none >"$tmp/slave.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [[ $(readlink "$tmp/link") == /dev/pts/[0-9]* ]] && break; sleep 0.1; done
out=$(timeout 300 "$sim" conformance --port "$tmp/link" --address 4 --gsd "$v1" 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "dfp-sim slave on a PTY: exit $rc"$'\n'"$(grep -A4 '^FAIL' <<<"$out" | head -20)"$'\n'"slave: $(tail -5 "$tmp/slave.out")"
# timing: TSDR and the baud search not measurable on a PTY, 12M not claimed
expect_in "dfp-sim slave on a PTY" "summary: 63 cases, 58 PASS, 0 FAIL, 5 NOT APPLICABLE" "$out"

# ---- a port of the virtual line (its card with the emulated drive) ----------------------------
mkdir -p "$tmp/line"
"$sim" line --dir "$tmp/line" --ports 1 --baud 19200 --card 6 --quiet >"$tmp/line.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -L "$tmp/line/port1" ] && break; sleep 0.1; done
out=$(timeout 300 "$sim" conformance --port "$tmp/line/port1" --address 6 --gsd "$v1" 2>&1)
rc=$?
[ $rc = 0 ] && ok || bad "a port of the line: exit $rc"$'\n'"$(grep -A4 '^FAIL' <<<"$out" | head -20)"$'\n'"line: $(tail -5 "$tmp/line.out")"
expect_in "a port of the line" "summary: 63 cases, 58 PASS, 0 FAIL, 5 NOT APPLICABLE" "$out"


# ---- bad command lines ---------------------------------------------------------------------
expect_exit 2 "no medium" -- "$sim" conformance --address 4 --gsd "$v1"
expect_exit 2 "two media" -- "$sim" conformance --card --port "$tmp/link" --address 4 --gsd "$v1"
expect_exit 2 "no --gsd" -- "$sim" conformance --card --address 4
expect_exit 2 "no --address" -- "$sim" conformance --card --gsd "$v1"
expect_exit 2 "address 126" -- "$sim" conformance --card --address 126 --gsd "$v1"
expect_exit 2 "a GSD that is none" -- "$sim" conformance --card --address 4 --gsd /etc/hostname
expect_exit 2 "a missing GSD" -- "$sim" conformance --card --address 4 --gsd "$tmp/none.gsd"
expect_exit 2 "no such module" -- "$sim" conformance --card --address 4 --gsd "$v1" --module nope
expect_in "the module named" 'no module "nope"' "$out"
expect_exit 2 "--baud all on a port" -- "$sim" conformance --port "$tmp/link" --address 4 \
  --gsd "$v1" --baud all
expect_exit 2 "a bad rate" -- "$sim" conformance --card --address 4 --gsd "$v1" --baud 1234
expect_exit 2 "a bad report kind" -- "$sim" conformance --card --address 4 --gsd "$v1" \
  --report pdf x
expect_exit 2 "the tester at the slave's address" -- "$sim" conformance --card --address 1 \
  --gsd "$v1"
expect_exit 1 "a report that cannot be written" -- "$sim" conformance --card --address 4 \
  --gsd "$v1" --only gsd.ident --report html "$tmp/no/such/dir/r.html"
expect_exit 2 "--only matching no case" -- "$sim" conformance --card --address 4 --gsd "$v1" \
  --only nothing
expect_in "--only named" "--only 'nothing' matches no case" "$out"
expect_exit 1 "a report path that cannot be created, before the run" -- "$sim" conformance \
  --card --address 4 --gsd "$v1" --report junit "$tmp/no/dir/r.xml"
[ "$(grep -c '^PASS' <<<"$out")" = 0 ] && ok || bad "the run went ahead of a report it cannot write"
# the slave at the addresses the tester would otherwise take for its other masters
out=$(timeout 120 "$sim" conformance --card --address 2 --gsd "$v0" --only dp. 2>&1)
expect_in "slave at 2: the class-2 master elsewhere" "summary: 24 cases, 24 PASS, 0 FAIL" "$out"
out=$(timeout 120 "$sim" conformance --card --address 3 --master-address 5 --gsd "$v0" \
        --only dp. 2>&1)
expect_in "slave at 3: the second master elsewhere" "summary: 24 cases, 24 PASS, 0 FAIL" "$out"
expect_exit 0 "--list" -- "$sim" conformance --list
[ "$(grep -c . <<<"$out")" = 63 ] && ok || bad "--list: $(grep -c . <<<"$out") lines, expected 63"
finish
