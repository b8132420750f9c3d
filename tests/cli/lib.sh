# Tiny assertion helpers for the shell tests; the last line is "N passed, M failed".
passed=0
failed=0
ok() { passed=$((passed + 1)); }
bad() { failed=$((failed + 1)); echo "FAIL: $*" >&2; }
# expect_exit CODE DESCRIPTION -- command...
expect_exit() {
  local want=$1 what=$2; shift 3
  out=$("$@" 2>&1); local got=$?
  if [ "$got" = "$want" ]; then ok; else bad "$what: exit $got, expected $want; output: $out"; fi
}
expect_in() { # expect_in DESCRIPTION NEEDLE HAYSTACK
  if grep -qF -- "$2" <<<"$3"; then ok; else bad "$1: '$2' not in output:"$'\n'"$3"; fi
}
finish() { echo "$passed passed, $failed failed"; [ "$failed" = 0 ] && [ "$passed" -gt 0 ]; }
# For tests with background processes: a temp dir $tmp, processes in pids[] killed at exit.
with_tmp() {
  tmp=$(mktemp -d)
  pids=()
  trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; rm -rf "$tmp"' EXIT
}
pty_pair() { # a socat PTY pair at $tmp/a and $tmp/b
  rm -f "$tmp/a" "$tmp/b"
  socat pty,raw,echo=0,link="$tmp/a" pty,raw,echo=0,link="$tmp/b" &
  pids+=($!)
  for _ in $(seq 50); do [ -e "$tmp/a" ] && [ -e "$tmp/b" ] && return 0; sleep 0.1; done
  echo "socat did not create the PTY pair" >&2; return 1
}
# dx_cycles CAPTURE: Data_Exchange cycles (to station 4, from the master at 2) in a master's text
# capture that got their reply. A cycle is a run of requests with the same FC (a repeat after a
# lost reply keeps it; a start-up service to the station ends the run, since it resets the FCB)
# and counts once, at its first reply; a cycle whose every try went unanswered does not count, so
# a loaded machine that loses a reply does not change the count.
dx_cycles() {
  awk '$2 == "TX" && $3 == "68" && $7 == "04" && $8 == "02" {
         if ($9 != fc || restart) run++; fc = $9; restart = 0; req = run; next }
       $2 == "TX" { if ($3 == "68" && $7 == "84") restart = 1; req = 0; next }
       $2 == "RX" && req && $3 == "68" && $7 == "02" && $8 == "04" {
         if (req != counted) n++; counted = req; req = 0 }
       END { print n + 0 }' "$1"
}
