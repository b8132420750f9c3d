/* Lengths of the I/O data a Chk_Cfg configuration describes (general and special identifier
 * formats, protocol.md §A3.3). Used by masters to size Data_Exchange telegrams. */
#ifndef DP_SLAVE_DP_CFG_H
#define DP_SLAVE_DP_CFG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Returns false for a malformed configuration (length octets missing, total > 244). */
bool dp_cfg_io_lengths(const uint8_t *cfg, size_t len, uint16_t *out_len, uint16_t *in_len);

#endif
