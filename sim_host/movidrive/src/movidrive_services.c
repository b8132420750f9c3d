/* The emulated MOVIDRIVE's MOVILINK parameter services: the answer to an 8-byte request, the
 * write rules in the order README.md "Parameter services" lists them, commands (P802, P804,
 * P840), Read attribute, and the values the drive computes for its display parameters. */
#include <limits.h>
#include <string.h>

#include "hal/hal_byte_order.h"
#include "movidrive_internal.h"

/* ---------------------------------------------------------------------------------------------
 * Write */

/* R parameters: controller inhibit by terminal, or output stage off and (if the bus controls
 * the unit) control word bit 0 set. */
static bool inhibit_for_write(const movidrive_t *md)
{
    if (!md->cfg.terminal_enable) {
        return true;
    }
    if (md->output_stage_enabled) {
        return false;
    }
    return !movidrive_cw_in_effect(md) || (md->control_word & MOVIDRIVE_CW_CONTROLLER_INHIBIT);
}

/* P870..P875: the process data mapping must not change under a running motor. */
static bool needs_output_stage_off(uint16_t index)
{
    return index >= MOVIDRIVE_IDX_P870_PO1 && index <= IDX_P873_PI1 + 2u;
}

static bool is_setpoint_description(uint16_t index)
{
    return index >= MOVIDRIVE_IDX_P870_PO1 && index <= MOVIDRIVE_IDX_P870_PO1 + 2u;
}

/* H0..H511: variables, not parameters, so P803 does not lock them (I). */
static uint8_t write_ipos(movidrive_t *md, uint16_t index, int32_t v, bool non_volatile)
{
    size_t i = index - MOVIDRIVE_IDX_IPOS_H0;
    md->ipos[i] = v;
    if (non_volatile) {
        md->ee_ipos[i] = v;
        if (movidrive_ee_save_ipos(md, i) != 0) {
            return ML_ADD_NOT_SAVED;
        }
    }
    return 0;
}

/* Whether the entry may be written now, whatever the value: the class 8 code or 0. */
static uint8_t access_code(const movidrive_t *md, uint16_t index, const movidrive_param_def_t *d,
                           bool non_volatile)
{
    if (d->flags & MOVIDRIVE_PF_READ_ONLY) {
        return ML_ADD_READ_ONLY;
    }
    if (movidrive_ram_value(md, MOVIDRIVE_IDX_P803_PARAM_LOCK) == 1 &&
        !(d->flags & MOVIDRIVE_PF_LOCK_EXEMPT)) {
        return ML_ADD_PARAMETER_LOCK;
    }
    if (!non_volatile && (d->flags & MOVIDRIVE_PF_NO_VOLATILE)) {
        return ML_ADD_VALUE_NOT_PERMITTED;
    }
    if ((d->flags & MOVIDRIVE_PF_INHIBIT_REQUIRED) && !inhibit_for_write(md)) {
        return ML_ADD_CONTROLLER_INHIBIT_REQUIRED;
    }
    if (needs_output_stage_off(index) && md->output_stage_enabled) {
        return ML_ADD_OUTPUT_STAGE_ENABLED;
    }
    return 0;
}

/* Whether the value fits the entry: too high, too low, not an enumeration value, or 0. */
static uint8_t value_code(const movidrive_param_def_t *d, int32_t v)
{
    if (d->flags & MOVIDRIVE_PF_UNSIGNED) {
        if ((d->flags & MOVIDRIVE_PF_HAS_MAX) && (uint32_t)v > (uint32_t)d->max) {
            return ML_ADD_TOO_HIGH;
        }
        if ((d->flags & MOVIDRIVE_PF_HAS_MIN) && (uint32_t)v < (uint32_t)d->min) {
            return ML_ADD_TOO_LOW;
        }
    } else {
        if ((d->flags & MOVIDRIVE_PF_HAS_MAX) && v > d->max) {
            return ML_ADD_TOO_HIGH;
        }
        if ((d->flags & MOVIDRIVE_PF_HAS_MIN) && v < d->min) {
            return ML_ADD_TOO_LOW;
        }
    }
    return movidrive_value_in_range(d, v) ? 0u : ML_ADD_VALUE_NOT_PERMITTED;
}

/* P804 = 1 ERROR MEMORY: P080..P084 to 0, in RAM and EEPROM. */
static uint8_t clear_error_memory(movidrive_t *md)
{
    int first = movidrive_find_def(md, IDX_P080_ERROR_T0);
    int last = movidrive_find_def(md, IDX_P084_ERROR_T4);
    for (int j = first; j >= 0 && j <= last; j++) {
        md->ram[j] = md->ee[j] = 0;
    }
    if (first >= 0 && last >= first &&
        movidrive_ee_save_params(md, (size_t)first, (size_t)last) != 0) {
        return ML_ADD_NOT_SAVED;
    }
    return 0;
}

/* Commands are executed, the parameter keeps reading 0. False: index is no command. */
static bool run_command(movidrive_t *md, uint16_t index, int32_t v, uint8_t *code)
{
    *code = 0;
    switch (index) {
    case IDX_P802_FACTORY:
        if (v == 1 && movidrive_factory_reset(md) != 0) {
            *code = ML_ADD_NOT_SAVED;
        }
        return true;
    case IDX_P840_MANUAL_RESET:
        if (v == 1) {
            movidrive_fault_reset(md);
            movidrive_evaluate(md);
        }
        return true;
    case IDX_P804_RESET_STATS:
        if (v == 1) {
            *code = clear_error_memory(md);
        }
        return true;
    default:
        return false;
    }
}

/* Sets defs[k] in RAM and, for "Write" of an N entry, in EEPROM: 0 or ML_ADD_NOT_SAVED. */
static uint8_t store(movidrive_t *md, int k, int32_t v, bool non_volatile)
{
    md->ram[k] = v;
    if (!non_volatile || !(md->defs[k].flags & MOVIDRIVE_PF_NON_VOLATILE)) {
        return 0;
    }
    md->ee[k] = v;
    return movidrive_ee_save_params(md, (size_t)k, (size_t)k) != 0 ? ML_ADD_NOT_SAVED : 0u;
}

/* Returns the class 8 additional code, 0 = done. */
static uint8_t write_param(movidrive_t *md, uint16_t index, int32_t v, bool non_volatile)
{
    if (movidrive_is_ipos(index)) {
        return write_ipos(md, index, v, non_volatile);
    }
    int k = movidrive_find_def(md, index);
    if (k < 0) {
        return ML_ADD_ILLEGAL_INDEX;
    }
    const movidrive_param_def_t *d = &md->defs[k];
    uint8_t code = access_code(md, index, d, non_volatile);
    if (code == 0) {
        code = value_code(d, v);
    }
    if (code != 0 || run_command(md, index, v, &code)) {
        return code;
    }
    int32_t old = md->ram[k];
    code = store(md, k, v, non_volatile);
    /* S5: changing P870..P872 sets P876 PO data enable to NO. */
    if (is_setpoint_description(index) && old != v) {
        int e = movidrive_find_def(md, MOVIDRIVE_IDX_P876_PO_ENABLE);
        if (e >= 0 && store(md, e, 0, non_volatile) != 0) {
            code = ML_ADD_NOT_SAVED;
        }
    }
    movidrive_evaluate(md);
    return code;
}

/* ---------------------------------------------------------------------------------------------
 * Read */

/* Values of read-only parameters the drive computes. */
static bool live_value(const movidrive_t *md, uint16_t index, int32_t *v)
{
    switch (index) {
    case MOVIDRIVE_IDX_STATUS:
        *v = movidrive_status_word(md);
        return true;
    case MOVIDRIVE_IDX_SPEED:
        *v = md->speed_actual_mrpm;
        return true;
    case IDX_P002_FREQUENCY:
        *v = md->speed_actual_mrpm * POLE_PAIRS / 60; /* mHz */
        return true;
    case IDX_P003_POSITION:
        *v = md->position_inc;
        return true;
    case IDX_P004_CURRENT:
        *v = md->current_mpct;
        return true;
    case IDX_P005_ACTIVE_CURRENT:
        *v = md->active_current_mpct;
        return true;
    case IDX_P008_DC_LINK:
        *v = DC_LINK_MV;
        return true;
    case IDX_P009_CURRENT_A:
        *v = (int32_t)((int64_t)md->current_mpct * RATED_CURRENT_MA / 100000);
        return true;
    case IDX_P014_HEAT_SINK:
        *v = HEAT_SINK_DEGC;
        return true;
    case IDX_P030_DI00:
        *v = md->cfg.terminal_enable ? 1 : 0;
        return true;
    case IDX_P071_RATED_CURRENT:
        *v = RATED_CURRENT_MA;
        return true;
    default:
        break;
    }
    if (index >= IDX_P094_PO1 && index < IDX_P097_PI1) {
        uint8_t i = (uint8_t)(index - IDX_P094_PO1);
        *v = i < md->po_count ? md->po[i] : 0;
        return true;
    }
    if (index >= IDX_P097_PI1 && index <= IDX_P099_PI3) {
        *v = movidrive_pi_word(md, (uint8_t)(index - IDX_P097_PI1));
        return true;
    }
    return false;
}

bool movidrive_read_value(const movidrive_t *md, uint16_t index, int32_t *value)
{
    if (movidrive_is_ipos(index)) {
        *value = md->ipos[index - MOVIDRIVE_IDX_IPOS_H0];
        return true;
    }
    int k = movidrive_find_def(md, index);
    if (k < 0) {
        return false;
    }
    if (!live_value(md, index, value)) {
        *value = md->ram[k];
    }
    return true;
}

/* Bytes 4..5 the next index (after the table: H0; after H511: 0), bytes 6..7 the access
 * attribute (MOVITRAC B coding, protocol.md §C1.3). */
static void put_attribute(const movidrive_t *md, uint16_t index, const movidrive_param_def_t *d,
                          uint8_t *rsp)
{
    uint16_t next = 0;
    if (movidrive_is_ipos(index)) {
        next =
            index + 1u < MOVIDRIVE_IDX_IPOS_H0 + MOVIDRIVE_IPOS_VARS ? (uint16_t)(index + 1u) : 0u;
    } else {
        int k = movidrive_find_def(md, index);
        next =
            (size_t)k + 1u < md->num_defs ? md->defs[k + 1].index : (uint16_t)MOVIDRIVE_IDX_IPOS_H0;
    }
    uint16_t a = 0;
    if (!(d->flags & MOVIDRIVE_PF_READ_ONLY)) {
        a |= MOVIDRIVE_ATTR_WRITE_ALLOWED | MOVIDRIVE_ATTR_FACTORY_RAM;
        if (d->flags & MOVIDRIVE_PF_NON_VOLATILE) {
            a |= MOVIDRIVE_ATTR_FACTORY_EEPROM;
        }
    }
    if (d->flags & MOVIDRIVE_PF_NON_VOLATILE) {
        a |= MOVIDRIVE_ATTR_EEPROM | MOVIDRIVE_ATTR_EEPROM_VALID_AT_INIT;
    }
    if (!(d->flags & MOVIDRIVE_PF_INHIBIT_REQUIRED)) {
        a |= MOVIDRIVE_ATTR_NO_INHIBIT_REQUIRED;
    }
    hal_put_be16(rsp + 4, next);
    hal_put_be16(rsp + 6, a);
}

/* Read min / read max of an entry without a bound: the type's range. */
static uint32_t min_value(const movidrive_param_def_t *d)
{
    if (d->flags & MOVIDRIVE_PF_HAS_MIN) {
        return (uint32_t)d->min;
    }
    return (d->flags & MOVIDRIVE_PF_UNSIGNED) ? 0u : (uint32_t)INT32_MIN;
}

static uint32_t max_value(const movidrive_param_def_t *d)
{
    if (d->flags & MOVIDRIVE_PF_HAS_MAX) {
        return (uint32_t)d->max;
    }
    return (d->flags & MOVIDRIVE_PF_UNSIGNED) ? UINT32_MAX : (uint32_t)INT32_MAX;
}

/* ---------------------------------------------------------------------------------------------
 * The service */

/* A request that passed the checks: its answer into rsp (management and index already set). */
static void answer(movidrive_t *md, uint8_t service, uint16_t index, const movidrive_param_def_t *d,
                   const uint8_t *req, uint8_t *rsp)
{
    switch (service) {
    case ML_SVC_READ: {
        int32_t v = 0;
        (void)movidrive_read_value(md, index, &v);
        ml_put_data(rsp, (uint32_t)v);
        break;
    }
    case ML_SVC_WRITE:
    case ML_SVC_WRITE_VOLATILE: {
        uint8_t add = write_param(md, index, (int32_t)ml_data(req), service == ML_SVC_WRITE);
        if (add != 0) {
            ml_put_error(rsp, ML_CLASS_OTHER, 0, add);
        } else {
            ml_put_data(rsp, ml_data(req));
        }
        break;
    }
    case ML_SVC_READ_MIN:
        ml_put_data(rsp, min_value(d));
        break;
    case ML_SVC_READ_MAX:
        ml_put_data(rsp, max_value(d));
        break;
    case ML_SVC_READ_DEFAULT:
        ml_put_data(rsp, (uint32_t)d->def);
        break;
    case ML_SVC_READ_SCALE:
        rsp[6] = d->quantity;
        rsp[7] = (uint8_t)d->conversion;
        break;
    case ML_SVC_READ_ATTRIBUTE:
        put_attribute(md, index, d, rsp);
        break;
    default:
        break;
    }
}

void movidrive_param(movidrive_t *md, const uint8_t req[ML_TELEGRAM_LEN],
                     uint8_t rsp[ML_TELEGRAM_LEN])
{
    uint8_t mgmt = (uint8_t)(req[ML_OFF_MANAGEMENT] & ~(ML_MGMT_HANDSHAKE | ML_MGMT_ERROR));
    uint8_t service = (uint8_t)(mgmt & ML_MGMT_SERVICE_MASK);
    uint16_t index = ml_index(req);
    memset(rsp, 0, ML_TELEGRAM_LEN);
    rsp[ML_OFF_MANAGEMENT] = mgmt;
    rsp[ML_OFF_INDEX_HIGH] = req[ML_OFF_INDEX_HIGH];
    rsp[ML_OFF_INDEX_LOW] = req[ML_OFF_INDEX_LOW];

    if (service == ML_SVC_NONE) {
        return;
    }
    if (service > ML_SVC_LAST) {
        ml_put_error(rsp, ML_CLASS_SERVICE, 0, 0x0001u); /* class 5: illegal service */
        return;
    }
    if ((service == ML_SVC_WRITE || service == ML_SVC_WRITE_VOLATILE) &&
        (mgmt & ML_MGMT_LENGTH_MASK) != ML_MGMT_LENGTH_4) {
        ml_put_error(rsp, ML_CLASS_ACCESS, ML_CODE_TYPE_CONFLICT, 0);
        return;
    }
    const movidrive_param_def_t *d = movidrive_param_def(md, index);
    if (d == NULL || req[ML_OFF_RESERVED] != 0) {
        ml_put_error(rsp, ML_CLASS_OTHER, 0, ML_ADD_ILLEGAL_INDEX);
        return;
    }
    answer(md, service, index, d, req, rsp);
}
