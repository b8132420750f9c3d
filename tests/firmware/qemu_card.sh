#!/usr/bin/env bash
# The DFP21B image on QEMU's netduinoplus2 (STM32F405), USART1 on a PTY, driven by dfp-sim:
#   1. fault image, three starts in one run (SYSRESETREQ keeps RAM): a deliberate bus fault
#      leaves a readable record; the start after it shows the record (BUS FAULT pattern) and
#      resets; the start after that shows nothing, the record kept for a debugger; exit 0
#   2. card without inverter (QEMU has no bxCAN): start-up, Data_Exchange (PI echo PO),
#      I&M0 by class 1 and class 2, a parameter read answered 0x0602 (no inverter);
#      the image's own verdict (semihosting exit 0: served a master, no character error,
#      stack within bounds)
#   3. card with a stand-in inverter on an SBus memory loop: PI from the inverter, read of
#      8300 by every path (cyclic channel, DP-V1 class 1 MOVILINK and PROFIdrive, class 2),
#      write + read back, a refused index
#   4. the conformance suite (dfp-sim conformance) against the card without inverter
# Every step is bounded by timeouts. QEMU models neither baud timing nor parity: the QEMU images
# use a fixed rate and relaxed timing (docs/porting.md, "Running under QEMU").
#
# usage: qemu_card.sh [--skip-if-missing] IMAGE_DIR DFP_SIM
set -u
skip_if_missing=0
if [ "${1:-}" = "--skip-if-missing" ]; then skip_if_missing=1; shift; fi
img_dir=${1:?image dir}
dfp_sim=${2:?dfp-sim}
qemu=$(command -v qemu-system-arm || true)
missing=""
for i in dfp21b-stm32f405-fault dfp21b-stm32f405-qemu dfp21b-stm32f405-qemu-sbus; do
  [ -f "$img_dir/$i.elf" ] || missing="$missing $i.elf"
done
[ -n "$qemu" ] || missing="$missing qemu-system-arm"
if [ -n "$missing" ]; then
  if [ $skip_if_missing = 1 ]; then
    echo "SKIP: missing$missing (built by 'make firmware'; 'make test-firmware' runs this test)"
    exit 77
  fi
  echo "missing:$missing"; echo "0 passed, 1 failed"; exit 1
fi

tmp=$(mktemp -d)
pass=0
fail=0
qpid=""
cleanup() {
  [ -n "$qpid" ] && kill "$qpid" 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT

ok() { pass=$((pass + 1)); echo "ok   $1"; }
bad() { fail=$((fail + 1)); echo "FAIL $1"; [ -n "${2:-}" ] && echo "     got: $2"; }
expect_eq() { # desc got want
  if [ "$2" = "$3" ]; then ok "$1"; else bad "$1" "$2"; echo "     want: $3"; fi
}
expect_has() { # desc text needle
  if printf '%s' "$2" | grep -qF -- "$3"; then ok "$1"; else bad "$1" "$2"; echo "     want: ...$3..."; fi
}

QEMU_ARGS=(-M netduinoplus2 -nographic -monitor none
           -semihosting-config enable=on,target=native)

# Starts an image with USART1 on a PTY; sets qpid, pts, qlog. The PTY stays open in fd 9 for
# the whole run: QEMU's pty backend drops output and polls for a reader only once a second
# after the last one closed, so consecutive dfp-sim runs would lose their first telegrams.
start_image() {
  qlog=$tmp/$1.log
  timeout 120 "$qemu" "${QEMU_ARGS[@]}" -serial pty -kernel "$img_dir/$1.elf" >"$qlog" 2>&1 &
  qpid=$!
  pts=""
  for _ in $(seq 100); do
    pts=$(grep -o '/dev/pts/[0-9]*' "$qlog" 2>/dev/null | head -1)
    [ -n "$pts" ] && break
    sleep 0.1
  done
  if [ -z "$pts" ]; then bad "$1 starts with USART1 on a PTY" "$(cat "$qlog")"; return 1; fi
  exec 9<>"$pts"
  ok "$1 starts with USART1 on $pts"
}

# Lets the image end by itself (2 s of silence after Data_Exch) and returns its exit code.
finish_image() {
  exec 9>&-
  local rc=0
  wait "$qpid" || rc=$?
  qpid=""
  return $rc
}

sim() { timeout 30 "$dfp_sim" "$@" --port "$pts" --timeout 20 2>&1; }

t0=$(date +%s%N)

# ---- 1. fault record ---------------------------------------------------------------------------
out=$(timeout 30 "$qemu" "${QEMU_ARGS[@]}" -serial null \
        -kernel "$img_dir/dfp21b-stm32f405-fault.elf" 2>&1)
rc=$?
expect_eq "fault image: third start shows no fault (semihosting exit 0)" "$rc" "0"
expect_has "fault record names the bus fault" "$out" "fault: BusFault exc=0x00000005"
expect_has "fault record: precise bus error, BFAR valid" "$out" "cfsr=0x00008200"
expect_has "fault record: the faulting address" "$out" "bfar=0xfffffff0"
expect_has "first start: no fault pattern" "$out" "fault test: start 1, fault pattern off"
expect_has "start after the fault: the record" \
  "$(printf '%s\n' "$out" | grep '^previous fault:')" "BusFault exc=0x00000005"
expect_has "start after the fault: count 1" "$(printf '%s\n' "$out" | grep '^previous fault:')" \
  "count=0x00000001"
expect_has "start after the fault: fault pattern" "$out" "fault test: start 2, fault pattern on"
expect_eq "the record is shown by one start only" "$(printf '%s\n' "$out" | grep -c '^previous fault:')" "1"
expect_has "second reset after the fault: no fault pattern" "$out" "fault test: start 3, fault pattern off"
expect_has "the shown record stays for a debugger" "$out" "the shown record is kept for a debugger"

# ---- 2. card without inverter ------------------------------------------------------------------
if start_image dfp21b-stm32f405-qemu; then
  out=$(sim master --address 4 --config F3F2 --cycles 20 --outputs 0000000000000000A1B2C3D4E5F6)
  expect_has "start-up and 20 Data_Exchange cycles" "$out" "done: slave 4 in data exchange"
  expect_has "no inverter: PI words echo PO words, parameter channel zero" "$out" \
    "last inputs 0000000000000000A1B2C3D4E5F6"
  out=$(sim param --address 4 --json im0)
  expect_eq "I&M0 by class 1" "$out" '{"op":"im0","via":"movilink","ok":true,"manufacturer_id":266,"manufacturer":"0x010A","order_id":"824 240 2","serial_number":"STM32F405-0001","hardware_revision":1,"software_revision":"V0.6.0","rev_counter":0,"profile_id":0,"profile_specific_type":0,"im_version":"1.1","im_supported":"0x001E"}'
  out=$(sim param --address 4 --via c2 --json im0)
  expect_has "I&M0 by class 2" "$out" '"via":"c2","ok":true,"manufacturer_id":266'
  out=$(sim param --address 4 --via movilink --json read 8300)
  expect_eq "no inverter: data set 47 read answers class 6 code 2" "$out" \
    '{"op":"read","index":8300,"p_number":"P076","name":"firmware basic unit","via":"movilink","ok":false,"error":"0x0602","text":"class 6 code 2: card <-> inverter communication fault"}'
  rc=0; finish_image || rc=$?
  expect_eq "image's own verdict (semihosting exit code)" "$rc" "0"
  summary=$(grep '^dfp21b-qemu:' "$qlog")
  expect_has "image summary: no character errors" "$summary" "rx errors 0,"
  expect_has "image summary: runs without inverter" "$summary" "inverter none"
  echo "     $summary"
fi

# ---- 3. card with the stand-in inverter on SBus ------------------------------------------------
if start_image dfp21b-stm32f405-qemu-sbus; then
  out=$(sim master --address 4 --config F3F2 --cycles 20 --outputs 00000000000000001234ABCD5678)
  expect_has "SBus: PI words from the inverter (echo of PO1..PO3)" "$out" \
    "last inputs 00000000000000001234ABCD5678"
  for via in channel movilink profidrive c2; do
    out=$(sim param --address 4 --via $via --json read 8300)
    expect_eq "SBus: read 8300 via $via" "$out" \
      "{\"op\":\"read\",\"index\":8300,\"p_number\":\"P076\",\"name\":\"firmware basic unit\",\"via\":\"$via\",\"ok\":true,\"value\":823947913,\"hex\":\"0x311C7289\",\"text\":\"823947913\"}"
  done
  out=$(sim param --address 4 --via movilink --json write 8601 4711 --volatile)
  expect_has "SBus: write 8601 = 4711" "$out" '"ok":true'
  out=$(sim param --address 4 --via c2 --json read 8601)
  expect_has "SBus: read back 8601 by class 2" "$out" '"value":4711,'
  out=$(sim param --address 4 --via channel --json read 1234)
  expect_has "SBus: illegal index 0x0810 through the cyclic channel" "$out" '"error":"0x0810"'
  rc=0; finish_image || rc=$?
  expect_eq "image's own verdict (semihosting exit code)" "$rc" "0"
  summary=$(grep '^dfp21b-qemu:' "$qlog")
  expect_has "image summary: no character errors" "$summary" "rx errors 0,"
  echo "     $summary"
fi

# ---- 4. the conformance suite against the image -------------------------------------------------
# docs/conformance.md: every case PASS or NOT APPLICABLE (timing and the baud search: a PTY has
# neither), the JUnit report well-formed with the same counts.
# The image starts while the tester already asks: the requests it finds queued in QEMU's USART
# are answered late, which the tester settles (docs/conformance.md) before the first case.
gsd="$(cd "$(dirname "$0")/../.." && pwd)/firmware/gsd/SEWA6003.GSD"
if start_image dfp21b-stm32f405-qemu; then
  out=$(timeout 300 "$dfp_sim" conformance --port "$pts" --address 4 --gsd "$gsd" \
          --report junit "$tmp/conformance.xml" 2>&1)
  rc=$?
  expect_eq "conformance suite against the image: exit 0 (no case fails)" "$rc" "0"
  summary=$(printf '%s\n' "$out" | grep '^summary:')
  expect_has "conformance: no case fails" "$summary" " 0 FAIL,"
  expect_has "conformance: timing not measurable on a PTY" "$out" \
    "NA    timing.tsdr.min"
  expect_has "conformance: DP-V1 data set 47 passes" "$out" "PASS  dpv1.ds47.profidrive"
  junit=$(python3 -c 'import sys, xml.etree.ElementTree as E
r = E.parse(sys.argv[1]).getroot()
print(sum(int(s.get("failures")) for s in r.iter("testsuite")))' "$tmp/conformance.xml" 2>&1)
  expect_eq "conformance: JUnit report, 0 failures" "$junit" "0"
  echo "     $summary"
  printf '%s\n' "$out" | grep -A4 '^FAIL' | sed 's/^/     /'
  kill "$qpid" 2>/dev/null; wait "$qpid" 2>/dev/null; qpid=""
  exec 9>&-
fi

t1=$(date +%s%N)
echo "qemu_card.sh: $(( (t1 - t0) / 1000000 )) ms"
echo "$pass passed, $fail failed"
[ $fail = 0 ]
