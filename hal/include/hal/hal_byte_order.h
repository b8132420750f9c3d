/* Big-endian ("Motorola") octet order: how PROFIBUS DP, DP-V1, PROFIdrive, MOVILINK and SBus put
 * 16- and 32-bit numbers on the wire (docs/protocol.md §A3.4, §B7, §C1.1), and how the host's
 * file formats store them. Bounds are the caller's: every function touches exactly 2 or 4 octets. */
#ifndef HAL_BYTE_ORDER_H
#define HAL_BYTE_ORDER_H

#include <stdint.h>

static inline uint16_t hal_get_be16(const uint8_t *p)
{
    return (uint16_t)(((uint16_t)p[0] << 8) | p[1]);
}

static inline uint32_t hal_get_be32(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

static inline void hal_put_be16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)((v >> 8) & 0xFFu);
    p[1] = (uint8_t)(v & 0xFFu);
}

static inline void hal_put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)((v >> 24) & 0xFFu);
    p[1] = (uint8_t)((v >> 16) & 0xFFu);
    p[2] = (uint8_t)((v >> 8) & 0xFFu);
    p[3] = (uint8_t)(v & 0xFFu);
}

#endif
