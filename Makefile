# Front door. `make demo` and `make test` work on a fresh Debian machine: they install what is
# missing (apt-get when root, pip into a local venv), configure and build first.
#
#   make demo      the simulated card and a DP master on an in-memory bus (no hardware)
#   make test      everything CI runs: host tests, sanitizer tests, Cortex-M4 cross build,
#                  interoperability with pyprofibus
#   make build     host build only
#   make bench     the benchmark program (figures for docs/performance.md)

SHELL := /bin/bash
APT_PACKAGES := cmake ninja-build gcc make python3 socat gcc-arm-none-eabi libnewlib-arm-none-eabi \
  qemu-system-x86 busybox-static cpio iproute2
# Each capability adds its own packages, build steps and test targets in mk/*.mk:
#   APT_PACKAGES += ...      EXTRA_TEST_TARGETS += target
EXTRA_TEST_TARGETS :=
-include mk/*.mk

VENV := build/venv
PYTHON := $(VENV)/bin/python3
CTEST_FLAGS := --output-on-failure --timeout 300

.PHONY: all deps deps-apt deps-python build demo test test-host test-asan cross bench clean

all: build

deps: deps-apt deps-python

deps-apt:
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  if [ "$$(id -u)" = 0 ]; then \
	    echo "installing:$$missing"; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
	  else \
	    echo "missing Debian packages:$$missing (run as root or install them)"; exit 1; \
	  fi; \
	fi

# pyprofibus is the independent DP master of the interoperability tests; pytest runs the Python
# client's tests (python/, installed editable), selenium drives chromium for the panel test,
# lizard measures function lengths for the repository's size limits (tests/repo), lcm is LCM 1.5
# (liblcm, its headers, lcm-gen, lcm-logger, the Python module; cmake/dfp_lcm.cmake); the
# editable install of python/ puts its console script dfp-lcm-view into $(VENV)/bin. The
# stamp's number goes up whenever this list or that script list changes, so an older venv is
# topped up.
VENV_STAMP := $(VENV)/.deps-5
$(VENV_STAMP):
	@mkdir -p build
	[ -x $(PYTHON) ] || python3 -m venv $(VENV) || { apt-get install -y -qq python3-venv && python3 -m venv $(VENV); }
	$(VENV)/bin/pip install -q --disable-pip-version-check pyprofibus==1.13 pyserial \
	  pytest==8.3.4 selenium==4.27.1 lizard==1.17.13 lcm==1.5.3
	$(VENV)/bin/pip install -q --disable-pip-version-check -e ./python
	touch $@

deps-python: $(VENV_STAMP)

build: deps
	cmake --preset host -DDFP_PYTHON=$(abspath $(PYTHON)) -DDFP_REQUIRE_INTEROP=ON -DDFP_REQUIRE_TSHARK=ON
	cmake --build build/host

demo: build
	./build/host/sim_host/dfp_sim/dfp-sim demo

test-host: build
	ctest --test-dir build/host $(CTEST_FLAGS)

test-asan: deps
	cmake --preset asan -DDFP_PYTHON=$(abspath $(PYTHON)) -DDFP_REQUIRE_INTEROP=ON -DDFP_REQUIRE_TSHARK=ON
	cmake --build build/asan
	ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	  ctest --test-dir build/asan $(CTEST_FLAGS)

cross: deps-apt
	cmake --preset cortex-m4
	cmake --build build/cortex-m4

test: test-host test-asan cross $(EXTRA_TEST_TARGETS)
	@echo "make test: host, sanitizer and Cortex-M4 builds$(if $(EXTRA_TEST_TARGETS), and $(EXTRA_TEST_TARGETS),) all passed"

bench: build
	./build/host/sim_host/bench/dfp-bench

clean:
	rm -rf build
