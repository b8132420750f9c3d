# libFuzzer targets (tests/fuzz/README.md): clang 14 with -fsanitize=fuzzer,address,undefined,
# a separate CMake build in build/fuzz that the gcc host build never sees.
#
#   make fuzz-smoke   what CI runs: every target over its regression corpus and the findings'
#                     reproducers, then FUZZ_SECONDS (30) of fuzzing each; any finding fails
#   make fuzz-long    FUZZ_RUNS (10^8) executions per target, shared by FUZZ_JOBS processes;
#                     corpora and artifacts in build/fuzz/long/, one line per run appended to
#                     build/fuzz/long/summary.txt (tests/fuzz/long_run.sh)
#   make fuzz-known   each reproducer in tests/fuzz/known/ with its own property named
#                     (FUZZ_KNOWN=name, which includes the opt-in strict forms); fails if any does
#   make fuzz-seeds   seed corpora from `dfp-sim demo --capture`, tests/fuzz/captures/*.pcap and
#                     protocol.md §A1.6

APT_PACKAGES += clang-14 libclang-rt-14-dev libpcap-dev
EXTRA_TEST_TARGETS += fuzz-smoke

FUZZ_BUILD := build/fuzz
FUZZ_LONG := $(FUZZ_BUILD)/long
FUZZ_TARGETS := fdl_rx fdl_collect card movilink dpv1 ds47 capture
FUZZ_SECONDS ?= 30
FUZZ_RUNS ?= 100000000
FUZZ_MAX_LEN ?= 2048
FUZZ_JOBS ?= 1
FUZZ_TRACE_CMP ?= ON
FUZZ_BIN := $(if $(filter OFF,$(FUZZ_TRACE_CMP)),build/fuzz-nocmp,$(FUZZ_BUILD))

.PHONY: fuzz-build fuzz-smoke fuzz-long fuzz-known fuzz-seeds

fuzz-build: deps
	cmake -S tests/fuzz -B $(FUZZ_BIN) -G Ninja -DCMAKE_C_COMPILER=clang-14 \
	  -DFUZZ_TRACE_CMP=$(FUZZ_TRACE_CMP)
	cmake --build $(FUZZ_BIN)

fuzz-smoke: fuzz-build
	@set -eo pipefail; for t in $(FUZZ_TARGETS); do \
	  work=$(FUZZ_BUILD)/smoke/$$t; rm -rf $$work; mkdir -p $$work/corpus $$work/artifacts; \
	  echo "== fuzz_$$t: regression corpus and known-finding reproducers"; \
	  ./$(FUZZ_BIN)/fuzz_$$t -runs=0 -artifact_prefix=$$work/artifacts/ tests/fuzz/corpus/$$t 2>&1 | tail -n 2; \
	  if [ -d tests/fuzz/known/$$t ]; then \
	    ./$(FUZZ_BIN)/fuzz_$$t -artifact_prefix=$$work/artifacts/ tests/fuzz/known/$$t/* 2>&1 | grep -c "^Executed"; fi; \
	  echo "== fuzz_$$t: $(FUZZ_SECONDS) s of fuzzing"; \
	  ./$(FUZZ_BIN)/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -max_len=$(FUZZ_MAX_LEN) \
	    -timeout=10 -print_final_stats=1 -artifact_prefix=$$work/artifacts/ \
	    $$work/corpus tests/fuzz/corpus/$$t 2>&1 | grep -E "^stat::(number_of_executed|average_exec)|ERROR|PROPERTY|SUMMARY" ; \
	  if [ -n "$$(ls $$work/artifacts)" ]; then echo "fuzz_$$t: finding in $$work/artifacts"; exit 1; fi; \
	done; echo "fuzz-smoke: $(words $(FUZZ_TARGETS)) targets, no finding"

# One target: make fuzz-long FUZZ_TARGETS=card FUZZ_RUNS=1000000 (tests/fuzz/long_run.sh)
# FUZZ_JOBS=N: N libFuzzer processes share the executions on one corpus directory.
# FUZZ_TRACE_CMP=OFF: binaries without comparison tracing, in their own build directory
# (build/fuzz-nocmp); corpora and summary stay in build/fuzz/long either way.
fuzz-long: fuzz-build
	tests/fuzz/long_run.sh $(FUZZ_BIN) $(FUZZ_LONG) $(FUZZ_RUNS) $(FUZZ_JOBS) $(FUZZ_MAX_LEN) $(FUZZ_TARGETS)

fuzz-known: fuzz-build
	@set -e; bad=0; for d in tests/fuzz/known/*/; do t=$$(basename $$d); \
	  for f in $$d*; do name=$$(basename $$f | sed 's/-[^-]*$$//'); \
	    if FUZZ_KNOWN=$$name ./$(FUZZ_BIN)/fuzz_$$t -artifact_prefix=$(FUZZ_BUILD)/ $$f >$(FUZZ_BUILD)/known.log 2>&1; then \
	      echo "$$t/$$(basename $$f): holds"; \
	    else bad=1; echo "$$t/$$(basename $$f): FAILS: $$(grep -A1 'PROPERTY VIOLATED' $(FUZZ_BUILD)/known.log | tail -n 1)"; fi; \
	  done; done; exit $$bad

fuzz-seeds: build
	./build/host/sim_host/dfp_sim/dfp-sim demo --capture $(FUZZ_BUILD)/demo.pcap >/dev/null
	python3 tests/fuzz/pcap2corpus.py $(FUZZ_BUILD)/seeds $(FUZZ_BUILD)/demo.pcap tests/replay/golden/*.pcap \
	  tests/fuzz/captures/*.pcap
