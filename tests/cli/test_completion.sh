#!/usr/bin/env bash
# The shell completions the build writes from the help table (sim_host/dfp_sim/completion.c):
# what bash completes for typed command lines (COMP_WORDS as readline would set them), the same
# for zsh with compadd and _files stood in, and that every option offered for a command is one
# the command accepts.
sim=$1
bash_file=$2
zsh_file=$3
. "$(dirname "$0")/lib.sh"

for f in "$bash_file" "$zsh_file"; do
  if [ -f "$f" ]; then ok; else bad "no completion file $f"; fi
done
if "$sim" --completion bash | cmp -s - "$bash_file"; then ok; else bad "$bash_file is not what --completion bash prints now"; fi
if "$sim" --completion zsh | cmp -s - "$zsh_file"; then ok; else bad "$zsh_file is not what --completion zsh prints now"; fi
expect_exit 2 "--completion without a shell" -- "$sim" --completion
expect_in "--completion says which shells" "--completion takes one shell: bash or zsh" "$out"
expect_exit 2 "--completion fish" -- "$sim" --completion fish

# shellcheck disable=SC1090
. "$bash_file"
reg=$(complete -p dfp-sim 2>&1)
if [ "$reg" = "complete -o default -F _dfp_sim dfp-sim" ]; then ok; else bad "registered as '$reg'"; fi

# comp LINE: what TAB at the end of LINE offers, one line, words sorted.
comp() {
  read -ra COMP_WORDS <<<"$1"
  [[ $1 == *" " ]] && COMP_WORDS+=("")
  COMP_CWORD=$((${#COMP_WORDS[@]} - 1))
  COMP_LINE=$1
  COMP_POINT=${#1}
  COMPREPLY=()
  _dfp_sim
  [ "${#COMPREPLY[@]}" -gt 0 ] && printf '%s\n' "${COMPREPLY[@]}" | sort | paste -sd " "
}
expect_comp() { # expect_comp LINE WANTED
  local got
  got=$(comp "$1")
  if [ "$got" = "$2" ]; then ok; else bad "bash: '$1<TAB>' gives '$got', expected '$2'"; fi
}
commands="check-cfg conformance convert demo gsd help inverter line master monitor param record replay slave"
expect_comp "dfp-sim sl" "slave"
expect_comp "dfp-sim master --co" "--config"
expect_comp "dfp-sim " "--help --version $commands"
expect_comp "dfp-sim help re" "record replay"
expect_comp "dfp-sim help slave " ""
expect_comp "dfp-sim master --capture-" "--capture-format --capture-linktype --capture-ns"
expect_comp "dfp-sim master --capture " ""
expect_comp "dfp-sim demo --log-level " "debug error info warn"
expect_comp "dfp-sim demo --timestamps w" "wall"
expect_comp "dfp-sim param --via p" "profidrive"
expect_comp "dfp-sim param --port /dev/ttyUSB1 --address 4 " "im0 read write"
expect_comp "dfp-sim param --port /dev/ttyUSB1 --address 4 w" "write"
expect_comp "dfp-sim param --address 4 read " ""
expect_comp "dfp-sim param --address 4 write P100 FIELDBUS --vo" "--volatile"
expect_comp "dfp-sim convert in.pcap out.pcap --linktype " "profibus user0"
expect_comp "dfp-sim replay x.pcap --speed " "max real"
expect_comp "dfp-sim slave --port " ""
expect_comp "dfp-sim slave --p" "--port --pty"
expect_comp "dfp-sim slave --pty " ""
expect_comp "dfp-sim slave --http-" "--http-allow-host --http-allow-origin --http-cert --http-key --http-no-auth --http-token-file --http-viewer-token-file"
expect_comp "dfp-sim replay x.pcap --http-v" "--http-viewer-token-file"
expect_comp "dfp-sim inverter --" "--can --channel2 --duration --eeprom --help --quiet --sbus-address"
expect_comp "dfp-sim check-cfg --" "--help"
expect_comp "dfp-sim fly --" ""

# Every option completed for a command is one it parses: given (with a value: the first it
# completes, else 1) before an option that is none, the command complains about the latter.
# --help is left out: it prints the help (cli_help).
for c in demo slave master inverter param convert replay record; do
  expect_exit 2 "$c: an unknown option" -- timeout 10 "$sim" "$c" --no-such-option
  expect_in "$c reports an unknown option" "unknown option '--no-such-option'" "$out"
  read -ra opts <<<"$(comp "dfp-sim $c --")"
  if [ "${#opts[@]}" -gt 3 ]; then ok; else bad "$c: only '${opts[*]}' completed"; fi
  for o in "${opts[@]}"; do
    [ "$o" = --help ] && continue
    read -ra values <<<"$(comp "dfp-sim $c $o ")"
    expect_exit 2 "$c $o" -- timeout 10 "$sim" "$c" "$o" "${values[0]:-1}" --no-such-option
    if grep -qF "unknown option '$o'" <<<"$out"; then bad "$c does not take $o, which completes: $out"; else ok; fi
  done
done

if command -v zsh >/dev/null; then
  # zcomp LINE: what the zsh function offers for LINE, with compadd filtering by the typed prefix
  # as zsh does and _files standing for file names.
  zcomp() {
    # shellcheck disable=SC2016 # expanded by zsh
    zsh -f -c '
      compadd() { [[ $1 == -- ]] && shift; local w; for w; do [[ $w == ${words[CURRENT]}* ]] && offered+=($w); done; (( $#offered )); }
      _files() { offered+=(_files) }
      eval "_dfp_sim() { $(<$1) }"
      words=(${(z)2}); [[ $2 == *" " ]] && words+=("")
      CURRENT=$#words; offered=()
      _dfp_sim
      print -r -- ${(j: :)${(o)offered}}' zcomp "$zsh_file" "$1"
  }
  expect_zcomp() {
    local got
    got=$(zcomp "$1" 2>&1)
    if [ "$got" = "$2" ]; then ok; else bad "zsh: '$1<TAB>' gives '$got', expected '$2'"; fi
  }
  expect_zcomp "dfp-sim sl" "slave"
  expect_zcomp "dfp-sim master --co" "--config"
  expect_zcomp "dfp-sim help re" "record replay"
  expect_zcomp "dfp-sim param --via " "c2 channel movilink profidrive"
  expect_zcomp "dfp-sim param --address 4 " "im0 read write"
  expect_zcomp "dfp-sim param --address 4 read " "_files"
  expect_zcomp "dfp-sim slave --port " "_files"
  expect_zcomp "dfp-sim slave --pty " "_files"
  expect_zcomp "dfp-sim demo --log-level i" "info"
else
  echo "zsh not installed: the zsh completion is not run"
fi
finish
