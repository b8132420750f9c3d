# The golden captures dfp-sim makes deterministically on the in-memory bus: one line per file,
# "NAME dfp-sim ARGUMENTS" (then --capture NAME). Read by make-goldens.sh and by
# ../test_replay_cli.sh, which makes them again and compares them with the committed ones.
golden_recipes() {
  cat <<'LIST'
startup.pcap record --cycles 5 --param-every 0
data_exchange.pcap record --cycles 100 --param-every 0
param_channel.pcap record --cycles 200
dpv1.pcapng record --cycles 200 --dpv1
faults.pcap record --cycles 150 --faults
multimaster.pcap record --cycles 100 --foreign
demo.pcap demo
LIST
}
