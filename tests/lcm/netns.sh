# Sourced first by the LCM tests that use udpm: re-runs the calling script in a private network
# namespace with the multicast route udpm needs on loopback (tooling-notes.md "LCM"), so a test
# never touches the machine's routes. Exit 77 (ctest: skipped) where no namespace can be made.
if [ -z "$DFP_LCM_NETNS" ]; then
  if ! unshare -n true 2>/dev/null; then
    echo "SKIP: cannot create a network namespace (unshare -n needs root or user namespaces)"
    exit 77
  fi
  exec unshare -n env DFP_LCM_NETNS=1 bash "$0" "$@"
fi
if ! { ip link set lo up && ip route add 239.0.0.0/8 dev lo; }; then
  echo "cannot add the multicast route 239.0.0.0/8 dev lo in the private namespace"
  echo "0 passed, 1 failed"
  exit 1
fi
