#!/bin/bash
# Every case of the DP state machine group gives its expected verdict: PASS, and NOT APPLICABLE
# only for dp.set_prm.user_prm with the DP-V1 GSD (it defines no ExtUserPrmData). In process at
# every rate the GSD claims (two modules: process data alone, and the parameter channel with
# ten words), and on a PTY against dfp-sim slave without an inverter.
set -u
SIM=$1
GSD=$2
pass=0
fail=0
IDS="dp.diag.wait_prm dp.wait_prm.services dp.wait_cfg.data_exchange dp.wait_cfg.services
dp.data_exch.services dp.set_prm.lock dp.set_prm.unlock dp.set_prm.min_tsdr_only
dp.set_prm.repeated dp.set_prm.wrong_ident dp.set_prm.user_prm dp.set_prm.watchdog_off
dp.watchdog.expiry dp.chk_cfg.right dp.chk_cfg.wrong dp.get_cfg dp.diag.data_exch
dp.global_control.clear dp.global_control.sync dp.global_control.freeze
dp.global_control.groups dp.class2.read dp.second_master"

ok() { pass=$((pass + 1)); }
bad() { echo "FAIL: $*"; fail=$((fail + 1)); }

# check OUTPUT RUNS NA_ID: every id PASS in each of RUNS runs, NA_ID (if any) NOT APPLICABLE.
check() {
    local out=$1 runs=$2 na=$3 id want got
    for id in $IDS; do
        want="PASS"
        [ "$id" = "$na" ] && want="NA"
        got=$(grep -cE -- "^$want +${id//./\\.}( |\$)" <<<"$out")
        if [ "$got" -eq "$runs" ]; then ok; else bad "$id: '$want' $got of $runs runs"; fi
    done
}

for module in "1 PD" "Param + 10 PD"; do
    out=$("$SIM" conformance --card --address 4 --gsd "$GSD/SEW_6003.GSD" --module "$module" \
          --baud all --only dp. 2>&1)
    [ $? -eq 0 ] && ok || bad "SEW_6003 $module: exit status"
    check "$out" 9 ""
    out=$("$SIM" conformance --card --address 4 --gsd "$GSD/SEWA6003.GSD" --module "$module" \
          --baud all --only dp. 2>&1)
    [ $? -eq 0 ] && ok || bad "SEWA6003 $module: exit status"
    check "$out" 9 dp.set_prm.user_prm
done

dir=$(mktemp -d)
trap 'kill "$slave" 2>/dev/null; wait "$slave" 2>/dev/null; rm -rf "$dir"' EXIT
"$SIM" slave --pty "$dir/pty" --address 4 --inverter none --duration 60 >"$dir/slave.log" 2>&1 &
slave=$!
for _ in $(seq 50); do [ -e "$dir/pty" ] && break; sleep 0.1; done
out=$(timeout 60 "$SIM" conformance --port "$dir/pty" --address 4 --gsd "$GSD/SEW_6003.GSD" \
      --only dp. 2>&1)
[ $? -eq 0 ] && ok || bad "PTY: exit status"
check "$out" 1 ""

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
