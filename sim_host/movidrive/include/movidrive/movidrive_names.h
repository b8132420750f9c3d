/* Names of the emulated MOVIDRIVE's parameters, values, faults and control/status word bits, for
 * people: command lines, logs, dissectors. Generated from sim_host/movidrive/data/ (the table in
 * movidrive_names_table.c); no heap, no mutable state, every function may be called from any
 * thread. */
#ifndef MOVIDRIVE_MOVIDRIVE_NAMES_H
#define MOVIDRIVE_MOVIDRIVE_NAMES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct movidrive_enum_text {
    int32_t value;
    const char *text;
} movidrive_enum_text_t;

typedef struct movidrive_param_info {
    const char *p_number; /* "P100"; the error memory's sub-entries "P080.Speed" */
    uint16_t index;       /* MOVILINK index, 8461 */
    const char *name;     /* "setpoint source" */
    const char *unit;     /* "rpm", "ms", "%", "" when none */
    int32_t scale_exp;    /* value in unit = raw * 10^scale_exp (P000: -3, P130: 0) */
    const movidrive_enum_text_t *enums;
    uint16_t num_enums;
    bool read_only, non_volatile, inhibit_required;
} movidrive_param_info_t;

/* One row per MOVILINK index; H0..H511 (11000 + n) are not rows. NULL if unknown. */
const movidrive_param_info_t *movidrive_param_info(uint16_t index);
/* Iteration, sorted by P-number. movidrive_param_at(i >= count) = NULL. */
size_t movidrive_param_count(void);
const movidrive_param_info_t *movidrive_param_at(size_t i);

/* "P100", "p100", "P600" (another P-number of P031's index), "8461", "0x210D", "setpoint
 * source" (case-insensitive; the exact name, else a unique substring). NULL and a one-line
 * reason in err (may be NULL) otherwise: "no parameter 'P999'", "'speed' matches 12 parameters:
 * P000 speed, ..." (at most 5 listed). */
const movidrive_param_info_t *movidrive_param_find(const char *text, char *err, size_t errlen);

/* "3 (FIELDBUS)", "300.000 rpm", "2000 ms", "12", "7 (unknown value)" for an enumerated
 * parameter's undefined value. Parameters the drive compares unsigned (P092) print unsigned.
 * Returns what snprintf returns. p == NULL: the raw number. */
int movidrive_value_text(const movidrive_param_info_t *p, int32_t raw, char *out, size_t n);
/* The enumeration text alone, or NULL. */
const char *movidrive_enum_text(const movidrive_param_info_t *p, int32_t raw);
/* Accepts an enumeration text ("FIELDBUS", case-insensitive), a raw integer ("3", "0x10", "-5";
 * -2^31..2^32-1, stored as the 32-bit pattern), a number with at most the unit's decimals
 * ("300.5" for a -3 scale -> 300500), or a number followed by the unit ("300 rpm" -> 300000).
 * Range checks are left to the drive. false and a one-line reason in err (may be NULL) otherwise.
 * p == NULL: raw integers only. */
bool movidrive_value_parse(const movidrive_param_info_t *p, const char *text, int32_t *raw,
                           char *err, size_t errlen);

/* "fieldbus timeout" for 28, "no fault" for 0, NULL if unknown. */
const char *movidrive_fault_name(uint8_t fault);
/* Status word 1 high byte without a fault: "enabled" for 4, NULL if unknown. */
const char *movidrive_unit_status_name(uint8_t code);

/* "0006 = enable, no rapid stop, no stop": bits 0..2 always (set or clear meaning), bits 3..7
 * when set, a non-zero high byte as "high byte 0xNN". Returns what snprintf returns. */
int movidrive_control_word_text(uint16_t cw, char *out, size_t n);
/* "0407 = output stage enabled, ready, PO data enabled, unit status 4 (enabled)"; with bit 5
 * "... fault 28 (fieldbus timeout)". Bits 0..2 always, 3, 4, 6, 7 when set. */
int movidrive_status_word_text(uint16_t sw, char *out, size_t n);

#endif
