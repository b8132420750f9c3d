/* The STM32F405 board drivers on the host, against register fakes: structs in RAM with the
 * hardware's layout (offsets checked below), so each test sets status bits the way the
 * peripheral would and checks what the driver wrote. The USART, its DE pin and the µs counter
 * sit on a page that sees every access (below), so the tests also see the bytes leaving DR in
 * order, DR reads and the spin on the counter. Interrupt timing on a real core is covered by the
 * QEMU test (qemu_card.sh). */
#define _GNU_SOURCE /* sigaction, mmap, the x86-64 register names of ucontext_t */
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "board/board.h"
#include "board/board_io.h"
#include "board/bxcan.h"
#include "board/rs485_uart.h"
#include "board/timebase.h"
#include "check.h"

#if defined(__linux__) && defined(__x86_64__)
#define BUS_TRAPS 1
#include <signal.h>
#include <sys/mman.h>
#include <ucontext.h>
#include <unistd.h>
#else
#define BUS_TRAPS 0
#endif

/* ---- register layout ------------------------------------------------------------------------ */
_Static_assert(offsetof(usart_regs_t, CR1) == 0x0C, "USART CR1");
_Static_assert(offsetof(usart_regs_t, GTPR) == 0x18, "USART GTPR");
_Static_assert(offsetof(gpio_regs_t, BSRR) == 0x18, "GPIO BSRR");
_Static_assert(offsetof(gpio_regs_t, AFR) == 0x20, "GPIO AFR");
_Static_assert(offsetof(rcc_regs_t, AHB1ENR) == 0x30, "RCC AHB1ENR");
_Static_assert(offsetof(rcc_regs_t, APB2ENR) == 0x44, "RCC APB2ENR");
_Static_assert(offsetof(rcc_regs_t, CSR) == 0x74, "RCC CSR");
_Static_assert(offsetof(iwdg_regs_t, SR) == 0x0C, "IWDG SR");
_Static_assert(offsetof(can_regs_t, BTR) == 0x1C, "CAN BTR");
_Static_assert(offsetof(can_regs_t, TX) == 0x180, "CAN TX mailboxes");
_Static_assert(offsetof(can_regs_t, RX) == 0x1B0, "CAN RX FIFOs");
_Static_assert(offsetof(can_regs_t, FMR) == 0x200, "CAN FMR");
_Static_assert(offsetof(can_regs_t, FA1R) == 0x21C, "CAN FA1R");
_Static_assert(offsetof(can_regs_t, FILTER) == 0x240, "CAN filter banks");
_Static_assert(offsetof(tim_regs_t, CNT) == 0x24, "TIM CNT");
_Static_assert(offsetof(tim_regs_t, PSC) == 0x28, "TIM PSC");
_Static_assert(offsetof(tim_regs_t, ARR) == 0x2C, "TIM ARR");
_Static_assert(offsetof(systick_regs_t, VAL) == 0x08, "SysTick VAL");

/* ---- a register page that sees every access ------------------------------------------------- */
/* The USART, the DE pin's port and the µs counter (TIM2 CNT) share a page of their own. While a
 * driver function runs the page is inaccessible: each access faults, the handler lets exactly
 * that instruction through (trap flag, one step), then logs it and plays the peripheral's part:
 * reading DR clears RXNE and the error flags (RM0090 §30.6.1: SR then DR), writing DR takes TXE
 * and TC away until the test moves the character on, and each read of the counter advances it by
 * cnt_step µs (the time the CPU spends looking). Needs x86-64 Linux; elsewhere the checks that
 * depend on it are skipped. */
typedef struct bus_regs {
    usart_regs_t usart;
    gpio_regs_t gpio_a;
    volatile uint32_t cnt; /* TIM2 CNT, the free-running µs counter */
} bus_regs_t;

enum bus_reg { BUS_SR, BUS_DR, BUS_BRR, BUS_CR1, BUS_BSRR, BUS_CNT, BUS_OTHER };
typedef struct bus_event {
    enum bus_reg reg;
    bool write;
    uint32_t value; /* read: what the driver got; write: what it wrote */
} bus_event_t;

#define BUS_EVENTS_MAX 1024u
static struct {
    uint32_t cnt_step;
    bool instant_tx; /* QEMU's USART: a character leaves at once, TXE and TC stay set */
    uintptr_t fault_addr;
    bool fault_write;
    unsigned n; /* events, counted past BUS_EVENTS_MAX too */
    bus_event_t ev[BUS_EVENTS_MAX];
    unsigned tx_n; /* characters written to DR */
    uint8_t tx[2u * RS485_TX_MAX];
    bool tx_bit8; /* a write with bit 8 set: the parity bit is the hardware's (PCE) */
} bus;
static bus_regs_t *hw;
static usart_regs_t *usart;
static gpio_regs_t *gpio_a;
#if BUS_TRAPS
static size_t bus_page;
#else
static bus_regs_t bus_plain;
#endif

#if BUS_TRAPS
static enum bus_reg bus_reg_at(uintptr_t a)
{
    uintptr_t b = (uintptr_t)hw;
    if (a == b + offsetof(bus_regs_t, usart.SR)) {
        return BUS_SR;
    }
    if (a == b + offsetof(bus_regs_t, usart.DR)) {
        return BUS_DR;
    }
    if (a == b + offsetof(bus_regs_t, usart.BRR)) {
        return BUS_BRR;
    }
    if (a == b + offsetof(bus_regs_t, usart.CR1)) {
        return BUS_CR1;
    }
    if (a == b + offsetof(bus_regs_t, gpio_a.BSRR)) {
        return BUS_BSRR;
    }
    return a == b + offsetof(bus_regs_t, cnt) ? BUS_CNT : BUS_OTHER;
}

/* After the access: what the peripheral does about it. */
static void bus_model(enum bus_reg reg, bool write, uint32_t value)
{
    if (bus.n < BUS_EVENTS_MAX) {
        bus.ev[bus.n] = (bus_event_t){.reg = reg, .write = write, .value = value};
    }
    bus.n++;
    if (reg == BUS_DR && write) {
        if (bus.tx_n < sizeof bus.tx) {
            bus.tx[bus.tx_n] = (uint8_t)value;
        }
        bus.tx_n++;
        bus.tx_bit8 = bus.tx_bit8 || value > 0xFFu;
        if (!bus.instant_tx) {
            hw->usart.SR &= ~(USART_SR_TXE | USART_SR_TC);
        }
    } else if (reg == BUS_DR) {
        hw->usart.SR &= ~(USART_SR_RXNE | USART_SR_IDLE | USART_SR_ORE | USART_SR_NF |
                          USART_SR_FE | USART_SR_PE);
    } else if (reg == BUS_CNT && !write) {
        hw->cnt += bus.cnt_step;
    }
}

#define TRAP_FLAG 0x100 /* EFLAGS.TF */
#define PF_WRITE 0x2    /* page-fault error code: the access was a write */

static void bus_on_segv(int sig, siginfo_t *si, void *ucv)
{
    uintptr_t a = (uintptr_t)si->si_addr;
    if (a < (uintptr_t)hw || a >= (uintptr_t)hw + bus_page) {
        (void)signal(sig, SIG_DFL); /* a real fault: it recurs and ends the program there */
        return;
    }
    ucontext_t *uc = ucv;
    bus.fault_addr = a;
    bus.fault_write = (uc->uc_mcontext.gregs[REG_ERR] & PF_WRITE) != 0;
    (void)mprotect(hw, bus_page, PROT_READ | PROT_WRITE);
    uc->uc_mcontext.gregs[REG_EFL] |= TRAP_FLAG;
}

static void bus_on_trap(int sig, siginfo_t *si, void *ucv)
{
    (void)sig;
    (void)si;
    ucontext_t *uc = ucv;
    uc->uc_mcontext.gregs[REG_EFL] &= ~(greg_t)TRAP_FLAG;
    bus_model(bus_reg_at(bus.fault_addr), bus.fault_write,
              *(volatile uint32_t *)bus.fault_addr);
    (void)mprotect(hw, bus_page, PROT_NONE);
}
#endif

static void bus_init(void)
{
#if BUS_TRAPS
    bus_page = (size_t)sysconf(_SC_PAGESIZE);
    void *p = mmap(NULL, bus_page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
        perror("mmap");
        exit(1);
    }
    hw = p;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_flags = SA_SIGINFO;
    sa.sa_sigaction = bus_on_segv;
    (void)sigaction(SIGSEGV, &sa, NULL);
    sa.sa_sigaction = bus_on_trap;
    (void)sigaction(SIGTRAP, &sa, NULL);
#else
    hw = &bus_plain;
    printf("register page without traps on this host: DR and counter checks skipped\n");
#endif
    usart = &hw->usart;
    gpio_a = &hw->gpio_a;
}

/* Around every driver call: the driver's accesses are seen, the test's own are not. */
static void bus_arm(void)
{
#if BUS_TRAPS
    (void)mprotect(hw, bus_page, PROT_NONE);
#endif
}

static void bus_disarm(void)
{
#if BUS_TRAPS
    (void)mprotect(hw, bus_page, PROT_READ | PROT_WRITE);
#endif
}

static void bus_clear(void)
{
    bus.n = 0;
    bus.tx_n = 0;
    bus.tx_bit8 = false;
}

static int bus_find(int from, enum bus_reg reg, bool write)
{
    for (unsigned i = from < 0 ? 0u : (unsigned)from; i < bus.n && i < BUS_EVENTS_MAX; i++) {
        if (bus.ev[i].reg == reg && bus.ev[i].write == write) {
            return (int)i;
        }
    }
    return -1;
}

static unsigned bus_count(enum bus_reg reg, bool write)
{
    unsigned k = 0;
    for (int i = bus_find(0, reg, write); i >= 0; i = bus_find(i + 1, reg, write)) {
        k++;
    }
    return k;
}

static unsigned bus_writes(void)
{
    unsigned k = 0;
    for (unsigned i = 0; i < bus.n && i < BUS_EVENTS_MAX; i++) {
        k += bus.ev[i].write ? 1u : 0u;
    }
    return k;
}

/* ---- USART ---------------------------------------------------------------------------------- */
/* What rx() was handed: a copy of the entry and its octets, which buffer they were in and
 * whether the driver still held it then (it must until rx() returns). */
typedef struct rx_entry {
    fdl_rx_telegram_t tg;
    uint8_t octets[FDL_FRAME_MAX];
    int buf;
    bool buf_held;
} rx_entry_t;

#define RX_LOG_MAX 8u
typedef struct rx_log {
    unsigned n;
    unsigned pending; /* rx_pending calls by the interrupt */
    rx_entry_t e[RX_LOG_MAX];
    const uint8_t *reply; /* when set, rx() answers at once with this frame (6 octets) */
    int reply_rc;
} rx_log_t;

static rs485_uart_t u;
static rx_log_t rxl;

static void rx_cb(void *ctx, const fdl_rx_telegram_t *tg)
{
    rx_log_t *l = ctx;
    if (l->n < RX_LOG_MAX) {
        rx_entry_t *e = &l->e[l->n];
        e->tg = *tg;
        e->buf = -1;
        e->buf_held = false;
        for (unsigned i = 0; i < RS485_RX_BUFFERS; i++) {
            if (tg->buf == u.rx_buf[i]) {
                e->buf = (int)i;
                e->buf_held = u.rx_buf_busy[i];
            }
        }
        if (tg->buf != NULL && tg->len <= FDL_FRAME_MAX) {
            memcpy(e->octets, tg->buf, tg->len);
        }
    }
    l->n++;
    if (l->reply != NULL) {
        l->reply_rc = rs485_uart_transmit(&u, l->reply, 6u, 0u);
    }
}

static void rx_pending_cb(void *ctx)
{
    rx_log_t *l = ctx;
    l->pending++;
}

static void test_brr(void)
{
    static const struct {
        uint32_t baud, brr;
        int over8;
    } want[] = {
        {6000000u, 0x16u, 1},  {3000000u, 28u, 0},   {1500000u, 56u, 0}, {500000u, 168u, 0},
        {187500u, 448u, 0},    {93750u, 896u, 0},    {45450u, 1848u, 0}, {19200u, 4375u, 0},
        {9600u, 8750u, 0},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        uint32_t brr = 0;
        bool over8 = false;
        CHECK(rs485_uart_brr(84000000u, want[i].baud, &brr, &over8));
        CHECK_EQ(brr, want[i].brr);
        CHECK_EQ(over8, want[i].over8);
    }
    uint32_t brr;
    bool over8;
    /* 12 Mbit/s needs USARTDIV 0.875 at 84 MHz: below 1, impossible on APB2 of an F405. */
    CHECK(!rs485_uart_brr(84000000u, 12000000u, &brr, &over8));
    /* 0.3 %: 45450 from 16 MHz HSI is 0.01 % off (ok), 6 Mbit/s impossible. */
    CHECK(rs485_uart_brr(16000000u, 45450u, &brr, &over8));
    CHECK(!rs485_uart_brr(16000000u, 6000000u, &brr, &over8));
}

/* Driver calls with the register page watched. */
static void isr(void)
{
    bus_arm();
    rs485_uart_isr(&u);
    bus_disarm();
}

static unsigned drain(void)
{
    bus_arm();
    unsigned n = rs485_uart_rx_drain(&u);
    bus_disarm();
    return n;
}

static int transmit(const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    bus_arm();
    int rc = rs485_uart_transmit(&u, frame, len, not_before);
    bus_disarm();
    return rc;
}

static int set_baud(uint32_t baud)
{
    bus_arm();
    int rc = rs485_uart_set_baud(&u, baud);
    bus_disarm();
    return rc;
}

static void uart_setup(uint32_t baud, bool strict)
{
    memset(hw, 0, sizeof *hw);
    memset(&rxl, 0, sizeof rxl);
    bus_clear();
    bus.cnt_step = 0;
    bus.instant_tx = false;
    hw->cnt = 1000;
    rs485_uart_cfg_t cfg = {.regs = usart, .de_port = gpio_a, .de_pin = 8, .pclk_hz = 84000000u,
                            .baud = baud, .strict_timing = strict, .clock_us = &hw->cnt,
                            .rx = rx_cb, .rx_ctx = &rxl, .rx_pending = rx_pending_cb};
    bus_arm();
    int rc = rs485_uart_init(&u, &cfg);
    bus_disarm();
    CHECK_EQ(rc, 0);
}

static uint32_t parity_bit(uint8_t b)
{
    uint32_t p = 0;
    for (unsigned i = 0; i < 8u; i++) {
        p ^= (uint32_t)(b >> i) & 1u;
    }
    return p;
}

/* One received character at counter time t, with SR error flags as the USART sets them; bit 8
 * of DR is the (even) parity bit, which is not data. */
static void rx_char(uint8_t byte, uint32_t sr_flags, hal_time_us_t t)
{
    hw->cnt = t;
    usart->SR = USART_SR_RXNE | sr_flags;
    usart->DR = byte | (parity_bit(byte) << 8);
    isr();
}

/* A telegram's characters 1 µs apart from t0; returns the last one's time. */
static hal_time_us_t rx_frame(const uint8_t *f, size_t n, hal_time_us_t t0)
{
    for (size_t i = 0; i < n; i++) {
        rx_char(f[i], 0u, t0 + (hal_time_us_t)i);
    }
    return t0 + (hal_time_us_t)(n - 1u);
}

/* Log entry k is telegram f from buffer buf, ended at end_t after idle_ns of idle line. */
static void check_telegram(unsigned k, const uint8_t *f, size_t n, int buf, hal_time_us_t end_t,
                           uint32_t idle_ns)
{
    const rx_entry_t *e = &rxl.e[k];
    CHECK_EQ(e->tg.error, FDL_RX_OK);
    CHECK_EQ(e->tg.len, n);
    CHECK(e->tg.len == n && memcmp(e->octets, f, n) == 0);
    CHECK_EQ(e->buf, buf);
    CHECK(e->buf_held);
    CHECK_EQ(e->tg.end_t, end_t);
    CHECK_EQ(e->tg.idle_before_ns, idle_ns);
}

static void check_error(unsigned k, fdl_rx_error_t error, hal_time_us_t t)
{
    const rx_entry_t *e = &rxl.e[k];
    CHECK_EQ(e->tg.error, error);
    CHECK(e->tg.buf == NULL);
    CHECK_EQ(e->tg.len, 0);
    CHECK_EQ(e->tg.end_t, t);
    CHECK_EQ(e->tg.idle_before_ns, UINT32_MAX);
}

static bool no_buffer_held(void)
{
    bool any = false;
    for (unsigned i = 0; i < RS485_RX_BUFFERS; i++) {
        any = any || u.rx_buf_busy[i];
    }
    return !any;
}

/* FDL status request to 4 from 2; a Data_Exchange request with 2 output octets; variants. */
static const uint8_t sd1[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t sd1b[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
static const uint8_t sd2[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x7D, 0xAB, 0xCD, 0xFB, 0x16};
static const uint8_t sd2b[] = {0x68, 0x05, 0x05, 0x68, 0x85, 0x82, 0x7D, 0x11, 0x22, 0xB7, 0x16};
/* One 11-bit character at 1.5 Mbit/s, in whole ns (hal_uart_char_ns). */
#define CHAR_NS_1M5 7333u

static void test_uart_init_and_baud(void)
{
    uart_setup(19200u, false);
    /* 9-bit word, parity on, even (PS=0), enabled, RX interrupts, no OVER8 at 19.2k */
    CHECK_EQ(usart->CR1, USART_CR1_M | USART_CR1_PCE | USART_CR1_UE | USART_CR1_TE |
                             USART_CR1_RE | USART_CR1_RXNEIE | USART_CR1_PEIE);
    CHECK_EQ(usart->CR2, 0);         /* 1 stop bit */
    CHECK_EQ(usart->CR3, USART_CR3_EIE);
    CHECK_EQ(usart->BRR, 4375u);
    CHECK_EQ(gpio_a->BSRR, 1u << (8 + 16)); /* DE low */
    CHECK(!u.collect.strict);               /* cfg.strict_timing reaches the collector */
    /* baud search: 6 Mbit/s needs OVER8, which may change only with UE off (RM0090 §30.6.4) */
    bus_clear();
    CHECK_EQ(set_baud(6000000u), 0);
    CHECK((usart->CR1 & USART_CR1_OVER8) != 0u);
    CHECK((usart->CR1 & USART_CR1_UE) != 0u);
    CHECK_EQ(usart->BRR, 0x16u);
    if (BUS_TRAPS) {
        int off = bus_find(0, BUS_CR1, true);
        int brr = bus_find(off, BUS_BRR, true);
        int on = bus_find(brr, BUS_CR1, true);
        CHECK(off >= 0 && (bus.ev[off].value & (USART_CR1_UE | USART_CR1_OVER8)) == 0u);
        CHECK(brr > off && bus.ev[brr].value == 0x16u);
        CHECK(on > brr && (bus.ev[on].value & (USART_CR1_UE | USART_CR1_OVER8)) ==
                              (USART_CR1_UE | USART_CR1_OVER8));
        CHECK_EQ(bus_count(BUS_CR1, true), 2);
    }
    CHECK_EQ(u.collect.char_ns, hal_uart_char_ns(6000000u)); /* the collector's timing follows */
    CHECK_EQ(set_baud(12000000u), -1);
    CHECK_EQ(u.baud, 6000000u);
    CHECK_EQ(u.baud_refused, 1);
    CHECK_EQ(set_baud(1500000u), 0);
    CHECK((usart->CR1 & USART_CR1_OVER8) == 0u);
    CHECK((usart->CR1 & USART_CR1_UE) != 0u);
    CHECK_EQ(usart->BRR, 56u);
    /* OVER8 stays: only BRR is written, the USART stays on */
    bus_clear();
    CHECK_EQ(set_baud(500000u), 0);
    CHECK_EQ(usart->BRR, 168u);
    if (BUS_TRAPS) {
        CHECK_EQ(bus_count(BUS_CR1, true), 0);
        CHECK_EQ(bus_count(BUS_BRR, true), 1);
    }
    CHECK_EQ(u.collect.char_ns, hal_uart_char_ns(500000u));
}

/* (1) An SD1 telegram, character by character as the interrupt takes them. */
static void test_uart_rx_sd1(void)
{
    uart_setup(1500000u, true);
    CHECK_EQ(hal_uart_char_ns(1500000u), CHAR_NS_1M5);
    CHECK(u.collect.strict);
    bool early = false;
    for (unsigned i = 0; i < sizeof sd1; i++) {
        early = early || rxl.pending != 0u || u.rx_telegrams != 0u;
        rx_char(sd1[i], 0u, 5000u + i);
    }
    CHECK(!early);            /* nothing before the last character */
    CHECK_EQ(rxl.pending, 1); /* once, with the last one */
    CHECK_EQ(rxl.n, 0);       /* the interrupt never calls rx() */
    CHECK_EQ(u.rx_telegrams, 1);
    CHECK(u.rx_buf_busy[0]);
    bus_clear();
    CHECK_EQ(drain(), 1u);
    CHECK_EQ(bus.n, 0);       /* the drain touches no register */
    CHECK_EQ(rxl.n, 1);
    check_telegram(0, sd1, sizeof sd1, 0, 5005u, UINT32_MAX); /* first character ever: unknown */
    CHECK(no_buffer_held());  /* released after rx() */
    CHECK_EQ(drain(), 0u);    /* once */
    CHECK_EQ(rxl.n, 1);
    /* 50 µs from the last character to the next: 50 µs - one character of idle line */
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 5055u), 5060u);
    CHECK_EQ(drain(), 1u);
    check_telegram(1, sd1, sizeof sd1, 1, 5060u, 42667u);
    CHECK_EQ(50000u - CHAR_NS_1M5, 42667u);
    /* the idle time is known up to FDL_RX_FORGET_US of silence, unknown from there on */
    hal_time_us_t t = 5060u + FDL_RX_FORGET_US - 1u;
    CHECK_EQ(rx_frame(sd1, sizeof sd1, t), t + 5u);
    t += 5u;
    CHECK_EQ(rx_frame(sd1, sizeof sd1, t + FDL_RX_FORGET_US), t + FDL_RX_FORGET_US + 5u);
    CHECK_EQ(drain(), 2u);
    check_telegram(2, sd1, sizeof sd1, 0, t, (FDL_RX_FORGET_US - 1u) * 1000u - CHAR_NS_1M5);
    check_telegram(3, sd1, sizeof sd1, 1, t + FDL_RX_FORGET_US + 5u, UINT32_MAX);
    CHECK_EQ(rxl.pending, 4);
    CHECK_EQ(u.rx_telegrams, 4);
    CHECK_EQ(u.rx_parity_errors + u.rx_framing_errors + u.rx_overruns + u.rx_buffer_overflows, 0);
}

/* (2) SD2: the length comes from LE; LE != LEr is refused at LEr. */
static void test_uart_rx_sd2(void)
{
    uart_setup(1500000u, true);
    const hal_time_us_t t0 = 0xFFFFFE00u;
    for (unsigned i = 0; i < sizeof sd2 - 1u; i++) {
        rx_char(sd2[i], 0u, t0 + i);
    }
    CHECK_EQ(rxl.pending, 0);
    CHECK_EQ(u.collect.len, sizeof sd2 - 1u);
    rx_char(sd2[sizeof sd2 - 1u], 0u, t0 + 10u); /* LE 5 + 6 */
    CHECK_EQ(rxl.pending, 1);
    CHECK_EQ(u.collect.len, 0);
    /* the longest, LE 249: 255 octets, and its characters run across the counter's wrap */
    uint8_t big[FDL_FRAME_MAX] = {0x68, 249, 249, 0x68, 0x84, 0x82, 0x7D};
    uint8_t fcs = (uint8_t)((0x84u + 0x82u + 0x7Du) & 0xFFu);
    for (unsigned i = 7; i < FDL_FRAME_MAX - 2u; i++) {
        big[i] = (uint8_t)(i * 37u);
        fcs = (uint8_t)(fcs + big[i]);
    }
    big[FDL_FRAME_MAX - 2u] = fcs;
    big[FDL_FRAME_MAX - 1u] = 0x16;
    const hal_time_us_t t1 = 0xFFFFFF80u;
    for (unsigned i = 0; i < FDL_FRAME_MAX - 1u; i++) {
        rx_char(big[i], 0u, t1 + i);
    }
    CHECK_EQ(rxl.pending, 1);
    rx_char(big[FDL_FRAME_MAX - 1u], 0u, t1 + FDL_FRAME_MAX - 1u);
    CHECK_EQ(rxl.pending, 2);
    CHECK_EQ(drain(), 2u);
    check_telegram(0, sd2, sizeof sd2, 0, t0 + 10u, UINT32_MAX);
    check_telegram(1, big, sizeof big, 1, 0x7Eu, (t1 - (t0 + 10u)) * 1000u - CHAR_NS_1M5);
    CHECK_EQ(t1 - (t0 + 10u), 374u);
    /* LE 5, LEr 6: dropped at LEr */
    static const uint8_t bad_le[] = {0x68, 0x05, 0x06};
    CHECK_EQ(rx_frame(bad_le, sizeof bad_le, 500u), 502u);
    CHECK_EQ(drain(), 1u);
    check_error(2, FDL_RX_ERR_LE, 502u);
    CHECK_EQ(u.rx_telegrams, 2);
}

/* (3) Characters with PE/FE/ORE: one FDL_RX_ERR_CHAR entry each, counted per flag; an error
 * flag without a character is cleared by reading DR and reports nothing. */
static void test_uart_rx_char_errors(void)
{
    uart_setup(1500000u, true);
    static const struct {
        uint32_t sr;
        uint32_t pe, fe, ore;
    } flagged[] = {
        {USART_SR_PE, 1, 0, 0},
        {USART_SR_FE, 1, 1, 0},
        {USART_SR_ORE, 1, 1, 1},
        {USART_SR_PE | USART_SR_FE | USART_SR_ORE, 2, 2, 2},
    };
    for (unsigned i = 0; i < sizeof flagged / sizeof flagged[0]; i++) {
        memset(&rxl, 0, sizeof rxl);
        bus_clear();
        hal_time_us_t t = 1000u + 100u * i;
        rx_char(0x10, flagged[i].sr, t);
        CHECK_EQ(rxl.pending, 1);
        CHECK_EQ(drain(), 1u);
        check_error(0, FDL_RX_ERR_CHAR, t);
        CHECK_EQ(u.rx_parity_errors, flagged[i].pe);
        CHECK_EQ(u.rx_framing_errors, flagged[i].fe);
        CHECK_EQ(u.rx_overruns, flagged[i].ore);
        if (BUS_TRAPS) {
            CHECK_EQ(bus_count(BUS_DR, false), 1);
            CHECK_EQ(usart->SR, 0); /* SR then DR: the flags are gone */
        }
    }
    /* inside a telegram: the telegram is dropped, the characters after the error are not taken
     * for a start until the line pauses; the next telegram comes through */
    memset(&rxl, 0, sizeof rxl);
    for (unsigned i = 0; i < sizeof sd1; i++) {
        rx_char(sd1[i], i == 3u ? USART_SR_PE : 0u, 2000u + i);
    }
    CHECK_EQ(rx_frame(sd1b, sizeof sd1b, 2050u), 2055u);
    CHECK_EQ(drain(), 2u);
    check_error(0, FDL_RX_ERR_CHAR, 2003u);
    check_telegram(1, sd1b, sizeof sd1b, 0, 2055u, 45000u - CHAR_NS_1M5);
    CHECK_EQ(u.rx_parity_errors, 3);
    /* ORE or FE without RXNE: DR is read to clear it, nothing is reported or counted */
    static const uint32_t no_data[] = {USART_SR_ORE, USART_SR_FE};
    for (unsigned i = 0; i < 2u; i++) {
        unsigned pending = rxl.pending;
        bus_clear();
        usart->SR = no_data[i];
        usart->DR = 0x1A5u;
        isr();
        if (BUS_TRAPS) {
            CHECK_EQ(bus_count(BUS_DR, false), 1);
            CHECK_EQ(bus_count(BUS_DR, true), 0);
            CHECK_EQ(usart->SR, 0);
        }
        CHECK_EQ(rxl.pending, pending);
        CHECK_EQ(drain(), 0u);
    }
    CHECK_EQ(u.rx_overruns, 2);
    CHECK_EQ(u.rx_framing_errors, 2);
    /* no flag, no character: DR is not touched */
    bus_clear();
    usart->SR = 0;
    isr();
    if (BUS_TRAPS) {
        CHECK_EQ(bus_count(BUS_DR, false) + bus_count(BUS_DR, true), 0);
    }
    CHECK_EQ(drain(), 0u);
    CHECK_EQ(u.rx_telegrams, 1);
}

/* (4) A pause inside a telegram (strict: stamps more than the character time rounded up to
 * whole µs plus FDL_RX_GAP_TOLERANCE_NS apart, fdl_gap.h; relaxed: above 20 ms). */
static void test_uart_rx_gap(void)
{
    uart_setup(1500000u, true);
    /* 8 and 9 µs from character to character (7.333 µs characters): the rounding and 1 µs of
     * interrupt latency, no pause */
    for (unsigned i = 0; i < sizeof sd1; i++) {
        rx_char(sd1[i], 0u, 200u + i + (i >= 3u ? 7u : 0u) + (i >= 4u ? 8u : 0u));
    }
    /* 10 µs is 2667 ns idle: a pause; the character after it starts the next telegram */
    for (unsigned i = 0; i < 3u; i++) {
        rx_char(sd1b[i], 0u, 300u + i);
    }
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 312u), 317u);
    CHECK_EQ(rxl.pending, 3);
    CHECK_EQ(drain(), 3u);
    check_telegram(0, sd1, sizeof sd1, 0, 220u, UINT32_MAX);
    check_error(1, FDL_RX_ERR_GAP, 312u);
    check_telegram(2, sd1, sizeof sd1, 1, 317u, 10000u - CHAR_NS_1M5);
    CHECK_EQ(u.rx_telegrams, 2);
    /* relaxed timing (QEMU, PTY): the same 9 µs inside a telegram is no pause */
    uart_setup(1500000u, false);
    for (unsigned i = 0; i < sizeof sd1; i++) {
        rx_char(sd1[i], 0u, 300u + i + (i >= 3u ? 8u : 0u));
    }
    CHECK_EQ(drain(), 1u);
    check_telegram(0, sd1, sizeof sd1, 0, 313u, UINT32_MAX);
}

/* (5) The core held off: two telegrams wait in their buffers, the third finds none and is
 * reported as an overrun; after the drain every buffer is free and reused correctly. */
static void test_uart_rx_overflow(void)
{
    uart_setup(1500000u, true);
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 1000u), 1005u);
    CHECK_EQ(rx_frame(sd2, sizeof sd2, 1100u), 1110u);
    CHECK_EQ(rx_frame(sd1b, sizeof sd1b, 1200u), 1205u);
    CHECK_EQ(rxl.pending, 3);
    CHECK_EQ(rxl.n, 0);
    CHECK_EQ(u.rx_telegrams, 2);
    CHECK_EQ(u.rx_buffer_overflows, 1);
    CHECK(u.rx_buf_busy[0] && u.rx_buf_busy[1] && !u.rx_buf_busy[2]);
    CHECK_EQ(drain(), 3u);
    check_telegram(0, sd1, sizeof sd1, 0, 1005u, UINT32_MAX);
    check_telegram(1, sd2, sizeof sd2, 1, 1110u, 95000u - CHAR_NS_1M5);
    check_error(2, FDL_RX_ERR_CHAR, 1205u);
    CHECK(no_buffer_held());
    /* the dropped telegram's buffer takes the next one, then the freed ones in turn */
    CHECK_EQ(rx_frame(sd2b, sizeof sd2b, 1300u), 1310u);
    CHECK_EQ(drain(), 1u);
    check_telegram(3, sd2b, sizeof sd2b, 2, 1310u, 95000u - CHAR_NS_1M5);
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 1400u), 1405u);
    CHECK_EQ(rx_frame(sd2, sizeof sd2, 1500u), 1510u);
    CHECK_EQ(drain(), 2u);
    check_telegram(4, sd1, sizeof sd1, 0, 1405u, 90000u - CHAR_NS_1M5);
    check_telegram(5, sd2, sizeof sd2, 1, 1510u, 95000u - CHAR_NS_1M5);
    CHECK_EQ(u.rx_telegrams, 5);
    CHECK_EQ(u.rx_buffer_overflows, 1);
    CHECK(no_buffer_held());
    /* the queue's free-running indices run across their 32-bit wrap */
    atomic_store(&u.rx_head, 0xFFFFFFFEu);
    atomic_store(&u.rx_tail, 0xFFFFFFFEu);
    rxl.n = 0;
    CHECK_EQ(rx_frame(sd2b, sizeof sd2b, 1600u), 1610u);
    CHECK_EQ(rx_frame(sd1b, sizeof sd1b, 1700u), 1705u);
    CHECK_EQ(drain(), 2u);
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 1800u), 1805u);
    CHECK_EQ(drain(), 1u);
    CHECK_EQ(atomic_load(&u.rx_head), 1u);
    check_telegram(0, sd2b, sizeof sd2b, 2, 1610u, 90000u - CHAR_NS_1M5);
    check_telegram(1, sd1b, sizeof sd1b, 0, 1705u, 90000u - CHAR_NS_1M5);
    check_telegram(2, sd1, sizeof sd1, 1, 1805u, 95000u - CHAR_NS_1M5);
}

/* (6) A reply is refused as stale while a telegram after its request waits or is coming in (it
 * would collide with it); the reply rx() sends to the telegram it is serving is not stale. */
static void test_uart_stale_reply(void)
{
    uart_setup(1500000u, true);
    static const uint8_t reply[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
    CHECK_EQ(rx_frame(sd1, sizeof sd1, 1000u), 1005u);
    usart->SR = USART_SR_TXE | USART_SR_TC;
    bus_clear();
    CHECK_EQ(transmit(reply, sizeof reply, 0u), -1);
    CHECK_EQ(u.tx_stale, 1);
    CHECK(!u.tx_busy);
    CHECK_EQ(gpio_a->BSRR, 1u << (8 + 16)); /* DE stayed low */
    CHECK((usart->CR1 & USART_CR1_RE) != 0u);
    CHECK_EQ(bus_writes(), 0);
    /* served: rx() answers, the entry is out of the queue by then */
    bus.instant_tx = true;
    rxl.reply = reply;
    rxl.reply_rc = 99;
    bus_clear();
    CHECK_EQ(drain(), 1u);
    CHECK_EQ(rxl.reply_rc, 0);
    CHECK_EQ(u.tx_frames, 1);
    CHECK(!u.tx_busy);
    if (BUS_TRAPS) {
        CHECK_BYTES(bus.tx, bus.tx_n, 0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    }
    rxl.reply = NULL;
    /* the collector in the middle of a telegram */
    rx_char(sd1[0], 0u, 2000u);
    rx_char(sd1[1], 0u, 2001u);
    CHECK_EQ(u.collect.len, 2);
    bus_clear();
    CHECK_EQ(transmit(reply, sizeof reply, 0u), -1);
    CHECK_EQ(u.tx_stale, 2);
    CHECK_EQ(bus_writes(), 0);
    for (unsigned i = 2; i < sizeof sd1; i++) {
        rx_char(sd1[i], 0u, 2000u + i);
    }
    CHECK_EQ(transmit(reply, sizeof reply, 0u), -1); /* now it waits in the queue */
    CHECK_EQ(u.tx_stale, 3);
    CHECK_EQ(drain(), 1u);
    usart->SR = USART_SR_TXE | USART_SR_TC;
    bus_clear();
    CHECK_EQ(transmit(reply, sizeof reply, 0u), 0);
    CHECK_EQ(u.tx_frames, 2);
    CHECK_EQ(u.tx_stale, 3);
    if (BUS_TRAPS) {
        CHECK_BYTES(bus.tx, bus.tx_n, 0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    }
}

/* Transmit: the min TSDR wait against the counter, then RE off, DE high, and the caller's
 * frame fed to DR one character per TXE, read in place (no copy), then TC ends it. */
static void test_uart_transmit(void)
{
    if (!BUS_TRAPS) {
        printf("test_uart_transmit: skipped (needs the trapping register page)\n");
        return;
    }
    uart_setup(19200u, false);
    uint8_t frame[] = {0x68, 0x05, 0x05, 0x68, 0x02, 0x04, 0x3C, 0x00, 0x3E, 0x80, 0x16};
    usart->SR = 0; /* shift register busy: nothing may be written yet */
    bus.cnt_step = 1;
    bus_clear();
    CHECK_EQ(transmit(frame, sizeof frame, 1010u), 0);
    /* the counter read until it showed not_before, and no longer: 1000 ... 1010 */
    CHECK_EQ(bus_count(BUS_CNT, false), 11);
    int last_cnt = -1;
    for (int i = bus_find(0, BUS_CNT, false); i >= 0; i = bus_find(i + 1, BUS_CNT, false)) {
        last_cnt = i;
    }
    CHECK(last_cnt >= 0 && bus.ev[last_cnt].value == 1010u);
    CHECK_EQ(hw->cnt, 1011u);
    int re_off = bus_find(0, BUS_CR1, true);
    int de_on = bus_find(0, BUS_BSRR, true);
    CHECK(re_off > last_cnt && (bus.ev[re_off].value & USART_CR1_RE) == 0u);
    CHECK(de_on > re_off && bus.ev[de_on].value == 1u << 8); /* DE high after RE off */
    CHECK_EQ(bus.tx_n, 0);
    CHECK((usart->CR1 & USART_CR1_RE) == 0u); /* own characters not heard */
    CHECK((usart->CR1 & USART_CR1_TXEIE) != 0u);
    CHECK_EQ(u.tx_pos, 0);
    /* a second frame while one is going out is refused, and so is a new rate (the interrupt
     * owns CR1 until TC) */
    CHECK_EQ(transmit(frame, sizeof frame, 0u), -1);
    CHECK_EQ(u.tx_refused, 1);
    uint32_t brr = usart->BRR;
    CHECK_EQ(set_baud(1500000u), -1);
    CHECK_EQ(usart->BRR, brr);
    CHECK_EQ(u.baud_refused, 1);
    /* No copy: the driver reads the caller's buffer as each character goes, so a change now
     * goes out (the core keeps its reply unchanged until it has gone, hal_uart.h). */
    frame[7] = 0x01;
    frame[9] = 0x81;
    bus_clear();
    bool one_each = true;
    for (unsigned k = 0; k < sizeof frame; k++) {
        usart->SR = USART_SR_TXE; /* the previous character moved to the shift register */
        isr();
        one_each = one_each && bus.tx_n == k + 1u && u.tx_busy;
    }
    CHECK(one_each);
    CHECK_BYTES(bus.tx, bus.tx_n, 0x68, 0x05, 0x05, 0x68, 0x02, 0x04, 0x3C, 0x01, 0x3E, 0x81,
                0x16);
    CHECK(!bus.tx_bit8);
    CHECK_EQ(u.tx_pos, sizeof frame);
    CHECK((usart->CR1 & USART_CR1_TXEIE) == 0u);
    CHECK((usart->CR1 & USART_CR1_TCIE) != 0u);
    CHECK_EQ(bus_count(BUS_BSRR, true), 0); /* DE stays high until TC */
    isr(); /* TXE gone, TC not yet: nothing */
    CHECK(u.tx_busy);
    CHECK_EQ(bus.tx_n, sizeof frame);
    usart->SR = USART_SR_TXE | USART_SR_TC; /* last stop bit out */
    isr();
    CHECK(!u.tx_busy);
    CHECK_EQ(gpio_a->BSRR, 1u << (8 + 16)); /* DE low */
    CHECK((usart->CR1 & (USART_CR1_RE | USART_CR1_TCIE)) == USART_CR1_RE);
    CHECK_EQ(bus.tx_n, sizeof frame);
    /* QEMU-like USART (TXE and TC at once): the whole frame leaves inside transmit(); a
     * not_before already passed costs two looks at the counter */
    bus.instant_tx = true;
    usart->SR = USART_SR_TXE | USART_SR_TC;
    bus_clear();
    CHECK_EQ(transmit(frame, 3, 0u), 0);
    CHECK(!u.tx_busy);
    CHECK_BYTES(bus.tx, bus.tx_n, 0x68, 0x05, 0x05);
    CHECK_EQ(bus_count(BUS_CNT, false), 2);
    CHECK_EQ(gpio_a->BSRR, 1u << (8 + 16));
    /* a not_before far away is a clock mix-up: one look, no 35-minute spin */
    bus_clear();
    CHECK_EQ(transmit(frame, 3, hw->cnt + 1000000u), 0);
    CHECK_EQ(u.tx_clock_mixups, 1);
    CHECK_EQ(bus_count(BUS_CNT, false), 1);
    CHECK_EQ(bus.tx_n, 3);
    CHECK_EQ(transmit(frame, 0, 0u), -1);
    CHECK_EQ(transmit(frame, RS485_TX_MAX + 1u, 0u), -1);
    CHECK_EQ(u.tx_refused, 3);
    CHECK_EQ(u.tx_frames, 3);
}

/* ---- bxCAN ---------------------------------------------------------------------------------- */
static can_regs_t canr;
typedef struct can_log {
    unsigned n;
    hal_can_frame_t last;
} can_log_t;
static void can_cb(void *ctx, const hal_can_frame_t *f)
{
    can_log_t *l = ctx;
    l->n++;
    l->last = *f;
}

static void test_bxcan(void)
{
    uint32_t btr = 0;
    CHECK(bxcan_timing(42000000u, 500000u, &btr));
    CHECK_EQ(btr, 0x011A0005u); /* BRP 6, 14 tq: TS1 11, TS2 2, SJW 2: sample point 85.7 % */
    CHECK(bxcan_timing(42000000u, 1000000u, &btr));
    CHECK(bxcan_timing(42000000u, 125000u, &btr));
    CHECK(!bxcan_timing(42000000u, 0u, &btr));

    memset(&canr, 0, sizeof canr);
    bxcan_t c;
    can_log_t log = {0};
    bxcan_cfg_t cfg = {.regs = &canr, .pclk_hz = 42000000u, .bitrate = 500000u, .rx = can_cb,
                       .rx_ctx = &log};
    /* A controller that never acknowledges initialisation (QEMU: reads as 0): init fails, the
     * card runs without inverter. */
    CHECK_EQ(bxcan_init(&c, &cfg), -1);
    CHECK(!c.up);
    hal_can_frame_t f = {.id = 779, .len = 8, .data = {0x31, 0, 0x20, 0x6C, 1, 2, 3, 4}};
    hal_can_t h = bxcan_hal(&c);
    CHECK_EQ(h.ops->send(h.ctx, &f), -1);

    c.up = true; /* as after a successful init */
    canr.TSR = CAN_TSR_TME0 << 1; /* only mailbox 1 free */
    CHECK_EQ(h.ops->send(h.ctx, &f), 0);
    CHECK_EQ(canr.TX[1].TIR, (779u << 21) | CAN_TIR_TXRQ);
    CHECK_EQ(canr.TX[1].TDTR, 8u);
    CHECK_EQ(canr.TX[1].TDLR, 0x6C200031u);
    CHECK_EQ(canr.TX[1].TDHR, 0x04030201u);
    canr.TSR = 0;
    CHECK_EQ(h.ops->send(h.ctx, &f), -1);
    CHECK_EQ(c.tx_full, 1);

    /* receive: one standard frame in FIFO 0 */
    canr.RF0R = 1;
    canr.RX[0].RIR = 780u << 21;
    canr.RX[0].RDTR = 8;
    canr.RX[0].RDLR = 0x6C200031u;
    canr.RX[0].RDHR = 0x29721C31u;
    bxcan_rx_isr(&c);
    CHECK_EQ(canr.RF0R, CAN_RF0R_RFOM); /* slot released */
    CHECK_EQ(log.n, 0);                 /* nothing handed on from the interrupt */
    CHECK_EQ(bxcan_drain(&c), 1);
    CHECK_EQ(log.last.id, 780);
    CHECK_EQ(log.last.len, 8);
    CHECK_BYTES(log.last.data, 8, 0x31, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x29);
    /* extended frames are not SBus */
    canr.RF0R = 1;
    canr.RX[0].RIR = CAN_RIR_IDE;
    bxcan_rx_isr(&c);
    CHECK_EQ(c.rx_ignored, 1);
    CHECK_EQ(bxcan_drain(&c), 0);
}

/* ---- time base ------------------------------------------------------------------------------ */
/* (7) now_us is the 1 MHz counter itself; SysTick's tick fires the deadline once the counter has
 * reached it, across the 32-bit wrap too. */
static void test_timebase(void)
{
    systick_regs_t st = {0};
    volatile uint32_t cnt = 0; /* TIM2 CNT */
    timebase_t tb;
    timebase_init(&tb, &st, 168000000u, &cnt);
    CHECK_EQ(st.LOAD, 167999u); /* 1 kHz from HCLK */
    CHECK_EQ(st.VAL, 0);
    CHECK_EQ(st.CTRL, SYSTICK_CTRL_CLKSOURCE | SYSTICK_CTRL_TICKINT | SYSTICK_CTRL_ENABLE);
    CHECK_EQ(timebase_prescaler(84000000u), 83u);    /* TIM2 at 2 x PCLK1 */
    CHECK_EQ(timebase_prescaler(1000000000u), 999u); /* QEMU's TIM2 */
    CHECK_EQ(timebase_prescaler(1000000u), 0u);
    cnt = 12345u;
    CHECK_EQ(timebase_now_us(&tb), 12345u);
    cnt = 0xFFFFFFFFu;
    CHECK_EQ(timebase_now_us(&tb), 0xFFFFFFFFu);
    cnt = 0;
    CHECK_EQ(timebase_now_us(&tb), 0u);
    /* nothing armed: no tick fires */
    cnt = 1000u;
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    /* fires in the first tick at or after it, once */
    timebase_set_deadline(&tb, 1500u);
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    cnt = 1499u;
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    cnt = 1500u;
    timebase_tick(&tb);
    CHECK(timebase_deadline_hit(&tb));
    CHECK(!timebase_deadline_hit(&tb)); /* reading clears it */
    cnt = 1600u;
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb)); /* disarmed once fired */
    /* a tick that comes late still fires */
    timebase_set_deadline(&tb, 2000u);
    cnt = 2999u;
    timebase_tick(&tb);
    CHECK(timebase_deadline_hit(&tb));
    /* across the wrap: 0xFFFFFF00 + 0x200 is 0x100 */
    cnt = 0xFFFFFF00u;
    timebase_set_deadline(&tb, cnt + 0x200u);
    CHECK_EQ(tb.deadline, 0x100u);
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    cnt = 0xFFFFFFFFu;
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    cnt = 0xFFu;
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
    cnt = 0x100u;
    timebase_tick(&tb);
    CHECK(timebase_deadline_hit(&tb));
    /* a deadline just before the wrap is reached by a counter just after it */
    cnt = 0x10u;
    timebase_set_deadline(&tb, 0xFFFFFFF0u);
    timebase_tick(&tb);
    CHECK(timebase_deadline_hit(&tb));
    /* a new deadline forgets a hit nobody took */
    timebase_set_deadline(&tb, 0x10u);
    timebase_tick(&tb);
    timebase_set_deadline(&tb, 0x1000u);
    CHECK(!timebase_deadline_hit(&tb));
    timebase_tick(&tb);
    CHECK(!timebase_deadline_hit(&tb));
}

/* ---- LEDs and DIP --------------------------------------------------------------------------- */
static void test_leds_dip(void)
{
    gpio_regs_t gb = {0};
    board_leds_t l = {.port = {&gb, &gb}, .pin = {0, 1}};
    board_leds_init(&l);
    CHECK_EQ(gb.MODER & 0xFu, 0x5u); /* PB0, PB1 outputs */
    hal_led_t h = board_leds_hal(&l);
    h.ops->set(h.ctx, HAL_LED_RUN, HAL_LED_ON);
    h.ops->set(h.ctx, HAL_LED_BUS_FAULT, HAL_LED_BLINK);
    unsigned on_ms = 0;
    unsigned bus_changes = 0;
    bool bus_lit = false;
    for (unsigned ms = 0; ms < 2000u; ms++) {
        board_leds_tick(&l);
        if (l.lit[HAL_LED_RUN]) {
            on_ms++;
        }
        if (l.lit[HAL_LED_BUS_FAULT] != bus_lit) {
            bus_lit = l.lit[HAL_LED_BUS_FAULT];
            bus_changes++;
        }
    }
    CHECK_EQ(on_ms, 2000);     /* RUN steady on */
    CHECK_EQ(bus_changes, 5);  /* BUS FAULT 1 Hz: on at 1 ms, then an edge every 500 ms */
    l.fault_pattern = true;
    bus_changes = 0;
    on_ms = 0;
    for (unsigned ms = 0; ms < 1000u; ms++) {
        board_leds_tick(&l);
        if (l.lit[HAL_LED_RUN]) {
            on_ms++;
        }
        if (l.lit[HAL_LED_BUS_FAULT] != bus_lit) {
            bus_lit = l.lit[HAL_LED_BUS_FAULT];
            bus_changes++;
        }
    }
    CHECK_EQ(bus_changes, 8); /* 4 Hz */
    CHECK_EQ(on_ms, 1000);    /* RUN keeps its meaning: not the blink of an address > 125 */

    gpio_regs_t gc = {0};
    gc.IDR = 0xFFFFu & ~((1u << 2) | (1u << 0)); /* switches 2^0 and 2^2 ON (pulled low) */
    board_dip_t d = {.port = &gc, .first_pin = 0, .active_low = true, .override = -1};
    hal_dip_t hd = board_dip_hal(&d);
    CHECK_EQ(hd.ops->read(hd.ctx), 5);
    gc.IDR = 0; /* all ON: 127, the card stays off the bus */
    CHECK_EQ(hd.ops->read(hd.ctx), 127);
    d.override = 4;
    CHECK_EQ(hd.ops->read(hd.ctx), 4);
}

/* ---- interrupt priorities ------------------------------------------------------------------- */
/* USART1 stamps each character with TIM2 in its handler, and strict timing tolerates 1 to 2 µs
 * of extra latency (docs/porting.md): nothing but the fault handlers may preempt it, SysTick
 * (~0.6-0.9 µs) included. SysTick stays above the core's
 * BASEPRI (deadlines and LEDs during main-loop sections); PendSV and CAN are below it. */
static void test_irq_priorities(void)
{
    uint8_t ipr[82];
    memset(ipr, 0xEE, sizeof ipr);
    uint32_t shpr3 = 0x0000A5A5u; /* DebugMonitor and reserved bytes: kept */
    board_irq_priorities(ipr, &shpr3);
    CHECK_EQ(ipr[IRQ_USART1], 0x10);
    CHECK_EQ(ipr[IRQ_CAN1_RX0], 0x40);
    CHECK_EQ(shpr3, 0x2030A5A5u); /* SysTick 2, PendSV 3 */
    unsigned untouched = 0;
    for (unsigned i = 0; i < sizeof ipr; i++) {
        untouched += ipr[i] == 0xEEu;
    }
    CHECK_EQ(untouched, sizeof ipr - 2u);
    uint32_t usart1 = ipr[IRQ_USART1], can = ipr[IRQ_CAN1_RX0];
    uint32_t systick = shpr3 >> 24, pendsv = (shpr3 >> 16) & 0xFFu;
    uint32_t basepri = BOARD_PRIO_CORE << BOARD_PRIO_SHIFT; /* core_enter */
    CHECK((BOARD_PRIO_FAULT << BOARD_PRIO_SHIFT) < usart1); /* faults still preempt it */
    CHECK(usart1 < systick && usart1 < pendsv && usart1 < can);
    CHECK(systick < basepri);                   /* not masked by the core's sections */
    CHECK(pendsv >= basepri && can >= basepri); /* masked by them */
    CHECK(((usart1 | systick | pendsv | can) & 0x0Fu) == 0u); /* only the 4 implemented bits */
}

/* ---- independent watchdog ------------------------------------------------------------------- */
/* Started with /32 (1 ms a count at the LSI's typical 32 kHz) and the timeout's count, then
 * reloaded: the key register's last word is the reload key, and nothing was left unlocked. */
static void test_iwdg(void)
{
    iwdg_regs_t w = {0};
    board_iwdg_start(&w, BOARD_IWDG_TIMEOUT_MS);
    CHECK_EQ(w.PR, IWDG_PR_DIV32);
    CHECK_EQ(w.RLR, 100u);
    CHECK_EQ(w.KR, IWDG_KEY_RELOAD);
    w.KR = 0u;
    board_iwdg_refresh(&w);
    CHECK_EQ(w.KR, IWDG_KEY_RELOAD);
    CHECK_EQ(board_iwdg_reload(0u), 1u);       /* the shortest the counter can do */
    CHECK_EQ(board_iwdg_reload(5000u), 0xFFFu); /* the longest: 4.1 s at 32 kHz */
    CHECK_EQ(board_iwdg_reload(250u), 250u);
    /* The reload at the LSI's extremes (17..47 kHz): still well above a main-loop pass. */
    uint32_t fastest_ms = board_iwdg_reload(BOARD_IWDG_TIMEOUT_MS) * 32u * 1000u / 47000u;
    CHECK(fastest_ms >= 60u);
    /* The reset cause: read, and the flags cleared for the next start. */
    rcc_regs_t rcc = {0};
    rcc.CSR = RCC_CSR_IWDGRSTF | (1u << 26); /* and PINRSTF */
    CHECK(board_reset_by_iwdg(&rcc));
    CHECK((rcc.CSR & RCC_CSR_RMVF) != 0u);
    rcc.CSR = 1u << 26;
    CHECK(!board_reset_by_iwdg(&rcc));
}

/* ---- clock and fault record ----------------------------------------------------------------- */
/* What the silicon makes of CFGR (RM0090 §7.3.3 for the codes, §7.2 for the timers): SYSCLK from
 * SW, HCLK through HPRE, PCLK1/2 through PPRE1/2, and APB1's timers at 2 x PCLK1 when APB1 is
 * divided. Worked out from the register model, independently of what board_clock_init reports. */
typedef struct hw_clocks {
    uint32_t hclk, pclk1, pclk2, tim2;
} hw_clocks_t;

static uint32_t apb_div(uint32_t code)
{
    return code < 4u ? 1u : 2u << (code - 4u); /* 0xx /1, 100 /2, 101 /4, 110 /8, 111 /16 */
}

static hw_clocks_t hw_clocks(const rcc_regs_t *rcc)
{
    uint32_t sysclk = (rcc->CFGR & RCC_CFGR_SW_MASK) == RCC_CFGR_SW_PLL ? 168000000u : 16000000u;
    uint32_t hpre = (rcc->CFGR >> 4) & 0xFu;
    uint32_t hdiv = hpre < 8u ? 1u : hpre < 12u ? 2u << (hpre - 8u) : 64u << (hpre - 12u);
    uint32_t ppre1 = (rcc->CFGR >> RCC_CFGR_PPRE1_SHIFT) & 7u;
    hw_clocks_t h = {.hclk = sysclk / hdiv};
    h.pclk1 = h.hclk / apb_div(ppre1);
    h.pclk2 = h.hclk / apb_div((rcc->CFGR >> RCC_CFGR_PPRE2_SHIFT) & 7u);
    h.tim2 = apb_div(ppre1) == 1u ? h.pclk1 : 2u * h.pclk1;
    return h;
}

/* The reported clocks against the hardware's, and what main.c computes from them: TIM2 must
 * count microseconds, USART1 (APB2) and bxCAN (APB1) must run at the wanted rates. */
static void check_clock_use(const rcc_regs_t *rcc, board_clocks_t c, uint32_t baud)
{
    hw_clocks_t h = hw_clocks(rcc);
    CHECK_EQ(c.hclk_hz, h.hclk);
    CHECK_EQ(c.pclk1_hz, h.pclk1);
    CHECK_EQ(c.pclk2_hz, h.pclk2);
    CHECK_EQ(board_tim2_hz(&c), h.tim2);
    uint32_t psc = timebase_prescaler(board_tim2_hz(&c));
    CHECK_EQ(h.tim2 / (psc + 1u), 1000000u);
    CHECK_EQ(h.tim2 % (psc + 1u), 0u);
    uint32_t brr = 0;
    bool over8 = false;
    CHECK(rs485_uart_brr(c.pclk2_hz, baud, &brr, &over8));
    /* RM0090 §30.3.4: baud = f_PCLK / (8 x (2 - OVER8) x USARTDIV), the fraction in 1/16 or
     * (OVER8) 1/8 in BRR's low bits. */
    uint32_t div_x = over8 ? ((brr >> 4) << 3) | (brr & 7u) : brr;
    uint32_t actual = h.pclk2 / div_x;
    CHECK(actual * 1000u >= baud * 997u && actual * 1000u <= baud * 1003u);
    uint32_t btr = 0;
    CHECK(bxcan_timing(c.pclk1_hz, 500000u, &btr));
    uint32_t tq = 1u + ((btr >> 16) & 0xFu) + 1u + ((btr >> 20) & 7u) + 1u;
    CHECK_EQ(h.pclk1 / (((btr & 0x3FFu) + 1u) * tq), 500000u);
}

static void test_clock(void)
{
    rcc_regs_t rcc = {0};
    flash_regs_t fl = {0};
    board_clocks_t c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_NOT_MODELLED);
    CHECK_EQ(c.hclk_hz, 168000000u);
    CHECK_EQ(c.pclk2_hz, 84000000u);
    CHECK_EQ(board_tim2_hz(&c), 84000000u);
    /* silicon out of reset, but no crystal and a PLL that never locks; CFGR holds dividers
     * (from a boot loader, say) that the 16 MHz fallback must not keep */
    rcc.CR = RCC_CR_HSION | RCC_CR_HSIRDY;
    rcc.CFGR = RCC_CFGR_HPRE_MASK | RCC_CFGR_PPRE1_MASK | RCC_CFGR_PPRE2_MASK;
    c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_HSI_ONLY);
    CHECK_EQ(c.hclk_hz, 16000000u);
    CHECK_EQ(c.pclk1_hz, 16000000u);
    CHECK_EQ(c.pclk2_hz, 16000000u);
    CHECK_EQ(rcc.CFGR & (RCC_CFGR_SW_MASK | RCC_CFGR_HPRE_MASK), 0u); /* HSI, AHB /1 */
    CHECK_EQ((rcc.CFGR >> RCC_CFGR_PPRE1_SHIFT) & 7u, 0u);           /* APB1 /1 */
    CHECK_EQ((rcc.CFGR >> RCC_CFGR_PPRE2_SHIFT) & 7u, 0u);           /* APB2 /1 */
    CHECK_EQ(rcc.PLLCFGR & 0x3Fu, 16u);          /* PLLM from HSI */
    CHECK_EQ((rcc.PLLCFGR >> 6) & 0x1FFu, 336u); /* PLLN */
    CHECK_EQ(fl.ACR & 7u, 5u);                   /* 5 wait states */
    check_clock_use(&rcc, c, 500000u);
    check_clock_use(&rcc, c, 19200u);
    /* the PLL locks, but SWS never shows it as SYSCLK: the same fallback */
    rcc.CR = RCC_CR_HSION | RCC_CR_HSIRDY | RCC_CR_PLLRDY;
    rcc.CFGR = 0;
    c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_HSI_ONLY);
    CHECK_EQ(rcc.CFGR & (RCC_CFGR_SW_MASK | RCC_CFGR_HPRE_MASK | RCC_CFGR_PPRE1_MASK |
                         RCC_CFGR_PPRE2_MASK), 0u);
    check_clock_use(&rcc, c, 500000u);
    /* the PLL from HSI runs: APB1 /4, APB2 /2 (RM0090 §7.3.3 codes 101 and 100) */
    rcc.CFGR = RCC_CFGR_SWS_PLL;
    c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_PLL_HSI);
    CHECK_EQ(rcc.CFGR & RCC_CFGR_SW_MASK, RCC_CFGR_SW_PLL);
    CHECK_EQ((rcc.CFGR >> RCC_CFGR_PPRE1_SHIFT) & 7u, 5u);
    CHECK_EQ((rcc.CFGR >> RCC_CFGR_PPRE2_SHIFT) & 7u, 4u);
    CHECK_EQ(c.pclk1_hz, 42000000u);
    CHECK_EQ(c.pclk2_hz, 84000000u);
    check_clock_use(&rcc, c, 6000000u);
    check_clock_use(&rcc, c, 9600u);
}

static void test_fault_record(void)
{
    board_fault_record_t r = {0};
    char line[320];
    board_fault_format(&r, line, sizeof line);
    CHECK_STR(line, "fault: none");
    r.magic = BOARD_FAULT_MAGIC;
    r.exception = 5;
    r.pc = 0x08000ef8u;
    r.bfar = 0xFFFFFFF0u;
    r.cfsr = 0x8200u;
    r.count = 1;
    board_fault_format(&r, line, sizeof line);
    CHECK(strncmp(line, "fault: BusFault exc=0x00000005 pc=0x08000ef8", 44) == 0);
    CHECK(strstr(line, " cfsr=0x00008200") != NULL);
    CHECK(strstr(line, " bfar=0xfffffff0") != NULL);
    CHECK_EQ(board_fault_format(&r, line, 12), 11); /* truncated, terminated */

    /* The start after the fault takes the record: marked shown, so a later reset (NRST, a
     * debugger) finds no fresh record and shows no pattern; the fields stay for a debugger. */
    board_fault_record_t before = r;
    board_fault_mark_shown(&r);
    CHECK_EQ(r.magic, BOARD_FAULT_SHOWN);
    CHECK(r.magic != BOARD_FAULT_MAGIC);
    CHECK(memcmp(&r.count, &before.count, sizeof r - offsetof(board_fault_record_t, count)) == 0);
    board_fault_format(&r, line, sizeof line);
    CHECK_STR(line, "fault: none");
    board_fault_mark_shown(&r); /* the next start: stays shown */
    CHECK_EQ(r.magic, BOARD_FAULT_SHOWN);
    r.magic = 0x12345678u; /* power-up garbage is not turned into a shown record */
    board_fault_mark_shown(&r);
    CHECK_EQ(r.magic, 0x12345678u);
}

int main(void)
{
    bus_init();
    RUN_TEST(test_brr);
    RUN_TEST(test_uart_init_and_baud);
    RUN_TEST(test_uart_rx_sd1);
    RUN_TEST(test_uart_rx_sd2);
    RUN_TEST(test_uart_rx_char_errors);
    RUN_TEST(test_uart_rx_gap);
    RUN_TEST(test_uart_rx_overflow);
    RUN_TEST(test_uart_stale_reply);
    RUN_TEST(test_uart_transmit);
    RUN_TEST(test_bxcan);
    RUN_TEST(test_timebase);
    RUN_TEST(test_leds_dip);
    RUN_TEST(test_irq_priorities);
    RUN_TEST(test_iwdg);
    RUN_TEST(test_clock);
    RUN_TEST(test_fault_record);
    return check_report();
}
