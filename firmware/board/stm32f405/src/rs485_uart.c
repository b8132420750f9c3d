#include "board/rs485_uart.h"

#include <string.h>

bool rs485_uart_brr(uint32_t pclk_hz, uint32_t baud, uint32_t *brr, bool *over8)
{
    if (baud == 0u) {
        return false;
    }
    /* x = USARTDIV in 1/16 (OVER8=0) or in 1/8 (OVER8=1): both are pclk / baud, rounded. */
    uint32_t x = (uint32_t)(((uint64_t)pclk_hz + baud / 2u) / baud);
    bool o8 = x < 16u;
    if (x < 8u) {
        return false; /* USARTDIV below 1 */
    }
    uint32_t actual = (uint32_t)(((uint64_t)pclk_hz) / x);
    uint32_t diff = actual > baud ? actual - baud : baud - actual;
    if ((uint64_t)diff * 1000u > (uint64_t)baud * 3u) {
        return false; /* more than 0.3 % off */
    }
    *over8 = o8;
    *brr = o8 ? (((x >> 3) << 4) | (x & 7u)) : x;
    return true;
}

static void de_set(const rs485_uart_t *u, bool on)
{
    if (u->cfg.de_port != NULL) {
        u->cfg.de_port->BSRR = on ? (1u << u->cfg.de_pin) : (1u << (u->cfg.de_pin + 16u));
    }
}

int rs485_uart_init(rs485_uart_t *u, const rs485_uart_cfg_t *cfg)
{
    memset(u, 0, sizeof *u);
    atomic_init(&u->rx_head, 0u);
    atomic_init(&u->rx_tail, 0u);
    u->cfg = *cfg;
    usart_regs_t *r = cfg->regs;
    de_set(u, false);
    r->CR1 = 0;
    r->CR2 = 0;                 /* 1 stop bit */
    r->CR3 = USART_CR3_EIE;     /* FE/ORE/NF raise the interrupt too */
    uint32_t brr;
    bool over8;
    if (!rs485_uart_brr(cfg->pclk_hz, cfg->baud, &brr, &over8)) {
        return -1;
    }
    r->BRR = brr;
    u->baud = cfg->baud;
    r->CR1 = (over8 ? USART_CR1_OVER8 : 0u) | USART_CR1_M | USART_CR1_PCE | USART_CR1_UE |
             USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE | USART_CR1_PEIE;
    return 0;
}

int rs485_uart_set_baud(rs485_uart_t *u, uint32_t baud)
{
    uint32_t brr;
    bool over8;
    /* Refused while a frame goes out (the interrupt owns CR1 until TC). The core changes the
     * rate only in its baud search and after the baud-control timeout, both long after its
     * last reply, so it never meets this refusal in practice. */
    if (u->tx_busy || !rs485_uart_brr(u->cfg.pclk_hz, baud, &brr, &over8)) {
        u->baud_refused++;
        return -1;
    }
    usart_regs_t *r = u->cfg.regs;
    uint32_t cr1 = r->CR1;
    if (((cr1 & USART_CR1_OVER8) != 0u) != over8) {
        /* OVER8 may only change with the USART disabled (RM0090 §30.6.4). */
        r->CR1 = cr1 & ~USART_CR1_UE;
        cr1 = over8 ? (cr1 | USART_CR1_OVER8) : (cr1 & ~USART_CR1_OVER8);
        r->BRR = brr;
        r->CR1 = cr1;
    } else {
        r->BRR = brr;
    }
    u->baud = baud;
    return 0;
}

static void tx_finish(rs485_uart_t *u)
{
    usart_regs_t *r = u->cfg.regs;
    de_set(u, false);
    r->CR1 = (r->CR1 & ~(USART_CR1_TXEIE | USART_CR1_TCIE)) | USART_CR1_RE;
    u->tx_busy = false;
}

/* Feed DR while it takes characters; then either wait for TXE again or for TC. */
static void tx_fill(rs485_uart_t *u)
{
    usart_regs_t *r = u->cfg.regs;
    while (u->tx_pos < u->tx_len && (r->SR & USART_SR_TXE) != 0u) {
        r->DR = u->tx_buf[u->tx_pos++];
    }
    if (u->tx_pos < u->tx_len) {
        r->CR1 |= USART_CR1_TXEIE;
    } else if ((r->SR & USART_SR_TC) != 0u) {
        tx_finish(u); /* only where TC follows DR at once (QEMU); real USARTs take a character */
    } else {
        r->CR1 = (r->CR1 & ~USART_CR1_TXEIE) | USART_CR1_TCIE;
    }
}

int rs485_uart_transmit(rs485_uart_t *u, const uint8_t *frame, size_t len,
                        hal_time_us_t not_before)
{
    if (len == 0u || len > RS485_TX_MAX || u->tx_busy) {
        u->tx_refused++;
        return -1;
    }
    /* Characters after the request are waiting in the ring: the drain ran late (the main loop
     * held it off) and the bus has moved on, e.g. to the master's retry. Answering now would
     * collide with it; the retry gets its answer when it is drained. */
    if (atomic_load_explicit(&u->rx_head, memory_order_acquire) !=
        atomic_load_explicit(&u->rx_tail, memory_order_relaxed)) {
        u->tx_stale++;
        return -1;
    }
    memcpy(u->tx_buf, frame, len);
    u->tx_len = (uint16_t)len;
    u->tx_pos = 0;
    u->tx_busy = true;
    u->tx_frames++;
    /* min TSDR: the bus is silent until we answer, so nothing else needs the CPU's receive path
     * now; a bounded spin costs less than a timer interrupt at high rates (11 bit times at
     * 1.5 Mbit/s = 7.3 µs) and is at most RS485_MAX_WAIT_US at 9600 bit/s. */
    if (u->cfg.now != NULL) {
        int32_t wait = hal_time_diff(not_before, u->cfg.now());
        if (wait > (int32_t)RS485_MAX_WAIT_US) {
            u->tx_clock_mixups++;
        } else {
            while (hal_time_diff(not_before, u->cfg.now()) > 0) {
            }
        }
    }
    usart_regs_t *r = u->cfg.regs;
    r->CR1 &= ~USART_CR1_RE; /* never hear our own characters */
    de_set(u, true);
    tx_fill(u);
    return 0;
}

static unsigned rx_store(rs485_uart_t *u, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    uint32_t head = atomic_load_explicit(&u->rx_head, memory_order_relaxed);
    uint32_t tail = atomic_load_explicit(&u->rx_tail, memory_order_acquire);
    if (head - tail >= RS485_RX_RING) {
        u->rx_ring_overflows++;
        u->rx_lost = true;
        return 0;
    }
    if (u->rx_lost) {
        flags |= HAL_UART_RX_OVERRUN_ERR; /* characters before this one were lost */
        u->rx_lost = false;
    }
    u->rx_ring[head % RS485_RX_RING] = (rs485_rx_entry_t){.t = t, .byte = byte, .flags = flags};
    atomic_store_explicit(&u->rx_head, head + 1u, memory_order_release);
    return 1;
}

unsigned rs485_uart_rx_drain(rs485_uart_t *u)
{
    unsigned n = 0;
    uint32_t tail = atomic_load_explicit(&u->rx_tail, memory_order_relaxed);
    while (tail != atomic_load_explicit(&u->rx_head, memory_order_acquire)) {
        rs485_rx_entry_t e = u->rx_ring[tail % RS485_RX_RING];
        tail++;
        atomic_store_explicit(&u->rx_tail, tail, memory_order_release);
        if (u->cfg.rx != NULL) {
            u->cfg.rx(u->cfg.rx_ctx, e.byte, e.flags, e.t);
        }
        n++;
    }
    return n;
}

void rs485_uart_isr(rs485_uart_t *u)
{
    usart_regs_t *r = u->cfg.regs;
    /* Receive: SR first, then DR, per character (that order clears PE/FE/ORE). At most a few
     * characters per call: the USART holds one, plus the one being shifted in. */
    unsigned stored = 0;
    for (unsigned n = 0; n < 4u; n++) {
        uint32_t sr = r->SR;
        if ((sr & USART_SR_RXNE) == 0u) {
            if ((sr & (USART_SR_ORE | USART_SR_FE)) != 0u) {
                (void)r->DR; /* clears an error flag without data (ORE after a read) */
            }
            break;
        }
        uint8_t byte = (uint8_t)(r->DR & 0xFFu); /* bit 8 is the parity bit */
        hal_time_us_t t = u->cfg.now != NULL ? u->cfg.now() : 0u;
        uint8_t flags = 0;
        if ((sr & USART_SR_PE) != 0u) {
            flags |= HAL_UART_RX_PARITY_ERR;
            u->rx_parity_errors++;
        }
        if ((sr & USART_SR_FE) != 0u) {
            flags |= HAL_UART_RX_FRAMING_ERR;
            u->rx_framing_errors++;
        }
        if ((sr & USART_SR_ORE) != 0u) {
            flags |= HAL_UART_RX_OVERRUN_ERR; /* a character before this one was lost */
            u->rx_overruns++;
        }
        u->rx_chars++;
        stored += rx_store(u, byte, flags, t);
    }
    if (stored != 0u && u->cfg.rx_pending != NULL) {
        u->cfg.rx_pending(u->cfg.rx_ctx);
    }
    /* Transmit. */
    uint32_t cr1 = r->CR1;
    uint32_t sr = r->SR;
    if ((cr1 & USART_CR1_TXEIE) != 0u && (sr & USART_SR_TXE) != 0u) {
        tx_fill(u);
    } else if ((cr1 & USART_CR1_TCIE) != 0u && (sr & USART_SR_TC) != 0u) {
        tx_finish(u);
    }
}

static int op_set_baud(void *ctx, uint32_t baud)
{
    return rs485_uart_set_baud(ctx, baud);
}

static int op_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    return rs485_uart_transmit(ctx, frame, len, not_before);
}

static const hal_uart_ops_t rs485_ops = {.set_baud = op_set_baud, .transmit = op_transmit};

hal_uart_t rs485_uart_hal(rs485_uart_t *u)
{
    return (hal_uart_t){.ops = &rs485_ops, .ctx = u};
}
