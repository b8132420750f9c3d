# Slow-loris against the control API (docs/api.md, "Limits"): 70 connections from 127.0.0.2,
# each sending one octet every 2 s, do not lock out the operator at 127.0.0.1: a STOP of the
# master answers 200 within 5 s, and every slow connection is closed once its 10 s to deliver
# a whole request are up (at most 8 of them are accepted at all). The card and the master run
# over a PTY pair (sim_host/bench/http_bench.py, which also gives the figures).
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp
bench="$(dirname "$0")/../../sim_host/bench/http_bench.py"

# The API needs a token (docs/api.md, "Security"): http_bench.py gives dfp-sim one in its
# environment (DFP_SIM_TOKEN) and sends it with every request.

out=$(timeout 120 python3 "$bench" "$sim" --part slowloris --conns 70 --addresses 1 --hold 16 \
      2>"$tmp/err") || { bad "http_bench.py failed: $(cat "$tmp/err")"; finish; exit 1; }
val() { sed -n "s/^$1=//p" <<<"$out"; }
[ "$(val stop_status)" = 200 ] && ok || bad "STOP answered $(val stop_status), not 200"
python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) < 5.0 else 1)" "$(val stop_seconds)" \
  && ok || bad "STOP took $(val stop_seconds) s (bound 5 s)"
[ "$(val slowloris_open_after_16s)" = 0 ] && ok || bad "every slow connection closed within 16 s: $(val slowloris_open_after_16s)"
python3 -c "import sys; sys.exit(0 if 0 <= float(sys.argv[1]) < 14.0 else 1)" \
  "$(val slowloris_last_closed_s)" && ok || bad "last slow connection closed at $(val slowloris_last_closed_s) s"
finish
