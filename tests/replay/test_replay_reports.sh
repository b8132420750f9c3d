#!/usr/bin/env bash
# dfp-sim replay --check for CI: every mismatch listed up to --max-mismatches, the report files
# (--report json / junit FILE, parsed with Python's json and xml.etree: verdict, counts per
# service, what was inferred, a known mismatch's octets), --ignore masks (process input words,
# octet ranges per service, the masked count) and their usage errors.
sim=$1
here=$(dirname "$0")
golden=$here/golden
. "$here/../cli/lib.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# py_checks DESCRIPTION SCRIPT ARGS...: a Python script of checks printing "FAIL: ..." per failed
# check and "PASSED n" at the end; both count here.
py_checks() {
  local what=$1 script=$2; shift 2
  local res; res=$(python3 -c "$script" "$@" 2>&1)
  local n; n=$(sed -n 's/^PASSED \([0-9]*\)$/\1/p' <<<"$res")
  if [ -z "$n" ]; then bad "$what: the checks did not run: $res"; return; fi
  passed=$((passed + n))
  while IFS= read -r line; do
    [[ $line == FAIL:* ]] && bad "$what: ${line#FAIL: }"
  done <<<"$res"
}
PY_HEAD='
import json, sys, xml.etree.ElementTree as ET
passed = 0
def check(cond, what):
    global passed
    if cond: passed += 1
    else: print("FAIL: " + what)
def eq(got, want, what):
    check(got == want, "%s: got %r, expected %r" % (what, got, want))
'

# ---- 15 answers altered ------------------------------------------------------------------------
# PI1's low octet + 1 in the card's Data_Exchange answers 60..74 of data_exchange.pcap, FCS fixed:
# 15 mismatches. The first one's record, position and octets (recorded, and the card's = the
# original) are printed for the checks.
python3 "$here/alter_answers.py" "$golden/data_exchange.pcap" "$tmp/alt.pcap" 60 15 >"$tmp/alt.txt"
{ read -r rec; read -r pos; read -r original; read -r altered; } <"$tmp/alt.txt"

# The text report lists 10 by default, then says how many more.
expect_exit 1 "15 altered answers" -- "$sim" replay "$tmp/alt.pcap" --check
expect_in "count" "mismatches: 15" "$out"
n=$(grep -c '^  #' <<<"$out")
[ "$n" = 10 ] && ok || bad "default list: $n mismatches listed, expected 10"
expect_in "the rest counted" "  ... and 5 more (--max-mismatches 0 lists all)" "$out"
expect_in "the first listed" "  #1   record $((rec - 1)) (byte " "$out"
expect_in "what differs" "Data_Exchange: octets 16 (data 9), 21 (FCS) differ" "$out"
expect_in "recorded octets" "       expected  $altered" "$out"
expect_in "the card's octets" "       actual    $original" "$out"
expect_in "the tenth listed" "  #10  record " "$out"
expect_exit 1 "--max-mismatches 3" -- "$sim" replay "$tmp/alt.pcap" --check --max-mismatches 3
n=$(grep -c '^  #' <<<"$out")
[ "$n" = 3 ] && ok || bad "--max-mismatches 3: $n listed"
expect_in "12 more" "  ... and 12 more (--max-mismatches 0 lists all)" "$out"
expect_exit 1 "--max-mismatches 0: all" -- "$sim" replay "$tmp/alt.pcap" --check --max-mismatches 0
n=$(grep -c '^  #' <<<"$out")
[ "$n" = 15 ] && ok || bad "--max-mismatches 0: $n listed"
if grep -q "more (--max-mismatches" <<<"$out"; then bad "all listed, yet 'more' said"; else ok; fi

# ---- JSON and JUnit ----------------------------------------------------------------------------
expect_exit 1 "both report files" -- "$sim" replay "$tmp/alt.pcap" --check --max-mismatches 0 \
  --report json "$tmp/r.json" --report junit "$tmp/r.xml"
expect_in "the text report too" "result: DIFFERENT: 15 of 127 replies differ" "$out"
py_checks "JSON report" "$PY_HEAD"'
j = json.load(open(sys.argv[1]))
rec, pos, original, altered = int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
eq(j["verdict"], "DIFFERENT", "verdict"); eq(j["exit_status"], 1, "exit status")
eq(j["checked"], True, "checked"); eq(j["records"], 232, "records")
svc = {s["service"]: s for s in j["services"]}
eq(sorted(svc), ["Chk_Cfg", "Data_Exchange", "FDL_Status", "Set_Prm", "Slave_Diag"], "services")
dx = svc["Data_Exchange"]
eq((dx["key"], dx["requests"], dx["matched"], dx["differ"], dx["missing"], dx["extra"]),
   ("data_exchange", 100, 85, 15, 0, 0), "Data_Exchange counts")
eq((svc["FDL_Status"]["capture_no_answer"], svc["FDL_Status"]["card_no_answer"]), (22, 22),
   "FDL_Status unanswered")
eq((j["total"]["requests"], j["total"]["matched"], j["total"]["differ"]), (127, 112, 15), "total")
inf = j["inferred"]
eq((inf["address"]["value"], inf["address"]["inferred"]), (4, True), "address inferred")
check(inf["address"]["source"].startswith("from the capture: the only slave that answers"),
      "address source: " + inf["address"]["source"])
eq((inf["rate"]["baud"], inf["rate"]["inferred"]), (1500000, True), "rate inferred")
check(inf["rate"]["source"].startswith("the capture records no rate; the lowest rate its timing"),
      "rate source: " + inf["rate"]["source"])
eq((inf["timing"]["mode"], inf["timing"]["inferred"]), ("line", True), "timing")
check("105 of 105 answers of station 4 begin within" in inf["timing"]["source"],
      "timing source: " + inf["timing"]["source"])
eq(inf["fixed_baud"]["value"], False, "the card searches its rate")
eq(inf["inverter_delay"]["us"], 3000, "inverter delay")
m = j["mismatches"]
eq((m["count"], m["listed"], m["not_listed"], m["list_error"]), (15, 15, 0, None), "mismatch counts")
eq([i["number"] for i in m["items"]], list(range(1, 16)), "numbered in order")
f = m["items"][0]
eq((f["record"], f["position_unit"], f["expected_record"]), (rec - 1, "byte", rec), "first: records")
eq((f["service"], f["key"]), ("Data_Exchange", "data_exchange"), "first: service")
eq(f["expected"], altered, "first: the recorded octets")
eq(f["actual"], original, "first: the card octets")
eq(f["differing_octets"], [16, 21], "first: differing octets (PI1 low and the FCS)")
eq((f["data_offset"], f["masked_octets"]), (7, 0), "first: data offset, masked")
check(abs(f["time_s"] - 0.179348) < 1e-9, "first: time %r" % f["time_s"])
eq((j["ignore"], j["masked_octets"], j["damaged_records"], j["file_error"], j["interrupted"]),
   (None, 0, 0, None, False), "no masks, no damage")
print("PASSED %d" % passed)
' "$tmp/r.json" "$rec" "$pos" "$original" "$altered"
py_checks "JUnit report" "$PY_HEAD"'
root = ET.parse(sys.argv[1]).getroot()
original, altered = sys.argv[2], sys.argv[3]
eq(root.tag, "testsuite", "one testsuite as the root")
eq((root.get("tests"), root.get("failures"), root.get("errors")), ("6", "1", "0"), "counts")
cases = {c.get("name"): c for c in root.findall("testcase")}
eq(sorted(cases), ["Chk_Cfg", "Data_Exchange", "FDL_Status", "Set_Prm", "Slave_Diag", "capture"],
   "a testcase per service and the capture")
eq({c.get("classname") for c in cases.values()}, {"replay.alt.pcap"}, "classname")
fail = cases["Data_Exchange"].find("failure")
check(fail is not None, "Data_Exchange failed")
eq(fail.get("message"), "15 of 100 replies differ", "failure message")
check(altered in fail.text and original in fail.text, "failure lists the octets")
eq(fail.text.count("Data_Exchange: octets 16 (data 9), 21 (FCS) differ"), 15, "all 15 listed")
for name in ("capture", "FDL_Status", "Set_Prm", "Chk_Cfg", "Slave_Diag"):
    check(cases[name].find("failure") is None, name + " passed")
props = {p.get("name"): p.get("value") for p in root.find("properties")}
eq(props["verdict"], "DIFFERENT", "verdict property")
check(props["timing"].startswith("line ("), "timing property: " + props["timing"])
print("PASSED %d" % passed)
' "$tmp/r.xml" "$original" "$altered"
# The files hold what the list holds: with the default, 10 items and 5 not listed.
expect_exit 1 "default list in the files" -- "$sim" replay "$tmp/alt.pcap" --check \
  --report json "$tmp/d.json" --report junit "$tmp/d.xml"
py_checks "default list in the files" "$PY_HEAD"'
j = json.load(open(sys.argv[1]))
eq((j["mismatches"]["listed"], j["mismatches"]["not_listed"], len(j["mismatches"]["items"])),
   (10, 5, 10), "JSON list")
fail = ET.parse(sys.argv[2]).getroot().find("testcase[@name=\"Data_Exchange\"]/failure")
check(fail.text.rstrip().endswith("... and 5 more"), "JUnit says the rest: " + fail.text[-40:])
print("PASSED %d" % passed)
' "$tmp/d.json" "$tmp/d.xml"
# A clean golden: no failure at all; a capture with nothing for the card: the capture case fails.
expect_exit 0 "a match" -- "$sim" replay "$golden/startup.pcap" --check --report junit "$tmp/m.xml" \
  --report json "$tmp/m.json"
expect_exit 1 "nothing checked" -- "$sim" replay "$golden/startup.pcap" --check --address 9 \
  --report junit "$tmp/n.xml" --report json "$tmp/n.json"
py_checks "match and nothing checked" "$PY_HEAD"'
m = ET.parse(sys.argv[1]).getroot()
eq((m.get("tests"), m.get("failures")), ("6", "0"), "match: counts")
eq(json.load(open(sys.argv[2]))["verdict"], "MATCH", "match: verdict")
eq(json.load(open(sys.argv[2]))["mismatches"]["items"], [], "match: no items")
n = ET.parse(sys.argv[3]).getroot()
eq((n.get("tests"), n.get("failures")), ("1", "1"), "nothing checked: counts")
eq(n.find("testcase/failure").get("message"),
   "nothing checked: no request to station 9 in the capture", "nothing checked: message")
eq(json.load(open(sys.argv[4]))["verdict"], "NOTHING CHECKED", "nothing checked: verdict")
print("PASSED %d" % passed)
' "$tmp/m.xml" "$tmp/m.json" "$tmp/n.xml" "$tmp/n.json"
# A report file that cannot be written: said, exit 1 even for a match (the text report stands).
expect_exit 1 "unwritable report file" -- "$sim" replay "$golden/startup.pcap" --check \
  --report json "$tmp/no/such/dir/r.json"
expect_in "says which" "dfp-sim: replay: --report json: cannot write $tmp/no/such/dir/r.json: No such file or directory" "$out"
expect_in "the text report still printed" "result: MATCH" "$out"

# ---- masks -------------------------------------------------------------------------------------
# PI1 masked: its 2 octets and the FCS of all 100 Data_Exchange answers are not compared.
expect_exit 0 "--ignore PI1" -- "$sim" replay "$tmp/alt.pcap" --check --ignore PI1
expect_in "PI1: match" "result: MATCH: all 127 replies match" "$out"
expect_in "PI1: masked count" "masked: 300 octets not compared (--ignore PI1)" "$out"
# The same octet by its place in the data unit (8 octets of parameter channel, then PI1 high, low).
expect_exit 0 "--ignore dx:9" -- "$sim" replay "$tmp/alt.pcap" --check --ignore dx:9
expect_in "dx:9: masked count" "masked: 200 octets not compared (--ignore dx:9)" "$out"
expect_exit 0 "--ignore data_exchange:8-9" -- "$sim" replay "$tmp/alt.pcap" --check --ignore "Data_Exchange:8-9"
expect_in "range: masked count" "masked: 300 octets not compared" "$out"
# Another word masked: still different, and each listed mismatch says what was left out.
expect_exit 1 "--ignore PI2" -- "$sim" replay "$tmp/alt.pcap" --check --ignore PI2
expect_rows() {
  local what=$1 text=$2; shift 2
  local table; table=$(tr -s ' ' <<<"$text")
  for row in "$@"; do
    if grep -qxF -- "$row" <<<"$table"; then ok; else bad "$what: no row '$row' in:"$'\n'"$text"; fi
  done
}
expect_rows "--ignore PI2" "$out" "Data_Exchange 100 85 15 0 0"
expect_in "PI2: masked per mismatch" "       masked    3 octets not compared" "$out"
expect_in "PI2: first difference not masked" "first difference at octet 16: expected" "$out"
# Two --ignore and a list: one text; the Slave_Diag answers' first 3 data octets too.
expect_exit 0 "two --ignore" -- "$sim" replay "$tmp/alt.pcap" --check --ignore PI2,PI1 \
  --ignore diag:0-2 --report json "$tmp/mask.json"
expect_in "two: masked count" "masked: 508 octets not compared (--ignore PI2,PI1,diag:0-2)" "$out"
py_checks "masks in JSON" "$PY_HEAD"'
j = json.load(open(sys.argv[1]))
eq((j["verdict"], j["exit_status"]), ("MATCH", 0), "verdict")
eq((j["ignore"], j["masked_octets"]), ("PI2,PI1,diag:0-2", 508), "masks")
svc = {s["service"]: s for s in j["services"]}
eq(svc["Data_Exchange"]["masked_octets"], 500, "Data_Exchange masked (PI1, PI2 and the FCS)")
eq(svc["Slave_Diag"]["masked_octets"], 8, "Slave_Diag masked (2 answers, 3 octets and the FCS)")
eq(svc["Set_Prm"]["masked_octets"], 0, "Set_Prm masked")
print("PASSED %d" % passed)
' "$tmp/mask.json"

# ---- bad command lines: exit 2, one line on stderr naming the bad part, nothing on stdout ------
usage_error() { # DESCRIPTION EXPECTED-TEXT args...
  local what=$1 want=$2; shift 2
  "$sim" replay "$golden/startup.pcap" "$@" >"$tmp/o" 2>"$tmp/e"; local rc=$?
  if [ $rc = 2 ] && [ ! -s "$tmp/o" ] && [ "$(wc -l <"$tmp/e")" = 1 ]; then ok
  else bad "$what: exit $rc, stdout '$(cat "$tmp/o")', stderr '$(cat "$tmp/e")'"; fi
  expect_in "$what: message" "$want" "$(cat "$tmp/e")"
}
usage_error "PI0" "replay: --ignore 'PI0': PI1..122 only" --check --ignore PI0
usage_error "PI200" "replay: --ignore 'PI200': PI1..122 only" --check --ignore PI2,PI200
usage_error "backwards" "replay: --ignore 'dx:9-4': the range runs backwards (4 after 9)" --check --ignore dx:9-4
usage_error "unknown service" "replay: --ignore 'foo:3': unknown service 'foo'" --check --ignore foo:3
usage_error "no octets" "replay: --ignore 'dx': neither PIn nor SERVICE:OCTETS" --check --ignore dx
usage_error "octet too high" "replay: --ignore 'dx:300': 0..245 only" --check --ignore dx:300
usage_error "not a number" "replay: --ignore 'diag:x': x is not a number" --check --ignore diag:x
usage_error "empty item" "replay: --ignore an empty item (two commas?)" --check --ignore PI2,,PI3
usage_error "--report kind" "replay: --report 'xml': use json FILE or junit FILE" --check --report xml "$tmp/x"
usage_error "--report without a file" "replay: --report json: which file? --report json FILE" --check --report json
usage_error "--ignore without --check" "add --check" --ignore PI1
usage_error "--report without --check" "add --check" --report json "$tmp/x.json"
usage_error "--max-mismatches" "--max-mismatches" --check --max-mismatches lots
usage_error "--timing" "replay: --timing 'fast': use auto" --check --timing fast
usage_error "five reports" "at most 4 report files" --check --report json a --report json b \
  --report json c --report json d --report json e

finish
