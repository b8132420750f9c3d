/* Non-volatile storage as a small array of bytes. The backend guarantees that a write which is
 * interrupted (power loss, crash) leaves either all old or all new bytes of that write; on flash
 * or EEPROM this is done with two copies and a sequence number, on the host with
 * write-to-temporary + fsync + rename. */
#ifndef HAL_NVM_H
#define HAL_NVM_H

#include <stddef.h>
#include <stdint.h>

typedef struct hal_nvm_ops {
    size_t (*size)(void *ctx);
    /* 0 on success, negative on failure (out of range, I/O error). */
    int (*read)(void *ctx, size_t offset, uint8_t *data, size_t len);
    int (*write)(void *ctx, size_t offset, const uint8_t *data, size_t len);
} hal_nvm_ops_t;

typedef struct hal_nvm {
    const hal_nvm_ops_t *ops;
    void *ctx;
} hal_nvm_t;

#endif
