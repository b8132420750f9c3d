#!/usr/bin/env bash
# tools/wireshark/profibus.lua in tshark, on captures dfp-sim writes (demo: DP-V0 start-up and the
# MOVILINK channel; param over a socat PTY against dfp-sim slave: MSAC1/MSAC2 and data set 47)
# and on hand-written captures (every start delimiter, DP-V0 services the simulator does not send,
# damaged and truncated telegrams, random data in correct frames). Asserts decoded values, and
# that tshark never reports a Lua error.
# Usage: test_dissector.sh DFP_SIM TSHARK PROFIBUS_LUA
sim=$1 tshark=$2 lua=$3
here=$(cd "$(dirname "$0")" && pwd)
. "$here/../cli/lib.sh"
tmp=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
mkdir -p "$tmp/home"

# dfp-sim writes LINKTYPE_PROFIBUS_DL (257), which Wireshark does not know; the dissector is
# registered for LINKTYPE_USER0 (147). The link type is the 4 octets at offset 20 of a pcap header.
to_user0() { "$sim" convert "$1" "$2" --linktype user0 --quiet; }
linktype_of() { od -An -tu4 -j20 -N4 "$1" | tr -d ' '; }

# ts OUT ARGS...: tshark with the dissector, isolated from the user's own plugins and
# preferences (HOME). Anything on stderr but the warning about running as root fails the check.
ts() {
  local out=$1; shift
  HOME="$tmp/home" XDG_CONFIG_HOME="$tmp/home/.config" "$tshark" -X "lua_script:$lua" "$@" \
    >"$out" 2>"$tmp/ts.err"
  local rc=$?
  local noise
  noise=$(grep -v '^Running as user "root"' "$tmp/ts.err")
  if [ "$rc" = 0 ] && [ -z "$noise" ]; then ok; else bad "tshark $*: exit $rc, stderr: $noise"; fi
}
# q PCAP FILTER FIELD...: the fields of the frames matching FILTER, tab-separated, in $tmp/q.out.
q() {
  local pcap=$1 filter=$2; shift 2
  local e=()
  for f in "$@"; do e+=(-e "$f"); done
  ts "$tmp/q.out" -r "$pcap" -Y "$filter" -T fields -E separator=/t "${e[@]}"
}
first() { head -n 1 "$tmp/q.out"; }
row() { sed -n "$1p" "$tmp/q.out"; }
count() { wc -l <"$tmp/q.out" | tr -d ' '; }
eq() { if [ "$2" = "$3" ]; then ok; else bad "$1: got '$2', want '$3'"; fi; }
tab=$'\t'
# no_lua_errors WHAT PCAP: the full tree of every frame has no Lua error, no internal error of
# the script, and every frame was dissected by it.
no_lua_errors() {
  ts "$tmp/v.out" -r "$2" -V
  local lua_err internal frames decoded
  lua_err=$(grep -c "Lua Error" "$tmp/v.out")
  internal=$(grep -c "Internal error in profibus.lua" "$tmp/v.out")
  frames=$(grep -c "^Frame [0-9]" "$tmp/v.out")
  decoded=$(grep -c "^PROFIBUS (FDL, DP, DP-V1)" "$tmp/v.out")
  eq "$1: Lua errors" "$lua_err" 0
  eq "$1: internal errors" "$internal" 0
  if [ "$frames" -gt 0 ] && [ "$frames" = "$decoded" ]; then ok; else
    bad "$1: $decoded of $frames frames dissected as PROFIBUS"; fi
}

# ---- dfp-sim demo: start-up, cyclic data with the MOVILINK channel, watchdog, wrong config
"$sim" demo --capture "$tmp/demo257.pcap" >"$tmp/demo.out" 2>&1
eq "dfp-sim demo exit status" "$?" 0
written=$(sed -n 's/.*capture: \([0-9]*\) telegrams written.*/\1/p' "$tmp/demo.out")
demo=$tmp/demo.pcap
to_user0 "$tmp/demo257.pcap" "$demo"
eq "demo capture converted to link type 147" "$(linktype_of "$demo")" 147
no_lua_errors demo "$demo"

q "$demo" 'profibus' frame.number
eq "every telegram the demo wrote is dissected" "$(count)" "$written"
q "$demo" 'profibus.fcs_ok==0 || profibus.malformed || profibus.trailing' frame.number
eq "demo: no FCS error, nothing malformed" "$(count)" 0

q "$demo" 'profibus.service=="Set_Prm" && profibus.fc.request==1' \
  profibus.dp.ident profibus.dp.prm.station_status profibus.dp.prm.lock_req \
  profibus.dp.prm.wd_on profibus.dp.prm.watchdog_ms profibus.dp.prm.min_tsdr
eq "first Set_Prm: ident, station status, Lock_Req, WD_On, watchdog ms, min TSDR" "$(first)" \
  "0x6003${tab}0x88${tab}1${tab}1${tab}100${tab}11"

q "$demo" 'profibus.service=="Slave_Diag" && profibus.fc.request==0' \
  profibus.sd profibus.dp.diag.status_1 profibus.dp.diag.station_not_ready \
  profibus.dp.diag.prm_req profibus.dp.diag.always_1 profibus.dp.diag.master_add profibus.dp.ident
eq "first Slave_Diag reply (SD2, 8 DU octets): not ready, Prm_Req, no master" "$(first)" \
  "0x68${tab}0x02${tab}1${tab}1${tab}1${tab}255${tab}0x6003"
q "$demo" 'profibus.dp.diag.cfg_fault==1' frame.number
if [ "$(count)" -ge 1 ]; then ok; else bad "demo scene 5: no Slave_Diag with Cfg_Fault decoded"; fi

q "$demo" 'profibus.service=="Chk_Cfg"' frame.number profibus.dp.cfg.id profibus.dp.cfg.direction \
  profibus.dp.cfg.consistency profibus.dp.cfg.total_in profibus.dp.cfg.total_out
chk=$(first | cut -f1)
eq "first Chk_Cfg: identifiers F3 F2, in/out, consistent, 14 octets each way" \
  "$(first | cut -f2-)" "0xf3,0xf2${tab}3,3${tab}1,1${tab}14${tab}14"
q "$demo" "profibus.response_to==$chk" profibus.sd
eq "the SC after Chk_Cfg is paired with it" "$(first)" 0xe5

# MOVILINK channel: read of 8300 (firmware) in the outputs, the reply in the inputs.
q "$demo" 'profibus.ml.index==8300 && profibus.fc.request==1' \
  profibus.service profibus.ml.management profibus.ml.service profibus.ml.length \
  profibus.ml.handshake profibus.ml.status profibus.ml.index profibus.pd.word
eq "first Data_Exchange with MOVILINK read 8300" "$(first)" \
  "Data_Exchange${tab}0x71${tab}1${tab}3${tab}1${tab}0${tab}8300${tab}0x0000,0x0000,0x0000"
q "$demo" 'profibus.ml.index==8300 && profibus.fc.request==0 && profibus.ml.handshake==1' \
  profibus.ml.service profibus.ml.status profibus.ml.data
eq "reply: 8300 = 0x311C7289" "$(first)" "1${tab}0${tab}0x311c7289"
q "$demo" 'profibus.ml.status==1' profibus.ml.index profibus.ml.error_class \
  profibus.ml.error_code profibus.ml.error_additional
eq "P302 = 99000 rpm refused: class 8, additional code 0x15" "$(first)" \
  "8517${tab}8${tab}0${tab}0x0015"
q "$demo" 'profibus.pd.word==0x05dc && profibus.fc.request==1' profibus.pd.word
eq "PO2 = 1500 (300 rpm) in the process data words" "$(first)" "0x0006,0x05dc,0x0000"

# FCB/FCV, from the bits alone: every start-up begins FCV=0 FCB=1, then FCB alternates.
q "$demo" 'profibus.fc.request==1 && profibus.sa==2 && profibus.da==4 && profibus.fc.function==0xd' \
  profibus.fc.fcb profibus.fc.fcv
fcb_check=$(awk -F'\t' '{ if ($2 == 0) { starts++; if ($1 != 1) wrong++ }
                            else if ($1 == last) wrong++
                            last = $1; n++ }
                          END { printf "%d %d %d", n, starts, wrong }' "$tmp/q.out")
read -r fcb_n fcb_starts fcb_wrong <<<"$fcb_check"
if [ "$fcb_n" -gt 100 ] && [ "$fcb_starts" -ge 2 ] && [ "$fcb_wrong" = 0 ]; then ok; else
  bad "FCB/FCV: $fcb_n SRD requests, $fcb_starts start-ups, $fcb_wrong out of sequence"; fi
q "$demo" 'profibus.fc.repeat' frame.number
eq "no FCB repetition flagged in the demo" "$(count)" 0

# The preference off: no MOVILINK channel, no process data words.
ts "$tmp/pref.out" -o profibus.dfp21b_movilink:FALSE -r "$demo" -Y 'profibus.ml.index || profibus.pd.word' \
  -T fields -e frame.number
eq "preference off: channel not decoded" "$(wc -l <"$tmp/pref.out" | tr -d ' ')" 0
# Two passes (as the GUI does): the request knows its response.
ts "$tmp/two.out" -2 -r "$demo" -Y "frame.number==$chk" -T fields -e profibus.response_in
eq "two passes: Chk_Cfg's response_in" "$(cat "$tmp/two.out")" "$((chk + 1))"

# ---- dfp-sim param against dfp-sim slave over a PTY pair: DP-V1 (MSAC1, MSAC2, data set 47)
socat pty,raw,echo=0,link="$tmp/a" pty,raw,echo=0,link="$tmp/b" &
pids+=($!)
for _ in $(seq 50); do [ -e "$tmp/a" ] && [ -e "$tmp/b" ] && break; sleep 0.1; done
"$sim" slave --port "$tmp/a" --address 4 --baud 19200 >"$tmp/slave.out" 2>&1 &
pids+=($!)
sleep 0.3
# capture NAME ARGS...: one param run, its capture converted to $tmp/NAME.pcap
capture() {
  local name=$1; shift
  "$sim" param --port "$tmp/b" --address 4 --timeout 10 --capture "$tmp/$name.257" "$@" \
    >"$tmp/$name.txt" 2>&1
  local rc=$?
  case $name in err) eq "param $*: exit status" "$rc" 1 ;; *) eq "param $*: exit status" "$rc" 0 ;; esac
  to_user0 "$tmp/$name.257" "$tmp/$name.pcap"
}
capture ml read 8300 --via movilink
capture pd read 8300 --via profidrive
capture wr write 11000 3000 --via movilink --volatile
capture err read 1 --via profidrive
capture c2 read 8300 --via c2
capture im im0 --via c2
for n in ml pd wr err c2 im; do no_lua_errors "param capture $n" "$tmp/$n.pcap"; done

q "$tmp/ml.pcap" 'profibus.service=="Set_Prm"' profibus.dp.prm.dpv1_enable profibus.dp.prm.watchdog_ms
eq "DP-V1 Set_Prm: DPV1_Enable" "$(first | cut -f1)" 1
q "$tmp/ml.pcap" 'profibus.dpv1.function==0x5f && profibus.fc.request==1' \
  profibus.dsap profibus.ssap profibus.dpv1.slot profibus.dpv1.index profibus.dpv1.length \
  profibus.ds47.ref profibus.ds47.id profibus.ds47.axis profibus.ds47.n_params \
  profibus.ds47.attribute profibus.ds47.elements profibus.ds47.pnu profibus.ds47.subindex
eq "MSAC1 Write.req DS47, MOVILINK read 8300" "$(first)" \
  "51${tab}51${tab}0${tab}47${tab}10${tab}1${tab}0x40${tab}0${tab}1${tab}0x10${tab}0${tab}8300${tab}0"
q "$tmp/ml.pcap" 'profibus.dpv1.function==0x5e && profibus.fc.request==0' \
  profibus.dpv1.length profibus.ds47.id profibus.ds47.n_params profibus.ds47.format \
  profibus.ds47.n_values profibus.ds47.value
eq "MSAC1 Read.res DS47: 0x311C7289" "$(first)" \
  "10${tab}0x40${tab}1${tab}0x43${tab}1${tab}0x311c7289"
q "$tmp/ml.pcap" 'profibus.dpv1.poll' frame.number
if [ "$(count)" -ge 2 ]; then ok; else bad "MSAC1 polls not recognised ($(count))"; fi

q "$tmp/pd.pcap" 'profibus.ds47.pnu && profibus.fc.request==1' profibus.ds47.id profibus.ds47.axis \
  profibus.ds47.attribute profibus.ds47.pnu
eq "PROFIdrive request parameter 8300, axis 0" "$(first)" "0x01${tab}0${tab}0x10${tab}8300"
q "$tmp/pd.pcap" 'profibus.ds47.value' profibus.ds47.id profibus.ds47.value
eq "PROFIdrive response 0x311C7289" "$(first)" "0x01${tab}0x311c7289"

q "$tmp/wr.pcap" 'profibus.ds47.pnu && profibus.fc.request==1' profibus.ds47.attribute \
  profibus.ds47.pnu profibus.ds47.format profibus.ds47.n_values profibus.ds47.value
eq "MOVILINK write volatile 11000 = 3000" "$(first)" "0x30${tab}11000${tab}0x43${tab}1${tab}0x00000bb8"
q "$tmp/wr.pcap" 'profibus.ds47.id && profibus.fc.request==0' profibus.ds47.id profibus.ds47.n_params \
  profibus.ds47.format
eq "write response: id 0x40, 1 parameter, no value block" "$(first)" "0x40${tab}1${tab}"

q "$tmp/err.pcap" 'profibus.ds47.id && profibus.fc.request==0' profibus.ds47.id profibus.ds47.format \
  profibus.ds47.error
eq "PROFIdrive negative response: 0x81, error 0x0000" "$(first)" "0x81${tab}0x44${tab}0x0000"
q "$tmp/err.pcap" 'profibus.ds47.negative' frame.number
eq "negative parameter response has its expert info" "$(count)" 1

q "$tmp/c2.pcap" 'profibus.dpv1.function==0x57 && profibus.fc.request==1' profibus.dsap \
  profibus.dpv1.send_timeout profibus.dpv1.features_1
eq "MSAC2 Initiate.req to SAP 49" "$(first)" "49${tab}200${tab}0x01"
q "$tmp/c2.pcap" 'profibus.dpv1.rm.sap' profibus.ssap profibus.dpv1.rm.sap
eq "resource manager answers: connection SAP 0" "$(first)" "49${tab}0"
q "$tmp/c2.pcap" 'profibus.dpv1.function==0x57 && profibus.fc.request==0' profibus.ssap \
  profibus.dpv1.max_len_data_unit
eq "Initiate.res on SAP 0" "$(first)" "0${tab}240"
q "$tmp/c2.pcap" 'profibus.ds47.value' profibus.service profibus.ssap profibus.ds47.value
eq "MSAC2 Read.res DS47 on SAP 0" "$(first)" "MSAC2${tab}0${tab}0x311c7289"
q "$tmp/c2.pcap" 'profibus.dpv1.function==0x58' profibus.dpv1.abort.instance
eq "Abort from the user" "$(first)" 2

q "$tmp/im.pcap" 'profibus.im.manufacturer_id' profibus.im.fi_index profibus.im.manufacturer_id \
  profibus.im.order_id profibus.im.supported
eq "I&M0 over MSAC2" "$(first | sed 's/ *\t/\t/g')" "65000${tab}0x010a${tab}824 240 2${tab}0x001e"

# ---- hand-written capture, link type 147 (frame numbers in the comments)
python3 "$here/mkpcap.py" "$tmp/hand.pcap" >/dev/null <<'EOF'
raw 10 04 02 49 4F 16                                   # 1 FDL status request (protocol.md §A1.6)
raw 10 02 04 00 06 16                                   # 2 its reply: OK, slave
raw DC 04 02                                            # 3 token SD4
raw 68 05 05 68 84 82 6D 3C 3E ED 16                    # 4 Slave_Diag request (FCV=0 FCB=1)
raw A2 82 84 08 3E 3C 02 05 00 FF 60 03 F1 16           # 5 Slave_Diag reply as SD3
raw 68 15 15 68 84 82 5D 3D 3E 88 01 64 0B 60 03 00 00 00 00 06 81 00 00 01 01 C2 16  # 6 Set_Prm
raw E5                                                  # 7 SC
raw 68 07 07 68 84 82 7D 3E 3E F3 F2 E4 16              # 8 Chk_Cfg F3 F2
raw E5                                                  # 9 SC
raw 68 07 07 68 FF 82 46 3A 3E 20 00 5F 16              # 10 Global_Control Sync, broadcast
sd2 04 02 5D 41 00 20 6C 00 00 00 00 00 06 05 DC 00 00  # 11 Data_Exchange: ML read 8300 HS=1, PO 0006 05DC 0000
sd2 02 04 08 71 00 20 6C 31 1C 72 89 02 06 00 00 00 00  # 12 reply: 8300 = 0x311C7289
sd2 04 02 5D 41 00 20 6C 00 00 00 00 00 06 05 DC 00 00  # 13 the same request again: FCB repetition
sd2 02 04 0A 71 00 20 6C 31 1C 72 89 02 06 00 00 00 00  # 14 reply DH
sd2 04 02 7D 33 00 21 45 05 E6 9E C0 00 06 05 DC 00 00  # 15 ML write volatile 8517 = 99000000 HS=0
sd2 02 04 08 B3 00 21 45 08 00 00 15 02 06 00 00 00 00  # 16 ML error class 8 add 0x15
sd2 84 82 5D 37 3E 05 60 03 00                          # 17 Set_Slave_Add new address 5
raw 10 02 04 03 09 16                                   # 18 RS
sd2 84 82 7D 3B 3E                                      # 19 Get_Cfg
sd2 82 84 08 3E 3B 00 F5 C1 83 C3 AA                    # 20 reply: free place, F5, special C1 83 C3 + 1 manufacturer octet
sd2 84 82 5D 38 3E                                      # 21 Rd_Inp
sd2 82 84 08 3E 38 02 06 05 DC 00 00                    # 22 Rd_Inp reply
sd2 84 82 7D 39 3E                                      # 23 Rd_Outp
sd2 82 84 08 3E 39 00 06 05 DC 00 00                    # 24 Rd_Outp reply
sd2 84 82 5D 3C 3E                                      # 25 Slave_Diag
sd2 82 84 08 3E 3C 08 0C 00 02 60 03 03 02 2A           # 26 reply with a device-related block 02 2A
raw 68 13 13 68 84 82 7D 33 33 5F 00 2F 0A 01 40 00 01 10 00 20 6C 00 00 5F 16  # 27 C1 Write DS47
raw E5                                                  # 28 SC
raw 68 09 09 68 84 82 5D 33 33 5E 00 2F F0 46 16        # 29 C1 Read DS47
raw 68 09 09 68 82 84 08 33 33 DE 80 B5 00 87 16        # 30 Read negative B5
sd2 82 84 08 33 33 5E 00 2F 08 01 C0 00 01 44 01 08 11  # 31 Read.res: MOVILINK negative 0x0811
sd2 84 82 7D 33 33 5F 00 2F 10 01 02 00 01 10 00 21 29 00 00 43 01 00 00 05 DC  # 32 change P160 8489 = 1500
raw 68 15 15 68 84 82 5D 3D 3E 88 01 64 0B 60 03 00 00 00 00 06 81 00 00 01 01 C3 16  # 33 Set_Prm, FCS damaged
raw 68 15 15 68 84 82 5D 3D 3E 88 01 64                 # 34 Set_Prm truncated after 12 octets
raw 68 07 08 68 84 82 7D 3E 3E F3 F2 E4 16              # 35 LE != LEr
raw 10 04 02 49 4F 17                                   # 36 wrong end delimiter
raw 55 01 02                                            # 37 unknown start delimiter
empty                                                   # 38 empty record
raw DC 04                                               # 39 token truncated
raw A2 82 84 08 3E 3C 02 05                             # 40 SD3 truncated
sd2 84 82 5D 3D 3E 88 01                                # 41 Set_Prm data unit too short (frame itself fine)
sd2 84 82 7D 33 33 5F 00 2F 06 01 40 00 01 10 00        # 42 DS47 request cut inside the parameter address
sd2 84 82 5D 33 33 5F 00 2F 0A 01 40                    # 43 Write.req length 10, 2 data octets
sd2 82 84 08 3E 3C 08 0C 00 02 60 03 00                 # 44 ext diag block of length 0
raw 10 02 04 00 06 16 00                                # 45 an octet after the end delimiter
sd1 84 82 49                                            # 46 DA extension bit without a DAE octet
raw 10 04 02 49 4F 16                                   # 47 a good telegram after all that
sd2 05 02 7D 00 01                                      # 48 Data_Exchange to slave 5, FCB=1 FCV=1
sd1 05 02 6D                                            # 49 restart FCV=0 FCB=1: no repetition
sd1 05 02 5D                                            # 50 FCB toggled
sd2 84 81 5D 00 32 48 00 00 00                          # 51 MSAC2 Idle.req on connection SAP 0
sd2 81 84 08 32 00 48 00 00 00                          # 52 Idle.res
sd2 81 84 08 32 00 58 01 13 00                          # 53 Abort: local, MSAC_C2, TO (connection timeout)
sd2 04 02 7D 41 00 21 0D 00 00 00 00 00 06 05 DC 00 00  # 54 Data_Exchange: ML read 8461 (P100) HS=1
EOF
hand=$tmp/hand.pcap
eq "hand-written capture has link type 147" "$(linktype_of "$hand")" 147
no_lua_errors "hand-written capture" "$hand"
ts "$tmp/hand.tsv" -r "$hand" -T fields -E separator=/t -e frame.number -e profibus.sd \
  -e profibus.fcs_ok -e profibus.malformed -e profibus.service -e _ws.col.Info
# hand FRAME COLUMN: one column of the dump above (2 sd, 3 fcs_ok, 4 malformed, 5 service, 6 info)
hand() { awk -F'\t' -v n="$1" -v c="$2" '$1 == n { print $c }' "$tmp/hand.tsv"; }
eq "SD1" "$(hand 1 2)" 0x10
eq "SD4 token" "$(hand 3 2)$(hand 3 5)" 0xdcToken
eq "SD2" "$(hand 4 2)" 0x68
eq "SD3" "$(hand 5 2)" 0xa2
eq "SC" "$(hand 7 2)" 0xe5
good_fcs=0
for n in 1 2 4 5 6 8 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 29 30 31 32 36 41 42 43 44 45 46 47 48 49 50 51 52 53; do
  [ "$(hand "$n" 3)" = 1 ] && good_fcs=$((good_fcs + 1))
done
eq "FCS correct on the 42 intact SD1/SD2/SD3 telegrams (spec examples and mkpcap's FCS)" "$good_fcs" 42
eq "tree text of a Data_Exchange" "$(hand 11 6)" \
  "SD2 DA=4 SA=2 SRD high FCB=0 FCV=1 Data_Exchange 14 octets ML read 8300 (P076 firmware basic unit) HS=1 PO 0006 05DC 0000"
eq "tree text of an SC" "$(hand 7 6)" "SC ack to Set_Prm (frame 6)"
malformed_frames=$(awk -F'\t' '$4 != "" { printf "%s ", $1 }' "$tmp/hand.tsv")
eq "exactly the broken telegrams are malformed" "$malformed_frames" \
  "34 35 36 37 38 39 40 41 42 43 44 46 "
eq "truncated telegram still shows who sent it" "$(hand 34 6)" \
  "SD2 DA=4 SA=2 [malformed: SD2 truncated: 12 of 27 octets]"
eq "the telegram after the broken ones is decoded" "$(hand 47 6)" "SD1 DA=4 SA=2 FDL status"

q "$hand" 'frame.number==33' profibus.fcs_ok profibus.fcs profibus.fcs.computed profibus.dp.ident
eq "damaged FCS detected, the rest still decoded" "$(first)" "0${tab}0xc3${tab}0xc2${tab}0x6003"
q "$hand" 'profibus.fcs.bad' frame.number
eq "FCS expert info only on the damaged telegram" "$(first)/$(count)" "33/1"
q "$hand" 'frame.number==35' _ws.expert.message
eq "LE != LEr" "$(first)" "Malformed: LE 7 differs from LEr 8"
q "$hand" 'frame.number==41' _ws.expert.message
eq "Set_Prm too short" "$(first)" "Malformed: Set_Prm truncated in WD_Fact_2 (needs 1, 0 left)"
q "$hand" 'frame.number==45' profibus.trailing
eq "octet after ED shown" "$(first)" 00

q "$hand" 'frame.number==10' profibus.da profibus.fc.function profibus.dsap profibus.dp.gc.sync \
  profibus.dp.gc.unsync profibus.dp.gc.freeze profibus.dp.gc.clear_data profibus.dp.gc.group_select
eq "Global_Control Sync to 127" "$(first)" "127${tab}0x06${tab}58${tab}1${tab}0${tab}0${tab}0${tab}0x00"
q "$hand" 'profibus.fc.repeat' frame.number
eq "FCB repetition: frame 13 only (not 33 with its bad FCS, not 49 with FCV=0)" "$(first)/$(count)" "13/1"
q "$hand" 'frame.number==14' profibus.fc.response profibus.fc.station_type profibus.diag_pending
eq "DH reply" "$(first | cut -f1-2)" "0x0a${tab}0"
q "$hand" 'frame.number==16' profibus.ml.status profibus.ml.error_class profibus.ml.error_additional \
  profibus.pd.word
eq "MOVILINK channel error reply" "$(first)" "1${tab}8${tab}0x0015${tab}0x0206,0x0000,0x0000"
q "$hand" 'frame.number==17' profibus.dp.ssa.new_address profibus.dp.ident profibus.dp.ssa.no_add_chg
eq "Set_Slave_Add" "$(first)" "5${tab}0x6003${tab}0x00"
q "$hand" 'frame.number==18' profibus.fc.response profibus.service profibus.response_to profibus.negative
eq "RS reply names the refused service" "$(first | cut -f1-3)" "0x03${tab}Set_Slave_Add${tab}17"
q "$hand" 'frame.number==20' profibus.dp.cfg.id profibus.dp.cfg.special profibus.dp.cfg.length_octet \
  profibus.dp.cfg.manufacturer_data profibus.dp.cfg.total_in profibus.dp.cfg.total_out
eq "Get_Cfg reply: free place, special format with length octets" "$(first)" \
  "0x00,0xf5,0xc1${tab}0,3${tab}0x83,0xc3${tab}aa${tab}20${tab}16"
q "$hand" 'frame.number==22 || frame.number==24' profibus.dp.inputs profibus.dp.outputs
eq "Rd_Inp / Rd_Outp replies" "$(row 1)|$(row 2)" "020605dc0000${tab}|${tab}000605dc0000"
q "$hand" 'frame.number==26' profibus.dp.diag.ext_diag profibus.dp.diag.wd_on \
  profibus.dp.diag.master_add profibus.dp.diag.block_type profibus.dp.diag.block_length \
  profibus.dp.diag.block_data
eq "Slave_Diag with a device-related block" "$(first)" \
  "1${tab}1${tab}2${tab}0${tab}3${tab}022a"
q "$hand" 'frame.number==30' profibus.dpv1.function profibus.dpv1.error_decode \
  profibus.dpv1.error_code_1 profibus.dpv1.error_class profibus.dpv1.error_code profibus.dpv1.error_code_2
eq "DP-V1 negative Read.res B5" "$(first)" "0xde${tab}0x80${tab}0xb5${tab}0x0b${tab}5${tab}0x00"
q "$hand" 'frame.number==31' profibus.ds47.id profibus.ds47.format profibus.ds47.error
eq "MOVILINK negative DS47 response 0x0811" "$(first)" "0xc0${tab}0x44${tab}0x0811"
q "$hand" 'frame.number==32' profibus.ds47.id profibus.ds47.axis profibus.ds47.pnu profibus.ds47.value
eq "PROFIdrive change parameter 8489 = 1500" "$(first)" "0x02${tab}0${tab}8489${tab}0x000005dc"

# MOVILINK indices carry the parameter's name (tools/wireshark/movidrive_params.lua).
q "$hand" 'frame.number==54' profibus.ml.index profibus.ml.param _ws.col.Info
eq "MOVILINK request for 8461 names P100" "$(first)" \
  "8461${tab}P100 setpoint source${tab}SD2 DA=4 SA=2 SRD high FCB=1 FCV=1 Data_Exchange 14 octets ML read 8461 (P100 setpoint source) HS=1 PO 0006 05DC 0000"
q "$tmp/ml.pcap" 'profibus.ds47.pnu && profibus.fc.request==1' profibus.ds47.pnu profibus.ds47.param
eq "data set 47 request for 8300 names P076" "$(first)" "8300${tab}P076 firmware basic unit"

q "$hand" 'frame.number>=51 && frame.number<=53' profibus.service profibus.dsap profibus.ssap profibus.dpv1.function \
  profibus.dpv1.abort.subnet profibus.dpv1.abort.instance profibus.dpv1.abort.reason
eq "MSAC2 Idle.req" "$(row 1)" "MSAC2${tab}0${tab}50${tab}0x48${tab}${tab}${tab}"
eq "MSAC2 Idle.res" "$(row 2)" "MSAC2${tab}50${tab}0${tab}0x48${tab}${tab}${tab}"
eq "MSAC2 Abort TO" "$(row 3)" "MSAC2${tab}50${tab}0${tab}0x58${tab}1${tab}1${tab}3"

# ---- robustness: every truncation and random damage of the captures above, and random data
# units in correct frames for every SAP; seeded, so a failure is reproducible.
python3 "$here/mutate.py" "$tmp/fuzz.pcap" 5 "$hand" "$tmp/c2.pcap" "$tmp/ml.pcap" "$tmp/im.pcap" \
  >"$tmp/fuzz.n"
no_lua_errors "damaged and random telegrams ($(cat "$tmp/fuzz.n"))" "$tmp/fuzz.pcap"

# ---- installed as a plugin (README): no -X needed
# (profibus.lua and its parts profibus_*.lua, as the README says; not movidrive_params.lua)
mkdir -p "$tmp/home/.local/lib/wireshark/plugins"
cp "$lua" "$(dirname "$lua")"/profibus_*.lua "$tmp/home/.local/lib/wireshark/plugins/"
HOME="$tmp/home" XDG_CONFIG_HOME="$tmp/home/.config" "$tshark" -r "$hand" -Y 'frame.number==6' \
  -T fields -e profibus.dp.ident >"$tmp/plugin.out" 2>"$tmp/plugin.err"
eq "from the personal plugin folder" "$(cat "$tmp/plugin.out")" 0x6003
eq "plugin folder: nothing on stderr" "$(grep -v '^Running as user "root"' "$tmp/plugin.err")" ""
# ... and without movidrive_params.lua beside it the indices are bare numbers
HOME="$tmp/home" XDG_CONFIG_HOME="$tmp/home/.config" "$tshark" -r "$hand" -Y 'frame.number==54' \
  -T fields -e profibus.ml.index -e profibus.ml.param >"$tmp/plugin.out" 2>"$tmp/plugin.err"
eq "no name table: bare index" "$(cat "$tmp/plugin.out")" "8461${tab}"
eq "no name table: nothing on stderr" "$(grep -v '^Running as user "root"' "$tmp/plugin.err")" ""

finish
