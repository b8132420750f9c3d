/* The emulated MOVIDRIVE: parameter services, EEPROM image, process data, drive model.
 * Sources and assumptions: sim_host/movidrive/README.md. */
#include "movidrive/movidrive.h"
#include "hal/hal_byte_order.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "md_params.h"

/* Indices used here besides the ones movidrive.h names. */
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

/* Drive modes, strongest first. */
enum {
    MODE_INHIBIT,   /* output stage off at once, brake applied */
    MODE_IMMEDIATE, /* immediate stop: output stage off at once */
    MODE_EMERGENCY, /* emergency ramp P137, then off */
    MODE_RAPID,     /* rapid stop ramp P136, then off */
    MODE_STOP,      /* process ramp down, then off */
    MODE_RUN,
};

/* Model constants (README.md: plausible values, not measured). */
#define RAMP_REFERENCE_MRPM 3000000  /* ramp times are for a change of 3000 rpm */
#define MAGNETISING_MPCT 30000       /* 30 % I_N whenever the output stage is on */
#define LOAD_MPCT_AT_1500 20000      /* + 20 % I_N at 1500 rpm, proportional to |n| */
#define ACCEL_MPCT 40000             /* + 40 % I_N while the speed changes */
#define RATED_CURRENT_MA 5500        /* P071: MDX61B0022 class unit, 5.5 A */
#define DC_LINK_MV 565000            /* P008: 400 V mains rectified */
#define HEAT_SINK_DEGC 35
#define INC_PER_REV 4096
#define POLE_PAIRS 2

static int find_def(const movidrive_t *md, uint16_t index)
{
    size_t lo = 0;
    size_t hi = md->num_defs;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (md->defs[mid].index == index) {
            return (int)mid;
        }
        if (md->defs[mid].index < index) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return -1;
}

static bool is_ipos(uint16_t index)
{
    return index >= MD_IDX_IPOS_H0 && index < MD_IDX_IPOS_H0 + MD_IPOS_VARS;
}

/* RAM value of a table parameter (0 if the table lacks it). */
static int32_t pv(const movidrive_t *md, uint16_t index)
{
    int k = find_def(md, index);
    return k < 0 ? 0 : md->ram[k];
}

static void set_ram(movidrive_t *md, uint16_t index, int32_t v)
{
    int k = find_def(md, index);
    if (k >= 0) {
        md->ram[k] = v;
    }
}

static bool value_in_range(const md_param_def_t *d, int32_t v)
{
    if (d->flags & MD_PF_UNSIGNED) {
        if ((d->flags & MD_PF_HAS_MIN) && (uint32_t)v < (uint32_t)d->min) {
            return false;
        }
        if ((d->flags & MD_PF_HAS_MAX) && (uint32_t)v > (uint32_t)d->max) {
            return false;
        }
    } else {
        if ((d->flags & MD_PF_HAS_MIN) && v < d->min) {
            return false;
        }
        if ((d->flags & MD_PF_HAS_MAX) && v > d->max) {
            return false;
        }
    }
    return d->enum_mask == 0u || (v >= 0 && v < 32 && (d->enum_mask >> v) & 1u);
}

/* ---------------------------------------------------------------------------------------------
 * EEPROM image */

static uint32_t ee_records(const movidrive_t *md)
{
    uint32_t n = 0;
    for (size_t k = 0; k < md->num_defs; k++) {
        n += (md->defs[k].flags & MD_PF_NON_VOLATILE) ? 1u : 0u;
    }
    return n;
}

size_t movidrive_eeprom_size(void)
{
    size_t n = 0;
    for (size_t k = 0; k < md_params_count; k++) {
        n += (md_params[k].flags & MD_PF_NON_VOLATILE) ? 1u : 0u;
    }
    return MD_EE_HEADER + n * MD_EE_RECORD + (size_t)MD_IPOS_VARS * 4u;
}

/* Largest image: header + every parameter + the IPOS variables. */
#define EE_MAX_IMAGE (MD_EE_HEADER + MD_MAX_PARAMS * MD_EE_RECORD + MD_IPOS_VARS * 4u)

static int ee_write(movidrive_t *md, size_t offset, const uint8_t *data, size_t len)
{
    md->eeprom_writes++;
    return md->cfg.eeprom.ops->write(md->cfg.eeprom.ctx, offset, data, len);
}

/* The whole image from ee[] / ee_ipos[], in one NVM write (atomic by the HAL contract). */
static int ee_save_all(movidrive_t *md)
{
    if (!md->ee_usable) {
        return 0;
    }
    static uint8_t img[EE_MAX_IMAGE];
    uint32_t nrec = ee_records(md);
    hal_put_be32(img, MD_EE_MAGIC);
    hal_put_be16(img + 4, MD_EE_VERSION);
    hal_put_be16(img + 6, (uint16_t)nrec);
    hal_put_be16(img + 8, MD_IPOS_VARS);
    hal_put_be16(img + 10, 0);
    uint8_t *p = img + MD_EE_HEADER;
    for (size_t k = 0; k < md->num_defs; k++) {
        if (md->defs[k].flags & MD_PF_NON_VOLATILE) {
            hal_put_be16(p, md->defs[k].index);
            hal_put_be32(p + 2, (uint32_t)md->ee[k]);
            p += MD_EE_RECORD;
        }
    }
    for (size_t i = 0; i < MD_IPOS_VARS; i++) {
        hal_put_be32(p, (uint32_t)md->ee_ipos[i]);
        p += 4;
    }
    if (ee_write(md, 0, img, (size_t)(p - img)) != 0) {
        return -1;
    }
    md->ee_layout_ok = true;
    return 0;
}

/* Records of the N parameters among defs[first..last], one contiguous write. */
static int ee_save_params(movidrive_t *md, size_t first, size_t last)
{
    if (!md->ee_usable) {
        return 0;
    }
    if (!md->ee_layout_ok) {
        return ee_save_all(md);
    }
    size_t slot = 0;
    for (size_t k = 0; k < first; k++) {
        slot += (md->defs[k].flags & MD_PF_NON_VOLATILE) ? 1u : 0u;
    }
    uint8_t buf[MD_MAX_PARAMS * MD_EE_RECORD];
    size_t n = 0;
    for (size_t k = first; k <= last; k++) {
        if (md->defs[k].flags & MD_PF_NON_VOLATILE) {
            hal_put_be16(buf + n, md->defs[k].index);
            hal_put_be32(buf + n + 2, (uint32_t)md->ee[k]);
            n += MD_EE_RECORD;
        }
    }
    if (n == 0) {
        return 0;
    }
    return ee_write(md, MD_EE_HEADER + slot * MD_EE_RECORD, buf, n);
}

static int ee_save_ipos(movidrive_t *md, size_t i)
{
    if (!md->ee_usable) {
        return 0;
    }
    if (!md->ee_layout_ok) {
        return ee_save_all(md);
    }
    uint8_t buf[4];
    hal_put_be32(buf, (uint32_t)md->ee_ipos[i]);
    return ee_write(md, MD_EE_HEADER + ee_records(md) * MD_EE_RECORD + i * 4u, buf, 4);
}

static bool all_bytes(const uint8_t *p, size_t n, uint8_t v)
{
    for (size_t i = 0; i < n; i++) {
        if (p[i] != v) {
            return false;
        }
    }
    return true;
}

/* Loads ee[]/ram[] from the NVM. 0: loaded or blank; -1 with err. */
static int ee_load(movidrive_t *md, char *err, size_t errlen)
{
    const hal_nvm_t *nvm = &md->cfg.eeprom;
    if (nvm->ops == NULL) {
        return 0;
    }
    size_t need = movidrive_eeprom_size();
    size_t have = nvm->ops->size(nvm->ctx);
    if (have < need) {
        snprintf(err, errlen, "EEPROM too small (%zu bytes, the image needs %zu): not stored", have,
                 need);
        return -1;
    }
    md->ee_usable = true;
    static uint8_t img[EE_MAX_IMAGE];
    if (nvm->ops->read(nvm->ctx, 0, img, MD_EE_HEADER) != 0) {
        snprintf(err, errlen, "EEPROM unreadable (corrupt or damaged image): factory defaults used");
        return -1;
    }
    if (all_bytes(img, MD_EE_HEADER, 0xFFu) || all_bytes(img, MD_EE_HEADER, 0x00u)) {
        return 0; /* blank: first start */
    }
    uint32_t magic = hal_get_be32(img);
    if (magic != MD_EE_MAGIC) {
        snprintf(err, errlen,
                 "EEPROM holds no MOVIDRIVE image (magic 0x%08X, expected 0x%08X): factory "
                 "defaults used",
                 (unsigned)magic, (unsigned)MD_EE_MAGIC);
        return -1;
    }
    unsigned version = hal_get_be16(img + 4);
    unsigned nrec = hal_get_be16(img + 6);
    unsigned nipos = hal_get_be16(img + 8);
    if (version != MD_EE_VERSION) {
        snprintf(err, errlen, "EEPROM image version %u not supported (%u): factory defaults used",
                 version, (unsigned)MD_EE_VERSION);
        return -1;
    }
    size_t len = MD_EE_HEADER + (size_t)nrec * MD_EE_RECORD + (size_t)nipos * 4u;
    if (nipos != MD_IPOS_VARS || nrec > MD_MAX_PARAMS || len > have) {
        snprintf(err, errlen,
                 "EEPROM image header inconsistent (%u records, %u IPOS variables): factory "
                 "defaults used",
                 nrec, nipos);
        return -1;
    }
    if (nvm->ops->read(nvm->ctx, 0, img, len) != 0) {
        snprintf(err, errlen, "EEPROM unreadable: factory defaults used");
        return -1;
    }
    bool layout = nrec == ee_records(md);
    unsigned bad = 0;
    size_t slot_k = 0;
    const uint8_t *p = img + MD_EE_HEADER;
    for (unsigned r = 0; r < nrec; r++, p += MD_EE_RECORD) {
        uint16_t index = hal_get_be16(p);
        int32_t v = (int32_t)hal_get_be32(p + 2);
        while (slot_k < md->num_defs && !(md->defs[slot_k].flags & MD_PF_NON_VOLATILE)) {
            slot_k++;
        }
        if (slot_k >= md->num_defs || md->defs[slot_k].index != index) {
            layout = false;
        }
        slot_k++;
        int k = find_def(md, index);
        if (k < 0 || !(md->defs[k].flags & MD_PF_NON_VOLATILE)) {
            continue; /* a parameter this table no longer has: dropped at the next save */
        }
        if (!value_in_range(&md->defs[k], v)) {
            bad++;
            continue;
        }
        md->ram[k] = v;
        md->ee[k] = v;
    }
    for (size_t i = 0; i < MD_IPOS_VARS; i++, p += 4) {
        md->ipos[i] = md->ee_ipos[i] = (int32_t)hal_get_be32(p);
    }
    md->ee_layout_ok = layout;
    if (bad != 0) {
        snprintf(err, errlen, "EEPROM: %u stored values out of range, defaults used for them", bad);
        return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------------
 * Process data and control */

static bool po_data_enabled(const movidrive_t *md)
{
    return pv(md, MD_IDX_P876_PO_ENABLE) == 1 &&
           (pv(md, MD_IDX_P100_SETPOINT_SOURCE) == MD_SOURCE_FIELDBUS_SETPOINT ||
            pv(md, MD_IDX_P101_CONTROL_SOURCE) == MD_SOURCE_FIELDBUS_CONTROL);
}

/* The control word comes from the bus (P101 = FIELDBUS, PO enabled, PO received). */
static bool cw_in_effect(const movidrive_t *md)
{
    return pv(md, MD_IDX_P101_CONTROL_SOURCE) == MD_SOURCE_FIELDBUS_CONTROL &&
           po_data_enabled(md) && md->po_received;
}

/* First received PO word whose P870..P872 description is `function`. */
static bool po_word(const movidrive_t *md, int32_t function, uint16_t *word)
{
    for (uint8_t i = 0; i < 3 && i < md->po_count; i++) {
        if (pv(md, (uint16_t)(MD_IDX_P870_PO1 + i)) == function) {
            *word = md->po[i];
            return true;
        }
    }
    return false;
}

static uint16_t compute_control_word(const movidrive_t *md)
{
    if (!cw_in_effect(md)) {
        return 0;
    }
    uint16_t w;
    if (po_word(md, PO_CTRL_WORD_1, &w)) {
        return w;
    }
    if (po_word(md, PO_CTRL_WORD_2, &w)) {
        return (uint16_t)(w & 0x00FFu); /* basic block; high byte: virtual terminals (ignored) */
    }
    return 0; /* no control word assigned: no enable */
}

static int32_t max_speed_mrpm(const movidrive_t *md)
{
    int32_t nmax = pv(md, MD_IDX_P302_MAX_SPEED);
    uint16_t w;
    if (po_data_enabled(md) && md->po_received && po_word(md, PO_MAX_SPEED, &w)) {
        int32_t po_max = (int32_t)(int16_t)w * 200;
        if (po_max >= 0 && po_max < nmax) {
            nmax = po_max;
        }
    }
    return nmax;
}

static int32_t compute_setpoint(const movidrive_t *md)
{
    if (pv(md, MD_IDX_P100_SETPOINT_SOURCE) != MD_SOURCE_FIELDBUS_SETPOINT ||
        !po_data_enabled(md) || !md->po_received) {
        return 0; /* other sources (analog, fixed setpoints via terminals) are not emulated */
    }
    int32_t nmax = max_speed_mrpm(md);
    int64_t n = 0;
    uint16_t w;
    if (po_word(md, PO_SPEED, &w)) {
        n = (int64_t)(int16_t)w * 200;
    } else if (po_word(md, PO_SPEED_PERCENT, &w)) {
        n = (int64_t)(int16_t)w * pv(md, MD_IDX_P302_MAX_SPEED) / 0x4000;
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
    bool bus = cw_in_effect(md);
    if (!md->cfg.terminal_enable || (bus && (cw & MD_CW_CONTROLLER_INHIBIT))) {
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
    if (!(cw & MD_CW_ENABLE_RAPID_STOP)) {
        return MODE_RAPID;
    }
    if (!(cw & MD_CW_ENABLE_STOP)) {
        return MODE_STOP;
    }
    return MODE_RUN;
}

static void update_currents(movidrive_t *md);

/* Re-evaluates mode, setpoint and the output stage after any input change. */
static void evaluate(movidrive_t *md)
{
    md->control_word = compute_control_word(md);
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
    update_currents(md);
}

static bool ramp_set_2(const movidrive_t *md)
{
    return cw_in_effect(md) && (md->control_word & MD_CW_RAMP_SET_2);
}

/* Ramp time in ms for a 3000 rpm change: `up` = |n| growing, `positive` = CW rotation. */
static int32_t ramp_ms(const movidrive_t *md, bool up, bool positive)
{
    bool set2 = ramp_set_2(md);
    switch (md->mode) {
    case MODE_RAPID:
        return pv(md, set2 ? IDX_P146_STOP_RAMP2 : IDX_P136_STOP_RAMP);
    case MODE_EMERGENCY:
        return pv(md, set2 ? IDX_P147_EMERGENCY_RAMP2 : IDX_P137_EMERGENCY_RAMP);
    default:
        break;
    }
    uint16_t w;
    if (po_data_enabled(md) && md->po_received && po_word(md, PO_RAMP, &w)) {
        return w; /* PO "RAMP": ms, up and down alike (I: 1 digit = 1 ms as on MOVIMOT) */
    }
    if (positive) {
        if (up) {
            return pv(md, set2 ? IDX_P140_RAMP2_UP : MD_IDX_P130_RAMP_UP);
        }
        return pv(md, set2 ? IDX_P141_RAMP2_DOWN : MD_IDX_P131_RAMP_DOWN);
    }
    if (up) {
        return pv(md, set2 ? IDX_P142_RAMP2_UP_CCW : IDX_P132_RAMP_UP_CCW);
    }
    return pv(md, set2 ? IDX_P143_RAMP2_DOWN_CCW : IDX_P133_RAMP_DOWN_CCW);
}

/* Moves the actual speed towards the setpoint for dt_us of simulated time. */
static void integrate_speed(movidrive_t *md, uint32_t dt_us)
{
    int64_t budget = (int64_t)dt_us * 3000 + md->ramp_residue; /* 0.001 rpm x ms */
    md->ramp_residue = 0;
    int32_t target = md->speed_setpoint_mrpm;
    while (md->speed_actual_mrpm != target) {
        int32_t n = md->speed_actual_mrpm;
        bool up;
        int32_t seg_end;
        if (n == 0 || (n > 0 && target > n) || (n < 0 && target < n)) {
            up = true;
            seg_end = target;
        } else {
            up = false; /* towards zero: down to the target, or to 0 if it is across */
            seg_end = ((n > 0 && target > 0) || (n < 0 && target < 0)) ? target : 0;
        }
        bool positive = n > 0 || (n == 0 && target > 0);
        int64_t t = ramp_ms(md, up, positive);
        if (t <= 0) {
            md->speed_actual_mrpm = seg_end;
            continue;
        }
        int64_t dist = (int64_t)seg_end - n;
        int64_t adist = dist < 0 ? -dist : dist;
        if (budget >= adist * t) {
            budget -= adist * t;
            md->speed_actual_mrpm = seg_end;
            continue;
        }
        int64_t step = budget / t;
        md->ramp_residue = budget % t;
        md->speed_actual_mrpm = (int32_t)(n + (dist < 0 ? -step : step));
        return;
    }
}

static int32_t abs32(int32_t v)
{
    return v < 0 ? -v : v;
}

static void update_currents(movidrive_t *md)
{
    if (!md->output_stage_enabled) {
        md->current_mpct = 0;
        md->active_current_mpct = 0;
        return;
    }
    int32_t n = md->speed_actual_mrpm;
    int32_t load = (int32_t)((int64_t)abs32(n) * LOAD_MPCT_AT_1500 / 1500000);
    int32_t accel = md->accel != 0 ? ACCEL_MPCT : 0;
    int32_t active = load + (md->accel > 0 ? accel : -accel);
    int32_t out = MAGNETISING_MPCT + load + accel;
    int32_t limit = pv(md, IDX_P303_CURRENT_LIMIT);
    if (limit > 0 && out > limit) {
        out = limit;
    }
    md->current_mpct = out;
    md->active_current_mpct = n < 0 ? -active : active;
}

/* ---------------------------------------------------------------------------------------------
 * Faults */

static void record_fault(movidrive_t *md, uint8_t number)
{
    int first = find_def(md, IDX_P080_ERROR_T0);
    int last = find_def(md, IDX_P084_ERROR_T4);
    if (first < 0 || last < first) {
        return;
    }
    for (int k = last; k > first; k--) {
        md->ram[k] = md->ram[k - 1];
        md->ee[k] = md->ee[k - 1];
    }
    md->ram[first] = number;
    md->ee[first] = number;
    (void)ee_save_params(md, (size_t)first, (size_t)last);
}

static void raise_fault(movidrive_t *md, uint8_t number, uint8_t reaction)
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
    raise_fault(md, number, REACT_IMM_ERROR);
    evaluate(md);
}

static void fault_reset(movidrive_t *md)
{
    if (md->fault == MD_FAULT_FIELDBUS_TIMEOUT && md->fieldbus_timeout) {
        return; /* the cause is still there */
    }
    md->fault = 0;
    md->fault_reaction = 0;
}

/* ---------------------------------------------------------------------------------------------
 * Status */

uint16_t movidrive_status_word(const movidrive_t *md)
{
    uint16_t sw = 0;
    if (md->output_stage_enabled) {
        sw |= MD_SW_OUTPUT_STAGE_ENABLED;
    }
    if (md->fault == 0) {
        sw |= MD_SW_READY;
    }
    if (po_data_enabled(md)) {
        sw |= MD_SW_PO_DATA_ENABLED;
    }
    if (ramp_set_2(md)) {
        sw |= MD_SW_RAMP_SET_2;
    }
    if (cw_in_effect(md) && (md->control_word & MD_CW_PARAM_SET_2)) {
        sw |= MD_SW_PARAM_SET_2;
    }
    uint8_t high;
    if (md->fault != 0) {
        sw |= MD_SW_FAULT;
        high = md->fault;
    } else if (md->warning) {
        sw |= MD_SW_FAULT;
        high = md->warning_code;
    } else if (md->mode == MODE_INHIBIT) {
        high = MD_UNIT_CONTROLLER_INHIBIT;
    } else if (pv(md, MD_IDX_P101_CONTROL_SOURCE) == MD_SOURCE_FIELDBUS_CONTROL &&
               po_data_enabled(md) && !md->po_received) {
        high = MD_UNIT_WAITING_FOR_DATA;
    } else if (md->mode == MODE_RUN) {
        high = MD_UNIT_ENABLED;
    } else {
        high = MD_UNIT_NO_ENABLE;
    }
    return (uint16_t)(sw | (high << 8));
}

static uint16_t pi_word(const movidrive_t *md, uint8_t i)
{
    if (i >= 3) {
        return md->ipos_pi[i];
    }
    int32_t n;
    switch (pv(md, (uint16_t)(IDX_P873_PI1 + i))) {
    case PI_SPEED:
        n = md->speed_actual_mrpm;
        n = (n + (n < 0 ? -100 : 100)) / 200;
        return (uint16_t)(int16_t)(n > INT16_MAX ? INT16_MAX : n < INT16_MIN ? INT16_MIN : n);
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
        int32_t nmax = pv(md, MD_IDX_P302_MAX_SPEED);
        if (nmax <= 0) {
            return 0;
        }
        int64_t r = (int64_t)md->speed_actual_mrpm * 0x4000 / nmax;
        return (uint16_t)(int16_t)(r > INT16_MAX ? INT16_MAX : r < INT16_MIN ? INT16_MIN : r);
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
        pi[i] = i < ML_MAX_PD ? pi_word(md, i) : 0;
    }
}

/* Values of read-only parameters the drive computes. */
static bool live_value(const movidrive_t *md, uint16_t index, int32_t *v)
{
    switch (index) {
    case MD_IDX_STATUS:
        *v = movidrive_status_word(md);
        return true;
    case MD_IDX_SPEED:
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
        *v = pi_word(md, (uint8_t)(index - IDX_P097_PI1));
        return true;
    }
    return false;
}

bool movidrive_read_value(const movidrive_t *md, uint16_t index, int32_t *value)
{
    if (is_ipos(index)) {
        *value = md->ipos[index - MD_IDX_IPOS_H0];
        return true;
    }
    int k = find_def(md, index);
    if (k < 0) {
        return false;
    }
    if (!live_value(md, index, value)) {
        *value = md->ram[k];
    }
    return true;
}

const md_param_def_t *movidrive_param_def(const movidrive_t *md, uint16_t index)
{
    if (is_ipos(index)) {
        return &md_ipos_def;
    }
    int k = find_def(md, index);
    return k < 0 ? NULL : &md->defs[k];
}

/* ---------------------------------------------------------------------------------------------
 * Init, factory setting */

static void load_defaults(movidrive_t *md, bool keep_read_only)
{
    for (size_t k = 0; k < md->num_defs; k++) {
        if (keep_read_only && (md->defs[k].flags & MD_PF_READ_ONLY)) {
            continue;
        }
        md->ram[k] = md->defs[k].def;
        md->ee[k] = md->defs[k].def;
    }
    memset(md->ipos, 0, sizeof md->ipos);
    memset(md->ee_ipos, 0, sizeof md->ee_ipos);
}

/* P819 is the exception: written through another interface it is shown until the master's
 * next parameterisation (protocol.md §B5), so it is taken only when that happened. */
static void apply_fieldbus_values(movidrive_t *md, bool take_p819)
{
    if (!md->have_fieldbus) {
        return;
    }
    const ml_fieldbus_status_t *st = &md->fieldbus;
    set_ram(md, MD_IDX_P090, st->pd_config);
    set_ram(md, IDX_P091_FIELDBUS_TYPE, 5); /* PROFIBUS DP */
    set_ram(md, IDX_P092_BAUD, (int32_t)st->baud);
    set_ram(md, IDX_P093_ADDRESS, st->address);
    if (take_p819) {
        set_ram(md, MD_IDX_P819_FIELDBUS_TIMEOUT, (int32_t)st->watchdog_ms);
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
    md->defs = md_params;
    md->num_defs = md_params_count;
    load_defaults(md, false);
    int rc = ee_load(md, err, errlen);
    if (cfg->sbus_address != 0) {
        set_ram(md, IDX_P813_SBUS_ADDRESS, cfg->sbus_address);
    }
    evaluate(md);
    return rc;
}

int movidrive_factory_reset(movidrive_t *md)
{
    load_defaults(md, true);
    apply_fieldbus_values(md, true); /* the defaults replaced the master's watchdog time */
    int rc = md->cfg.eeprom.ops != NULL ? ee_save_all(md) : 0;
    evaluate(md);
    return rc;
}

void movidrive_set_terminal_enable(movidrive_t *md, bool enabled)
{
    md->cfg.terminal_enable = enabled;
    evaluate(md);
}

/* ---------------------------------------------------------------------------------------------
 * Parameter services */

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
    return !cw_in_effect(md) || (md->control_word & MD_CW_CONTROLLER_INHIBIT);
}

/* P870..P875: the process data mapping must not change under a running motor. */
static bool needs_output_stage_off(uint16_t index)
{
    return index >= MD_IDX_P870_PO1 && index <= IDX_P873_PI1 + 2u;
}

/* Returns the class 8 additional code, 0 = done. */
static uint8_t write_param(movidrive_t *md, uint16_t index, int32_t v, bool non_volatile)
{
    if (is_ipos(index)) {
        size_t i = index - MD_IDX_IPOS_H0;
        md->ipos[i] = v; /* variables, not parameters: P803 does not lock them (I) */
        if (non_volatile) {
            md->ee_ipos[i] = v;
            if (ee_save_ipos(md, i) != 0) {
                return ML_ADD_NOT_SAVED;
            }
        }
        return 0;
    }
    int k = find_def(md, index);
    if (k < 0) {
        return ML_ADD_ILLEGAL_INDEX;
    }
    const md_param_def_t *d = &md->defs[k];
    if (d->flags & MD_PF_READ_ONLY) {
        return ML_ADD_READ_ONLY;
    }
    if (pv(md, MD_IDX_P803_PARAM_LOCK) == 1 && !(d->flags & MD_PF_LOCK_EXEMPT)) {
        return ML_ADD_PARAMETER_LOCK;
    }
    if (!non_volatile && (d->flags & MD_PF_NO_VOLATILE)) {
        return ML_ADD_VALUE_NOT_PERMITTED;
    }
    if ((d->flags & MD_PF_INHIBIT_REQUIRED) && !inhibit_for_write(md)) {
        return ML_ADD_CONTROLLER_INHIBIT_REQUIRED;
    }
    if (needs_output_stage_off(index) && md->output_stage_enabled) {
        return ML_ADD_OUTPUT_STAGE_ENABLED;
    }
    if (d->flags & MD_PF_UNSIGNED) {
        if ((d->flags & MD_PF_HAS_MAX) && (uint32_t)v > (uint32_t)d->max) {
            return ML_ADD_TOO_HIGH;
        }
        if ((d->flags & MD_PF_HAS_MIN) && (uint32_t)v < (uint32_t)d->min) {
            return ML_ADD_TOO_LOW;
        }
    } else {
        if ((d->flags & MD_PF_HAS_MAX) && v > d->max) {
            return ML_ADD_TOO_HIGH;
        }
        if ((d->flags & MD_PF_HAS_MIN) && v < d->min) {
            return ML_ADD_TOO_LOW;
        }
    }
    if (!value_in_range(d, v)) {
        return ML_ADD_VALUE_NOT_PERMITTED;
    }
    /* Commands: executed, the parameter keeps reading 0. */
    switch (index) {
    case IDX_P802_FACTORY:
        if (v == 1 && movidrive_factory_reset(md) != 0) {
            return ML_ADD_NOT_SAVED;
        }
        return 0;
    case IDX_P840_MANUAL_RESET:
        if (v == 1) {
            fault_reset(md);
            evaluate(md);
        }
        return 0;
    case IDX_P804_RESET_STATS:
        if (v == 1) { /* ERROR MEMORY */
            int first = find_def(md, IDX_P080_ERROR_T0);
            int last = find_def(md, IDX_P084_ERROR_T4);
            for (int j = first; j >= 0 && j <= last; j++) {
                md->ram[j] = md->ee[j] = 0;
            }
            if (first >= 0 && last >= first &&
                ee_save_params(md, (size_t)first, (size_t)last) != 0) {
                return ML_ADD_NOT_SAVED;
            }
        }
        return 0;
    default:
        break;
    }
    int32_t old = md->ram[k];
    md->ram[k] = v;
    uint8_t rc = 0;
    if (non_volatile && (d->flags & MD_PF_NON_VOLATILE)) {
        md->ee[k] = v;
        if (ee_save_params(md, (size_t)k, (size_t)k) != 0) {
            rc = ML_ADD_NOT_SAVED;
        }
    }
    /* S5: changing P870..P872 sets P876 PO data enable to NO. */
    if (index >= MD_IDX_P870_PO1 && index <= MD_IDX_P870_PO1 + 2u && old != v) {
        int e = find_def(md, MD_IDX_P876_PO_ENABLE);
        if (e >= 0) {
            md->ram[e] = 0;
            if (non_volatile) {
                md->ee[e] = 0;
                if (ee_save_params(md, (size_t)e, (size_t)e) != 0) {
                    rc = ML_ADD_NOT_SAVED;
                }
            }
        }
    }
    evaluate(md);
    return rc;
}

static void put_attribute(const movidrive_t *md, uint16_t index, const md_param_def_t *d,
                          uint8_t *rsp)
{
    uint16_t next = 0;
    if (is_ipos(index)) {
        next = index + 1u < MD_IDX_IPOS_H0 + MD_IPOS_VARS ? (uint16_t)(index + 1u) : 0u;
    } else {
        int k = find_def(md, index);
        next = (size_t)k + 1u < md->num_defs ? md->defs[k + 1].index : (uint16_t)MD_IDX_IPOS_H0;
    }
    uint16_t a = 0;
    if (!(d->flags & MD_PF_READ_ONLY)) {
        a |= MD_ATTR_WRITE_ALLOWED | MD_ATTR_FACTORY_RAM;
        if (d->flags & MD_PF_NON_VOLATILE) {
            a |= MD_ATTR_FACTORY_EEPROM;
        }
    }
    if (d->flags & MD_PF_NON_VOLATILE) {
        a |= MD_ATTR_EEPROM | MD_ATTR_EEPROM_VALID_AT_INIT;
    }
    if (!(d->flags & MD_PF_INHIBIT_REQUIRED)) {
        a |= MD_ATTR_NO_INHIBIT_REQUIRED;
    }
    hal_put_be16(rsp + 4, next);
    hal_put_be16(rsp + 6, a);
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
    const md_param_def_t *d = movidrive_param_def(md, index);
    if (d == NULL || req[ML_OFF_RESERVED] != 0) {
        ml_put_error(rsp, ML_CLASS_OTHER, 0, ML_ADD_ILLEGAL_INDEX);
        return;
    }
    bool uns = (d->flags & MD_PF_UNSIGNED) != 0;
    int32_t v = 0;
    switch (service) {
    case ML_SVC_READ:
        (void)movidrive_read_value(md, index, &v);
        ml_put_data(rsp, (uint32_t)v);
        break;
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
        ml_put_data(rsp, (d->flags & MD_PF_HAS_MIN) ? (uint32_t)d->min
                         : uns                      ? 0u
                                                    : (uint32_t)INT32_MIN);
        break;
    case ML_SVC_READ_MAX:
        ml_put_data(rsp, (d->flags & MD_PF_HAS_MAX) ? (uint32_t)d->max
                         : uns                      ? UINT32_MAX
                                                    : (uint32_t)INT32_MAX);
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

/* ---------------------------------------------------------------------------------------------
 * Process data, fieldbus, time */

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
    uint16_t cw = compute_control_word(md);
    if (cw_in_effect(md) && (cw & MD_CW_RESET) && !(prev & MD_CW_RESET)) {
        fault_reset(md);
    }
    evaluate(md);
}

void movidrive_fieldbus_status(movidrive_t *md, const ml_fieldbus_status_t *st)
{
    bool parameterised = st->prm_count != 0u &&
                         (!md->have_fieldbus || st->prm_count != md->fieldbus.prm_count);
    md->fieldbus = *st;
    md->have_fieldbus = true;
    apply_fieldbus_values(md, parameterised);
    if (st->timeout && !md->fieldbus_timeout) {
        md->fieldbus_timeout = true;
        uint8_t r = (uint8_t)pv(md, MD_IDX_P831_FIELDBUS_REACTION);
        switch (r) {
        case REACT_NONE:
            break;
        case REACT_IMM_ERROR:
        case REACT_EMERG_ERROR:
        case REACT_RAPID_ERROR:
            raise_fault(md, MD_FAULT_FIELDBUS_TIMEOUT, r);
            break;
        default: /* DISPLAY ERROR and the .../WARNG reactions */
            md->warning = true;
            md->warning_code = MD_FAULT_FIELDBUS_TIMEOUT;
            md->warning_reaction = r == REACT_DISPLAY ? REACT_NONE : r;
            break;
        }
    } else if (!st->timeout && md->fieldbus_timeout) {
        md->fieldbus_timeout = false;
        if (md->warning && md->warning_code == MD_FAULT_FIELDBUS_TIMEOUT) {
            md->warning = false;
            md->warning_code = 0;
            md->warning_reaction = 0;
        }
    }
    evaluate(md);
}

hal_time_us_t movidrive_tick(movidrive_t *md, hal_time_us_t now)
{
    if (!md->ticked) {
        md->ticked = true;
        md->last_tick = now;
        evaluate(md);
        return now + 1000u;
    }
    int32_t dt = hal_time_diff(now, md->last_tick);
    if (dt <= 0) {
        return now + (md->speed_actual_mrpm != md->speed_setpoint_mrpm ? 1000u
                                                                        : HAL_TIME_NO_DEADLINE_US);
    }
    md->last_tick = now;
    evaluate(md);
    int32_t before = md->speed_actual_mrpm;
    uint32_t left = (uint32_t)dt;
    while (left > 0) {
        uint32_t chunk = left > 1000000u ? 1000000u : left;
        int32_t n0 = md->speed_actual_mrpm;
        integrate_speed(md, chunk);
        /* position: trapezoid, 4096 increments per revolution */
        int64_t num = ((int64_t)n0 + md->speed_actual_mrpm) * chunk * (INC_PER_REV / 2) +
                      md->pos_residue;
        const int64_t den = 60LL * 1000000 * 1000;
        md->position_inc += (int32_t)(num / den);
        md->pos_residue = num % den;
        left -= chunk;
    }
    int32_t after = md->speed_actual_mrpm;
    md->accel = (int8_t)(abs32(after) > abs32(before) ? 1 : abs32(after) < abs32(before) ? -1 : 0);
    evaluate(md); /* a stop ramp that reached 0 switches the output stage off */
    return now + (md->speed_actual_mrpm != md->speed_setpoint_mrpm ? 1000u
                                                                    : HAL_TIME_NO_DEADLINE_US);
}
