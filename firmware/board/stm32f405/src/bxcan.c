#include "board/bxcan.h"

#include <string.h>

bool bxcan_timing(uint32_t pclk_hz, uint32_t bitrate, uint32_t *btr)
{
    if (bitrate == 0u) {
        return false;
    }
    for (uint32_t tq = 25u; tq >= 8u; tq--) {
        uint32_t div = bitrate * tq;
        if (pclk_hz % div != 0u) {
            continue;
        }
        uint32_t brp = pclk_hz / div;
        if (brp < 1u || brp > 1024u) {
            continue;
        }
        uint32_t ts2 = (tq + 4u) / 8u; /* sample point ~87.5 % */
        if (ts2 < 1u) {
            ts2 = 1u;
        }
        uint32_t ts1 = tq - 1u - ts2;
        if (ts1 < 1u || ts1 > 16u || ts2 > 8u) {
            continue;
        }
        uint32_t sjw = ts2 < 4u ? ts2 : 4u;
        *btr = ((sjw - 1u) << 24) | ((ts2 - 1u) << 20) | ((ts1 - 1u) << 16) | (brp - 1u);
        return true;
    }
    return false;
}

static bool wait_msr(can_regs_t *r, uint32_t mask, uint32_t want)
{
    for (uint32_t i = 0; i < BXCAN_INIT_SPINS; i++) {
        if ((r->MSR & mask) == want) {
            return true;
        }
    }
    return false;
}

int bxcan_init(bxcan_t *c, const bxcan_cfg_t *cfg)
{
    memset(c, 0, sizeof *c);
    c->cfg = *cfg;
    can_regs_t *r = cfg->regs;
    uint32_t btr;
    if (!bxcan_timing(cfg->pclk_hz, cfg->bitrate, &btr)) {
        return -1;
    }
    r->MCR = CAN_MCR_INRQ; /* leave sleep, request initialisation */
    if (!wait_msr(r, CAN_MSR_INAK | CAN_MSR_SLAK, CAN_MSR_INAK)) {
        return -1;
    }
    /* Automatic bus-off recovery; transmit in request order (SBus parameter frames). */
    r->MCR = CAN_MCR_INRQ | CAN_MCR_ABOM | CAN_MCR_TXFP;
    r->BTR = btr;
    /* Filter bank 0: 32-bit mask 0/0 = every frame, into FIFO 0. */
    r->FMR |= CAN_FMR_FINIT;
    r->FA1R &= ~1u;
    r->FS1R |= 1u;
    r->FM1R &= ~1u;
    r->FFA1R &= ~1u;
    r->FILTER[0].FR1 = 0;
    r->FILTER[0].FR2 = 0;
    r->FA1R |= 1u;
    r->FMR &= ~CAN_FMR_FINIT;
    r->IER = CAN_IER_FMPIE0;
    r->MCR = CAN_MCR_ABOM | CAN_MCR_TXFP; /* normal mode */
    if (!wait_msr(r, CAN_MSR_INAK, 0u)) {
        return -1;
    }
    c->up = true;
    return 0;
}

int bxcan_send(bxcan_t *c, const hal_can_frame_t *f)
{
    if (!c->up || f->len > HAL_CAN_MAX_DLC) {
        return -1;
    }
    can_regs_t *r = c->cfg.regs;
    uint32_t tsr = r->TSR;
    unsigned mb;
    for (mb = 0; mb < 3u; mb++) {
        if ((tsr & (CAN_TSR_TME0 << mb)) != 0u) {
            break;
        }
    }
    if (mb == 3u) {
        c->tx_full++;
        return -1;
    }
    uint8_t d[8] = {0};
    memcpy(d, f->data, f->len);
    r->TX[mb].TDTR = f->len;
    r->TX[mb].TDLR = (uint32_t)d[0] | ((uint32_t)d[1] << 8) | ((uint32_t)d[2] << 16) |
                     ((uint32_t)d[3] << 24);
    r->TX[mb].TDHR = (uint32_t)d[4] | ((uint32_t)d[5] << 8) | ((uint32_t)d[6] << 16) |
                     ((uint32_t)d[7] << 24);
    r->TX[mb].TIR = ((uint32_t)(f->id & HAL_CAN_ID_MASK) << 21) | CAN_TIR_TXRQ;
    c->tx_frames++;
    return 0;
}

void bxcan_rx_isr(bxcan_t *c)
{
    can_regs_t *r = c->cfg.regs;
    for (unsigned n = 0; n < 3u && (r->RF0R & CAN_RF0R_FMP_MASK) != 0u; n++) {
        uint32_t rir = r->RX[0].RIR;
        uint32_t rdtr = r->RX[0].RDTR;
        uint32_t lo = r->RX[0].RDLR;
        uint32_t hi = r->RX[0].RDHR;
        r->RF0R = CAN_RF0R_RFOM; /* release the FIFO slot */
        if ((rir & (CAN_RIR_IDE | CAN_RIR_RTR)) != 0u) {
            c->rx_ignored++;
            continue;
        }
        uint32_t head = c->head;
        if (head - c->tail >= BXCAN_RING) {
            c->rx_dropped++;
            continue;
        }
        hal_can_frame_t *f = &c->ring[head & (BXCAN_RING - 1u)];
        f->id = (uint16_t)((rir >> 21) & HAL_CAN_ID_MASK);
        f->len = (uint8_t)((rdtr & 0xFu) > 8u ? 8u : (rdtr & 0xFu));
        for (unsigned i = 0; i < 4u; i++) {
            f->data[i] = (uint8_t)(lo >> (8u * i));
            f->data[4u + i] = (uint8_t)(hi >> (8u * i));
        }
        c->head = head + 1u;
        c->rx_frames++;
    }
    if ((r->RF0R & CAN_RF0R_FOVR) != 0u) {
        r->RF0R = CAN_RF0R_FOVR;
        c->rx_dropped++;
    }
}

unsigned bxcan_drain(bxcan_t *c)
{
    unsigned n = 0;
    while (c->tail != c->head) {
        hal_can_frame_t f = c->ring[c->tail & (BXCAN_RING - 1u)];
        c->tail = c->tail + 1u;
        if (c->cfg.rx != NULL) {
            c->cfg.rx(c->cfg.rx_ctx, &f);
        }
        n++;
    }
    return n;
}

static int op_send(void *ctx, const hal_can_frame_t *f)
{
    return bxcan_send(ctx, f);
}

static const hal_can_ops_t bxcan_ops = {.send = op_send};

hal_can_t bxcan_hal(bxcan_t *c)
{
    return (hal_can_t){.ops = &bxcan_ops, .ctx = c};
}
