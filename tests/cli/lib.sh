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
