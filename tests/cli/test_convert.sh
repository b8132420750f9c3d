#!/usr/bin/env bash
# dfp-sim convert and the capture options of the commands: every format and link type round-
# trips the demo's telegrams exactly; the output never replaces its input; records without a
# time stay untimed in text and are refused for pcap/pcapng (no invented timing); damaged input
# is reported with positions; bad command lines exit 2.
sim=$1
. "$(dirname "$0")/lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp" || exit 1

expect_exit 0 "demo with a pcapng capture for Wireshark" -- "$sim" demo --capture d.pcapng \
  --capture-linktype user0 --capture-ns
expect_in "the demo names the capture" "written to d.pcapng (pcapng, link type 147)" "$out"
expect_exit 0 "the demo's pcap" -- "$sim" demo --capture d.pcap
# Link type 147 at offset 20 of the pcap header after converting.
expect_exit 0 "pcapng to pcap keeps USER0" -- "$sim" convert d.pcapng u.pcap
expect_in "summary" "d.pcapng (pcapng) -> u.pcap (pcap, link type 147, µs): 3880 records" "$out"
if [ "$(od -An -tu4 -j20 -N4 u.pcap | tr -d ' ')" = 147 ]; then ok; else bad "link type not 147"; fi
expect_exit 0 "back to PROFIBUS_DL" -- "$sim" convert u.pcap p.pcap --linktype profibus
# Two conversions give the file one conversion gives (the same demo run: its wall-clock base
# differs between runs).
expect_exit 0 "pcapng straight to PROFIBUS_DL pcap" -- "$sim" convert d.pcapng p1.pcap --linktype profibus
if cmp -s p.pcap p1.pcap; then ok; else bad "records differ after two conversions"; fi
expect_exit 0 "to text" -- "$sim" convert d.pcap d.txt
expect_exit 0 "text back to pcap" -- "$sim" convert d.txt d2.pcap
if cmp -s d.pcap d2.pcap; then ok; else bad "pcap -> text -> pcap is not identical"; fi
lines=$(wc -l <d.txt)
if [ "$lines" = 3880 ]; then ok; else bad "text has $lines lines"; fi
expect_in "export shape" "-- DC 02 02" "$(head -1 d.txt)"
# pcapng written by a tty session carries directions; text shows them.
expect_exit 0 "pcapng to text" -- "$sim" convert d.pcapng dn.txt
if diff <(cut -d' ' -f3- dn.txt) <(cut -d' ' -f3- d.txt) >/dev/null; then ok; else bad "pcapng and pcap octets differ"; fi

# The output never replaces the input, whatever the spelling.
cp d.pcap same.pcap
size=$(stat -c %s same.pcap)
expect_exit 2 "same file by another name" -- "$sim" convert same.pcap ./same.pcap
expect_in "said why" "IN and OUT are the same file" "$out"
if [ "$(stat -c %s same.pcap)" = "$size" ]; then ok; else bad "the input was changed"; fi
ln -s same.pcap link.pcap
expect_exit 2 "same file through a symlink" -- "$sim" convert same.pcap link.pcap

# Untimed text: kept untimed in text, refused for pcap (and no file left behind).
printf '10 04 02 49 4F 16\nE5\n' >untimed.txt
expect_exit 1 "untimed to pcap" -- "$sim" convert untimed.txt untimed.pcap
expect_in "names the record" "record 1 (line 1) has no time; pcap needs one" "$out"
if [ ! -e untimed.pcap ]; then ok; else bad "a half-converted untimed.pcap was left"; fi
expect_exit 0 "untimed to text" -- "$sim" convert untimed.txt untimed2.txt
expect_in "counted" "2 records, 2 without a time (kept untimed)" "$out"
if [ "$(cat untimed2.txt)" = $'10 04 02 49 4F 16\nE5' ]; then ok; else bad "untimed text: $(cat untimed2.txt)"; fi

# Damaged input: a bad line and a bad FCS are reported with their lines, the rest converted.
printf '0.1 10 04 02 49 4F 16\nhello\n0.2 10 04 02 49 4E 16\n' >bad.txt
expect_exit 0 "damaged text converts" -- "$sim" convert bad.txt bad.pcap
expect_in "bad line reported" "record 2 (line 2)" "$out"
expect_in "bad FCS reported" "record 3 (line 3): bad FCS (0x4E, computed 0x4F)" "$out"
expect_in "summary counts" "2 records, 1 without octets left out, 2 damaged" "$out"
head -c 1000 d.pcap >cut.pcap
expect_exit 1 "truncated pcap" -- "$sim" convert cut.pcap cut2.pcap
expect_in "position of the truncation" "record 48 at byte 998: truncated" "$out"
expect_exit 2 "no telegram at all: not a capture" -- "$sim" convert /etc/hostname x.pcap
expect_exit 2 "replay says the same of that file" -- "$sim" replay /etc/hostname --check

# Bad command lines.
expect_exit 2 "no files" -- "$sim" convert
expect_exit 2 "one file" -- "$sim" convert d.pcap
expect_exit 2 "three files" -- "$sim" convert d.pcap a b
expect_exit 2 "bad format" -- "$sim" convert d.pcap x --format lcm
expect_exit 2 "bad link type" -- "$sim" convert d.pcap x --linktype ethernet
expect_exit 2 "missing input" -- "$sim" convert nosuch.pcap x.pcap
expect_exit 2 "unknown option" -- "$sim" convert d.pcap x.pcap --frobnicate
expect_exit 2 "bad --capture-format" -- "$sim" demo --capture x --capture-format lcm
expect_exit 2 "bad --capture-linktype" -- "$sim" demo --capture x --capture-linktype 1
expect_exit 1 "unwritable capture" -- "$sim" demo --capture /nonexistent/x.pcap
finish
