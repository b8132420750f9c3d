/* The emulated MOVIDRIVE's control: where the control word and the setpoint come from (P100,
 * P101, P870..P872, P876), the drive mode they and a fault or warning give, and faults (latch,
 * error memory P080..P084, reset). README.md "Drive model". */
#include "movidrive_internal.h"

bool movidrive_po_data_enabled(const movidrive_t *md)
{
    return movidrive_ram_value(md, MOVIDRIVE_IDX_P876_PO_ENABLE) == 1 &&
           (movidrive_ram_value(md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE) ==
                MOVIDRIVE_SOURCE_FIELDBUS_SETPOINT ||
            movidrive_ram_value(md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE) ==
                MOVIDRIVE_SOURCE_FIELDBUS_CONTROL);
}

bool movidrive_cw_in_effect(const movidrive_t *md)
{
    return movidrive_ram_value(md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE) ==
               MOVIDRIVE_SOURCE_FIELDBUS_CONTROL &&
           movidrive_po_data_enabled(md) && md->po_received;
}

bool movidrive_po_word(const movidrive_t *md, int32_t function, uint16_t *word)
{
    for (uint8_t i = 0; i < 3 && i < md->po_count; i++) {
        if (movidrive_ram_value(md, (uint16_t)(MOVIDRIVE_IDX_P870_PO1 + i)) == function) {
            *word = md->po[i];
            return true;
        }
    }
    return false;
}

bool movidrive_ramp_set_2(const movidrive_t *md)
{
    return movidrive_cw_in_effect(md) && (md->control_word & MOVIDRIVE_CW_RAMP_SET_2);
}

uint16_t movidrive_compute_control_word(const movidrive_t *md)
{
    if (!movidrive_cw_in_effect(md)) {
        return 0;
    }
    uint16_t w;
    if (movidrive_po_word(md, PO_CTRL_WORD_1, &w)) {
        return w;
    }
    if (movidrive_po_word(md, PO_CTRL_WORD_2, &w)) {
        return (uint16_t)(w & 0x00FFu); /* basic block; high byte: virtual terminals (ignored) */
    }
    return 0; /* no control word assigned: no enable */
}

static int32_t max_speed_mrpm(const movidrive_t *md)
{
    int32_t nmax = movidrive_ram_value(md, MOVIDRIVE_IDX_P302_MAX_SPEED);
    uint16_t w;
    if (movidrive_po_data_enabled(md) && md->po_received &&
        movidrive_po_word(md, PO_MAX_SPEED, &w)) {
        int32_t po_max = (int32_t)(int16_t)w * 200;
        if (po_max >= 0 && po_max < nmax) {
            nmax = po_max;
        }
    }
    return nmax;
}

static int32_t compute_setpoint(const movidrive_t *md)
{
    if (movidrive_ram_value(md, MOVIDRIVE_IDX_P100_SETPOINT_SOURCE) !=
            MOVIDRIVE_SOURCE_FIELDBUS_SETPOINT ||
        !movidrive_po_data_enabled(md) || !md->po_received) {
        return 0; /* other sources (analog, fixed setpoints via terminals) are not emulated */
    }
    int32_t nmax = max_speed_mrpm(md);
    int64_t n = 0;
    uint16_t w;
    if (movidrive_po_word(md, PO_SPEED, &w)) {
        n = (int64_t)(int16_t)w * 200;
    } else if (movidrive_po_word(md, PO_SPEED_PERCENT, &w)) {
        n = (int64_t)(int16_t)w * movidrive_ram_value(md, MOVIDRIVE_IDX_P302_MAX_SPEED) / 0x4000;
    }
    if (n > nmax) {
        n = nmax;
    }
    if (n < -(int64_t)nmax) {
        n = -(int64_t)nmax;
    }
    return (int32_t)n;
}

static uint8_t reaction_mode(uint8_t reaction)
{
    switch (reaction) {
    case REACT_IMM_ERROR:
    case REACT_IMM_WARN:
        return MODE_IMMEDIATE;
    case REACT_EMERG_ERROR:
    case REACT_EMERG_WARN:
        return MODE_EMERGENCY;
    case REACT_RAPID_ERROR:
    case REACT_RAPID_WARN:
        return MODE_RAPID;
    default:
        return MODE_RUN;
    }
}

static uint8_t compute_mode(const movidrive_t *md)
{
    uint16_t cw = md->control_word;
    bool bus = movidrive_cw_in_effect(md);
    if (!md->cfg.terminal_enable || (bus && (cw & MOVIDRIVE_CW_CONTROLLER_INHIBIT))) {
        return MODE_INHIBIT;
    }
    uint8_t mode = MODE_RUN;
    if (md->fault != 0) {
        mode = reaction_mode(md->fault_reaction);
    } else if (md->warning) {
        mode = reaction_mode(md->warning_reaction);
    }
    if (mode != MODE_RUN) {
        return mode;
    }
    if (!bus) {
        /* P101 = TERMINALS (DI01..DI05 not wired in the emulation), or PO not (yet) enabled */
        return MODE_STOP;
    }
    if (!(cw & MOVIDRIVE_CW_ENABLE_RAPID_STOP)) {
        return MODE_RAPID;
    }
    if (!(cw & MOVIDRIVE_CW_ENABLE_STOP)) {
        return MODE_STOP;
    }
    return MODE_RUN;
}

void movidrive_evaluate(movidrive_t *md)
{
    md->control_word = movidrive_compute_control_word(md);
    md->mode = compute_mode(md);
    switch (md->mode) {
    case MODE_INHIBIT:
    case MODE_IMMEDIATE:
        md->output_stage_enabled = false;
        md->speed_actual_mrpm = 0;
        md->speed_setpoint_mrpm = 0;
        md->ramp_residue = 0;
        break;
    case MODE_RUN:
        md->output_stage_enabled = true;
        md->speed_setpoint_mrpm = compute_setpoint(md);
        break;
    default: /* stop kinds: ramp to 0 if running, then the output stage goes off */
        md->speed_setpoint_mrpm = 0;
        if (md->speed_actual_mrpm == 0) {
            md->output_stage_enabled = false;
        }
        break;
    }
    movidrive_update_currents(md);
}

/* ---------------------------------------------------------------------------------------------
 * Faults */

/* Error memory: P080 = the newest fault, older ones move down to P084; kept in EEPROM. */
static void record_fault(movidrive_t *md, uint8_t number)
{
    int first = movidrive_find_def(md, IDX_P080_ERROR_T0);
    int last = movidrive_find_def(md, IDX_P084_ERROR_T4);
    if (first < 0 || last < first) {
        return;
    }
    for (int k = last; k > first; k--) {
        md->ram[k] = md->ram[k - 1];
        md->ee[k] = md->ee[k - 1];
    }
    md->ram[first] = number;
    md->ee[first] = number;
    (void)movidrive_ee_save_params(md, (size_t)first, (size_t)last);
}

void movidrive_raise_fault(movidrive_t *md, uint8_t number, uint8_t reaction)
{
    if (md->fault != 0) {
        return;
    }
    md->fault = number;
    md->fault_reaction = reaction;
    record_fault(md, number);
}

void movidrive_inject_fault(movidrive_t *md, uint8_t number)
{
    if (number == 0u) {
        return;
    }
    movidrive_raise_fault(md, number, REACT_IMM_ERROR);
    movidrive_evaluate(md);
}

void movidrive_fault_reset(movidrive_t *md)
{
    if (md->fault == MOVIDRIVE_FAULT_FIELDBUS_TIMEOUT && md->fieldbus_timeout) {
        return; /* the cause is still there */
    }
    md->fault = 0;
    md->fault_reaction = 0;
}
