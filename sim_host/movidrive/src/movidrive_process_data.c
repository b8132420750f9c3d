/* The emulated MOVIDRIVE's process data: PO words in (and the control word edge that resets a
 * fault), status word 1, PI words out as P873..P875 describe them (protocol.md §C3.3..§C3.5,
 * README.md "Process data"). */
#include <limits.h>
#include <string.h>

#include "movidrive_internal.h"

#define SPEED_MRPM_PER_DIGIT 200 /* PO/PI SPEED: 0.2 rpm per digit */
#define SPEED_PERCENT_FULL 0x4000 /* PI SPEED [%]: 0x4000 = P302 */

void movidrive_process_outputs(movidrive_t *md, const uint16_t *po, uint8_t n)
{
    if (n > ML_MAX_PD) {
        n = ML_MAX_PD;
    }
    memcpy(md->po, po, n * sizeof po[0]);
    memcpy(md->ipos_po, po, n * sizeof po[0]);
    for (uint8_t i = n; i < ML_MAX_PD; i++) {
        md->po[i] = 0;
        md->ipos_po[i] = 0;
    }
    md->po_count = n;
    if (n > 0) {
        md->po_received = true;
    }
    uint16_t prev = md->control_word;
    const movidrive_derived_t *d = movidrive_derive(md);
    uint16_t cw = movidrive_compute_control_word(md);
    if (movidrive_cw_in_effect_d(md, d) && (cw & MOVIDRIVE_CW_RESET) &&
        !(prev & MOVIDRIVE_CW_RESET)) {
        movidrive_fault_reset(md);
    }
    movidrive_evaluate(md);
}

/* Status word 1 high byte without a fault or warning (README.md "Status word 1"). */
static uint8_t unit_status(const movidrive_t *md, const movidrive_derived_t *d)
{
    if (md->mode == MODE_INHIBIT) {
        return MOVIDRIVE_UNIT_CONTROLLER_INHIBIT;
    }
    if (d->control_from_bus && d->po_enabled && !md->po_received) {
        return MOVIDRIVE_UNIT_WAITING_FOR_DATA;
    }
    return md->mode == MODE_RUN ? MOVIDRIVE_UNIT_ENABLED : MOVIDRIVE_UNIT_NO_ENABLE;
}

uint16_t movidrive_status_word_d(const movidrive_t *md, const movidrive_derived_t *d)
{
    uint16_t sw = 0;
    if (md->output_stage_enabled) {
        sw |= MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED;
    }
    if (md->fault == 0) {
        sw |= MOVIDRIVE_SW_READY;
    }
    if (d->po_enabled) {
        sw |= MOVIDRIVE_SW_PO_DATA_ENABLED;
    }
    if (movidrive_ramp_set_2_d(md, d)) {
        sw |= MOVIDRIVE_SW_RAMP_SET_2;
    }
    if (movidrive_cw_in_effect_d(md, d) && (md->control_word & MOVIDRIVE_CW_PARAM_SET_2)) {
        sw |= MOVIDRIVE_SW_PARAM_SET_2;
    }
    uint8_t high;
    if (md->fault != 0) {
        sw |= MOVIDRIVE_SW_FAULT;
        high = md->fault;
    } else if (md->warning) {
        sw |= MOVIDRIVE_SW_FAULT;
        high = md->warning_code;
    } else {
        high = unit_status(md, d);
    }
    return (uint16_t)(sw | (high << 8));
}

uint16_t movidrive_status_word(const movidrive_t *md)
{
    movidrive_derived_t scratch;
    return movidrive_status_word_d(md, movidrive_derived(md, &scratch));
}

static uint16_t clamp_int16(int64_t v)
{
    return (uint16_t)(int16_t)(v > INT16_MAX ? INT16_MAX : v < INT16_MIN ? INT16_MIN : v);
}

static uint16_t pi_word_d(const movidrive_t *md, const movidrive_derived_t *d, uint8_t i)
{
    if (i >= 3) {
        return md->ipos_pi[i];
    }
    int32_t n = md->speed_actual_mrpm;
    switch (d->key[DK_P873 + i]) {
    case PI_SPEED: /* rounded half away from zero */
        return clamp_int16((n + (n < 0 ? -SPEED_MRPM_PER_DIGIT / 2 : SPEED_MRPM_PER_DIGIT / 2)) /
                           SPEED_MRPM_PER_DIGIT);
    case PI_OUTPUT_CURRENT:
        return (uint16_t)(int16_t)(md->current_mpct / 100);
    case PI_ACTIVE_CURRENT:
        return (uint16_t)(int16_t)(md->active_current_mpct / 100);
    case PI_POSITION_LO:
        return (uint16_t)((uint32_t)md->position_inc & 0xFFFFu);
    case PI_POSITION_HI:
        return (uint16_t)((uint32_t)md->position_inc >> 16);
    case PI_STATUS_WORD_1:
        return movidrive_status_word_d(md, d);
    case PI_STATUS_WORD_2:
    case PI_STATUS_WORD_3:
        /* basic block as status word 1; high byte (virtual outputs) not known: 0 */
        return (uint16_t)(movidrive_status_word_d(md, d) & 0x00FFu);
    case PI_SPEED_PERCENT: {
        int32_t nmax = d->key[DK_P302];
        return nmax <= 0 ? 0u : clamp_int16((int64_t)n * SPEED_PERCENT_FULL / nmax);
    }
    case PI_IPOS:
        return md->ipos_pi[i];
    default:
        return 0;
    }
}

uint16_t movidrive_pi_word(const movidrive_t *md, uint8_t i)
{
    movidrive_derived_t scratch;
    return pi_word_d(md, movidrive_derived(md, &scratch), i);
}

void movidrive_process_inputs(const movidrive_t *md, uint16_t *pi, uint8_t n)
{
    movidrive_derived_t scratch;
    const movidrive_derived_t *d = movidrive_derived(md, &scratch);
    for (uint8_t i = 0; i < n; i++) {
        pi[i] = i < ML_MAX_PD ? pi_word_d(md, d, i) : 0;
    }
}
