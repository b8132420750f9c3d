#!/usr/bin/env bash
# The monitor's pcapng files in tshark: the writer's sample (test_pcapng_writer DIR sample) with
# link type 147 is decoded by the project's dissector (tools/wireshark/profibus.lua), the garbled
# records carry their comment, times are the written ns; with link type 257 (what the monitor
# writes: Wireshark has no dissector for it) tshark still reads every record and comment.
# Usage: test_pcapng_tshark.sh TEST_PCAPNG_WRITER TSHARK PROFIBUS_LUA
writer=$1 tshark=$2 lua=$3
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../cli/lib.sh"
with_tmp
mkdir -p "$tmp/home"
tab=$'\t'

"$writer" "$tmp" sample >/dev/null 2>"$tmp/writer.err"
if [ $? = 0 ]; then ok; else bad "writing the sample: $(cat "$tmp/writer.err")"; fi

# ts OUT ARGS...: tshark with the dissector, isolated from the user's plugins and preferences.
# Anything on stderr but the warning about running as root fails the check.
ts() {
  local out=$1; shift
  HOME="$tmp/home" XDG_CONFIG_HOME="$tmp/home/.config" "$tshark" -X "lua_script:$lua" "$@" \
    >"$out" 2>"$tmp/ts.err"
  local rc=$?
  local noise
  noise=$(grep -v '^Running as user "root"' "$tmp/ts.err")
  if [ "$rc" = 0 ] && [ -z "$noise" ]; then ok; else bad "tshark $*: exit $rc, stderr: $noise"; fi
}
eq() { if [ "$2" = "$3" ]; then ok; else bad "$1: got '$2', want '$3'"; fi; }

ts "$tmp/147.out" -r "$tmp/sample147.pcapng" -T fields -E separator=/t -e frame.comment \
  -e frame.time_epoch -e frame.len -e frame.cap_len -e profibus.sd -e profibus.da \
  -e profibus.sa -e profibus.fcs_ok -e profibus.malformed
eq "147: records" "$(wc -l <"$tmp/147.out" | tr -d ' ')" 6
eq "147: token" "$(sed -n 1p "$tmp/147.out")" \
  "${tab}1700000000.000000001${tab}3${tab}3${tab}0xdc${tab}2${tab}1${tab}${tab}"
eq "147: FDL status request" "$(sed -n 2p "$tmp/147.out")" \
  "${tab}1700000000.123456789${tab}6${tab}6${tab}0x10${tab}4${tab}2${tab}1${tab}"
eq "147: SC" "$(sed -n 3p "$tmp/147.out" | cut -f1-5)" \
  "${tab}1700000000.123499999${tab}1${tab}1${tab}0xe5"
eq "147: garbled, cut SD2" "$(sed -n 4p "$tmp/147.out" | cut -f1-5,9)" \
  "garbled${tab}1700000002.000000001${tab}5${tab}5${tab}0x68${tab}1"
eq "147: SD2 request" "$(sed -n 5p "$tmp/147.out")" \
  "${tab}1700000002.000000500${tab}11${tab}11${tab}0x68${tab}4${tab}2${tab}1${tab}"
eq "147: garbled long run, 1024 of 1500 kept" "$(sed -n 6p "$tmp/147.out" | cut -f1-4)" \
  "garbled${tab}1700000003.000000000${tab}1500${tab}1024"

# The section and interface as written (capinfos comes with tshark): application, link type,
# name, description, speed, ns resolution.
capinfos=$(dirname "$tshark")/capinfos
"$capinfos" "$tmp/sample147.pcapng" >"$tmp/cap.out" 2>&1
keys='Capture application\|Name\|Description\|Encapsulation\|Speed\|Time precision'
info=$(sed -n "s/^ *\\($keys\\) *[:=] *//p" "$tmp/cap.out" | tr '\n' '|')
eq "capinfos" "$info" \
  "dfp-sim|/dev/ttyUSB0|dfp-sim monitor, 1.5 Mbit/s|USER 0 (45 - user0)|1500000|nanoseconds (9)|"

ts "$tmp/if.out" -r "$tmp/sample257.pcapng" -T fields -E separator=/t -e frame.comment \
  -e frame.len -e frame.time_epoch
want="${tab}3${tab}1700000000.000000001|${tab}6${tab}1700000000.123456789|"
want+="${tab}1${tab}1700000000.123499999|garbled${tab}5${tab}1700000002.000000001|"
want+="${tab}11${tab}1700000002.000000500|garbled${tab}1500${tab}1700000003.000000000|"
eq "257: records, comments and times" "$(tr '\n' '|' <"$tmp/if.out")" "$want"
finish
