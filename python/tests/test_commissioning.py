"""Commissioning checklist: MOVIDRIVE with DFP21B at PROFIBUS address 4, "Param + 3 PD".

The PLC is `dfp-sim master` (DP master 2, 19200 bit/s, configuration F3 F2 = 8 octets
MOVILINK parameter channel + 3 process data words), the card and its drive are
`dfp-sim slave --address 4` with a drive at factory settings; the two are wired with a PTY pair.
The steps run top to bottom and build on each other: once one fails, the rest are skipped.

 1. Start-up: the card finds the baud rate and reaches Data_Exch; RUN on, BUS FAULT off.
 2. Controller inhibit (PO1 = 0x0001) while parameterising.
 3. P100 setpoint source = FIELDBUS and P101 control signal source = FIELDBUS, by name,
    through the cyclic parameter channel; read back: "3 (FIELDBUS)" and "2 (FIELDBUS)".
 4. Read the ramp time P130, enable (PO1 = 0x0006) with PO2 = 1500 (x 0.2 rpm = 300 rpm):
    the motor reaches 300 rpm within the ramp time; status word 0x0407, PI2 = 1500.
 5. Pull the PROFIBUS connector: within the DP watchdog time the card leaves Data_Exch,
    BUS FAULT lights, the drive trips with fault 28 "fieldbus timeout" and stops.
 6. Plug it back: Data_Exch again, BUS FAULT off; fault 28 stays until it is reset.
 7. Fault reset by a rising edge of control word bit 6 (0x0046, then 0x0006): fault 0, the
    drive runs up to 300 rpm again.
 8. DI00 (/CONTROLLER INHIBIT) to 0 V: the drive is inhibited and the speed goes to 0.

Run it:  pytest python/tests/test_commissioning.py --dfp-sim build/host/sim_host/dfp_sim/dfp-sim
"""

import time

import pytest

from dfpsim import wait_for, wait_until

pytestmark = pytest.mark.incremental

SLAVE = 4                # PROFIBUS address (DIP switches)
MASTER = 2               # the PLC's address
BAUD = 19200
SPEED_DIGITS = 1500      # PO2 in 0.2 rpm: 300 rpm
SPEED_RPM = 300.0
MARGIN_S = 1.0           # on top of every time the drive or the card promises
START_UP_S = 10.0        # baud search and start-up by the master

# Control word 1 (PO1), status word 1 (PI1): MOVIDRIVE fieldbus profile
CW_INHIBIT = 0x0001      # bit 0: controller inhibit
CW_ENABLE = 0x0006       # bits 1, 2: enable / rapid stop, enable / stop
CW_RESET = 0x0040        # bit 6: fault reset on the rising edge
SW_OUTPUT_STAGE = 0x0001
SW_READY = 0x0002
SW_PO_ENABLED = 0x0004
SW_FAULT = 0x0020


@pytest.fixture(scope="module")
def drive(bus):
    """The card at address 4 with its MOVIDRIVE, as the simulator shows them."""
    return bus.slave.card(SLAVE)


@pytest.fixture(scope="module")
def plc(bus):
    """The DP master: process data and parameter services, as a PLC program does them."""
    return bus.master.master()


def test_1_start_up_reaches_data_exchange(drive, plc):
    wait_until(lambda: drive.dp_state == "Data_Exch", timeout=START_UP_S,
               what="card 4 in Data_Exch")
    wait_until(lambda: plc.in_data_exchange(SLAVE), timeout=2,
               what="the master exchanging data with slave 4")
    dp = drive.dp
    assert dp["state"] == "Data_Exch"
    assert dp["master"] == MASTER
    assert dp["baud"] == BAUD
    assert dp["config"] == "F3F2"
    # The LEDs need one more snapshot after Data_Exch at most.
    wait_until(lambda: drive.leds["bus_fault"] == "off", timeout=1, what="BUS FAULT off")
    assert drive.leds["run"] == "on"
    assert drive.fault == 0
    assert drive.fault_name == "no fault"


def test_2_controller_inhibit_while_parameterising(drive, plc):
    plc.set_po(SLAVE, [CW_INHIBIT, 0, 0])
    wait_until(lambda: plc.po(SLAVE) == [CW_INHIBIT, 0, 0], timeout=1, what="PO = 0001 0 0")
    wait_until(lambda: drive.monitor["po"] == [CW_INHIBIT, 0, 0], timeout=1,
               what="the card passing PO 0001 0 0 to the drive")
    assert drive.speed_actual_rpm == 0.0
    assert drive.enabled is False


def test_3_setpoint_and_control_source_fieldbus(drive, plc):
    # Written by name through the cyclic 8-octet parameter channel, non-volatile.
    p100 = plc.write_param(SLAVE, "P100", "FIELDBUS", via="channel")
    assert (p100.p_number, p100.index) == ("P100", 8461)
    assert p100.text == "3 (FIELDBUS)"
    p101 = plc.write_param(SLAVE, "P101", "FIELDBUS", via="channel")
    assert (p101.p_number, p101.index) == ("P101", 8462)
    assert p101.text == "2 (FIELDBUS)"
    # Read back, as a separate service each.
    assert plc.read_param(SLAVE, "P100", via="channel").text == "3 (FIELDBUS)"
    assert plc.read_param(SLAVE, "P101", via="channel").text == "2 (FIELDBUS)"
    assert plc.read_param(SLAVE, "P100", via="channel").value == 3
    assert plc.read_param(SLAVE, "P101", via="channel").value == 2
    # The drive itself agrees (read directly, not over the bus).
    assert drive.read_param("P100").text == "3 (FIELDBUS)"
    assert drive.read_param("P101").text == "2 (FIELDBUS)"


def test_4_enable_and_run_up_to_300_rpm(drive, plc):
    ramp = plc.read_param(SLAVE, "P130", via="channel")   # ramp t11 up, ms per 3000 rpm
    assert ramp.p_number == "P130"
    ramp_ms = ramp.value
    assert ramp_ms == drive.ramp_up_ms
    plc.set_po(SLAVE, [CW_ENABLE, SPEED_DIGITS, 0])
    t0 = time.monotonic()
    rpm = wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm >= SPEED_RPM - 0.5,
                   timeout=ramp_ms / 1000.0 + MARGIN_S,
                   what="speed >= 299.5 rpm within P130 = %d ms + %.0f s" % (ramp_ms, MARGIN_S))
    print("300 rpm reached after %.2f s (%.1f rpm)" % (time.monotonic() - t0, rpm))
    assert drive.speed_setpoint_rpm == SPEED_RPM
    assert drive.enabled is True
    assert drive.control_word == CW_ENABLE
    wait_until(lambda: drive.speed_actual_rpm == SPEED_RPM, timeout=1, what="exactly 300.0 rpm")
    # Status word 1 = 0x0407: output stage enabled, ready, PO data enabled, unit status 4.
    wait_until(lambda: drive.status_word == 0x0407, timeout=1, what="status word 0x0407")
    # The PLC sees the same in PI1 (status word) and PI2 (actual speed, 0.2 rpm).
    wait_until(lambda: plc.pi(SLAVE)[:2] == [0x0407, SPEED_DIGITS], timeout=1,
               what="PI1 = 0x0407, PI2 = 1500 at the master")


def test_5_cable_pulled_fieldbus_timeout(drive, plc):
    watchdog_ms = drive.watchdog_ms
    assert watchdog_ms > 0, "the master must parameterise the DP watchdog"
    drive.pull_cable()
    t0 = time.monotonic()
    assert drive.cable is False
    wait_until(lambda: drive.dp_state != "Data_Exch", timeout=watchdog_ms / 1000.0 + MARGIN_S,
               what="card leaving Data_Exch within the watchdog (%d ms)" % watchdog_ms)
    elapsed = time.monotonic() - t0
    # Not before the watchdog time either (less one bus cycle and the 50 ms snapshot).
    assert elapsed >= watchdog_ms / 1000.0 - 0.2, "left Data_Exch after %.3f s" % elapsed
    assert drive.dp_state == "Wait_Prm"
    assert drive.master_address is None
    wait_until(lambda: drive.fault == 28, timeout=MARGIN_S, what="drive fault 28")
    assert drive.fault_name == "fieldbus timeout"
    assert drive.status_word & SW_FAULT
    assert drive.status_word >> 8 == 28      # with bit 5 set, the high byte is the fault
    assert drive.leds["bus_fault"] == "on"
    assert drive.leds["run"] == "on"
    # P831 (factory setting: RAPID STOP/FAULT): the motor stops.
    wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm == 0.0,
             timeout=drive.ramp_down_ms / 1000.0 + MARGIN_S, what="motor stopped")
    assert drive.enabled is False
    # The master has lost the slave as well.
    wait_until(lambda: not plc.in_data_exchange(SLAVE), timeout=MARGIN_S,
               what="the master noticing slave 4 is gone")


def test_6_cable_plugged_back_data_exchange_again(drive, plc):
    drive.plug_cable()
    assert drive.cable is True
    wait_until(lambda: drive.dp_state == "Data_Exch", timeout=START_UP_S,
               what="card 4 back in Data_Exch")
    wait_until(lambda: plc.in_data_exchange(SLAVE), timeout=2, what="master in data exchange")
    assert drive.master_address == MASTER
    wait_until(lambda: drive.leds["bus_fault"] == "off", timeout=1, what="BUS FAULT off")
    # The fault is latched: the drive stays off until the PLC resets it.
    assert drive.fault == 28
    assert drive.fault_name == "fieldbus timeout"
    assert drive.speed_actual_rpm == 0.0


def test_7_fault_reset_by_control_word_bit_6(drive, plc):
    plc.set_po(SLAVE, [CW_RESET | CW_ENABLE, SPEED_DIGITS, 0])     # 0x0046: rising edge
    wait_until(lambda: drive.control_word == CW_RESET | CW_ENABLE, timeout=1,
               what="control word 0x0046 at the drive")
    plc.set_po(SLAVE, [CW_ENABLE, SPEED_DIGITS, 0])                # 0x0006
    wait_until(lambda: drive.fault == 0, timeout=1, what="fault reset")
    assert drive.fault_name == "no fault"
    wait_until(lambda: drive.control_word == CW_ENABLE, timeout=1,
               what="control word 0x0006 at the drive")
    assert not drive.status_word & SW_FAULT
    wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm >= SPEED_RPM - 0.5,
             timeout=drive.ramp_up_ms / 1000.0 + MARGIN_S, what="300 rpm again after the reset")


def test_8_di00_off_stops_the_drive(drive, plc):
    assert drive.inputs["DI00"] is True
    drive.set_input("DI00", False)
    assert drive.inputs["DI00"] is False
    wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm == 0.0,
             timeout=drive.ramp_down_ms / 1000.0 + MARGIN_S, what="speed 0 with DI00 off")
    assert drive.enabled is False
    sw = drive.status_word
    assert not sw & SW_OUTPUT_STAGE
    assert not sw & SW_FAULT
    assert sw >> 8 == 1, "unit status 1 (controller inhibit), status word 0x%04X" % sw
    # The bus is not affected.
    assert drive.dp_state == "Data_Exch"
    assert drive.fault == 0
