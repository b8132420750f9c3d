#!/usr/bin/env bash
# SBus end to end on vcan0, run inside the VM (tests/vm/vm-run.sh):
#   dfp-sim inverter (the emulated MOVIDRIVE, its own process) <-> the card's SBus link as
#   dfp-sim slave uses it (test_sbus_socketcan --external), over SocketCAN.
# 1. parameter read/write/error and PO -> PI against the inverter at SBus address 1;
# 2. a non-volatile write survives a restart of the inverter (--eeprom), a volatile one does not;
# 3. an inverter at address 2 on the same bus does not answer address-1 traffic twice;
# 4. the inverter prints its services and stops on SIGINT with status 0;
# 5. the drive over SBus: enable, ramp, a PO gap -> SBus timeout -> F28, reset;
# 6. the whole chain master -> PTY -> dfp-sim slave --inverter can:vcan0:1 -> dfp-sim inverter.
#   sbus_e2e.sh DFP_SIM TEST_SBUS_SOCKETCAN
set -u
sim="$1"
client="$2"
work="$(mktemp -d)"
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
check() { if eval "$2"; then ok; else bad "$1"; fi; }

start_inverter() { # address log; sets $pid (in this shell, so that `wait` can reap it)
  "$sim" inverter --can vcan0 --sbus-address "$1" --eeprom "$work/md$1.eeprom" >"$2" 2>&1 &
  pid=$!
  for _ in $(seq 100); do grep -q "^dfp-sim inverter:" "$2" 2>/dev/null && break; sleep 0.05; done
}

stop_inverter() { # pid -> exit status
  kill -INT "$1"
  wait "$1"
}

# 1 + 3: two inverters on the bus, the card talks to address 1.
start_inverter 1 "$work/inv1.log"; p1=$pid
start_inverter 2 "$work/inv2.log"; p2=$pid
"$client" --can vcan0 --external 1 --expect-h0 0 --write-h1 4242
check "client run 1 passed" '[ $? = 0 ]'
stop_inverter "$p1"; rc1=$?
stop_inverter "$p2"; rc2=$?
check "inverter 1 exits 0 on SIGINT" '[ $rc1 = 0 ]'
check "inverter 2 exits 0 on SIGINT" '[ $rc2 = 0 ]'
echo "---- inverter 1 ----"; cat "$work/inv1.log"
check "inverter 1 logged the firmware read" 'grep -q "param  read 8300 -> 0x311C7289 (823947913)" "$work/inv1.log"'
check "inverter 1 logged the H0 write" 'grep -q "param  write volatile 11000 = 3000 -> ok" "$work/inv1.log"'
check "inverter 1 logged the refused index" 'grep -q "param  read 7 -> error: class 8, additional code 0x10" "$work/inv1.log"'
check "inverter 1 logged its state" 'grep -q "state  status word 0x" "$work/inv1.log"'
check "inverter 1 stop line" 'grep -q "stopping (signal): 7 parameter services (1 refused), 1 PO frames" "$work/inv1.log"'
check "inverter 2 heard no service" 'grep -q "stopping (signal): 0 parameter services (0 refused), 0 PO frames" "$work/inv2.log"'

# 2: after a restart H1 (written non-volatile) is back, H0 (volatile) is not.
start_inverter 1 "$work/inv1b.log"; p1=$pid
"$client" --can vcan0 --external 1 --expect-h0 0 --expect-h1 4242
check "client run 2 (after restart) passed" '[ $? = 0 ]'
stop_inverter "$p1"
check "inverter 1 exits 0 after restart" '[ $? = 0 ]'
check "EEPROM file exists" '[ -s "$work/md1.eeprom" ]'

# 5. The drive over SBus: enable and ramp, then a PO gap -> SBus timeout -> F28, reset.
start_inverter 1 "$work/inv1c.log"; p1=$pid
"$client" --can vcan0 --external 1 --drive
check "client drive run passed" '[ $? = 0 ]'
stop_inverter "$p1"
echo "---- inverter 1, drive ----"; cat "$work/inv1c.log"
check "inverter logged the enable" 'grep -q "output stage enabled" "$work/inv1c.log"'
check "inverter logged the SBus timeout" 'grep -q "SBus timeout: no PO frame for 100 ms" "$work/inv1c.log"'
check "inverter logged F28" 'grep -q "fault F28" "$work/inv1c.log"'

# 6. The whole chain: dfp-sim master -> PTY pair -> dfp-sim slave --inverter can:vcan0:1 ->
#    SBus on vcan0 -> dfp-sim inverter. The master reads P076 (index 8300) through the cyclic
#    parameter channel (handshake bit set: a new service) and sends PO 0006 05DC 0000.
start_inverter 1 "$work/inv1d.log"; p1=$pid
rm -f "$work/a" "$work/b"
socat pty,raw,echo=0,link="$work/a" pty,raw,echo=0,link="$work/b" &
psocat=$!
for _ in $(seq 50); do [ -e "$work/a" ] && [ -e "$work/b" ] && break; sleep 0.1; done
"$sim" slave --port "$work/a" --address 4 --baud 19200 --inverter can:vcan0:1 >"$work/slave.log" 2>&1 &
pslave=$!
sleep 0.3
timeout 60 "$sim" master --port "$work/b" --address 4 --config F3F2 --baud 19200 --cycles 100 \
  --outputs 4100206C00000000000605DC0000 >"$work/master.log" 2>&1
check "master ran 100 cycles through the card" '[ $? = 0 ]'
sleep 0.3 # PO frames have stopped with the master: the inverter's SBus timeout runs out
kill -INT "$pslave"; wait "$pslave"
check "slave exits 0 on SIGINT" '[ $? = 0 ]'
stop_inverter "$p1"
kill "$psocat" 2>/dev/null; wait "$psocat" 2>/dev/null
echo "---- master ----"; tail -n 3 "$work/master.log"
echo "---- slave ----"; head -n 3 "$work/slave.log"
echo "---- inverter 1, chain ----"; cat "$work/inv1d.log"
check "master got P076 through card and SBus" 'grep -q "last inputs 4100206C311C7289" "$work/master.log"'
check "inverter answered the card's read" 'grep -q "param  read 8300 -> 0x311C7289" "$work/inv1d.log"'
check "card sent PO frames" 'grep -Eq "stopping \(signal\): 1 parameter services \(0 refused\), [1-9][0-9]* PO frames" "$work/inv1d.log"'
check "no PO after the master left: SBus timeout" 'grep -q "SBus timeout" "$work/inv1d.log"'
check "slave named its inverter" 'grep -q "inverter: can:vcan0:1" "$work/slave.log"'

# Errors: no such interface, one line, status 1.
"$sim" inverter --can nosuchcan0 >"$work/err.log" 2>&1
check "missing interface -> status 1" '[ $? = 1 ]'
check "missing interface -> one line" '[ "$(wc -l <"$work/err.log")" = 1 ] && grep -q "cannot open CAN interface nosuchcan0: No such device" "$work/err.log"'

rm -rf "$work"
echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
