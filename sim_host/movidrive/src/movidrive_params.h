/* The generated parameter table (movidrive_params.c, from tools/gen_params.py). */
#ifndef MOVIDRIVE_MOVIDRIVE_PARAMS_H
#define MOVIDRIVE_MOVIDRIVE_PARAMS_H

#include <stddef.h>

#include "movidrive/movidrive.h"

/* Sorted by index, one entry per MOVILINK index, H0..H511 excluded. */
extern const movidrive_param_def_t movidrive_params[];
extern const size_t movidrive_params_count;
/* The one definition all IPOS variables H0..H511 share. */
extern const movidrive_param_def_t movidrive_ipos_def;

#endif
