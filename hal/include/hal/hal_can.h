/* CAN as the SBus link between the card and its inverter needs it: 11-bit identifiers, up to 8
 * data octets. Received frames are pushed into the user by the backend (like UART characters);
 * send() queues one frame. */
#ifndef HAL_CAN_H
#define HAL_CAN_H

#include <stdint.h>

#define HAL_CAN_MAX_DLC 8u
#define HAL_CAN_ID_MASK 0x7FFu

typedef struct hal_can_frame {
    uint16_t id; /* 11-bit identifier */
    uint8_t len;
    uint8_t data[HAL_CAN_MAX_DLC];
} hal_can_frame_t;

typedef struct hal_can_ops {
    /* Queue one frame. 0, or negative (bus off, queue full, no interface). */
    int (*send)(void *ctx, const hal_can_frame_t *frame);
} hal_can_ops_t;

typedef struct hal_can {
    const hal_can_ops_t *ops;
    void *ctx;
} hal_can_t;

/* The receiving side of a CAN backend calls this for every frame. */
typedef void (*hal_can_rx_fn)(void *ctx, const hal_can_frame_t *frame);

#endif
