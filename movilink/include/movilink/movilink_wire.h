/* The 8-byte MOVILINK parameter telegram (protocol.md §B6, protocol.md §C1): management byte,
 * reserved/subindex byte, index high/low, 4 data octets big-endian. The same 8 octets travel in
 * the PROFIBUS cyclic channel, in SBus parameter frames and (field by field) in data set 47. */
#ifndef MOVILINK_MOVILINK_WIRE_H
#define MOVILINK_MOVILINK_WIRE_H

#include <stdint.h>

#include "hal/hal_byte_order.h"

#define ML_TELEGRAM_LEN 8u

#define ML_OFF_MANAGEMENT 0u
#define ML_OFF_RESERVED 1u
#define ML_OFF_INDEX_HIGH 2u
#define ML_OFF_INDEX_LOW 3u
#define ML_OFF_DATA 4u
/* An error reply's data octets: class, code, additional code (high, low). */
#define ML_OFF_ERROR_CLASS 4u
#define ML_OFF_ERROR_CODE 5u
#define ML_OFF_ERROR_ADD_HIGH 6u
#define ML_OFF_ERROR_ADD_LOW 7u

/* Management byte. */
#define ML_MGMT_SERVICE_MASK 0x0Fu
#define ML_MGMT_LENGTH_MASK 0x30u
#define ML_MGMT_LENGTH_4 0x30u
#define ML_MGMT_HANDSHAKE 0x40u
#define ML_MGMT_ERROR 0x80u

/* Services (bits 3..0). */
#define ML_SVC_NONE 0x0u
#define ML_SVC_READ 0x1u
#define ML_SVC_WRITE 0x2u
#define ML_SVC_WRITE_VOLATILE 0x3u
#define ML_SVC_READ_MIN 0x4u
#define ML_SVC_READ_MAX 0x5u
#define ML_SVC_READ_DEFAULT 0x6u
#define ML_SVC_READ_SCALE 0x7u
#define ML_SVC_READ_ATTRIBUTE 0x8u
#define ML_SVC_LAST ML_SVC_READ_ATTRIBUTE

/* Error classes (byte 4 of an error reply) and the codes the card itself produces. */
#define ML_CLASS_SERVICE 5u
#define ML_CLASS_ACCESS 6u
#define ML_CLASS_OTHER 8u
#define ML_CODE_ILLEGAL_PARAMETER 5u /* class 5: wrong management/reserved coding */
#define ML_CODE_HARDWARE_FAULT 2u    /* class 6: card <-> inverter communication */
#define ML_CODE_TYPE_CONFLICT 8u     /* class 6: data length other than 4 octets */

/* Class 8 additional codes (low byte; high byte 0), from the inverter. */
#define ML_ADD_ILLEGAL_INDEX 0x10u
#define ML_ADD_NOT_IMPLEMENTED 0x11u
#define ML_ADD_READ_ONLY 0x12u
#define ML_ADD_PARAMETER_LOCK 0x13u
#define ML_ADD_FACTORY_SETTING_ACTIVE 0x14u
#define ML_ADD_TOO_HIGH 0x15u
#define ML_ADD_TOO_LOW 0x16u
#define ML_ADD_OPTION_MISSING 0x17u
#define ML_ADD_SYSTEM_ERROR 0x18u
#define ML_ADD_ACCESS_PROTECTED 0x1Bu
#define ML_ADD_CONTROLLER_INHIBIT_REQUIRED 0x1Cu
#define ML_ADD_VALUE_NOT_PERMITTED 0x1Du
#define ML_ADD_FACTORY_SETTING_ACTIVATED 0x1Eu
#define ML_ADD_NOT_SAVED 0x1Fu
#define ML_ADD_OUTPUT_STAGE_ENABLED 0x20u

/* A MOVILINK error as one word, class in the high octet (protocol.md §B7.3): 0x0810 illegal
 * index, 0x0505 wrong management coding. */
#define ML_ERROR_WORD(err_class, code) ((uint16_t)(((err_class) << 8) | (code)))
#define ML_ERROR_ILLEGAL_INDEX ML_ERROR_WORD(ML_CLASS_OTHER, ML_ADD_ILLEGAL_INDEX)
#define ML_ERROR_ILLEGAL_PARAMETER ML_ERROR_WORD(ML_CLASS_SERVICE, ML_CODE_ILLEGAL_PARAMETER)

static inline uint16_t ml_index(const uint8_t *t)
{
    return hal_get_be16(&t[ML_OFF_INDEX_HIGH]);
}

static inline uint32_t ml_data(const uint8_t *t)
{
    return hal_get_be32(&t[ML_OFF_DATA]);
}

static inline void ml_put_data(uint8_t *t, uint32_t v)
{
    hal_put_be32(&t[ML_OFF_DATA], v);
}

/* An error reply: management with the error bit, class/code/additional code in the data. */
static inline void ml_put_error(uint8_t *t, uint8_t err_class, uint8_t code, uint16_t add)
{
    t[ML_OFF_MANAGEMENT] = (uint8_t)(t[ML_OFF_MANAGEMENT] | ML_MGMT_ERROR);
    t[ML_OFF_ERROR_CLASS] = err_class;
    t[ML_OFF_ERROR_CODE] = code;
    hal_put_be16(&t[ML_OFF_ERROR_ADD_HIGH], add);
}

#endif
