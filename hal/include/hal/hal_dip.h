/* The seven address DIP switches (2^0..2^6), read once at power-up: the DFP21B manual (3.6)
 * says an address change takes effect only after the next power cycle. */
#ifndef HAL_DIP_H
#define HAL_DIP_H

#include <stdint.h>

typedef struct hal_dip_ops {
    /* Bits 0..6 = switches 2^0..2^6 (1 = ON). */
    uint8_t (*read)(void *ctx);
} hal_dip_ops_t;

typedef struct hal_dip {
    const hal_dip_ops_t *ops;
    void *ctx;
} hal_dip_t;

#endif
