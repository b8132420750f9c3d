#!/usr/bin/env bash
# Files the user names are never destroyed by a slip of the command line, and results are not
# lost in silence:
# - slave: --capture, --eeprom, --card-nvm (and an LCM log, --lcm file://...?mode=w) naming one
#   file, by name, by another spelling, or per card of a line, are refused (exit 2, one line)
#   before anything is opened: the EEPROM's md5 is unchanged, a new file is not created;
# - replay: --report over the capture, or two --report files that are one, refused (exit 2);
# - a second process on an EEPROM file is refused (exit 2, naming the file, the holder's pid and
#   the lock) and the first one's acknowledged write survives; after it ends the file is free;
# - --inverter can: with a bad value and --eeprom in a missing directory: exit 2, not 1 or 0;
# - replay --check with its output lost (stdout /dev/full): exit 1 and a message on stderr;
# - a symbolic link planted (by another user of a shared directory) where dfp-sim writes a file:
#   PATH.lock / PATH.tmp beside --eeprom and --card-nvm, --capture (pcap, pcapng, text), an LCM
#   log, replay --report json/junit, record's capture, convert's OUT: refused at the command
#   line (exit 2, one line), the link's target keeps its bytes; a PATH.tmp link planted while the
#   card runs is replaced, not written through, and the write still lands in PATH;
# - text from a file reaches the terminal with its control characters escaped: an LCM log whose
#   channel name holds a screen clear, an OSC 52 clipboard write and a CR is named \x1b... .
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp
cd "$tmp" || exit 1

same="refused before anything was opened (give each its own file)"
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
export DFP_SIM_TOKEN=cli-test-token-0123456789 # the API's operator token (docs/api.md)
api() { curl -s --max-time 5 -H "Authorization: Bearer $DFP_SIM_TOKEN" -H 'Content-Type: application/json' "$@"; }
# start_slave LINK EEPROM: a slave with the API on $port; returns once the API answers.
start_slave() {
  port=$(free_port); slave_link=$1
  "$sim" slave --pty "$1" --eeprom "$2" --http "$port" --quiet >"$1.out" 2>&1 &
  slave=$!; pids+=($slave)
  for _ in $(seq 100); do api "http://127.0.0.1:$port/api/v1/state" >/dev/null && return 0; sleep 0.1; done
  bad "the slave did not start: $(cat "$1.out")"; return 1
}
stop_slave() { # stop_slave DESCRIPTION: SIGINT, and a clean exit 0
  kill -INT "$slave"; wait "$slave"; local rc=$?
  [ "$rc" = 0 ] && ok || bad "$1: the slave exited with $rc: $(cat "$slave_link.out")"; }
p130() { api "http://127.0.0.1:$port/api/v1/cards/4/params/P130" |
  python3 -c 'import json,sys; print(json.load(sys.stdin)["value"])'; }

# An EEPROM image with P130 = 1111 in it.
start_slave pa drive.ee || exit 1
api -X PUT -d '{"value": 1111}' "http://127.0.0.1:$port/api/v1/cards/4/params/P130" >/dev/null
[ "$(p130)" = 1111 ] && ok || bad "P130 not written: $(p130)"
stop_slave "the image written"
sum=$(md5sum <drive.ee)
intact() { [ "$(md5sum <drive.ee)" = "$sum" ] && ok || bad "$1: drive.ee was changed"; }

# F1: the capture, the EEPROM and the card's NVM are three files.
expect_exit 2 "--capture = --eeprom" -- \
  "$sim" slave --pty p1 --eeprom drive.ee --capture drive.ee --duration 1
[ "$out" = "dfp-sim: slave: --capture and --eeprom are the same file (drive.ee, drive.ee): $same" ] &&
  ok || bad "--capture = --eeprom message: $out"
intact "--capture = --eeprom"
expect_exit 2 "--capture ./drive.ee, --eeprom drive.ee" -- \
  "$sim" slave --pty p1 --eeprom drive.ee --capture ./drive.ee --duration 1
expect_in "another spelling" "--capture and --eeprom are the same file (./drive.ee, drive.ee)" "$out"
intact "another spelling"
ln -s drive.ee link.ee
expect_exit 2 "--card-nvm through a symbolic link" -- \
  "$sim" slave --pty p1 --eeprom drive.ee --card-nvm link.ee --duration 1
[ "$out" = "dfp-sim: slave: --eeprom and --card-nvm are the same file (drive.ee, link.ee): $same" ] &&
  ok || bad "--card-nvm link message: $out"
intact "--card-nvm through a symbolic link"
expect_exit 2 "--eeprom = --card-nvm, neither there yet" -- \
  "$sim" slave --pty p1 --eeprom new.ee --card-nvm ./new.ee --duration 1
expect_in "neither there yet" "--eeprom and --card-nvm are the same file (new.ee, ./new.ee)" "$out"
[ ! -e new.ee ] && [ ! -e p1 ] && ok || bad "something was created: $(ls)"
# A capture through a link that points where the EEPROM file will be made (a dangling link).
mkdir sub && ln -s ../later.ee sub/cap.pcap
expect_exit 2 "--capture through a dangling link to the --eeprom file" -- \
  "$sim" slave --pty p1 --eeprom later.ee --capture sub/cap.pcap --duration 1
expect_in "dangling link" "--capture and --eeprom are the same file (sub/cap.pcap, later.ee)" "$out"
[ ! -e later.ee ] && ok || bad "later.ee was created"
expect_exit 2 "--capture as an LCM log" -- \
  "$sim" slave --pty p1 --eeprom drive.ee --lcm "file://$tmp/drive.ee?mode=w" --duration 1
expect_in "LCM log" "--lcm and --eeprom are the same file ($tmp/drive.ee, drive.ee)" "$out"
intact "--capture as an LCM log"
mkdir line && cp drive.ee line/drive5.ee
expect_exit 2 "a line of cards, the capture one card's EEPROM" -- \
  "$sim" slave --pty p1 --address 4-6 --eeprom line --capture line/drive5.ee --duration 1
[ "$out" = "dfp-sim: slave: --capture and --eeprom are the same file (line/drive5.ee, line/drive5.ee): $same" ] &&
  ok || bad "line of cards message: $out"
[ "$(md5sum <line/drive5.ee)" = "$sum" ] && ok || bad "line/drive5.ee was changed"
expect_exit 2 "demo: --capture as its LCM log" -- \
  "$sim" demo --capture out.pcap --lcm "file://./out.pcap?mode=w"
expect_in "demo" "demo: --capture and --lcm are the same file (out.pcap, ./out.pcap)" "$out"

# F2: the capture and the reports.
"$sim" record --capture bus.pcap --cycles 20 >/dev/null || bad "record failed"
bus=$(md5sum <bus.pcap)
expect_exit 2 "--report over the capture" -- "$sim" replay bus.pcap --check --report json bus.pcap
[ "$out" = "dfp-sim: replay: FILE and --report json are the same file (bus.pcap, bus.pcap): $same" ] &&
  ok || bad "--report over the capture message: $out"
[ "$(md5sum <bus.pcap)" = "$bus" ] && ok || bad "bus.pcap was changed"
expect_exit 2 "two reports in one file" -- \
  "$sim" replay bus.pcap --check --report json a.json --report junit ./a.json
expect_in "two reports" "--report json and --report junit are the same file (a.json, ./a.json)" "$out"
[ ! -e a.json ] && ok || bad "a.json was written"
expect_exit 2 "replay --lcm over the capture" -- \
  "$sim" replay bus.pcap --lcm "file://bus.pcap?mode=w"
[ "$(md5sum <bus.pcap)" = "$bus" ] && ok || bad "bus.pcap was changed by --lcm"
expect_exit 0 "replay --check with distinct reports" -- \
  "$sim" replay bus.pcap --check --report json a.json --report junit a.xml

# F3: one process at a time on an EEPROM file; the first one's write survives.
start_slave pa drive.ee || exit 1
api -X PUT -d '{"value": 2222}' "http://127.0.0.1:$port/api/v1/cards/4/params/P130" >/dev/null
sum=$(md5sum <drive.ee)
first=$slave
expect_exit 2 "a second slave on the file" -- "$sim" slave --pty pb --eeprom ./drive.ee --duration 1
[ "$out" = "dfp-sim: slave: --eeprom ./drive.ee: in use by another process (pid $first, lock ./drive.ee.lock): refused" ] &&
  ok || bad "second slave message: $out"
[ ! -e pb ] && ok || bad "the second slave made its PTY link"
expect_exit 2 "inverter on the file" -- timeout 10 "$sim" inverter --can vcan0 --eeprom drive.ee
[ "$out" = "dfp-sim: inverter: --eeprom drive.ee: in use by another process (pid $first, lock drive.ee.lock): refused" ] &&
  ok || bad "inverter message: $out"
intact "a second user"
stop_slave "the first slave"
start_slave pc drive.ee || exit 1 # one after the other: a restart
[ "$(p130)" = 2222 ] && ok || bad "the acknowledged P130 = 2222 is gone: $(p130)"
stop_slave "the restart"

# F8: exit 2 for bad values, found with the command line.
expect_exit 2 "--inverter can: with a bad address" -- "$sim" slave --pty p1 --inverter can:vcan0:99
[ "$out" = "dfp-sim: slave: --inverter can:vcan0:99: SBus address must be 0..63" ] && ok ||
  bad "can address message: $out"
expect_exit 2 "--inverter can: without an interface" -- "$sim" slave --pty p1 --inverter can:
[ "$out" = "dfp-sim: slave: --inverter can:: expected can:IFACE[:ADDR], e.g. can:vcan0:1" ] && ok ||
  bad "can interface message: $out"
expect_exit 2 "--eeprom in a missing directory" -- \
  "$sim" slave --pty p1 --eeprom "$tmp/nodir/drive.ee" --duration 1
[ "$out" = "dfp-sim: slave: --eeprom $tmp/nodir/drive.ee: the directory $tmp/nodir does not exist: refused" ] &&
  ok || bad "missing directory message: $out"
expect_exit 2 "inverter --eeprom in a missing directory" -- \
  "$sim" inverter --can vcan0 --eeprom "$tmp/nodir/drive.ee"
[ ! -e p1 ] && ok || bad "a refused slave made its PTY link"
"$sim" replay bus.pcap --check >/dev/full 2>err.txt; rc=$?
[ "$rc" = 1 ] && ok || bad "replay --check >/dev/full: exit $rc"
expect_in "output lost" "dfp-sim: standard output: write error" "$(cat err.txt)"
"$sim" check-cfg F3F2 >/dev/full 2>/dev/null; rc=$?
[ "$rc" = 1 ] && ok || bad "check-cfg >/dev/full: exit $rc"

# F9: symbolic links planted where dfp-sim writes: refused, their target untouched.
mkdir -p plant vdir && printf 'the victim file\n' >vdir/victim
victim=$(md5sum <vdir/victim)
spared() { [ "$(md5sum <vdir/victim)" = "$victim" ] && ok || bad "$1: the victim was written"; }
linked="is a symbolic link (dfp-sim writes no file through a link): refused"
for side in lock tmp; do
  ln -s ../vdir/victim "plant/drive.ee.$side"
  expect_exit 2 "a link at drive.ee.$side" -- \
    "$sim" slave --pty plant/p1 --eeprom plant/drive.ee --duration 1
  [ "$out" = "dfp-sim: slave: --eeprom plant/drive.ee: plant/drive.ee.$side $linked" ] &&
    ok || bad "drive.ee.$side message: $out"
  spared "drive.ee.$side"
  ln -s ../vdir/victim "plant/card.nvm.$side"
  expect_exit 2 "a link at card.nvm.$side" -- \
    "$sim" slave --pty plant/p1 --card-nvm plant/card.nvm --duration 1
  [ "$out" = "dfp-sim: slave: --card-nvm plant/card.nvm: plant/card.nvm.$side $linked" ] &&
    ok || bad "card.nvm.$side message: $out"
  spared "card.nvm.$side"
  expect_exit 2 "inverter, a link at drive.ee.$side" -- \
    timeout 10 "$sim" inverter --can vcan0 --eeprom plant/drive.ee
  [ "$out" = "dfp-sim: inverter: --eeprom plant/drive.ee: plant/drive.ee.$side $linked" ] &&
    ok || bad "inverter drive.ee.$side message: $out"
  spared "inverter drive.ee.$side"
  rm "plant/drive.ee.$side" "plant/card.nvm.$side"
  [ ! -e plant/drive.ee ] && [ ! -e plant/card.nvm ] && [ ! -e plant/p1 ] && ok ||
    bad "a refused run created files: $(ls plant)"
done
refused="is a symbolic link: refused (dfp-sim writes no file through a link)"
# planted NAME EXPECTED-LINE COMMAND...: a link at plant/NAME, exit 2, that line, no write.
planted() {
  local name=$1 line=$2; shift 2
  ln -s ../vdir/victim "plant/$name"
  expect_exit 2 "a link at $name: $*" -- "$@"
  [ "$out" = "$line" ] && ok || bad "a link at $name: $out"
  spared "$name: $*"
  rm "plant/$name"
}
for cap in c.pcap c.pcapng c.txt; do
  planted "$cap" "dfp-sim: slave: --capture plant/$cap $refused" \
    "$sim" slave --pty plant/p1 --capture "plant/$cap" --duration 1
  planted "$cap" "dfp-sim: record: --capture plant/$cap $refused" \
    "$sim" record --capture "plant/$cap" --cycles 5
  planted "$cap" "dfp-sim: convert: OUT plant/$cap $refused" "$sim" convert bus.pcap "plant/$cap"
done
planted e.ee "dfp-sim: slave: --eeprom plant/e.ee $refused" \
  "$sim" slave --pty plant/p1 --eeprom plant/e.ee --duration 1
planted e.ee "dfp-sim: inverter: --eeprom plant/e.ee: plant/e.ee $linked" \
  timeout 10 "$sim" inverter --can vcan0 --eeprom plant/e.ee
planted m.pcap "dfp-sim: master: --capture plant/m.pcap $refused" \
  "$sim" master --port plant/none --address 4 --config F3F2 --capture plant/m.pcap
planted d.pcap "dfp-sim: demo: --capture plant/d.pcap $refused" \
  "$sim" demo --capture plant/d.pcap
planted r.json "dfp-sim: replay: --report json plant/r.json $refused" \
  "$sim" replay bus.pcap --check --report json plant/r.json
planted r.xml "dfp-sim: replay: --report junit plant/r.xml $refused" \
  "$sim" replay bus.pcap --check --report junit plant/r.xml
planted l.lcm "dfp-sim: slave: --lcm plant/l.lcm $refused" \
  "$sim" slave --pty plant/p1 --lcm "file://plant/l.lcm?mode=w" --duration 1
planted l.lcm "dfp-sim: replay: --lcm plant/l.lcm $refused" \
  "$sim" replay bus.pcap --lcm "file://plant/l.lcm?mode=w"
# A link planted at PATH.tmp while the card runs: the next write replaces it with its own file.
start_slave pd plant/run.ee || exit 1
ln -s ../vdir/victim plant/run.ee.tmp
api -X PUT -d '{"value": 3333}' "http://127.0.0.1:$port/api/v1/cards/4/params/P130" >/dev/null
[ "$(p130)" = 3333 ] && ok || bad "P130 not written past the planted run.ee.tmp: $(p130)"
stop_slave "the slave with a planted run.ee.tmp"
spared "run.ee.tmp planted while running"
[ ! -L plant/run.ee.tmp ] && ok || bad "the planted run.ee.tmp is still there"
start_slave pe plant/run.ee || exit 1
[ "$(p130)" = 3333 ] && ok || bad "P130 = 3333 did not reach run.ee: $(p130)"
stop_slave "the restart on run.ee"

# F10: an LCM log's channel names are the file's text: shown escaped in the error that lists them.
"$sim" replay bus.pcap --lcm "file://$tmp/t.lcm?mode=w" >/dev/null 2>&1 || bad "no LCM log made"
python3 - "$tmp/t.lcm" "$tmp/evil.lcm" <<'PY'
import struct, sys
d, out, o = open(sys.argv[1], "rb").read(), b"", 0
evil = b"EVIL\x1b[2J\x1b]52;c;ZXZpbA==\x07\r\xc2\x9b"
while o < len(d):   # every event moved to the channel EVIL...: sync, number, time, lengths
    sync, num, ts, cl, dl = struct.unpack_from(">IQQII", d, o)
    out += struct.pack(">IQQII", sync, num, ts, len(evil), dl) + evil + d[o + 28 + cl:o + 28 + cl + dl]
    o += 28 + cl + dl
open(sys.argv[2], "wb").write(out)
PY
expect_exit 2 "an LCM log with control characters in its channel name" -- \
  "$sim" replay "$tmp/evil.lcm" --channel NOPE
[ "$out" = "dfp-sim: $tmp/evil.lcm: no telegram_t on LCM channel 'NOPE' (channels with telegrams: EVIL\\x1b[2J\\x1b]52;c;ZXZpbA==\\x07\\x0d\\x9b)" ] &&
  ok || bad "escaped channel names: $(printf %q "$out")"

finish
