/* The generated name tables (md_names_table.c, from tools/gen_params.py) behind md_names.h. */
#ifndef MOVIDRIVE_MD_NAMES_TABLE_H
#define MOVIDRIVE_MD_NAMES_TABLE_H

#include <stddef.h>
#include <stdint.h>

#include "movidrive/md_names.h"

typedef struct md_param_alias {
    const char *p_number;
    uint16_t index;
} md_param_alias_t;

typedef struct md_code_name {
    uint8_t code;
    const char *name;
} md_code_name_t;

typedef struct md_bit_text {
    const char *set;
    const char *clear; /* "" = not worth saying when clear */
} md_bit_text_t;

extern const md_param_info_t md_param_infos[]; /* sorted by P-number */
extern const size_t md_param_infos_count;
extern const uint16_t md_param_infos_by_index[]; /* positions in md_param_infos, by index */
extern const md_param_alias_t md_param_aliases[];
extern const size_t md_param_aliases_count;
extern const md_code_name_t md_fault_names[]; /* sorted by code */
extern const size_t md_fault_names_count;
extern const md_code_name_t md_unit_status_names[];
extern const size_t md_unit_status_names_count;
extern const md_bit_text_t md_control_bits[8];
extern const md_bit_text_t md_status_bits[8];

#endif
