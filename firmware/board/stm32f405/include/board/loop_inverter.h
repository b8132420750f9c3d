/* A stand-in inverter for images without a CAN controller (QEMU does not model bxCAN): the
 * card's SBus link (movilink/sbus.c, unchanged) sends its frames into a memory loop instead of
 * bxCAN, and an sbus_inverter_t on the other end answers them: read of index 8300 (firmware
 * part number, 823947913 like the emulated MOVIDRIVE's default), 8301 (0), read/write of index
 * 8600..8603 (four RAM words), everything else class 8 "illegal index"; PI words echo PO words.
 * Frames cross in loop_inverter_poll() from the main loop, never from an interrupt. */
#ifndef BOARD_LOOP_INVERTER_H
#define BOARD_LOOP_INVERTER_H

#include <stdint.h>

#include "hal/hal_can.h"
#include "movilink/sbus.h"

#define LOOP_INVERTER_QUEUE 16u

typedef struct loop_can_queue {
    hal_can_frame_t f[LOOP_INVERTER_QUEUE];
    uint32_t head, tail;
    uint32_t dropped;
} loop_can_queue_t;

typedef struct loop_inverter {
    sbus_inverter_t inv;
    loop_can_queue_t to_inverter;
    loop_can_queue_t to_card;
    uint16_t po[SBUS_PD_WORDS];
    uint32_t ram[4];
    uint32_t services;
} loop_inverter_t;

void loop_inverter_init(loop_inverter_t *l, uint8_t sbus_address);
/* The CAN the card's SBus link sends on. */
hal_can_t loop_inverter_card_can(loop_inverter_t *l);
/* Moves frames both ways; card frames go to rx(ctx, frame). Returns how many moved. */
/* between(ctx), if set, runs between two frames the stand-in takes, so that the main loop's
 * sections stay short (each frame is one section of the stand-in's work). */
unsigned loop_inverter_poll(loop_inverter_t *l, hal_time_us_t now, hal_can_rx_fn rx, void *ctx,
                            void (*between)(void *ctx));

#endif
