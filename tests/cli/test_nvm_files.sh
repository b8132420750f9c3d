#!/usr/bin/env bash
# dfp-sim slave with --eeprom / --card-nvm files that are damaged or not files at all: a FIFO, a
# directory or a device is refused at once (exit 2, one line, the FIFO untouched, `timeout 10`
# catches a hang); good files give no note; a damaged drive EEPROM falls back to FILE.bak with a
# note naming file, reason and backup in the log and in the API state (nvm.note), and the values
# after the restart are the backup's; both images damaged: both files and reasons named, factory
# settings; the card's NVM likewise.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
export DFP_SIM_TOKEN=cli-test-token-0123456789 # the API's operator token (docs/api.md)
note() { curl -s --max-time 5 -H "Authorization: Bearer $DFP_SIM_TOKEN" "http://127.0.0.1:$port/api/v1/state" |
  python3 -c 'import json,sys; print(json.load(sys.stdin)["cards"][0]["nvm"]["note"])'; }
hint="refused (give a regular file, or a path where one can be created)"

# Not regular files: refused before anything is opened (no PTY needed: the check comes first).
mkfifo "$tmp/fifo"
expect_exit 2 "--eeprom FIFO" -- timeout 10 "$sim" slave --port "$tmp/none" --eeprom "$tmp/fifo"
[ "$out" = "dfp-sim: slave: --eeprom $tmp/fifo: a FIFO, not a regular file: $hint" ] && ok ||
  bad "--eeprom FIFO message: $out"
expect_exit 2 "--card-nvm FIFO" -- timeout 10 "$sim" slave --port "$tmp/none" --card-nvm "$tmp/fifo"
[ "$out" = "dfp-sim: slave: --card-nvm $tmp/fifo: a FIFO, not a regular file: $hint" ] && ok ||
  bad "--card-nvm FIFO message: $out"
expect_exit 2 "inverter --eeprom FIFO" -- timeout 10 "$sim" inverter --eeprom "$tmp/fifo"
[ "$out" = "dfp-sim: inverter: --eeprom $tmp/fifo: a FIFO, not a regular file: $hint" ] && ok ||
  bad "inverter --eeprom FIFO message: $out"
[ -p "$tmp/fifo" ] && [ ! -e "$tmp/fifo.tmp" ] && ok || bad "the FIFO was replaced or written"
expect_exit 2 "--card-nvm directory" -- timeout 10 "$sim" slave --port "$tmp/none" --card-nvm "$tmp"
[ "$out" = "dfp-sim: slave: --card-nvm $tmp: a directory, not a regular file: $hint" ] && ok ||
  bad "directory message: $out"
expect_exit 2 "--eeprom /dev/null" -- timeout 10 "$sim" slave --port "$tmp/none" --eeprom /dev/null
[ "$out" = "dfp-sim: slave: --eeprom /dev/null: a character device, not a regular file: $hint" ] &&
  ok || bad "device message: $out"
mkdir "$tmp/line" && mkfifo "$tmp/line/drive5.ee"
expect_exit 2 "a line of cards, one drive's file a FIFO" -- \
  timeout 10 "$sim" slave --port "$tmp/none" --address 4-6 --eeprom "$tmp/line"
[ "$out" = "dfp-sim: slave: --eeprom $tmp/line/drive5.ee: a FIFO, not a regular file: $hint" ] &&
  ok || bad "line of cards message: $out"

pty_pair || exit 1
# start_slave NAME ARGS...: the card on $tmp/a with the API on $port, output in $tmp/NAME.out;
# returns once the API answers (the start-up note is logged before it starts).
start_slave() {
  local name=$1; shift
  port=$(free_port)
  "$sim" slave --port "$tmp/a" --address 4 --baud 19200 --http "$port" "$@" >"$tmp/$name.out" 2>&1 &
  slave=$!; pids+=($slave)
  for _ in $(seq 100); do note >/dev/null 2>&1 && { log=$(cat "$tmp/$name.out"); return 0; }; sleep 0.1; done
  bad "$name: the slave did not start: $(cat "$tmp/$name.out")"; return 1
}
stop_slave() { kill "$slave"; wait "$slave" 2>/dev/null; }
param() { "$sim" param --port "$tmp/b" --address 4 --timeout 10 "$@"; }
p130() { expect_exit 0 "$1: read P130" -- param read P130
  expect_in "$1: P130 = $2" "read 8470 via channel: P130 ramp t11 UP CW = $2 ms (raw $2," "$out"; }
no_note() {
  if grep -q "non-volatile storage" <<<"$log"; then bad "$1: a note in the log: $log"; else ok; fi
  [ "$(note)" = None ] && ok || bad "$1: nvm.note is $(note)"
}
ends_line() { # ends_line DESCRIPTION TEXT: a line of $log ends with TEXT
  local l
  while IFS= read -r l; do [[ "$l" == *"$2" ]] && { ok; return 0; }; done <<<"$log"
  bad "$1: no line ends with '$2':"$'\n'"$log"
}
ee=$tmp/d.ee
short="file too short (10 bytes, less than the 20-byte header)"

# Fresh files: no note. Two generations: P130 = 3000 in d.ee.bak, 4000 in d.ee.
start_slave fresh --eeprom "$ee" --card-nvm "$tmp/c.nvm" || exit 1
no_note "fresh files"
expect_exit 0 "write P130 3000" -- param write P130 3000
expect_exit 0 "write P130 4000" -- param write P130 4000
stop_slave
start_slave good --eeprom "$ee" || exit 1
no_note "good file"
p130 "good file" 4000
stop_slave
cp "$ee" "$tmp/good.ee"

# The file damaged: the backup's values, and the note says so in the log and in the API.
head -c 10 "$tmp/good.ee" >"$ee"
start_slave damaged --eeprom "$ee" || exit 1
want="drive EEPROM: $ee: $short; using the previous image $ee.bak (the writes after it are lost)"
expect_in "damaged: the log" "card     non-volatile storage: $want" "$log"
[ "$(note)" = "$want" ] && ok || bad "damaged: nvm.note is '$(note)', expected '$want'"
p130 "damaged" 3000
# The next write replaces the damaged file: the restart after it has nothing to say.
expect_exit 0 "write P130 5000" -- param write P130 5000
stop_slave
start_slave healed --eeprom "$ee" || exit 1
no_note "healed"
p130 "healed" 5000
stop_slave

# Both images damaged: both named with their reasons; factory settings.
head -c 10 "$tmp/good.ee" >"$ee"
printf 'Z%.0s' $(seq 64) >"$ee.bak"
start_slave both --eeprom "$ee" || exit 1
bakwhy="not an EEPROM image (magic 0x5A5A5A5A, expected 0x44465045)"
want="drive EEPROM: $ee: $short; $ee.bak: $bakwhy: no usable image; the drive starts from its factory settings"
[ "$(note)" = "$want" ] && ok || bad "both: nvm.note is '$(note)', expected '$want'"
# A log line holds 240 characters: the note may go on in a second line, cut at a "; ".
expect_in "both: the log names the file" "non-volatile storage: drive EEPROM: $ee: $short" "$log"
expect_in "both: the log names the backup" "$ee.bak: $bakwhy: no usable image" "$log"
expect_in "both: the log says what is used" "the drive starts from its factory settings" "$log"
p130 "both damaged" 2000
stop_slave

# The card's NVM: a damaged file with a good backup, then without one.
cp "$tmp/good.ee" "$tmp/c.nvm.bak" # any valid image will do: the note is about the file
head -c 10 "$tmp/good.ee" >"$tmp/c.nvm"
start_slave card --card-nvm "$tmp/c.nvm" || exit 1
want="card NVM: $tmp/c.nvm: $short; using the previous image $tmp/c.nvm.bak (the writes after it are lost)"
expect_in "card NVM: the log" "card     non-volatile storage: $want" "$log"
[ "$(note)" = "$want" ] && ok || bad "card NVM: nvm.note is '$(note)', expected '$want'"
stop_slave
rm "$tmp/c.nvm.bak"
start_slave card_none --card-nvm "$tmp/c.nvm" || exit 1
want="card NVM: $tmp/c.nvm: $short; $tmp/c.nvm.bak: no such file: no usable image; I&M1..I&M4 start empty"
expect_in "card NVM without backup: the log" "card     non-volatile storage: $want" "$log"
[ "$(note)" = "$want" ] && ok || bad "card NVM without backup: nvm.note is '$(note)'"
stop_slave

# Both files unusable at once: the log has all of it (longer than the API's note holds), each
# file starting a line of its own.
start_slave all --eeprom "$ee" --card-nvm "$tmp/c.nvm" || exit 1
expect_in "all: the drive's line" "card     non-volatile storage: drive EEPROM: $ee: $short" "$log"
ends_line "all: the card's line" "card     non-volatile storage: $want"
expect_in "all: the drive's backup" "$ee.bak: $bakwhy: no usable image" "$log"
ends_line "all: the factory settings" "the drive starts from its factory settings"
[ "$(grep -c 'non-volatile storage' <<<"$log")" -ge 2 ] && ok || bad "all: not two files' lines"
stop_slave

finish
