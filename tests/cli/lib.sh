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
