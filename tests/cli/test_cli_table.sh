#!/usr/bin/env bash
# dfp-sim's option tables (sim_host/dfp_sim/cli_table.h) against what a user sees: every option
# the bash completion offers for a command (written from the command's table) is named in
# `dfp-sim help CMD` and is accepted by the command's parser (not an unknown option), and every
# --option `dfp-sim help CMD` names is offered by the completion.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp
cd "$tmp" || exit 1

comp=$("$sim" --completion bash)
commands="demo slave master inverter param convert replay record check-cfg"
for cmd in $commands; do
  opts=$(sed -n "s/^    $cmd) opts='\([^']*\)'.*/\1/p" <<<"$comp")
  if [ -n "$opts" ]; then ok; else bad "$cmd: no options in the completion"; continue; fi
  # the command's part: EXIT STATUS, the same for all, names options of other commands
  help=$("$sim" help "$cmd" | sed '/^EXIT STATUS/,$d')
  for opt in $opts; do
    [ "$opt" = --help ] && continue
    if grep -qE -- "(^|[^a-z-])$opt([^a-z0-9-]|$)" <<<"$help"; then ok; else
      bad "$cmd $opt: in the table and the completion, not in 'dfp-sim help $cmd'"; fi
    # The option, then words no command takes: the parser stops at those (or at the option's
    # value) with exit 2 and never runs the command.
    out=$(timeout 10 "$sim" "$cmd" "$opt" --zz-not-an-option --zz-not-an-option 2>&1)
    rc=$?
    if [ "$rc" = 2 ]; then ok; else bad "$cmd $opt --zz...: exit $rc, expected 2: $out"; fi
    if grep -qF -- "unknown option '$opt'" <<<"$out"; then
      bad "$cmd $opt: completed, but the parser does not know it: $out"; else ok; fi
  done
  for named in $(grep -oE -- "(^|[ [|(])--[a-z0-9][a-z0-9-]*[a-z0-9]" <<<"$help" | sed 's/^[^-]*//' | sort -u); do
    if [[ " $opts " == *" $named "* ]]; then ok; else
      bad "$cmd: 'dfp-sim help $cmd' names $named, which the completion does not offer"; fi
  done
done
# The one option check-cfg has is --help.
if [ "$(sed -n "s/^    check-cfg) opts='\([^']*\)'.*/\1/p" <<<"$comp")" = "--help" ]; then ok; else
  bad "check-cfg offers more than --help"; fi
finish
