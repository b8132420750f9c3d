#!/usr/bin/env bash
# Makes the golden captures again: make-goldens.sh DFP-SIM [DIR]. The recorded ones
# (recipes.sh) come out identical unless the card or the master changed; the two PTY ones
# (dfp-sim param against dfp-sim slave over a socat PTY pair, wall-clock timing) differ in
# their timing every time. See README.md.
set -euo pipefail
sim=$1
dir=${2:-$(dirname "$0")}
. "$(dirname "$0")/recipes.sh"
while read -r name args; do
  # shellcheck disable=SC2086
  "$sim" $args --capture "$dir/$name" >/dev/null
done < <(golden_recipes)

# DP-V1 over a PTY: a fresh slave (and PTY pair) for each capture, so no state and no stale
# telegram of an earlier session reaches it.
pty_capture() { # NAME param-arguments...
  local name=$1; shift
  local tmp; tmp=$(mktemp -d)
  socat pty,raw,echo=0,link="$tmp/a" pty,raw,echo=0,link="$tmp/b" & local socat=$!
  for _ in $(seq 50); do [ -e "$tmp/a" ] && [ -e "$tmp/b" ] && break; sleep 0.1; done
  "$sim" slave --port "$tmp/a" --address 4 --baud 19200 >/dev/null 2>&1 & local slave=$!
  sleep 0.3
  "$sim" param --port "$tmp/b" --address 4 "$@" --capture "$dir/$name" >/dev/null
  kill "$slave" "$socat"; wait "$slave" "$socat" 2>/dev/null || true
  rm -rf "$tmp"
}
pty_capture dpv1_pty_movilink.pcap --via movilink read 8300
pty_capture dpv1_pty_c2.pcap --via c2 write 8489 1500
