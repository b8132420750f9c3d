/* The emulated MOVIDRIVE's life cycle and its inputs from outside the parameter channel:
 * init (defaults, then the EEPROM image), factory setting, terminal DI00, the card's fieldbus
 * status and the timeout reaction P831. The parts: README.md "Files". */
#include <string.h>

#include "movidrive_internal.h"
#include "movidrive_params.h"

#define FIELDBUS_TYPE_PROFIBUS_DP 5 /* P091 */

/* P819 is the exception: written through another interface it is shown until the master's
 * next parameterisation (protocol.md §B5), so it is taken only when that happened. */
static void apply_fieldbus_values(movidrive_t *md, bool take_p819)
{
    if (!md->have_fieldbus) {
        return;
    }
    const ml_fieldbus_status_t *st = &md->fieldbus;
    movidrive_set_ram_value(md, MOVIDRIVE_IDX_P090, st->pd_config);
    movidrive_set_ram_value(md, IDX_P091_FIELDBUS_TYPE, FIELDBUS_TYPE_PROFIBUS_DP);
    movidrive_set_ram_value(md, IDX_P092_BAUD, (int32_t)st->baud);
    movidrive_set_ram_value(md, IDX_P093_ADDRESS, st->address);
    if (take_p819) {
        movidrive_set_ram_value(md, MOVIDRIVE_IDX_P819_FIELDBUS_TIMEOUT, (int32_t)st->watchdog_ms);
    }
}

int movidrive_init(movidrive_t *md, const movidrive_cfg_t *cfg, char *err, size_t errlen)
{
    char dummy[1];
    if (err == NULL || errlen == 0) {
        err = dummy;
        errlen = sizeof dummy;
    }
    err[0] = '\0';
    memset(md, 0, sizeof *md);
    md->cfg = *cfg;
    md->defs = movidrive_params;
    md->num_defs = movidrive_params_count;
    movidrive_build_slots(md);
    movidrive_load_defaults(md, false);
    int rc = movidrive_ee_load(md, err, errlen);
    if (cfg->sbus_address != 0) {
        movidrive_set_ram_value(md, IDX_P813_SBUS_ADDRESS, cfg->sbus_address);
    }
    movidrive_evaluate(md);
    return rc;
}

int movidrive_factory_reset(movidrive_t *md)
{
    movidrive_load_defaults(md, true);
    apply_fieldbus_values(md, true); /* the defaults replaced the master's watchdog time */
    int rc = md->cfg.eeprom.ops != NULL ? movidrive_ee_save_all(md) : 0;
    movidrive_evaluate(md);
    return rc;
}

void movidrive_set_terminal_enable(movidrive_t *md, bool enabled)
{
    md->cfg.terminal_enable = enabled;
    movidrive_evaluate(md);
}

/* P831 once when the timeout begins (protocol.md §C3.6): a fault, or a warning that goes with
 * the timeout. */
static void timeout_began(movidrive_t *md)
{
    md->fieldbus_timeout = true;
    uint8_t r = (uint8_t)movidrive_ram_value(md, MOVIDRIVE_IDX_P831_FIELDBUS_REACTION);
    switch (r) {
    case REACT_NONE:
        break;
    case REACT_IMM_ERROR:
    case REACT_EMERG_ERROR:
    case REACT_RAPID_ERROR:
        movidrive_raise_fault(md, MOVIDRIVE_FAULT_FIELDBUS_TIMEOUT, r);
        break;
    default: /* DISPLAY ERROR and the .../WARNG reactions */
        md->warning = true;
        md->warning_code = MOVIDRIVE_FAULT_FIELDBUS_TIMEOUT;
        md->warning_reaction = r == REACT_DISPLAY ? REACT_NONE : r;
        break;
    }
}

/* A timeout warning ends with the timeout; a fault stays until reset. */
static void timeout_ended(movidrive_t *md)
{
    md->fieldbus_timeout = false;
    if (md->warning && md->warning_code == MOVIDRIVE_FAULT_FIELDBUS_TIMEOUT) {
        md->warning = false;
        md->warning_code = 0;
        md->warning_reaction = 0;
    }
}

void movidrive_fieldbus_status(movidrive_t *md, const ml_fieldbus_status_t *st)
{
    bool parameterised = st->prm_count != 0u &&
                         (!md->have_fieldbus || st->prm_count != md->fieldbus.prm_count);
    md->fieldbus = *st;
    md->have_fieldbus = true;
    apply_fieldbus_values(md, parameterised);
    if (st->timeout && !md->fieldbus_timeout) {
        timeout_began(md);
    } else if (!st->timeout && md->fieldbus_timeout) {
        timeout_ended(md);
    }
    movidrive_evaluate(md);
}
