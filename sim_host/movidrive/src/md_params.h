/* The generated parameter table (md_params.c, from tools/gen_params.py). */
#ifndef MOVIDRIVE_MD_PARAMS_H
#define MOVIDRIVE_MD_PARAMS_H

#include <stddef.h>

#include "movidrive/movidrive.h"

/* Sorted by index, one entry per MOVILINK index, H0..H511 excluded. */
extern const md_param_def_t md_params[];
extern const size_t md_params_count;
/* The one definition all IPOS variables H0..H511 share. */
extern const md_param_def_t md_ipos_def;

#endif
