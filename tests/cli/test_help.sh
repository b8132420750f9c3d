#!/usr/bin/env bash
# dfp-sim help CMD, CMD --help, CMD -h, --version and the man page: every command's help is its
# own section of the whole text (sim_host/dfp_sim/help.c), on stdout, exit 0; the man page built
# beside the binary is what --man prints and names every command.
sim=$1
manpage=$2
. "$(dirname "$0")/lib.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

commands=(demo slave master inverter param convert replay record line check-cfg)
with_log=" demo slave master "

expect_exit 2 "unknown command" -- "$sim" fly
expect_in "the unknown-command message lists the commands of the help" \
  "(commands: demo, slave, master, inverter, param, convert, replay, record, line, monitor, check-cfg, gsd, conformance; see --help)" "$out"

expect_exit 0 "--help" -- "$sim" --help
full=$out
if "$sim" --help 2>/dev/null | cmp -s - <(printf '%s\n' "$full"); then ok; else bad "--help is not all on stdout"; fi
for want in "usage: dfp-sim COMMAND [options]" "       dfp-sim help [COMMAND]" \
    "       dfp-sim COMMAND --help|-h" "       dfp-sim --version" \
    "EXIT STATUS (the same for every command):" "  0  success" "  1  failure at run time" \
    "  2  bad command line" "LCM_DEFAULT_URL" "LOG OPTIONS: --quiet"; do
  expect_in "--help has '$want'" "$want" "$full"
done
expect_exit 0 "help" -- "$sim" help
if [ "$out" = "$full" ]; then ok; else bad "help differs from --help"; fi
expect_exit 0 "-h" -- "$sim" -h
if [ "$out" = "$full" ]; then ok; else bad "-h differs from --help"; fi

# Each command's first synopsis line, as the whole text prints it ("  slave --port DEV|...").
declare -A syn
for c in "${commands[@]}"; do
  syn[$c]=$(grep -m1 "^  $c " <<<"$full" | sed 's/^  //')
  if [ -n "${syn[$c]}" ]; then ok; else bad "no synopsis line for $c in --help"; fi
done

for c in "${commands[@]}"; do
  for form in "help $c" "$c --help" "$c -h"; do
    # shellcheck disable=SC2086 # form is split on purpose
    expect_exit 0 "$form" -- "$sim" $form
    expect_in "$form: the synopsis" "usage: dfp-sim ${syn[$c]}" "$out"
    expect_in "$form: the exit status" "EXIT STATUS (the same for every command):" "$out"
    for other in "${commands[@]}"; do
      [ "$other" = "$c" ] && continue
      if grep -qF -- "${syn[$other]}" <<<"$out"; then bad "$form shows $other's synopsis"; else ok; fi
    done
    if [[ $with_log == *" $c "* ]]; then
      expect_in "$form: LOG OPTIONS" "LOG OPTIONS: --quiet" "$out"
    elif grep -qF "LOG OPTIONS:" <<<"$out"; then
      bad "$form: $c takes no LOG OPTIONS but its help explains them"
    else
      ok
    fi
    # shellcheck disable=SC2086
    first=$("$sim" $form 2>/dev/null | head -n1)
    if [ "$first" = "usage: dfp-sim ${syn[$c]}" ]; then ok; else bad "$form: stdout starts '$first'"; fi
  done
done

# --help among other options: still help, nothing opened; only the whole word counts.
expect_exit 0 "slave with --help after its options" -- "$sim" slave --port /dev/does-not-exist --help
expect_in "no attempt to open the port" "usage: dfp-sim ${syn[slave]}" "$out"
expect_exit 2 "--helpme is no help" -- "$sim" slave --port /dev/null --helpme
expect_in "--helpme is an unknown option" "unknown option '--helpme'" "$out"
expect_exit 2 "-hx is no help" -- "$sim" master --port /dev/null -hx
expect_exit 0 "help --help" -- "$sim" help --help
if [ "$out" = "$full" ]; then ok; else bad "help --help is not the whole text"; fi

expect_exit 2 "help of an unknown command" -- "$sim" help nosuch
expect_in "help nosuch says so" "dfp-sim: help: unknown command 'nosuch' (commands: demo, slave" "$out"
if [ -z "$("$sim" help nosuch 2>/dev/null)" ]; then ok; else bad "help nosuch printed on stdout"; fi
expect_exit 2 "help of two commands" -- "$sim" help demo slave
expect_in "help of two says so" "help takes one command at most" "$out"

expect_exit 0 "--version" -- "$sim" --version
version=$out
if [[ $version =~ ^dfp-sim\ [A-Za-z0-9._+-]+$ ]]; then ok; else bad "--version printed '$version'"; fi
expect_exit 0 "version" -- "$sim" version
if [ "$out" = "$version" ]; then ok; else bad "version '$out' differs from --version '$version'"; fi
expect_exit 2 "--version with an argument" -- "$sim" --version x

# The man page: written by the build from --man, man(7) macros, every section and command.
if [ -f "$manpage" ]; then ok; else bad "no man page at $manpage"; fi
if "$sim" --man | cmp -s - "$manpage"; then ok; else bad "$manpage is not what --man prints now"; fi
man_text=$(cat "$manpage" 2>/dev/null)
v=${version#dfp-sim }
th=".TH DFP\\-SIM 1 \"\" \"dfp\\-sim ${v//-/\\-}\" \"User Commands\""
if [ "$(head -n1 <<<"$man_text")" = "$th" ]; then ok; else bad "man page starts '$(head -n1 <<<"$man_text")', not '$th'"; fi
for section in NAME SYNOPSIS DESCRIPTION COMMANDS '"COMMON OPTIONS"' '"EXIT STATUS"' ENVIRONMENT \
    '"SEE ALSO"'; do
  if grep -qxF ".SH $section" <<<"$man_text"; then ok; else bad "man page without .SH $section"; fi
done
for c in "${commands[@]}"; do
  if grep -qxF ".SS ${c//-/\\-}" <<<"$man_text"; then ok; else bad "man page without .SS $c"; fi
done
expect_in "man NAME line" 'dfp\-sim \- the DFP21B PROFIBUS\-DP card, simulated on Linux' "$man_text"
if grep -q '^[.'"'"']' <<<"$(grep -v '^\.\(TH\|SH\|SS\|TP\|PP\|nf\|fi\|nh\|ad\) \?' <<<"$man_text")"; then
  bad "a text line of the man page starts with . or ' unescaped"
else
  ok
fi

# Rendered, every command's synopsis reads as in --help (minus signs and all).
if command -v groff >/dev/null; then
  groff -man -Tascii -ww -P-c "$manpage" 2>"$tmp/warn" | col -bx >"$tmp/man.txt"
  if [ ! -s "$tmp/warn" ]; then ok; else bad "groff warns: $(cat "$tmp/warn")"; fi
  for c in "${commands[@]}"; do
    expect_in "rendered man page: $c" "dfp-sim ${syn[$c]}" "$(cat "$tmp/man.txt")"
  done
  expect_in "rendered exit status" "bad command line: unknown command or option" "$(cat "$tmp/man.txt")"
else
  echo "groff not installed: the man page is not rendered"
fi
finish
