# Static analysis, warnings, coverage (docs/quality.md "Static analysis, warnings,
# coverage"). The warning flags themselves are DFP_WARNINGS in CMakeLists.txt (-Werror in every
# build). Both targets run in `make test` and so in CI.
#
#   make lint       cppcheck + clang-tidy on dp_slave dpv1 movilink firmware/dfp21b hal sim_host
#                   (.clang-tidy, sim_host/.clang-tidy, tools/quality/cppcheck-suppressions.txt);
#                   fails on any finding
#   make coverage   gcovr of dp_slave dpv1 movilink firmware/dfp21b from the host tests in
#                   build/coverage; fails below 90 % lines / 80 % branches (total and per directory)

APT_PACKAGES += cppcheck clang-tidy gcovr
EXTRA_TEST_TARGETS += lint coverage

.PHONY: lint coverage

lint: deps
	tools/quality/lint.sh

coverage: deps
	COVERAGE_CMAKE_ARGS="-DDFP_PYTHON=$(abspath $(PYTHON))" tools/quality/coverage.sh
