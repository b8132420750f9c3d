/* What the parts of the emulated MOVIDRIVE share (private to sim_host/movidrive/src/):
 * parameter indices and codes, the RAM value table, the EEPROM image, the drive model's entry
 * points. Sources and assumptions: sim_host/movidrive/README.md. */
#ifndef MOVIDRIVE_MOVIDRIVE_INTERNAL_H
#define MOVIDRIVE_MOVIDRIVE_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "movidrive/movidrive.h"

/* Indices used inside the library besides the ones movidrive.h names. */
#define IDX_P002_FREQUENCY 8319u
#define IDX_P003_POSITION 8320u
#define IDX_P004_CURRENT 8321u
#define IDX_P005_ACTIVE_CURRENT 8322u
#define IDX_P008_DC_LINK 8325u
#define IDX_P009_CURRENT_A 8326u
#define IDX_P014_HEAT_SINK 8327u
#define IDX_P030_DI00 8334u
#define IDX_P071_RATED_CURRENT 8361u
#define IDX_P080_ERROR_T0 8366u
#define IDX_P084_ERROR_T4 8370u
#define IDX_P091_FIELDBUS_TYPE 8452u
#define IDX_P092_BAUD 8453u
#define IDX_P093_ADDRESS 8454u
#define IDX_P094_PO1 8455u
#define IDX_P097_PI1 8458u
#define IDX_P099_PI3 8460u
#define IDX_P132_RAMP_UP_CCW 8472u
#define IDX_P133_RAMP_DOWN_CCW 8473u
#define IDX_P136_STOP_RAMP 8476u
#define IDX_P137_EMERGENCY_RAMP 8477u
#define IDX_P140_RAMP2_UP 8478u
#define IDX_P141_RAMP2_DOWN 8479u
#define IDX_P142_RAMP2_UP_CCW 8480u
#define IDX_P143_RAMP2_DOWN_CCW 8481u
#define IDX_P146_STOP_RAMP2 8484u
#define IDX_P147_EMERGENCY_RAMP2 8485u
#define IDX_P303_CURRENT_LIMIT 8518u
#define IDX_P802_FACTORY 8594u
#define IDX_P804_RESET_STATS 8596u
#define IDX_P813_SBUS_ADDRESS 8600u
#define IDX_P840_MANUAL_RESET 8617u
#define IDX_P873_PI1 8307u

/* P870..P872 setpoint descriptions (protocol.md §C3.4). */
#define PO_NO_FUNCTION 0
#define PO_SPEED 1
#define PO_MAX_SPEED 5
#define PO_RAMP 8
#define PO_CTRL_WORD_1 9
#define PO_CTRL_WORD_2 10
#define PO_SPEED_PERCENT 11
#define PO_IPOS 12
/* P873..P875 actual value descriptions. */
#define PI_SPEED 1
#define PI_OUTPUT_CURRENT 2
#define PI_ACTIVE_CURRENT 3
#define PI_POSITION_LO 4
#define PI_POSITION_HI 5
#define PI_STATUS_WORD_1 6
#define PI_STATUS_WORD_2 7
#define PI_SPEED_PERCENT 8
#define PI_IPOS 9
#define PI_STATUS_WORD_3 11

/* P83x reactions (protocol.md §C3.6). */
#define REACT_NONE 0
#define REACT_DISPLAY 1
#define REACT_IMM_ERROR 2
#define REACT_EMERG_ERROR 3
#define REACT_RAPID_ERROR 4
#define REACT_IMM_WARN 5
#define REACT_EMERG_WARN 6
#define REACT_RAPID_WARN 7

/* Drive modes (movidrive_t.mode), strongest first. */
enum {
    MODE_INHIBIT,   /* output stage off at once, brake applied */
    MODE_IMMEDIATE, /* immediate stop: output stage off at once */
    MODE_EMERGENCY, /* emergency ramp P137, then off */
    MODE_RAPID,     /* rapid stop ramp P136, then off */
    MODE_STOP,      /* process ramp down, then off */
    MODE_RUN,
};

/* Model constants (README.md: plausible values, not measured). */
#define RAMP_REFERENCE_MRPM 3000000 /* ramp times are for a change of 3000 rpm */
#define MAGNETISING_MPCT 30000      /* 30 % I_N whenever the output stage is on */
#define LOAD_MPCT_AT_1500 20000     /* + 20 % I_N at 1500 rpm, proportional to |n| */
#define ACCEL_MPCT 40000            /* + 40 % I_N while the speed changes */
#define RATED_CURRENT_MA 5500       /* P071: MDX61B0022 class unit, 5.5 A */
#define DC_LINK_MV 565000           /* P008: 400 V mains rectified */
#define HEAT_SINK_DEGC 35
#define INC_PER_REV 4096
#define POLE_PAIRS 2

/* ---- parameter values in RAM (movidrive_values.c) ---- */

static inline bool movidrive_is_ipos(uint16_t index)
{
    return index >= MOVIDRIVE_IDX_IPOS_H0 && index < MOVIDRIVE_IDX_IPOS_H0 + MOVIDRIVE_IPOS_VARS;
}

/* The index table behind movidrive_find_def for the current defs (none if they span more than
 * MOVIDRIVE_SLOT_SPAN indices). */
void movidrive_build_slots(movidrive_t *md);
/* movidrive_find_def without the index table (a table swapped in after init). */
int movidrive_find_def_search(const movidrive_t *md, uint16_t index);

/* Position of a table parameter in defs[]/ram[]/ee[], -1 if the table lacks it. Inline, with
 * movidrive_ram_value: the other parts call them dozens of times per card poll. */
static inline int movidrive_find_def(const movidrive_t *md, uint16_t index)
{
    if (md->slot_defs != NULL && md->slot_defs == md->defs && md->slot_num == md->num_defs) {
        unsigned off = (unsigned)index - md->slot_base;
        return off < MOVIDRIVE_SLOT_SPAN ? md->slot[off] : -1;
    }
    return movidrive_find_def_search(md, index);
}

/* RAM value of a table parameter (0 if the table lacks it). */
static inline int32_t movidrive_ram_value(const movidrive_t *md, uint16_t index)
{
    int k = movidrive_find_def(md, index);
    return k < 0 ? 0 : md->ram[k];
}
/* Sets the RAM value of a table parameter (nothing if the table lacks it). */
void movidrive_set_ram_value(movidrive_t *md, uint16_t index, int32_t value);
/* Within min..max (unsigned compare for unsigned entries) and a known enumeration value. */
bool movidrive_value_in_range(const movidrive_param_def_t *d, int32_t value);
/* Defaults into RAM and the EEPROM copy; keep_read_only leaves RO entries (P802). */
void movidrive_load_defaults(movidrive_t *md, bool keep_read_only);

/* ---- EEPROM image (movidrive_eeprom.c) ---- */

/* Loads ee[]/ram[] from the NVM. 0: loaded or blank; -1 with a message in err. */
int movidrive_ee_load(movidrive_t *md, char *err, size_t errlen);
/* The whole image, one NVM write. 0 or -1. */
int movidrive_ee_save_all(movidrive_t *md);
/* The records of the N parameters among defs[first..last], one contiguous write. 0 or -1. */
int movidrive_ee_save_params(movidrive_t *md, size_t first, size_t last);
/* IPOS variable H<i>. 0 or -1. */
int movidrive_ee_save_ipos(movidrive_t *md, size_t i);

/* ---- the derived view of the model's parameters (movidrive_control.c) ---- */

/* Positions of the parameters in movidrive_derived_t.key[]. */
enum {
    DK_P100,
    DK_P101,
    DK_P876,
    DK_P870,
    DK_P873 = DK_P870 + 3,
    DK_P302 = DK_P873 + 3,
    DK_P303,
};

/* Whether d still holds for md: the same table, the same values. Without a branch per value
 * (it runs several times per card poll); a table that lacks one of them is never current. */
static inline bool movidrive_derived_current(const movidrive_t *md, const movidrive_derived_t *d)
{
    if (d->defs != md->defs || d->num_defs != md->num_defs || !d->complete) {
        return false;
    }
    uint32_t diff = 0;
    for (unsigned i = 0; i < MOVIDRIVE_DERIVED_KEYS; i++) {
        diff |= (uint32_t)(md->ram[d->pos[i]] ^ d->key[i]);
    }
    return diff == 0u;
}

/* Works the derived view out from md's parameters. */
void movidrive_derive_into(const movidrive_t *md, movidrive_derived_t *d);

/* md's own derived view when current, else one worked out into scratch (const callers). */
static inline const movidrive_derived_t *movidrive_derived(const movidrive_t *md,
                                                           movidrive_derived_t *scratch)
{
    if (movidrive_derived_current(md, &md->derived)) {
        return &md->derived;
    }
    movidrive_derive_into(md, scratch);
    return scratch;
}

/* Brings md's own derived view up to date and returns it. */
static inline const movidrive_derived_t *movidrive_derive(movidrive_t *md)
{
    if (!movidrive_derived_current(md, &md->derived)) {
        movidrive_derive_into(md, &md->derived);
    }
    return &md->derived;
}

/* The control word comes from the bus (P101 = FIELDBUS, PO enabled, PO received). */
static inline bool movidrive_cw_in_effect_d(const movidrive_t *md, const movidrive_derived_t *d)
{
    return d->control_from_bus && d->po_enabled && md->po_received;
}

/* movidrive_po_word over a derived view. */
bool movidrive_po_word_d(const movidrive_t *md, const movidrive_derived_t *d, int32_t function,
                         uint16_t *word);

/* Control word bit 4 from the bus. */
static inline bool movidrive_ramp_set_2_d(const movidrive_t *md, const movidrive_derived_t *d)
{
    return movidrive_cw_in_effect_d(md, d) && (md->control_word & MOVIDRIVE_CW_RAMP_SET_2);
}

/* ---- control source and drive mode (movidrive_control.c) ---- */

/* Status bit 2: P876 = YES and P100 or P101 = FIELDBUS. */
bool movidrive_po_data_enabled(const movidrive_t *md);
/* The control word comes from the bus (P101 = FIELDBUS, PO enabled, PO received). */
bool movidrive_cw_in_effect(const movidrive_t *md);
/* First received PO word (PO1..PO3) whose P870..P872 description is `function`. */
bool movidrive_po_word(const movidrive_t *md, int32_t function, uint16_t *word);
/* Control word 1 from the PO words (0 when the bus does not control the unit). */
uint16_t movidrive_compute_control_word(const movidrive_t *md);
/* Control word bit 4 from the bus. */
bool movidrive_ramp_set_2(const movidrive_t *md);
/* Re-evaluates control word, mode, setpoint and the output stage after any input change. */
void movidrive_evaluate(movidrive_t *md);

/* ---- faults (movidrive_control.c) ---- */

/* Latches a fault (if none is latched) and records it in P080..P084. */
void movidrive_raise_fault(movidrive_t *md, uint8_t number, uint8_t reaction);
/* Clears the fault unless its cause (the fieldbus timeout) persists. */
void movidrive_fault_reset(movidrive_t *md);

/* ---- motion (movidrive_motion.c) ---- */

/* Output and active current from the speed and its change in the last tick. */
void movidrive_update_currents(movidrive_t *md, const movidrive_derived_t *d);

/* ---- process input data (movidrive_process_data.c) ---- */

/* PI word i (0..ML_MAX_PD-1) as P873..P875 describe it. */
uint16_t movidrive_pi_word(const movidrive_t *md, uint8_t i);
/* Status word 1 over a derived view. */
uint16_t movidrive_status_word_d(const movidrive_t *md, const movidrive_derived_t *d);

#endif
