# The conformance suite's example report (docs/conformance.md): the card in process at 1.5 Mbit/s
# with its DP-V1 GSD, as HTML in docs/ (--baud all would give every rate the GSD claims).
.PHONY: conformance-report
conformance-report: build
	build/host/sim_host/dfp_sim/dfp-sim conformance --card --address 4 \
	  --gsd firmware/gsd/SEWA6003.GSD --baud 1.5M --report html docs/conformance-dfp21b.html
