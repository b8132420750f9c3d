# A request flood against the card's control API does not disturb its data exchange: the card
# (dfp-sim slave) and dfp-sim master over a PTY pair, the master setting a 10 ms DP watchdog;
# 4 clients send GET state, GET log?limit=4096 and refused POSTs, and 2 read the event stream,
# for 5 s. Asserts no watchdog expiry during the flood and the card still in Data_Exch. Exit 77
# (skipped) when the machine is too busy for a 10 ms watchdog even without a flood (expiries in
# a quiet 2 s before it): the figure would then say nothing about the server.
# sim_host/bench/http_bench.py gives the figures (rate, expiries) for longer floods.
sim=$1
. "$(dirname "$0")/lib.sh"
with_tmp
bench="$(dirname "$0")/../../sim_host/bench/http_bench.py"

# The API needs a token (docs/api.md, "Security"): http_bench.py gives dfp-sim one in its
# environment (DFP_SIM_TOKEN) and sends it with every request.

# Real-time priority for the simulation where allowed (root, RLIMIT_RTPRIO): other work on the
# machine then disturbs a 10 ms watchdog less; the server's own threads drop it.
rt=()
if chrt -f 10 true 2>/dev/null; then rt=(--rt 10); fi
out=$(timeout 120 python3 "$bench" "$sim" --part flood --seconds 5 --workers 4 "${rt[@]}" \
      2>"$tmp/err") || { bad "http_bench.py failed: $(cat "$tmp/err")"; finish; exit 1; }
val() { sed -n "s/^$1=//p" <<<"$out"; }
if [ "$(val quiet_watchdog_expiries_2s)" != 0 ]; then
  echo "skipped: $(val quiet_watchdog_expiries_2s) watchdog expiries in 2 s without a flood (busy machine)"
  exit 77
fi
req=$(val flood_requests)
[ "${req:-0}" -gt 100 ] && ok || bad "the flood sent only ${req:-0} requests"
[ "$(val flood_watchdog_expiries)" = 0 ] && ok || bad "no watchdog expiry during the flood: $(val flood_watchdog_expiries)"
[ "$(val flood_card_state)" = Data_Exch ] && ok || bad "the card in $(val flood_card_state), not Data_Exch"
finish
