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
# - replay --check with its output lost (stdout /dev/full): exit 1 and a message on stderr.
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

finish
