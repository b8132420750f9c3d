/* The generated name tables (movidrive_names_table.c, from tools/gen_params.py) behind
 * movidrive_names.h. */
#ifndef MOVIDRIVE_MOVIDRIVE_NAMES_TABLE_H
#define MOVIDRIVE_MOVIDRIVE_NAMES_TABLE_H

#include <stddef.h>
#include <stdint.h>

#include "movidrive/movidrive_names.h"

typedef struct movidrive_param_alias {
    const char *p_number;
    uint16_t index;
} movidrive_param_alias_t;

typedef struct movidrive_code_name {
    uint8_t code;
    const char *name;
} movidrive_code_name_t;

typedef struct movidrive_bit_text {
    const char *set;
    const char *clear; /* "" = not worth saying when clear */
} movidrive_bit_text_t;

extern const movidrive_param_info_t movidrive_param_infos[]; /* sorted by P-number */
extern const size_t movidrive_param_infos_count;
/* positions in movidrive_param_infos, by index */
extern const uint16_t movidrive_param_infos_by_index[];
extern const movidrive_param_alias_t movidrive_param_aliases[];
extern const size_t movidrive_param_aliases_count;
extern const movidrive_code_name_t movidrive_fault_names[]; /* sorted by code */
extern const size_t movidrive_fault_names_count;
extern const movidrive_code_name_t movidrive_unit_status_names[];
extern const size_t movidrive_unit_status_names_count;
extern const movidrive_bit_text_t movidrive_control_bits[8];
extern const movidrive_bit_text_t movidrive_status_bits[8];

#endif
