# The STM32F405 firmware image: cross build with reports, and the QEMU test.
#   make firmware        .elf/.bin/.hex/.map of every image, size report by module, stack report
#   make test-firmware   board driver unit tests (host) + the images under QEMU driven by dfp-sim
#   make firmware-measure  the real-time budgets on the target (QEMU instruction trace); part of
#                          make test: a budget exceeded fails the build
APT_PACKAGES += qemu-system-arm gcc-arm-none-eabi libnewlib-arm-none-eabi
EXTRA_TEST_TARGETS += test-firmware firmware-measure

FIRMWARE_DIR := build/cortex-m4/firmware/board/stm32f405

.PHONY: firmware test-firmware

firmware: deps-apt
	cmake --preset cortex-m4
	cmake --build build/cortex-m4

test-firmware: firmware build
	ctest --test-dir build/host $(CTEST_FLAGS) -R '^board_drivers$$'
	timeout 300 tests/firmware/qemu_card.sh $(FIRMWARE_DIR) build/host/sim_host/dfp_sim/dfp-sim

# Instruction counts of the reply path on the target (docs/performance.md, "On the target").
.PHONY: firmware-measure
firmware-measure: firmware build
	timeout 600 tests/firmware/measure_reply_path.sh $(FIRMWARE_DIR) build/host/sim_host/dfp_sim/dfp-sim build/measure
