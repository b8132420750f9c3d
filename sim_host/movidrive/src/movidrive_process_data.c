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
    uint16_t cw = movidrive_compute_control_word(md);
    if (movidrive_cw_in_effect(md) && (cw & MOVIDRIVE_CW_RESET) && !(prev & MOVIDRIVE_CW_RESET)) {
        movidrive_fault_reset(md);
    }
    movidrive_evaluate(md);
}

/* Status word 1 high byte without a fault or warning (README.md "Status word 1"). */
static uint8_t unit_status(const movidrive_t *md)
{
    if (md->mode == MODE_INHIBIT) {
        return MOVIDRIVE_UNIT_CONTROLLER_INHIBIT;
    }
    if (movidrive_ram_value(md, MOVIDRIVE_IDX_P101_CONTROL_SOURCE) ==
            MOVIDRIVE_SOURCE_FIELDBUS_CONTROL &&
        movidrive_po_data_enabled(md) && !md->po_received) {
        return MOVIDRIVE_UNIT_WAITING_FOR_DATA;
    }
    return md->mode == MODE_RUN ? MOVIDRIVE_UNIT_ENABLED : MOVIDRIVE_UNIT_NO_ENABLE;
}

uint16_t movidrive_status_word(const movidrive_t *md)
{
    uint16_t sw = 0;
    if (md->output_stage_enabled) {
        sw |= MOVIDRIVE_SW_OUTPUT_STAGE_ENABLED;
    }
    if (md->fault == 0) {
        sw |= MOVIDRIVE_SW_READY;
    }
    if (movidrive_po_data_enabled(md)) {
        sw |= MOVIDRIVE_SW_PO_DATA_ENABLED;
    }
    if (movidrive_ramp_set_2(md)) {
        sw |= MOVIDRIVE_SW_RAMP_SET_2;
    }
    if (movidrive_cw_in_effect(md) && (md->control_word & MOVIDRIVE_CW_PARAM_SET_2)) {
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
        high = unit_status(md);
    }
    return (uint16_t)(sw | (high << 8));
}

static uint16_t clamp_int16(int64_t v)
{
    return (uint16_t)(int16_t)(v > INT16_MAX ? INT16_MAX : v < INT16_MIN ? INT16_MIN : v);
}

uint16_t movidrive_pi_word(const movidrive_t *md, uint8_t i)
{
    if (i >= 3) {
        return md->ipos_pi[i];
    }
    int32_t n = md->speed_actual_mrpm;
    switch (movidrive_ram_value(md, (uint16_t)(IDX_P873_PI1 + i))) {
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
        return movidrive_status_word(md);
    case PI_STATUS_WORD_2:
    case PI_STATUS_WORD_3:
        /* basic block as status word 1; high byte (virtual outputs) not known: 0 */
        return (uint16_t)(movidrive_status_word(md) & 0x00FFu);
    case PI_SPEED_PERCENT: {
        int32_t nmax = movidrive_ram_value(md, MOVIDRIVE_IDX_P302_MAX_SPEED);
        return nmax <= 0 ? 0u : clamp_int16((int64_t)n * SPEED_PERCENT_FULL / nmax);
    }
    case PI_IPOS:
        return md->ipos_pi[i];
    default:
        return 0;
    }
}

void movidrive_process_inputs(const movidrive_t *md, uint16_t *pi, uint8_t n)
{
    for (uint8_t i = 0; i < n; i++) {
        pi[i] = i < ML_MAX_PD ? movidrive_pi_word(md, i) : 0;
    }
}
