/* bxCAN driver behind hal_can_t (the same CAN HAL as the host's SocketCAN backend), for the SBus
 * link to the inverter: 11-bit identifiers, one filter bank accepting everything into FIFO 0.
 *
 * Receive runs in two halves: bxcan_rx_isr() (FIFO 0 message pending interrupt) moves frames
 * from the hardware FIFO into a ring; bxcan_drain() in the main loop hands them to rx(), so the
 * SBus link and the MOVILINK client run in main-loop context only. */
#ifndef BOARD_BXCAN_H
#define BOARD_BXCAN_H

#include <stdbool.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "hal/hal_can.h"

#define BXCAN_RING 16u /* power of two */
/* Polls of MSR while waiting for the controller to enter/leave initialisation. A controller that
 * is absent or not clocked (QEMU does not model bxCAN) never answers: init fails after this. */
#define BXCAN_INIT_SPINS 100000u

typedef struct bxcan_cfg {
    can_regs_t *regs;
    uint32_t pclk_hz; /* APB1 */
    uint32_t bitrate; /* SBus: P816, default 500 kbit/s */
    hal_can_rx_fn rx;
    void *rx_ctx;
} bxcan_cfg_t;

typedef struct bxcan {
    bxcan_cfg_t cfg;
    bool up;
    hal_can_frame_t ring[BXCAN_RING];
    volatile uint32_t head; /* written by the ISR */
    volatile uint32_t tail; /* written by the main loop */
    uint32_t rx_frames;
    uint32_t rx_dropped;   /* ring full, or FIFO overrun in the controller */
    uint32_t rx_ignored;   /* extended or remote frames */
    uint32_t tx_frames;
    uint32_t tx_full;      /* all three mailboxes busy */
} bxcan_t;

/* Bit timing for a rate: prescaler, TS1, TS2 with the sample point near 87.5 %. Returns false if
 * no prescaler gives 8..25 time quanta. */
bool bxcan_timing(uint32_t pclk_hz, uint32_t bitrate, uint32_t *btr);
/* 0, or -1 (rate impossible, or the controller did not acknowledge initialisation/normal mode:
 * then the card runs without inverter). */
int bxcan_init(bxcan_t *c, const bxcan_cfg_t *cfg);
hal_can_t bxcan_hal(bxcan_t *c);
int bxcan_send(bxcan_t *c, const hal_can_frame_t *f);
void bxcan_rx_isr(bxcan_t *c);
/* Hands queued frames to rx(); returns how many. */
unsigned bxcan_drain(bxcan_t *c);

#endif
