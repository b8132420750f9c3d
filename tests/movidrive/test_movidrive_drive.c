/* Emulated MOVIDRIVE drive model: control word -> status word sequences, speed ramps in
 * simulated time, stop kinds, fault reset edge, P100/P101/P876 gating, fieldbus timeout (P831),
 * monitor values P090..P099 and P819, PO/PI assignments, IPOS data area. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "movidrive_test_util.h"

static movidrive_t md;
static hal_time_us_t now;

#define MS 1000u

static void fresh(void)
{
    movidrive_cfg_t cfg = {.eeprom = {0}, .terminal_enable = true};
    CHECK_EQ(movidrive_init(&md, &cfg, NULL, 0), 0);
    now = 0;
    movidrive_tick(&md, now);
}

/* Commissioning per protocol.md §B9: P100 = P101 = FIELDBUS (P876 is YES by default). */
static void fieldbus_mode(void)
{
    fresh();
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE,
                             MOVIDRIVE_SOURCE_FIELDBUS_SETPOINT, 1), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE,
                             MOVIDRIVE_SOURCE_FIELDBUS_CONTROL, 1), 0);
}

/* Advance simulated time in 1 ms ticks (or one big step). */
static void run_ms(uint32_t ms)
{
    for (uint32_t i = 0; i < ms; i++) {
        now += MS;
        movidrive_tick(&md, now);
    }
}

static int32_t speed(void)
{
    return (int32_t)movidrive_read(&md, MOVIDRIVE_IDX_SPEED);
}

static uint16_t sw(void)
{
    return movidrive_status_word(&md);
}

static void test_enable_and_ramp(void)
{
    fieldbus_mode();
    /* no PO yet: ready, PO data enabled, unit status 16 "waiting for data" */
    CHECK_EQ(sw(), 0x1006);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_STATUS), 0x1006);
    /* controller inhibit */
    movidrive_po3(&md, 0x0001, 1500, 0);
    CHECK_EQ(sw(), 0x0106);
    CHECK_EQ(movidrive_pi(&md, 0), 0x0106); /* PI1 = STATUS WORD1 */
    run_ms(50);
    CHECK_EQ(speed(), 0);
    /* enable 0x0006, speed 1500 = 300 rpm (protocol.md §B5 example) */
    movidrive_po3(&md, 0x0006, 1500, 0);
    CHECK_EQ(sw(), 0x0407); /* output stage, ready, PO enabled; unit status 4 enabled */
    CHECK_EQ(md.speed_setpoint_mrpm, 300000);
    CHECK_EQ(speed(), 0);
    /* P130 = 2000 ms per 3000 rpm: 1.5 rpm per ms */
    run_ms(100);
    CHECK_EQ(speed(), 150000);
    CHECK_EQ(movidrive_pi(&md, 1), 750);  /* PI2 = SPEED, 0.2 rpm per digit */
    CHECK_EQ(movidrive_pi(&md, 2), 300 + 20 + 400); /* PI3 current: 30 % + 2 % load + 40 % accel */
    run_ms(50);
    CHECK_EQ(speed(), 225000);
    run_ms(49);
    CHECK_EQ(speed(), 298500);
    run_ms(1);
    CHECK_EQ(speed(), 300000);
    run_ms(1);
    CHECK_EQ(speed(), 300000);
    CHECK_EQ(movidrive_pi(&md, 1), 1500);
    CHECK_EQ(movidrive_pi(&md, 2), 300 + 40); /* steady: magnetising + load */
    CHECK_EQ(movidrive_read(&md, 8321), 34000); /* P004 output current, 0.001 % */
    CHECK_EQ(movidrive_read(&md, 8319), 10000); /* P002 frequency: 300 rpm, 2 pole pairs = 10 Hz */
    /* a faster ramp, and one big time step instead of 1 ms ticks */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 1000, 0), 0);
    movidrive_po3(&md, 0x0006, 7500, 0); /* 1500 rpm */
    now += 200 * MS;
    movidrive_tick(&md, now);
    CHECK_EQ(speed(), 300000 + 600000);
    now += 1000 * MS;
    CHECK(movidrive_tick(&md, now) - now >= HAL_TIME_NO_DEADLINE_US - 1u);
    CHECK_EQ(speed(), 1500000);
    /* above P302 = 1500 rpm: limited */
    movidrive_po3(&md, 0x0006, 10000, 0);
    run_ms(100);
    CHECK_EQ(speed(), 1500000);
    CHECK_EQ(md.speed_setpoint_mrpm, 1500000);
    /* ramp down with P131 = 2000 ms */
    movidrive_po3(&md, 0x0006, 1500, 0);
    CHECK(movidrive_tick(&md, now) == now + MS); /* ramping: wants 1 ms ticks */
    run_ms(100);
    CHECK_EQ(speed(), 1500000 - 150000);
    now += 10 * 1000 * MS;
    movidrive_tick(&md, now);
    CHECK_EQ(speed(), 300000);
}

static void test_ccw_and_reversal(void)
{
    fieldbus_mode();
    CHECK_EQ(movidrive_write(&md, 8472, 1000, 0), 0); /* P132 up CCW */
    CHECK_EQ(movidrive_write(&md, 8473, 3000, 0), 0); /* P133 down CCW */
    movidrive_po3(&md, 0x0006, (uint16_t)-1500, 0);   /* -300 rpm */
    run_ms(50);
    CHECK_EQ(speed(), -150000); /* 3 rpm per ms */
    run_ms(100);
    CHECK_EQ(speed(), -300000);
    CHECK_EQ((int16_t)movidrive_pi(&md, 1), -1500);
    /* reversal: down along P133 (1 rpm/ms) to 0, then up CW along P130 (1.5 rpm/ms) */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(300);
    CHECK_EQ(speed(), 0);
    run_ms(100);
    CHECK_EQ(speed(), 150000);
    /* ramp set 2 (control word bit 4): P140/P141, status bit 3 */
    CHECK_EQ(movidrive_write(&md, 8478, 500, 0), 0); /* P140: 6 rpm per ms */
    movidrive_po3(&md, 0x0016, 3000, 0);             /* 600 rpm */
    CHECK_EQ(sw() & MOVIDRIVE_SW_RAMP_SET_2, MOVIDRIVE_SW_RAMP_SET_2);
    run_ms(10);
    CHECK_EQ(speed(), 210000);
    /* parameter set 2 bit mirrored in status bit 4 */
    movidrive_po3(&md, 0x0026, 3000, 0);
    CHECK_EQ(sw() & (MOVIDRIVE_SW_PARAM_SET_2 | MOVIDRIVE_SW_RAMP_SET_2), MOVIDRIVE_SW_PARAM_SET_2);
    /* ramp time 0: immediate */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 0, 0), 0);
    run_ms(1);
    CHECK_EQ(speed(), 600000);
}

static void test_stop_kinds(void)
{
    fieldbus_mode();
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(300);
    CHECK_EQ(speed(), 300000);
    /* stop (bit 2 = 0): process ramp P131, output stage on until 0, then "no enable" */
    movidrive_po3(&md, 0x0002, 1500, 0);
    CHECK_EQ(sw(), 0x0207);
    run_ms(100);
    CHECK_EQ(speed(), 150000);
    CHECK_EQ(sw() & MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED, MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED);
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0206);
    CHECK_EQ(movidrive_pi(&md, 2), 0); /* no current with the output stage off */
    /* stop again while standing: stays off */
    run_ms(10);
    CHECK_EQ(sw(), 0x0206);

    /* rapid stop (bit 1 = 0) uses P136 */
    CHECK_EQ(movidrive_write(&md, 8476, 1000, 0), 0); /* P136 = 1 s per 3000 rpm */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    CHECK_EQ(speed(), 300000);
    movidrive_po3(&md, 0x0004, 1500, 0);
    CHECK_EQ(sw(), 0x0207);
    run_ms(50);
    CHECK_EQ(speed(), 150000);
    run_ms(50);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0206);
    /* 0x0000 is rapid stop too */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    movidrive_po3(&md, 0x0000, 1500, 0);
    run_ms(50);
    CHECK_EQ(speed(), 150000);
    /* controller inhibit: output stage off at once */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    movidrive_po3(&md, 0x0007, 1500, 0);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0106);
    /* terminal DI00 open: inhibit whatever the bus says; P030 shows it */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    CHECK_EQ(movidrive_read(&md, 8334), 1);
    movidrive_set_terminal_enable(&md, false);
    CHECK_EQ(movidrive_read(&md, 8334), 0);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0106);
    run_ms(10);
    CHECK_EQ(sw(), 0x0106);
    movidrive_set_terminal_enable(&md, true);
    CHECK_EQ(sw(), 0x0407);
}

static ml_fieldbus_status_t fb(bool timeout)
{
    ml_fieldbus_status_t st = {.pd_config = 4, .pd_words = 3, .param_channel = true,
                               .baud = 1500000, .address = 4, .watchdog_ms = 120,
                               .prm_count = 1, .data_exchange = !timeout, .timeout = timeout};
    return st;
}

static void test_timeout_fault(void)
{
    fieldbus_mode();
    ml_fieldbus_status_t ok = fb(false), lost = fb(true);
    movidrive_fieldbus_status(&md, &ok);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION), 4); /* RAPID STOP/ERROR */
    CHECK_EQ(movidrive_write(&md, 8476, 1000, 0), 0);                  /* P136 */
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    CHECK_EQ(speed(), 300000);
    movidrive_fieldbus_status(&md, &lost);
    /* fault F28: bit 5, not ready, high byte 28; rapid stop with P136 */
    CHECK_EQ(sw(), 0x1C25);
    run_ms(50);
    CHECK_EQ(speed(), 150000);
    run_ms(50);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x1C24);
    CHECK_EQ(movidrive_read(&md, 8366), 28); /* P080 error t-0 */
    /* telegrams return: the fault stays */
    movidrive_fieldbus_status(&md, &ok);
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(10);
    CHECK_EQ(sw(), 0x1C24);
    CHECK_EQ(speed(), 0);
    /* the reset bit must rise: a control word arriving with bit 6 already set resets (0 -> 1
     * against the previous word); holding it does nothing more, and it is reset once */
    movidrive_po3(&md, 0x0046, 1500, 0);
    CHECK_EQ(md.fault, 0);
    CHECK_EQ(sw(), 0x0407);
    run_ms(200);
    CHECK_EQ(speed(), 300000);
    /* a reset while the bus is still down does not clear the fault */
    movidrive_po3(&md, 0x0006, 1500, 0);
    movidrive_fieldbus_status(&md, &lost);
    CHECK_EQ(md.fault, 28);
    movidrive_po3(&md, 0x0046, 1500, 0);
    CHECK_EQ(md.fault, 28);
    CHECK_EQ(movidrive_write(&md, 8617, 1, 0), 0); /* P840 manual reset: nor this */
    CHECK_EQ(md.fault, 28);
    movidrive_fieldbus_status(&md, &ok);
    movidrive_po3(&md, 0x0046, 1500, 0); /* bit 6 still high: no edge */
    CHECK_EQ(md.fault, 28);
    movidrive_po3(&md, 0x0006, 1500, 0);
    movidrive_po3(&md, 0x0046, 1500, 0); /* edge */
    CHECK_EQ(md.fault, 0);
    CHECK_EQ(movidrive_read(&md, 8367), 28); /* P081: the older one */

    /* P831 = 2 IMM. STOP/ERROR: output stage off at once */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 2, 1), 0);
    run_ms(300);
    CHECK_EQ(speed(), 300000);
    movidrive_fieldbus_status(&md, &lost);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x1C24);
    movidrive_fieldbus_status(&md, &ok);
    CHECK_EQ(movidrive_write(&md, 8617, 1, 0), 0); /* P840 manual reset, bus back */
    CHECK_EQ(sw(), 0x0407);

    /* P831 = 3 EMERG. STOP/ERROR: P137 */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 3, 1), 0);
    CHECK_EQ(movidrive_write(&md, 8477, 500, 0), 0); /* P137: 6 rpm per ms */
    run_ms(300);
    movidrive_fieldbus_status(&md, &lost);
    run_ms(25);
    CHECK_EQ(speed(), 150000);
    run_ms(25);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x1C24);
}

static void test_timeout_warning(void)
{
    fieldbus_mode();
    ml_fieldbus_status_t ok = fb(false), lost = fb(true);
    /* RAPID STOP/WARNG */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 7, 1), 0);
    CHECK_EQ(movidrive_write(&md, 8476, 1000, 0), 0);
    movidrive_fieldbus_status(&md, &ok);
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(200);
    movidrive_fieldbus_status(&md, &lost);
    /* warning: bit 5 and 28 in the high byte, but still ready */
    CHECK_EQ(sw(), 0x1C27);
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x1C26);
    CHECK_EQ(md.fault, 0);
    CHECK_EQ(movidrive_read(&md, 8366), 0); /* warnings are not in the fault memory */
    /* telegrams return: warning gone, the last process data act again */
    movidrive_fieldbus_status(&md, &ok);
    CHECK_EQ(sw(), 0x0407);
    run_ms(100);
    CHECK_EQ(speed(), 150000);

    /* P831 = 5 IMM. STOP/WARNG */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 5, 1), 0);
    movidrive_fieldbus_status(&md, &lost);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x1C26);
    movidrive_fieldbus_status(&md, &ok);
    CHECK_EQ(sw(), 0x0407);

    /* P831 = 1 DISPLAY ERROR: shown, the drive goes on */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 1, 1), 0);
    run_ms(300);
    movidrive_fieldbus_status(&md, &lost);
    run_ms(10);
    CHECK_EQ(speed(), 300000);
    CHECK_EQ(sw(), 0x1C27);
    movidrive_fieldbus_status(&md, &ok);
    CHECK_EQ(sw(), 0x0407);

    /* P831 = 0 NO RESPONSE */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION, 0, 1), 0);
    movidrive_fieldbus_status(&md, &lost);
    CHECK_EQ(sw(), 0x0407);
    movidrive_fieldbus_status(&md, &ok);
}

static void test_gating(void)
{
    /* factory setting: P100 = BIPOL/FIX, P101 = TERMINALS -> PO ignored, bit 2 clear */
    fresh();
    CHECK_EQ(sw(), 0x0202);
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0202);
    CHECK_EQ(movidrive_read(&md, 8455), 0x0006); /* P094 still shows what arrived */
    CHECK_EQ(movidrive_read(&md, 8456), 1500);
    /* P101 = FIELDBUS alone: PO data enabled (S3 logic: either source), control from the bus,
     * but no setpoint from it */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE, 2, 0), 0);
    CHECK_EQ(sw(), 0x0407); /* the PO received before count */
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(md.speed_setpoint_mrpm, 0);
    /* P100 = FIELDBUS, P101 = TERMINALS: bit 2 set, setpoint from the bus, no enable */
    movidrive_po3(&md, 0x0001, 1500, 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE, 0, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE, 3, 0), 0);
    CHECK_EQ(sw(), 0x0206);
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0206);
    /* both FIELDBUS, P876 = NO: ignored, bit 2 clear */
    movidrive_po3(&md, 0x0001, 0, 0);
    fieldbus_mode();
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 0, 0), 0);
    movidrive_po3(&md, 0x0006, 1500, 0);
    run_ms(100);
    CHECK_EQ(speed(), 0);
    CHECK_EQ(sw(), 0x0202);
    /* P876 = YES: acts */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 1, 0), 0);
    CHECK_EQ(sw(), 0x0407);
    run_ms(100);
    CHECK_EQ(speed(), 150000);
    /* changing P870..P872 sets P876 to NO (S5); only under controller inhibit / stage off */
    movidrive_po3(&md, 0x0001, 1500, 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 2, 0, 0), 0); /* same value: no change */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P876_PO_ENABLE), 1);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 2, 5, 0), 0); /* PO3 = MAX. SPEED */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P876_PO_ENABLE), 0);
    CHECK_EQ(sw() & MOVIDRIVE_SW_PO_DATA_ENABLED, 0);
}

static void test_assignments(void)
{
    fieldbus_mode();
    /* PO3 = MAX. SPEED: limits the setpoint */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 2, 5, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 1, 0), 0);
    movidrive_po3(&md, 0x0006, 5000, 500); /* 1000 rpm requested, max 100 rpm */
    CHECK_EQ(md.speed_setpoint_mrpm, 100000);
    movidrive_po3(&md, 0x0006, (uint16_t)-5000, 500);
    CHECK_EQ(md.speed_setpoint_mrpm, -100000);
    /* PO2 = SPEED [%]: 0x4000 = 100 % of P302 (1500 rpm) */
    movidrive_po3(&md, 0x0001, 0, 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 1, 11, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 2, 8, 0), 0); /* PO3 = RAMP (ms) */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 1, 0), 0);
    movidrive_po3(&md, 0x0006, 0x2000, 100); /* 50 % = 750 rpm, ramp 100 ms per 3000 rpm */
    CHECK_EQ(md.speed_setpoint_mrpm, 750000);
    run_ms(10);
    CHECK_EQ(speed(), 300000);
    run_ms(20);
    CHECK_EQ(speed(), 750000);
    /* PI: P873..P875 = SPEED [%], ACTIVE CURR., POSITION LO */
    movidrive_po3(&md, 0x0001, 0, 0);
    CHECK_EQ(movidrive_write(&md, 8307, 8, 0), 0);
    CHECK_EQ(movidrive_write(&md, 8308, 3, 0), 0);
    CHECK_EQ(movidrive_write(&md, 8309, 4, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 1, 1, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1 + 2, 0, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 1, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P130_RAMP_UP, 0, 0), 0);
    movidrive_po3(&md, 0x0006, 3750, 0); /* 750 rpm */
    run_ms(1);
    CHECK_EQ((int16_t)movidrive_pi(&md, 1), 500); /* active: 10 % load + 40 % while accelerating */
    run_ms(1);
    CHECK_EQ(movidrive_pi(&md, 0), 0x2000); /* 50 % */
    CHECK_EQ((int16_t)movidrive_pi(&md, 1), 100); /* active: 10 % load */
    int32_t pos0 = (int32_t)movidrive_read(&md, 8320);
    run_ms(1000);
    /* 750 rpm for 1 s = 12.5 revolutions x 4096 increments */
    CHECK_EQ((int32_t)movidrive_read(&md, 8320) - pos0, 51200);
    CHECK_EQ(movidrive_pi(&md, 2), (uint16_t)movidrive_read(&md, 8320));
    CHECK_EQ(movidrive_read(&md, 8458), 0x2000); /* P097 PI1 */
    CHECK_EQ(movidrive_read(&md, 8460), movidrive_pi(&md, 2));
    /* STATUS WORD 2/3: the basic block */
    /* P873 while running */
    CHECK_EQ(movidrive_write(&md, 8307, 7, 0), ML_ADD_OUTPUT_STAGE_ENABLED);
    movidrive_po3(&md, 0x0001, 0, 0);
    CHECK_EQ(movidrive_write(&md, 8307, 7, 0), 0);
    CHECK_EQ(movidrive_pi(&md, 0), 0x0006);
}

static void test_monitor_values(void)
{
    fieldbus_mode();
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P090), 4); /* CSV default before the card reports */
    CHECK_EQ(movidrive_read(&md, 8452), 0);        /* P091: no fieldbus yet */
    /* A card not yet parameterised (prm_count 0) leaves the drive's own P819 alone. */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT, 700, 1), 0);
    ml_fieldbus_status_t st = fb(false);
    st.prm_count = 0;
    st.watchdog_ms = 0;
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 700);
    CHECK_EQ(movidrive_read(&md, 8454), 4); /* the monitor values are taken */
    st = fb(false);
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P090), 4);
    CHECK_EQ(movidrive_read(&md, 8452), 5);       /* PROFIBUS DP */
    CHECK_EQ(movidrive_read(&md, 8453), 1500000); /* P092 baud (conversion -3: kBaud) */
    CHECK_EQ(movidrive_read(&md, 8454), 4);       /* P093 address */
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 120);
    /* P819 written elsewhere: shown until the master's next parameterisation, however often
     * the card reports other changes (baud, data exchange, timeout) in between */
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT, 300, 1), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 300);
    st.data_exchange = false;
    movidrive_fieldbus_status(&md, &st);
    st.baud = 500000;
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 300);
    CHECK_EQ(movidrive_read(&md, 8453), 500000);
    /* the same watchdog time at the next Set_Prm still overwrites it */
    st.prm_count++;
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 120);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT, 300, 1), 0);
    st.watchdog_ms = 250;
    st.prm_count++;
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 250);
    /* no valid configuration: "0PD" is shown as 255 */
    st.pd_config = 255;
    st.pd_words = 0;
    movidrive_fieldbus_status(&md, &st);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P090), 255);
    /* P094..P099 */
    movidrive_po3(&md, 0x0006, 0x1234, 0xBEEF);
    CHECK_EQ(movidrive_read(&md, 8455), 0x0006);
    CHECK_EQ(movidrive_read(&md, 8456), 0x1234);
    CHECK_EQ(movidrive_read(&md, 8457), 0xBEEF);
    CHECK_EQ(movidrive_read(&md, 8458), sw());
    CHECK_EQ(movidrive_read(&md, 8459), movidrive_pi(&md, 1));
    CHECK_EQ(movidrive_read(&md, 8460), movidrive_pi(&md, 2));
    /* the factory setting keeps the card's values */
    movidrive_po3(&md, 0x0001, 0, 0);
    CHECK_EQ(movidrive_factory_reset(&md), 0);
    CHECK_EQ(movidrive_read(&md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT), 250);
    CHECK_EQ(movidrive_read(&md, 8454), 4);
}

static void test_ipos_area(void)
{
    fieldbus_mode();
    uint16_t po[10] = {0x0006, 100, 200, 4, 5, 6, 7, 8, 9, 10};
    movidrive_process_outputs(&md, po, 10);
    CHECK_EQ(md.ipos_po[0], 0x0006);
    CHECK_EQ(md.ipos_po[3], 4);
    CHECK_EQ(md.ipos_po[9], 10);
    CHECK_EQ(md.speed_setpoint_mrpm, 100 * 200); /* PO4..PO10 do not act on the drive */
    for (int i = 0; i < 10; i++) {
        md.ipos_pi[i] = (uint16_t)(0xA000 + i);
    }
    uint16_t pi[10];
    movidrive_process_inputs(&md, pi, 10);
    CHECK_EQ(pi[0], sw());
    CHECK_EQ(pi[3], 0xA003);
    CHECK_EQ(pi[9], 0xA009);
    /* PO1 = IPOS PO-DATA, PI3 = IPOS PI-DATA */
    movidrive_po3(&md, 0x0001, 0, 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P870_PO1, 12, 0), 0);
    CHECK_EQ(movidrive_write(&md, 8309, 9, 0), 0);
    CHECK_EQ(movidrive_write(&md, MOVIDRIVE_IDX_P876_PO_ENABLE, 1, 0), 0);
    movidrive_po3(&md, 0x4321, 1500, 0);
    CHECK_EQ(md.ipos_po[0], 0x4321);
    CHECK_EQ(md.control_word, 0); /* no control word assigned: no enable */
    CHECK_EQ(sw() >> 8, MOVIDRIVE_UNIT_NO_ENABLE);
    CHECK_EQ(movidrive_pi(&md, 2), 0xA002);
    /* fewer words: the rest reads 0 */
    movidrive_process_outputs(&md, po, 2);
    CHECK_EQ(md.ipos_po[2], 0);
    CHECK_EQ(movidrive_read(&md, 8457), 0);
}

int main(void)
{
    RUN_TEST(test_enable_and_ramp);
    RUN_TEST(test_ccw_and_reversal);
    RUN_TEST(test_stop_kinds);
    RUN_TEST(test_timeout_fault);
    RUN_TEST(test_timeout_warning);
    RUN_TEST(test_gating);
    RUN_TEST(test_assignments);
    RUN_TEST(test_monitor_values);
    RUN_TEST(test_ipos_area);
    return check_report();
}
