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
    fdl_collect_init(&u->collect, u->rx_buf[0], cfg->baud, cfg->strict_timing);
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

/* The collector belongs to the interrupt; the rest of the driver touches it only like this. */
static uint32_t irq_mask(void)
{
#ifndef BOARD_HOST_TEST
    uint32_t primask;
    __asm volatile("mrs %0, primask\n cpsid i" : "=r"(primask)::"memory");
    return primask;
#else
    return 0;
#endif
}

static void irq_restore(uint32_t primask)
{
#ifndef BOARD_HOST_TEST
    __asm volatile("msr primask, %0" ::"r"(primask) : "memory");
#else
    (void)primask;
#endif
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
    uint32_t m = irq_mask();
    fdl_collect_set_baud(&u->collect, baud);
    irq_restore(m);
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
        r->DR = u->tx_frame[u->tx_pos++];
    }
    if (u->tx_pos < u->tx_len) {
        r->CR1 |= USART_CR1_TXEIE;
    } else if ((r->SR & USART_SR_TC) != 0u) {
        tx_finish(u); /* only where TC follows DR at once (QEMU); real USARTs take a character */
    } else {
        r->CR1 = (r->CR1 & ~USART_CR1_TXEIE) | USART_CR1_TCIE;
    }
}

/* Its own function so that tools/reply_path_count.py can tell the wait from the work: the spin
 * is the line's min TSDR, not the CPU's cost. */
__attribute__((noinline)) void rs485_wait_until(const volatile uint32_t *clock_us,
                                                hal_time_us_t t)
{
    while (hal_time_diff(t, *clock_us) > 0) {
    }
}

int rs485_uart_transmit(rs485_uart_t *u, const uint8_t *frame, size_t len,
                        hal_time_us_t not_before)
{
    if (len == 0u || len > RS485_TX_MAX || u->tx_busy) {
        u->tx_refused++;
        return -1;
    }
    /* A telegram after the request is waiting or coming in: the core ran late (the main loop
     * held it off) and the bus has moved on, e.g. to the master's retry. Answering now would
     * collide with it; the retry gets its answer when it is served. */
    if (atomic_load_explicit(&u->rx_head, memory_order_acquire) !=
            atomic_load_explicit(&u->rx_tail, memory_order_relaxed) ||
        u->collect.len != 0u) {
        u->tx_stale++;
        return -1;
    }
    u->tx_frame = frame;
    u->tx_len = (uint16_t)len;
    u->tx_pos = 0;
    u->tx_busy = true;
    u->tx_frames++;
    /* min TSDR: the bus is silent until we answer, so nothing else needs the CPU's receive path
     * now; a bounded spin costs less than a timer interrupt at high rates (11 bit times at
     * 1.5 Mbit/s = 7.3 µs) and is at most RS485_MAX_WAIT_US at 9600 bit/s. */
    int32_t wait = hal_time_diff(not_before, *u->cfg.clock_us);
    if (wait > (int32_t)RS485_MAX_WAIT_US) {
        u->tx_clock_mixups++;
    } else {
        rs485_wait_until(u->cfg.clock_us, not_before);
    }
    usart_regs_t *r = u->cfg.regs;
    r->CR1 &= ~USART_CR1_RE; /* never hear our own characters */
    de_set(u, true);
    tx_fill(u);
    return 0;
}

static unsigned rx_buf_index(const rs485_uart_t *u, const uint8_t *buf)
{
    return (unsigned)((size_t)(buf - &u->rx_buf[0][0]) / FDL_FRAME_MAX);
}

static inline __attribute__((always_inline)) void rx_queue_put(rs485_uart_t *u,
                                                                const fdl_rx_telegram_t *tg)
{
    uint32_t head = atomic_load_explicit(&u->rx_head, memory_order_relaxed);
    u->rx_queue[head % RS485_RX_QUEUE] = *tg;
    atomic_store_explicit(&u->rx_head, head + 1u, memory_order_release);
}

static inline __attribute__((always_inline)) bool rx_queue_full(const rs485_uart_t *u)
{
    return atomic_load_explicit(&u->rx_head, memory_order_relaxed) -
               atomic_load_explicit(&u->rx_tail, memory_order_acquire) >=
           RS485_RX_QUEUE;
}

static void rx_queue_error(rs485_uart_t *u, fdl_rx_error_t e, hal_time_us_t t)
{
    if (!rx_queue_full(u)) {
        fdl_rx_telegram_t tg = {.error = e, .end_t = t, .idle_before_ns = UINT32_MAX};
        rx_queue_put(u, &tg);
    }
}

/* A finished telegram waits in its buffer; the collector goes on in a free one. With none free
 * the telegram is given up (its buffer reused) and reported like a hardware overrun. */
static void rx_take_telegram(rs485_uart_t *u)
{
    const fdl_rx_telegram_t *tg = &u->collect.telegram;
    unsigned cur = rx_buf_index(u, tg->buf);
    unsigned next = RS485_RX_BUFFERS;
    for (unsigned i = 0; i < RS485_RX_BUFFERS; i++) {
        if (i != cur && !u->rx_buf_busy[i]) {
            next = i;
            break;
        }
    }
    if (next == RS485_RX_BUFFERS || rx_queue_full(u)) {
        u->rx_buffer_overflows++;
        rx_queue_error(u, FDL_RX_ERR_CHAR, tg->end_t);
        return;
    }
    u->rx_telegrams++;
    u->rx_buf_busy[cur] = true;
    rx_queue_put(u, tg);
    fdl_collect_give_buffer(&u->collect, u->rx_buf[next]);
}

void rs485_uart_rx_hand_over(rs485_uart_t *u, unsigned collected)
{
    if ((collected & FDL_COLLECT_ERROR) != 0u) {
        rx_queue_error(u, u->collect.error, u->collect.error_t);
    }
    if ((collected & FDL_COLLECT_TELEGRAM) != 0u) {
        rx_take_telegram(u);
    }
    if (u->cfg.rx_pending != NULL) {
        u->cfg.rx_pending(u->cfg.rx_ctx);
    }
}

unsigned rs485_uart_rx_drain(rs485_uart_t *u)
{
    unsigned n = 0;
    uint32_t tail = atomic_load_explicit(&u->rx_tail, memory_order_relaxed);
    while (tail != atomic_load_explicit(&u->rx_head, memory_order_acquire)) {
        fdl_rx_telegram_t tg = u->rx_queue[tail % RS485_RX_QUEUE];
        tail++;
        /* Out of the queue before rx(), so a reply to it is not taken for a late one; the
         * buffer is released only after rx() has served it. */
        atomic_store_explicit(&u->rx_tail, tail, memory_order_release);
        if (u->cfg.rx != NULL) {
            u->cfg.rx(u->cfg.rx_ctx, &tg);
        }
        if (tg.buf != NULL) {
            u->rx_buf_busy[rx_buf_index(u, tg.buf)] = false;
        }
        n++;
    }
    return n;
}

/* A character with an error flag (SR then DR, which clears PE/FE/ORE). */
static void rx_char_with_error(rs485_uart_t *u, uint32_t sr)
{
    uint8_t byte = (uint8_t)(u->cfg.regs->DR & 0xFFu);
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
    unsigned collected = fdl_collect_slow(&u->collect, byte, flags, *u->cfg.clock_us);
    if (collected != 0u) {
        rs485_uart_rx_hand_over(u, collected);
    }
}

void rs485_uart_isr_other(rs485_uart_t *u, uint32_t sr)
{
    usart_regs_t *r = u->cfg.regs;
    if ((sr & USART_SR_RXNE) != 0u) {
        rx_char_with_error(u, sr);
        return;
    }
    if ((sr & (USART_SR_ORE | USART_SR_FE)) != 0u) {
        (void)r->DR; /* clears an error flag without data (ORE after a read) */
    }
    uint32_t cr1 = r->CR1;
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
