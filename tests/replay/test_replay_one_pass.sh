#!/usr/bin/env bash
# dfp-sim replay --speed max reads a regular file once: the first pass goes along with the
# replay, which starts from what the first 4096 records say and is replayed again when the
# whole file says otherwise. --verbose always takes the two passes (a second replay would print
# the trace twice), so the two ways are compared by their --report json files and their text
# reports, which must be the same octets: on every golden capture, on one with a reply altered,
# on a capture longer than the guess, and on one whose first 4096 records do not show the
# card's first request (the guess is wrong and the replay runs again). A replay held to one CPU
# (no reading thread) gives the same reports as one on two.
sim=$1
here=$(dirname "$0")
golden=$here/golden
. "$here/../cli/lib.sh"
with_tmp

# same_both DESCRIPTION FILE ARG...: exit status, text report and JSON report of one pass
# equal to those of two passes.
same_both() {
  local what=$1 file=$2; shift 2
  "$sim" replay "$file" "$@" --report json "$tmp/one.json" >"$tmp/one.txt" 2>&1
  local one=$?
  "$sim" replay "$file" "$@" --verbose --report json "$tmp/two.json" >"$tmp/two.all" 2>&1
  local two=$?
  # The text report begins at "replay of"; the trace before it is --verbose's.
  sed -n '/^replay of /,$p' "$tmp/two.all" >"$tmp/two.txt"
  if [ "$one" = "$two" ]; then ok; else bad "$what: exit $one in one pass, $two in two"; fi
  if cmp -s "$tmp/one.json" "$tmp/two.json"; then ok; else
    bad "$what: JSON reports differ:"$'\n'"$(diff "$tmp/one.json" "$tmp/two.json" | head -20)"
  fi
  if cmp -s "$tmp/one.txt" "$tmp/two.txt"; then ok; else
    bad "$what: text reports differ:"$'\n'"$(diff "$tmp/one.txt" "$tmp/two.txt" | head -20)"
  fi
}

for f in startup.pcap data_exchange.pcap param_channel.pcap dpv1.pcapng faults.pcap demo.pcap \
         dpv1_pty_c2.pcap dpv1_pty_movilink.pcap; do
  same_both "$f" "$golden/$f" --check
done
same_both "multimaster.pcap --address 4" "$golden/multimaster.pcap" --check --address 4
same_both "multimaster.pcap --address 5" "$golden/multimaster.pcap" --check --address 5 \
  --inverter none

# A mismatch: the 60th Data_Exchange answer with PI1's low octet + 1 (FCS fixed).
python3 "$here/alter_answers.py" "$golden/data_exchange.pcap" "$tmp/altered.pcap" >/dev/null
same_both "altered reply" "$tmp/altered.pcap" --check
expect_exit 1 "altered reply differs" -- "$sim" replay "$tmp/altered.pcap" --check
expect_in "altered reply result" "result: DIFFERENT: 1 of 127 replies differ" "$out"

# Longer than the guess: 6 000 telegrams, the guess holds.
"$sim" record --capture "$tmp/long.pcap" --cycles 3000 >/dev/null
same_both "6000 telegrams" "$tmp/long.pcap" --check
same_both "6000 telegrams, address and rate given" "$tmp/long.pcap" --check --address 4 --baud 1.5M

# The guess wrong: 5 000 FDL status requests to station 9 (nobody answers), then the card's
# traffic from its first request with SAPs on (the FDL status polls of its rate search left
# out, so its first request is answered). The first 4096 records
# show no request to the card, so the card is guessed to search its rate; the whole file says
# it had its rate (fixed), and the replay runs again with that.
python3 - "$tmp/long.pcap" "$tmp/late.pcap" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
head, o, recs = d[:24], 24, []
while o < len(d):
    sec, frac, incl, orig = struct.unpack_from('<IIII', d, o)
    recs.append([sec, frac, d[o + 16:o + 16 + incl]])
    o += 16 + incl
nano = struct.unpack_from('<I', d, 0)[0] == 0xA1B23C4D
unit = 1 if nano else 1000
def ns(r): return r[0] * 10**9 + r[1] * unit
# From the first SD2 request to station 4 with SAPs (DA 0x84) on.
start = next(i for i, r in enumerate(recs) if r[2][0] == 0x68 and r[2][4] == 0x84)
out = bytearray(head)
t0 = ns(recs[0])
for k in range(5000):
    t = t0 + k * 1000000
    f = bytes([0x10, 0x09, 0x02, 0x49, (0x09 + 0x02 + 0x49) & 0xFF, 0x16])
    out += struct.pack('<IIII', t // 10**9, (t % 10**9) // unit, len(f), len(f)) + f
shift = t0 + 5000 * 1000000 - ns(recs[start])
for r in recs[start:]:
    t = ns(r) + shift
    out += struct.pack('<IIII', t // 10**9, (t % 10**9) // unit, len(r[2]), len(r[2])) + r[2]
open(sys.argv[2], 'wb').write(out)
PY
same_both "first request to the card after record 4096" "$tmp/late.pcap" --check --address 4 \
  --baud 1.5M
expect_exit 0 "late first request" -- "$sim" replay "$tmp/late.pcap" --check --address 4 --baud 1.5M
expect_in "the whole file decides" "fixed at the bus rate (inferred: the capture's first request to it, record 5001, is answered" "$out"

# Held to one CPU, the replay reads the file in its own thread, not in a second one: the same
# exit status and the same reports, also for a mismatch and a file cut inside a record (the
# records before the cut are replayed, the error names the record).
head -c $(( $(stat -c %s "$tmp/long.pcap") - 7 )) "$tmp/long.pcap" >"$tmp/cut.pcap"
for f in long.pcap altered.pcap cut.pcap; do
  "$sim" replay "$tmp/$f" --check --report json "$tmp/two_cpus.json" >"$tmp/two_cpus.txt" 2>&1
  two=$?
  taskset -c 0 "$sim" replay "$tmp/$f" --check --report json "$tmp/one_cpu.json" \
    >"$tmp/one_cpu.txt" 2>&1
  one=$?
  if [ "$one" = "$two" ]; then ok; else bad "$f: exit $one on one CPU, $two on two"; fi
  if cmp -s "$tmp/one_cpu.json" "$tmp/two_cpus.json" && cmp -s "$tmp/one_cpu.txt" "$tmp/two_cpus.txt"
  then ok; else
    bad "$f: reports differ on one CPU:"$'\n'"$(diff "$tmp/one_cpu.txt" "$tmp/two_cpus.txt" | head -20)"
  fi
done
expect_in "the cut file's error" "truncated record: 16 of 23 octets" "$(cat "$tmp/one_cpu.txt")"
expect_in "the cut file's records before the cut" "result: INCOMPLETE" "$(cat "$tmp/one_cpu.txt")"
finish
