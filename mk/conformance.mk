# The conformance suite's example report (docs/conformance.md): the card in process at every
# rate its DP-V1 GSD claims, as HTML in docs/.
.PHONY: conformance-report
conformance-report: build
	build/host/sim_host/dfp_sim/dfp-sim conformance --card --address 4 \
	  --gsd firmware/gsd/SEWA6003.GSD --baud all --report html docs/conformance-dfp21b.html
