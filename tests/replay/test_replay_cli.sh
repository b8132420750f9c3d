#!/usr/bin/env bash
# dfp-sim replay and record on the golden captures (golden/README.md): every golden replays with
# --check to exit 0 and its exact counts per service; a copy with one reply octet altered, a
# wrong --address, a two-slave capture without --address, damaged files (truncated record,
# garbage, a garbage record between telegrams, unknown link type), --speed real, times going
# back and long gaps (re-anchored, shortened, SIGINT), pipes, --baud over a recorded rate, the
# goldens made again now (same telegrams, or the test names the first one that changed) and bad
# command lines.
sim=$1
diff_tool=$2
here=$(dirname "$0")
golden=$here/golden
. "$here/../cli/lib.sh"
. "$golden/recipes.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# expect_rows DESCRIPTION OUTPUT ROW...: each row ("Data_Exchange 100 100 0 0 0", blanks
# squeezed) is a line of the per-service table.
expect_rows() {
  local what=$1 text=$2; shift 2
  local table; table=$(tr -s ' ' <<<"$text")
  for row in "$@"; do
    if grep -qxF -- "$row" <<<"$table"; then ok; else bad "$what: no row '$row' in:"$'\n'"$text"; fi
  done
}

# ---- every golden: exit 0 and the exact counts ---------------------------------------------
# Start-up rows shared by the recorded goldens: 22 FDL status polls while the card searches its
# rate (unanswered in the capture and by the card), then the one it answers.
expect_exit 0 "startup.pcap" -- "$sim" replay "$golden/startup.pcap" --check
expect_rows startup.pcap "$out" "FDL_Status 23 23 0 22 22" "Data_Exchange 5 5 0 0 0" \
  "Set_Prm 1 1 0 0 0" "Chk_Cfg 1 1 0 0 0" "Slave_Diag 2 2 0 0 0" "total 32 32 0 22 22"
expect_in "startup.pcap result" "result: MATCH: all 32 replies match" "$out"
expect_in "address found" "DFP21B at address 4 (from the capture: the only slave that answers" "$out"
expect_in "rate from the timing" "1.5 Mbit/s (the capture records no rate; the lowest rate its timing allows: record 28 begins 206.0 us after record 27" "$out"

expect_exit 0 "data_exchange.pcap" -- "$sim" replay "$golden/data_exchange.pcap" --check
expect_rows data_exchange.pcap "$out" "FDL_Status 23 23 0 22 22" "Data_Exchange 100 100 0 0 0" \
  "total 127 127 0 22 22"

expect_exit 0 "param_channel.pcap" -- "$sim" replay "$golden/param_channel.pcap" --check
expect_rows param_channel.pcap "$out" "Data_Exchange 200 200 0 0 0" "total 227 227 0 22 22"

expect_exit 0 "dpv1.pcapng" -- "$sim" replay "$golden/dpv1.pcapng" --check
expect_rows dpv1.pcapng "$out" "Data_Exchange 203 203 0 0 0" "MSAC1 read 11 11 0 0 0" \
  "MSAC1 write 11 11 0 0 0" "MSAC1 poll 22 22 0 0 0" "MSAC2 initiate 1 1 0 0 0" \
  "MSAC2 poll 8 8 0 0 0" "MSAC2 read 6 6 0 0 0" "MSAC2 write 1 1 0 0 0" \
  "MSAC2 abort 1 1 0 0 0" "total 291 291 0 22 22"
expect_in "pcapng carries the rate" "1.5 Mbit/s (recorded in the capture)" "$out"

expect_exit 0 "faults.pcap" -- "$sim" replay "$golden/faults.pcap" --check
expect_rows faults.pcap "$out" "FDL_Status 29 29 0 22 22" "Data_Exchange 150 150 0 0 0" \
  "Set_Prm 7 7 0 0 0" "Chk_Cfg 7 7 0 0 0" "Slave_Diag 14 14 0 0 0" "total 207 207 0 22 22"

expect_exit 0 "multimaster.pcap --address 4" -- "$sim" replay "$golden/multimaster.pcap" --check --address 4
expect_rows multimaster.pcap "$out" "FDL_Status 32 32 0 22 22" "Data_Exchange 100 100 0 0 0" \
  "Slave_Diag 11 11 0 0 0" "total 145 145 0 22 22"
expect_exit 0 "multimaster.pcap, the other DFP21B" -- "$sim" replay "$golden/multimaster.pcap" \
  --check --address 5 --inverter none
expect_rows "multimaster.pcap --address 5" "$out" "Data_Exchange 99 99 0 0 0" "total 126 126 0 22 22"

expect_exit 0 "demo.pcap" -- "$sim" replay "$golden/demo.pcap" --check
expect_rows demo.pcap "$out" "FDL_Status 39 39 0 23 23" "Data_Exchange 578 578 0 0 0" \
  "Set_Prm 7 7 0 0 0" "Chk_Cfg 7 7 0 0 0" "Slave_Diag 15 15 0 0 0" "total 646 646 0 23 23"
# The demo ends with the master's token; cut after its last Data_Exchange request, the replay
# says the answer is missing from the file.
"$sim" convert "$golden/demo.pcap" "$tmp/demo.txt" >/dev/null
last_dx=$(grep -n -- "-- 68 11 11 68 04 02 " "$tmp/demo.txt" | tail -1 | cut -d: -f1)
head -n "$last_dx" "$tmp/demo.txt" >"$tmp/demo_cut.txt"
expect_exit 0 "demo cut after a request" -- "$sim" replay "$tmp/demo_cut.txt" --check
expect_in "demo ends after a request" "the capture ends with a request to the card (record $last_dx" "$out"

# Over a PTY the line has no rate: 12M keeps the recorded spacing possible.
expect_exit 0 "dpv1_pty_movilink.pcap" -- "$sim" replay "$golden/dpv1_pty_movilink.pcap" --check --baud 12M
expect_rows dpv1_pty_movilink.pcap "$out" "MSAC1 read 1 1 0 0 0" "MSAC1 write 1 1 0 0 0" \
  "MSAC1 poll 2 2 0 0 0" "total 14 14 0 0 0"
expect_exit 0 "dpv1_pty_c2.pcap" -- "$sim" replay "$golden/dpv1_pty_c2.pcap" --check --baud 12M
expect_rows dpv1_pty_c2.pcap "$out" "MSAC2 initiate 1 1 0 0 0" "MSAC2 abort 1 1 0 0 0" \
  "total 7 7 0 0 0"
# At the nominal 19200 bit/s the PTY's spacing does not fit: the report says so (the card, fixed
# at that rate as on the tty, still answers as recorded).
expect_exit 0 "dpv1_pty_movilink.pcap at 19200" -- "$sim" replay "$golden/dpv1_pty_movilink.pcap" --check --baud 19200
expect_in "timing conflict reported" "would have overlapped the one before at 19.2 kbit/s" "$out"
expect_in "relaxed judged at the given rate" "too late for a line at 19.2 kbit/s (given with --baud) or before the request could have ended" "$out"

# On a terminal a progress line on stderr (the first after 4096 records), then cleared.
"$sim" record --capture "$tmp/p.pcap" --cycles 3000 --param-every 0 >/dev/null
script -qec "$sim replay $tmp/p.pcap --check --address 4 >/dev/null" /dev/null >"$tmp/tty.txt" 2>&1
expect_in "progress on a terminal" "replay: 4096 records (" "$(cat "$tmp/tty.txt")"
expect_in "progress rate" "telegrams/s" "$(cat "$tmp/tty.txt")"
# The same telegrams as a text capture (dfp-sim convert): positions are lines; a line that is
# not a telegram is listed with its line number and changes nothing else.
"$sim" convert "$golden/param_channel.pcap" "$tmp/pc.txt" >/dev/null
sed -i '151a this line is no telegram' "$tmp/pc.txt"
expect_exit 0 "text capture" -- "$sim" replay "$tmp/pc.txt" --check
expect_in "text format" "replay of $tmp/pc.txt (text)" "$out"
expect_rows "text capture" "$out" "Data_Exchange 200 200 0 0 0" "total 227 227 0 22 22"
expect_in "bad line listed" "record 152 (line 152):" "$out"
# Not a terminal: no progress display.
"$sim" replay "$golden/param_channel.pcap" --check >/dev/null 2>"$tmp/err"
if [ ! -s "$tmp/err" ]; then ok; else bad "stderr not empty without a terminal: $(cat "$tmp/err")"; fi

# ---- one reply octet altered ---------------------------------------------------------------
# The 60th Data_Exchange answer of the card: PI1's low octet + 1, FCS fixed so the telegram is
# valid and only its content differs.
python3 "$here/alter_answers.py" "$golden/data_exchange.pcap" "$tmp/altered.pcap" >"$tmp/altered.txt"
{ read -r rec; read -r pos; read -r original; read -r altered; } <"$tmp/altered.txt"
expect_exit 1 "altered reply" -- "$sim" replay "$tmp/altered.pcap" --check
expect_in "names the request" "first mismatch: record $((rec - 1)) (byte" "$out"
expect_in "names the altered record" "expected  record $rec (byte $pos):" "$out"
expect_in "shows the recorded octets" "$altered" "$out"
expect_in "shows the card's octets" "$original" "$out"
expect_rows "altered reply" "$out" "Data_Exchange 100 99 1 0 0" "total 127 126 1 22 22"
expect_in "result" "result: DIFFERENT: 1 of 127 replies differ" "$out"

# ---- parameter services named (movidrive_names.h) --------------------------------------------
# --verbose names every MOVILINK service of the cyclic channel and of data set 47 below its
# telegram, requests and answers alike; so does the first mismatch of a check report.
expect_exit 0 "param_channel.pcap --verbose" -- "$sim" replay "$golden/param_channel.pcap" --verbose
expect_in "channel write named" "                       write P100 setpoint source (8461) = 3 (FIELDBUS)" "$out"
expect_in "channel read answered in its unit" "                       read P000 speed (8318) = 39.000 rpm" "$out"
expect_in "refused write" "                       write volatile P302 maximum speed 1 (8517) refused" "$out"
expect_in "IPOS variable" "                       write volatile H0 (11000) = 0" "$out"
expect_exit 0 "dpv1.pcapng --verbose" -- "$sim" replay "$golden/dpv1.pcapng" --verbose
expect_in "data set 47 request named" "                       read P076 firmware basic unit (8300)" "$out"
expect_in "data set 47 answer named after its request" "                       read P160 internal setpoint n11 (8489) = 150.000 rpm" "$out"
expect_in "data set 47 change" "                       write P160 internal setpoint n11 (8489) = 2.000 rpm" "$out"
python3 "$here/alter_answers.py" "$golden/param_channel.pcap" "$tmp/altered_pc.pcap" >/dev/null
expect_exit 1 "altered param_channel reply" -- "$sim" replay "$tmp/altered_pc.pcap" --check
expect_in "mismatch request named" $'handshake 0, read index 8318 data 0x00000000; PO 0006 05DC 0000\n            read P000 speed (8318)\n  expected' "$out"
expect_in "mismatch answer named" $'PI 0407 0143 02C4\n            read P000 speed (8318) = 39.000 rpm\n  card' "$out"
expect_in "context named" $'PI 0407 0116 02C3\n                     read P000 speed (8318) = 39.000 rpm' "$out"

# ---- addresses -----------------------------------------------------------------------------
expect_exit 2 "two slaves, no --address" -- "$sim" replay "$golden/multimaster.pcap" --check
expect_in "lists both" "2 slaves answer in" "$out"
expect_in "lists 4" "4 (" "$out"
expect_in "lists 5" "5 (" "$out"
expect_in "asks for --address" "--address N" "$out"
# Address 14 is where master 3 looks for new stations: nobody answers there in the capture, the
# emulated card does.
expect_exit 1 "--address 14" -- "$sim" replay "$golden/multimaster.pcap" --check --address 14
expect_rows "--address 14" "$out" "FDL_Status 9 0 9 9 0" "total 9 0 9 9 0"
expect_in "the card answered" "the capture shows no answer to this request, the card answered" "$out"
expect_exit 1 "--address 9: nothing addressed to it" -- "$sim" replay "$golden/startup.pcap" --check --address 9
expect_in "nothing checked" "result: NOTHING CHECKED: no request to station 9 in the capture" "$out"
printf '\xd4\xc3\xb2\xa1\x02\x00\x04\x00\0\0\0\0\0\0\0\0\xff\xff\0\0\x01\x01\0\0' >"$tmp/empty.pcap"
expect_exit 2 "no slave answers" -- "$sim" replay "$tmp/empty.pcap" --check
expect_in "says why" "no slave answers in" "$out"

# ---- damaged files -------------------------------------------------------------------------
size=$(stat -c %s "$golden/startup.pcap")
head -c $((size - 10)) "$golden/startup.pcap" >"$tmp/truncated.pcap"
expect_exit 1 "truncated record" -- "$sim" replay "$tmp/truncated.pcap" --check
expect_in "position of the truncated record" "file error: $tmp/truncated.pcap: record 42 at byte" "$out"
expect_in "truncated: incomplete" "result: INCOMPLETE" "$out"
python3 -c 'import random; random.seed(5); open("'"$tmp"'/garbage.pcap","wb").write(bytes(random.randrange(256) for _ in range(300)))'
expect_exit 2 "garbage file" -- "$sim" replay "$tmp/garbage.pcap" --check
expect_in "garbage named" "garbage.pcap" "$out"
python3 - "$golden/startup.pcap" "$tmp/linktype.pcap" <<'PY'
import sys
d = bytearray(open(sys.argv[1], 'rb').read()); d[20:24] = (1).to_bytes(4, 'little')
open(sys.argv[2], 'wb').write(d)
PY
expect_exit 2 "unknown link type" -- "$sim" replay "$tmp/linktype.pcap" --check --address 4
expect_in "link type named" "link type 1" "$out"
# A garbage record in the first pause of at least 1 ms after record 30 (300 us into it):
# replayed as it was on the wire, listed with its position, and the card's answers still match.
python3 - "$golden/startup.pcap" "$tmp/between.pcap" >"$tmp/between.txt" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
recs, o = [], 24
while o < len(d):
    s, us, incl, orig = struct.unpack_from('<IIII', d, o)
    recs.append((s * 1000000 + us, d[o:o + 16 + incl]))
    o += 16 + incl
out, done = bytearray(d[:24]), False
for i, (t, raw) in enumerate(recs):
    out += raw
    if not done and i + 1 >= 30 and i + 1 < len(recs) and recs[i + 1][0] - t >= 1000:
        print(i + 2, len(out))
        junk, tj = bytes([0x00, 0xFF, 0x42]), t + 300
        out += struct.pack('<IIII', tj // 1000000, tj % 1000000, len(junk), len(junk)) + junk
        done = True
open(sys.argv[2], 'wb').write(out)
PY
read -r junk_rec junk_pos <"$tmp/between.txt"
expect_exit 0 "garbage between telegrams" -- "$sim" replay "$tmp/between.pcap" --check
expect_in "damaged record listed" "record $junk_rec (byte $junk_pos):" "$out"
expect_in "damaged count" "damaged records: 1" "$out"
expect_exit 2 "missing file" -- "$sim" replay "$tmp/none.pcap" --check --address 4
expect_in "missing file named" "none.pcap" "$out"

# ---- --speed real --------------------------------------------------------------------------
# Never faster than the capture: a lower bound only (a loaded machine may take longer).
t0=$(date +%s%N)
expect_exit 0 "--speed real" -- "$sim" replay "$golden/startup.pcap" --check --speed real
t1=$(date +%s%N)
span_ms=$(sed -n 's/.* records, \([0-9.]*\) s of bus time/\1/p' <<<"$out" | awk '{printf "%d", $1 * 1000}')
took_ms=$(( (t1 - t0) / 1000000 ))
if [ -n "$span_ms" ] && [ "$span_ms" -gt 50 ] && [ "$took_ms" -ge "$span_ms" ]; then ok
else bad "--speed real took $took_ms ms for $span_ms ms of capture"; fi

# SIGINT during an hour-long pause of a --speed real replay: it stops at once, reports what was
# replayed, exit 1.
python3 - "$golden/startup.pcap" "$tmp/pause.pcap" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
out, o, n = bytearray(d[:24]), 24, 0
while o < len(d):
    s, us, incl, orig = struct.unpack_from('<IIII', d, o)
    n += 1
    out += struct.pack('<IIII', s + (3600 if n > 30 else 0), us, incl, orig) + d[o + 16:o + 16 + incl]
    o += 16 + incl
open(sys.argv[2], 'wb').write(out)
PY
# Starts a replay (output to $1), interrupts it after 1 s; it must end within 5 s with exit 1.
interrupt_replay() {
  local out=$1 what=$2; shift 2
  "$sim" replay "$@" >"$out" 2>&1 &
  local pid=$!
  sleep 1
  kill -INT $pid
  for _ in $(seq 50); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done
  if kill -0 $pid 2>/dev/null; then bad "SIGINT did not stop $what"; kill -9 $pid; fi
  wait $pid; local rc=$?
  [ $rc = 1 ] && ok || bad "$what interrupted: exit $rc"
}
interrupt_replay "$tmp/pause.out" "--speed real" "$tmp/pause.pcap" --check --speed real
expect_in "interrupted reported" "interrupted after" "$(cat "$tmp/pause.out")"

# ---- times going back, long gaps -------------------------------------------------------------
# pcap_edit SRC DST PYTHON-EXPR: every record's time (us) replaced by EXPR of n (1-based) and t.
pcap_edit() {
  python3 - "$1" "$2" "$3" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
recs, o = [], 24
while o < len(d):
    s, us, incl, orig = struct.unpack_from('<IIII', d, o)
    recs.append([s * 1000000 + us, d[o + 8:o + 16 + incl]])
    o += 16 + incl
times = [r[0] for r in recs]
out = bytearray(d[:24])
for n, (t, rest) in enumerate(recs, 1):
    t = eval(sys.argv[3], {'n': n, 't': t, 'times': times})
    out += struct.pack('<II', t // 1000000, t % 1000000) + rest
open(sys.argv[2], 'wb').write(out)
PY
}
# A text capture over midnight: the second record is a day "earlier". Its time was taken as
# 2^64 ns after the first and the replay ran for ~584 years of bus time.
printf '23:59:59.999 10 04 02 49 4F 16\n00:00:00.001 10 04 02 49 4F 16\n' >"$tmp/midnight.txt"
expect_exit 0 "time going back a day" -- timeout -k 2 20 "$sim" replay "$tmp/midnight.txt" --address 4 --baud 1.5M
expect_in "re-anchored at the step" "1 records stamped earlier than the record before (first: record 2 (line 2); at most 86399.998000 s back): 1 clock steps, re-anchored" "$out"
expect_in "no bus time lost" "2 records, 0.000066 s of bus time" "$out"
# A pcap whose record 2 is 1 us before record 1.
pcap_edit "$golden/startup.pcap" "$tmp/back1us.pcap" "times[0] - 1 if n == 2 else t"
expect_exit 0 "record 2 1 us before record 1" -- timeout -k 2 20 "$sim" replay "$tmp/back1us.pcap" --address 4 --baud 1.5M
expect_in "1 us back" "(first: record 2 (byte 46); at most 0.000001 s back)" "$out"
# One record 3 ms before the one before it: the first pass inferred 12 Mbit/s from that pair
# (DIFFERENT 22 of 127), and the replay packed it. Now the pair is left out and the capture
# replays clean.
pcap_edit "$golden/data_exchange.pcap" "$tmp/back3ms.pcap" "times[39] - 3000 if n == 41 else t"
expect_exit 0 "one record 3 ms back" -- "$sim" replay "$tmp/back3ms.pcap" --check
expect_in "rate still 1.5M" "1.5 Mbit/s (the capture records no rate; the lowest rate its timing allows: record 28 begins 206.0 us after record 27, which needs 308 bit times in that gap; 1 records earlier than the one before left out" "$out"
expect_in "one record 3 ms back: match" "result: MATCH: all 127 replies match" "$out"
# A clock stepping back 150 ms in the middle (records 301 on): every later record was late and
# packed behind the one before (DIFFERENT 48 of 227). Re-anchored at the step, the cycle kept.
pcap_edit "$golden/param_channel.pcap" "$tmp/step.pcap" "t - 150000 if n >= 301 else t"
expect_exit 0 "clock step back" -- "$sim" replay "$tmp/step.pcap" --check --baud 1.5M
expect_in "clock step named" "(first: record 301 (byte 11230); at most 0.148000 s back): 1 clock steps, re-anchored" "$out"
expect_in "clock step: match" "result: MATCH: all 227 replies match" "$out"
# A 30-day pause: the card woke at every step of its baud search through it (4.5 s). Shortened
# by whole search cycles once the card has settled; the figures are bus time.
printf '0.0 10 04 02 49 4F 16\n2592000.0 10 04 02 49 4F 16\n' >"$tmp/month.txt"
expect_exit 0 "30-day gap" -- timeout -k 2 20 "$sim" replay "$tmp/month.txt" --address 4 --baud 1.5M
expect_in "30 days: bus time" "2 records, 1301.146968 s of bus time" "$out"
expect_in "30 days: shortened" "1 idle gaps shortened, by 2590698.853032 s of bus time in all (first: before record 2 (line 2)): after at least 1300.5 s" "$out"
# 285 years, and a pcap whose first record is at the epoch and the rest in 2024: the first ran
# for hours, the second for most of an hour.
printf '0.0 10 04 02 49 4F 16\n9000000000.0 10 04 02 49 4F 16\n' >"$tmp/centuries.txt"
expect_exit 0 "285-year gap" -- timeout -k 2 20 "$sim" replay "$tmp/centuries.txt" --address 4 --baud 1.5M
expect_in "285 years: shortened" "1 idle gaps shortened, by 8999998699.289307 s" "$out"
pcap_edit "$golden/startup.pcap" "$tmp/epoch.pcap" "0 if n == 1 else t"
expect_exit 1 "record 1 at the epoch" -- timeout -k 2 20 "$sim" replay "$tmp/epoch.pcap" --check --address 4 --baud 1.5M
expect_in "epoch: shortened" "1 idle gaps shortened, by " "$out"
expect_in "epoch: the rest replayed" "records   32 put on the bus" "$out"
# The same 30 days inside data exchange: the card's watchdog expires, the drive stops, the
# card loses the rate and searches when the master comes back. The counts are those of
# replaying the whole gap (12 s before the gaps were shortened).
pcap_edit "$golden/param_channel.pcap" "$tmp/pause30d.pcap" "t + 2592000000000 if n >= 151 else t"
expect_exit 1 "30 days in data exchange" -- timeout -k 2 20 "$sim" replay "$tmp/pause30d.pcap" --check --address 4 --baud 1.5M
expect_rows "30 days in data exchange" "$out" "Data_Exchange 200 59 141 0 141" "total 227 86 141 22 163"
expect_in "30 days in data exchange: shortened" "1 idle gaps shortened, by 2590698.853032 s" "$out"
# Without a watchdog the drive turns through a gap: its position changes, nothing is cut. And
# SIGINT there ends the run at once (the bus ran a whole gap before looking at it).
python3 - "$golden/param_channel.pcap" "$tmp/nowd.pcap" <<'PY'
import struct, sys
d = bytearray(open(sys.argv[1], 'rb').read())
out, o, n = bytearray(d[:24]), 24, 0
while o < len(d):
    s, us, incl, orig = struct.unpack_from('<IIII', d, o)
    n += 1
    f = bytearray(d[o + 16:o + 16 + incl])
    if len(f) > 10 and f[0] == 0x68 and f[4] & 0x7F == 4 and f[7] == 0x3D:
        f[9] &= 0xF7                             # Set_Prm: WD_On off
        f[-2] = sum(f[4:-2]) & 0xFF
    if n >= 301:
        s += 10800                               # three hours
    out += struct.pack('<IIII', s, us, incl, orig) + f
    o += 16 + incl
open(sys.argv[2], 'wb').write(out)
PY
expect_exit 1 "drive turning through 3 h" -- timeout -k 2 20 "$sim" replay "$tmp/nowd.pcap" --check
expect_in "not shortened" "1 idle gaps longer than 1300.5 s simulated whole: the emulated drive was still turning" "$out"
expect_rows "drive turning through 3 h" "$out" "Data_Exchange 200 134 66 0 66"
pcap_edit "$tmp/nowd.pcap" "$tmp/nowd80y.pcap" "t + 2500000000000000 if n >= 301 else t"
interrupt_replay "$tmp/nowd80y.out" "a replay inside a long gap" "$tmp/nowd80y.pcap" --check
expect_in "interrupted in a gap" "interrupted after 300 records" "$(cat "$tmp/nowd80y.out")"

# ---- pipes and rates -----------------------------------------------------------------------
# A pipe cannot be read twice: the first pass (address, rate) would leave nothing to replay.
"$sim" convert "$golden/startup.pcap" "$tmp/startup.txt" >/dev/null
out=$(cat "$tmp/startup.txt" | "$sim" replay /dev/stdin --format text --check 2>&1); rc=$?
[ $rc = 2 ] && ok || bad "pipe without --address/--baud: exit $rc: $out"
expect_in "pipe: says what to do" "replay: /dev/stdin is not a regular file (a pipe?) and can be read only once: give --address and --baud" "$out"
out=$(cat "$tmp/startup.txt" | "$sim" replay /dev/stdin --format text --check --address 4 --baud 1.5M 2>&1); rc=$?
[ $rc = 0 ] && ok || bad "pipe with --address and --baud: exit $rc: $out"
expect_in "pipe replayed" "result: MATCH: all 32 replies match" "$out"
# --baud overrides the rate a pcapng records (if_speed): the card then finds 12 Mbit/s at once.
expect_exit 1 "--baud over a recorded rate" -- "$sim" replay "$golden/dpv1.pcapng" --check --baud 12M
expect_in "override named" "12 Mbit/s (given with --baud; it overrides the capture's own rate, 1.5 Mbit/s, for every record)" "$out"
expect_rows "--baud 12M over 1.5M" "$out" "FDL_Status 23 1 22 22 0"
expect_exit 0 "--baud equal to the recorded rate" -- "$sim" replay "$golden/dpv1.pcapng" --check --baud 1.5M
expect_in "equal rate named" "1.5 Mbit/s (given with --baud, the rate the capture records too)" "$out"

# ---- the goldens made again now ------------------------------------------------------------
# Same telegrams at the same times, or the first one that changed is named; and what dfp-sim
# records now replays clean.
while read -r name args; do
  # shellcheck disable=SC2086
  if ! "$sim" $args --capture "$tmp/$name" >/dev/null; then bad "making $name failed"; continue; fi
  if d=$("$diff_tool" "$golden/$name" "$tmp/$name"); then ok
  else bad "$name made now differs from the committed golden (make it again: golden/README.md):"$'\n'"$d"; fi
  o=""; [ "$name" = multimaster.pcap ] && o="--address 4"
  # shellcheck disable=SC2086
  expect_exit 0 "$name made now replays clean" -- "$sim" replay "$tmp/$name" --check $o
done < <(golden_recipes)

# ---- record: a larger run in other formats --------------------------------------------------
expect_exit 0 "record everything at 12M" -- "$sim" record --capture "$tmp/all.pcapng" --cycles 400 \
  --baud 12M --dpv1 --faults --foreign --address 9
expect_in "record summary" "400 Data_Exchange cycles of the card at address 9" "$out"
expect_exit 0 "replay it" -- "$sim" replay "$tmp/all.pcapng" --check --address 9
expect_in "rate from pcapng" "12 Mbit/s (recorded in the capture)" "$out"
expect_in "all match" "result: MATCH" "$out"
expect_exit 0 "record with nanosecond pcap" -- "$sim" record --capture "$tmp/ns.pcap" --cycles 50 --capture-ns --baud 12M
expect_exit 0 "replay ns, rate from the timing" -- "$sim" replay "$tmp/ns.pcap" --check
expect_in "12M from the timing" "12 Mbit/s (the capture records no rate; the lowest rate its timing allows" "$out"
expect_in "ns pcap matches" "result: MATCH" "$out"
# Over a PTY the timing is not a line's: taken as a line's (--timing line), the lowest rate it
# allows is 500 kbit/s, and a card already on the line (--fixed-baud) answers as recorded.
expect_exit 0 "PTY capture as a line's, inferred rate, --fixed-baud" -- "$sim" replay "$golden/dpv1_pty_movilink.pcap" --check --fixed-baud --timing line
expect_in "500k inferred" "500 kbit/s (the capture records no rate; the lowest rate its timing allows" "$out"
expect_in "line timing as given" "  timing    line (given with --timing)" "$out"
# Without flags the PTY goldens are recognised: relaxed timing, 12 Mbit/s, the card at its rate.
for g in dpv1_pty_movilink dpv1_pty_c2; do
  expect_exit 0 "$g.pcap without flags" -- "$sim" replay "$golden/$g.pcap" --check
  expect_in "$g: relaxed inferred" "  timing    relaxed (inferred: a tty/PTY capture: " "$out"
  expect_in "$g: 12 Mbit/s" "  bus       12 Mbit/s (relaxed timing: every record at its recorded time on the fastest rate" "$out"
  expect_in "$g: match" "result: MATCH" "$out"
done
# A line capture that begins in the middle of operation (its first request answered): the card
# had its rate before, so it starts at the bus rate instead of searching (data_exchange.pcap
# without its first 22 unanswered polls and the answered poll after them).
python3 - "$golden/data_exchange.pcap" "$tmp/mid.pcap" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
out, o, n = bytearray(d[:24]), 24, 0
while o < len(d):
    incl = struct.unpack_from('<I', d, o + 8)[0]
    n += 1
    if n > 22:
        out += d[o:o + 16 + incl]
    o += 16 + incl
open(sys.argv[2], 'wb').write(out)
PY
expect_exit 0 "capture from the middle" -- "$sim" replay "$tmp/mid.pcap" --check
expect_in "fixed inferred" "fixed at the bus rate (inferred: the capture's first request to it, record 1, is answered: the card had its rate before the capture began)" "$out"
expect_in "still a line" "1.5 Mbit/s (the capture records no rate; the lowest rate its timing allows" "$out"
expect_rows "capture from the middle" "$out" "total 105 105 0 0 0"

# ---- bad command lines: exit 2, one line on stderr, nothing on stdout -----------------------
usage_error() { # DESCRIPTION args...
  local what=$1; shift
  "$sim" "$@" >"$tmp/o" 2>"$tmp/e"; local rc=$?
  if [ $rc = 2 ] && [ ! -s "$tmp/o" ] && [ "$(wc -l <"$tmp/e")" = 1 ]; then ok
  else bad "$what: exit $rc, stdout '$(cat "$tmp/o")', stderr '$(cat "$tmp/e")'"; fi
}
usage_error "replay without a file" replay
usage_error "replay two files" replay a.pcap b.pcap
usage_error "replay unknown option" replay "$golden/startup.pcap" --fast
usage_error "replay --speed" replay "$golden/startup.pcap" --speed quick
usage_error "replay --format" replay "$golden/startup.pcap" --format csv
usage_error "replay --baud" replay "$golden/startup.pcap" --baud 123
usage_error "replay --address 126" replay "$golden/startup.pcap" --address 126
usage_error "replay --address without value" replay "$golden/startup.pcap" --address
usage_error "replay --inverter" replay "$golden/startup.pcap" --inverter can:vcan0
usage_error "replay --inverter-delay with none" replay "$golden/startup.pcap" --inverter none --inverter-delay 5
usage_error "record without --cycles" record --capture "$tmp/x.pcap"
usage_error "record without --capture" record --cycles 5
usage_error "record --cycles 0" record --capture "$tmp/x.pcap" --cycles 0
usage_error "record --foreign at 120" record --capture "$tmp/x.pcap" --cycles 5 --foreign --address 120
usage_error "record unknown option" record --capture "$tmp/x.pcap" --cycles 5 --fast
usage_error "record --capture-format" record --capture "$tmp/x.pcap" --cycles 5 --capture-format csv

finish
