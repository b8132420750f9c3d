/* The emulated MOVIDRIVE's control: where the control word and the setpoint come from (P100,
 * P101, P870..P872, P876), the drive mode they and a fault or warning give, and faults (latch,
 * error memory P080..P084, reset). README.md "Drive model". */
#include "movidrive_internal.h"

/* The parameters behind movidrive_derived_t, in the order of its key[]. */
static const uint16_t derived_index[MOVIDRIVE_DERIVED_KEYS] = {
    MOVIDRIVE_IDX_P100_SETPOINT_SOURCE, MOVIDRIVE_IDX_P101_CONTROL_SOURCE,
    MOVIDRIVE_IDX_P876_PO_ENABLE,       MOVIDRIVE_IDX_P870_PO1,
    MOVIDRIVE_IDX_P870_PO1 + 1u,        MOVIDRIVE_IDX_P870_PO1 + 2u,
    IDX_P873_PI1,                       IDX_P873_PI1 + 1u,
    IDX_P873_PI1 + 2u,                  MOVIDRIVE_IDX_P302_MAX_SPEED,
    IDX_P303_CURRENT_LIMIT,
};

void movidrive_derive_into(const movidrive_t *md, movidrive_derived_t *d)
{
    d->defs = md->defs;
    d->num_defs = md->num_defs;
    d->complete = true;
    for (unsigned i = 0; i < MOVIDRIVE_DERIVED_KEYS; i++) {
        int k = movidrive_find_def(md, derived_index[i]);
        d->pos[i] = (int16_t)k;
        d->key[i] = k < 0 ? 0 : md->ram[k];
        d->complete = d->complete && k >= 0;
    }
    d->setpoint_from_bus = d->key[DK_P100] == MOVIDRIVE_SOURCE_FIELDBUS_SETPOINT;
    d->control_from_bus = d->key[DK_P101] == MOVIDRIVE_SOURCE_FIELDBUS_CONTROL;
    d->po_enabled = d->key[DK_P876] == 1 && (d->setpoint_from_bus || d->control_from_bus);
    for (unsigned f = 0; f < MOVIDRIVE_DERIVED_PO_FUNCTIONS; f++) {
        d->po_first[f] = 3u;
    }
    for (uint8_t i = 0; i < 3u; i++) {
        int32_t f = d->key[DK_P870 + i];
        if (f >= 0 && f < (int32_t)MOVIDRIVE_DERIVED_PO_FUNCTIONS && d->po_first[f] == 3u) {
            d->po_first[f] = i;
        }
    }
}

bool movidrive_po_data_enabled(const movidrive_t *md)
{
    movidrive_derived_t scratch;
    return movidrive_derived(md, &scratch)->po_enabled;
}

bool movidrive_cw_in_effect(const movidrive_t *md)
{
    movidrive_derived_t scratch;
    return movidrive_cw_in_effect_d(md, movidrive_derived(md, &scratch));
}

bool movidrive_po_word_d(const movidrive_t *md, const movidrive_derived_t *d, int32_t function,
                         uint16_t *word)
{
    /* The first of PO1..PO3 described as function counts, and only if it was received. */
    uint8_t i = 3u;
    if (function >= 0 && function < (int32_t)MOVIDRIVE_DERIVED_PO_FUNCTIONS) {
        i = d->po_first[function];
    } else {
        for (uint8_t k = 0; k < 3u && i == 3u; k++) {
            i = d->key[DK_P870 + k] == function ? k : i;
        }
    }
    if (i < 3u && i < md->po_count) {
        *word = md->po[i];
        return true;
    }
    return false;
}

bool movidrive_po_word(const movidrive_t *md, int32_t function, uint16_t *word)
{
    movidrive_derived_t scratch;
    return movidrive_po_word_d(md, movidrive_derived(md, &scratch), function, word);
}

bool movidrive_ramp_set_2(const movidrive_t *md)
{
    movidrive_derived_t scratch;
    return movidrive_ramp_set_2_d(md, movidrive_derived(md, &scratch));
}

static uint16_t control_word_d(const movidrive_t *md, const movidrive_derived_t *d)
{
    if (!movidrive_cw_in_effect_d(md, d)) {
        return 0;
    }
    uint16_t w;
    if (movidrive_po_word_d(md, d, PO_CTRL_WORD_1, &w)) {
        return w;
    }
    if (movidrive_po_word_d(md, d, PO_CTRL_WORD_2, &w)) {
        return (uint16_t)(w & 0x00FFu); /* basic block; high byte: virtual terminals (ignored) */
    }
    return 0; /* no control word assigned: no enable */
}

uint16_t movidrive_compute_control_word(const movidrive_t *md)
{
    movidrive_derived_t scratch;
    return control_word_d(md, movidrive_derived(md, &scratch));
}

static int32_t max_speed_mrpm(const movidrive_t *md, const movidrive_derived_t *d)
{
    int32_t nmax = d->key[DK_P302];
    uint16_t w;
    if (d->po_enabled && md->po_received && movidrive_po_word_d(md, d, PO_MAX_SPEED, &w)) {
        int32_t po_max = (int32_t)(int16_t)w * 200;
        if (po_max >= 0 && po_max < nmax) {
            nmax = po_max;
        }
    }
    return nmax;
}

static int32_t compute_setpoint(const movidrive_t *md, const movidrive_derived_t *d)
{
    if (!d->setpoint_from_bus || !d->po_enabled || !md->po_received) {
        return 0; /* other sources (analog, fixed setpoints via terminals) are not emulated */
    }
    int32_t nmax = max_speed_mrpm(md, d);
    int64_t n = 0;
    uint16_t w;
    if (movidrive_po_word_d(md, d, PO_SPEED, &w)) {
        n = (int64_t)(int16_t)w * 200;
    } else if (movidrive_po_word_d(md, d, PO_SPEED_PERCENT, &w)) {
        n = (int64_t)(int16_t)w * d->key[DK_P302] / 0x4000;
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

static uint8_t compute_mode(const movidrive_t *md, const movidrive_derived_t *d)
{
    uint16_t cw = md->control_word;
    bool bus = movidrive_cw_in_effect_d(md, d);
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
    const movidrive_derived_t *d = movidrive_derive(md);
    md->control_word = control_word_d(md, d);
    md->mode = compute_mode(md, d);
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
        md->speed_setpoint_mrpm = compute_setpoint(md, d);
        break;
    default: /* stop kinds: ramp to 0 if running, then the output stage goes off */
        md->speed_setpoint_mrpm = 0;
        if (md->speed_actual_mrpm == 0) {
            md->output_stage_enabled = false;
        }
        break;
    }
    movidrive_update_currents(md, d);
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
