/* The STM32F405 board drivers on the host, against register fakes: plain structs in RAM with the
 * hardware's layout (offsets checked below), so each test sets status bits the way the
 * peripheral would and checks what the driver wrote. What a fake cannot show (bytes leaving the
 * USART in order, interrupt timing) is covered by the QEMU test (qemu_card.sh). */
#include <stddef.h>
#include <string.h>

#include "board/board.h"
#include "board/board_io.h"
#include "board/bxcan.h"
#include "board/rs485_uart.h"
#include "board/timebase.h"
#include "check.h"

/* ---- register layout ------------------------------------------------------------------------ */
_Static_assert(offsetof(usart_regs_t, CR1) == 0x0C, "USART CR1");
_Static_assert(offsetof(usart_regs_t, GTPR) == 0x18, "USART GTPR");
_Static_assert(offsetof(gpio_regs_t, BSRR) == 0x18, "GPIO BSRR");
_Static_assert(offsetof(gpio_regs_t, AFR) == 0x20, "GPIO AFR");
_Static_assert(offsetof(rcc_regs_t, AHB1ENR) == 0x30, "RCC AHB1ENR");
_Static_assert(offsetof(rcc_regs_t, APB2ENR) == 0x44, "RCC APB2ENR");
_Static_assert(offsetof(can_regs_t, BTR) == 0x1C, "CAN BTR");
_Static_assert(offsetof(can_regs_t, TX) == 0x180, "CAN TX mailboxes");
_Static_assert(offsetof(can_regs_t, RX) == 0x1B0, "CAN RX FIFOs");
_Static_assert(offsetof(can_regs_t, FMR) == 0x200, "CAN FMR");
_Static_assert(offsetof(can_regs_t, FA1R) == 0x21C, "CAN FA1R");
_Static_assert(offsetof(can_regs_t, FILTER) == 0x240, "CAN filter banks");
_Static_assert(offsetof(systick_regs_t, VAL) == 0x08, "SysTick VAL");

/* ---- USART ---------------------------------------------------------------------------------- */
static usart_regs_t usart;
static gpio_regs_t gpio_a;
static hal_time_us_t fake_now;
static unsigned now_calls;
static hal_time_us_t clock_now(void)
{
    now_calls++;
    return fake_now++; /* every look at the clock takes 1 µs */
}

#define RX_LOG_MAX 600u
typedef struct rx_log {
    unsigned n;
    unsigned pending; /* rx_pending calls by the interrupt */
    uint8_t byte[RX_LOG_MAX];
    uint8_t flags[RX_LOG_MAX];
    hal_time_us_t t[RX_LOG_MAX];
} rx_log_t;
static void rx_cb(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    rx_log_t *l = ctx;
    if (l->n < RX_LOG_MAX) {
        l->byte[l->n] = byte;
        l->flags[l->n] = flags;
        l->t[l->n] = t;
    }
    l->n++;
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

static rs485_uart_t u;
static rx_log_t rxl;

static void uart_setup(void)
{
    memset(&usart, 0, sizeof usart);
    memset(&gpio_a, 0, sizeof gpio_a);
    memset(&rxl, 0, sizeof rxl);
    fake_now = 1000;
    rs485_uart_cfg_t cfg = {.regs = &usart, .de_port = &gpio_a, .de_pin = 8, .pclk_hz = 84000000u,
                            .baud = 19200u, .now = clock_now, .rx = rx_cb, .rx_ctx = &rxl,
                            .rx_pending = rx_pending_cb};
    CHECK_EQ(rs485_uart_init(&u, &cfg), 0);
}

static void test_uart_init_and_baud(void)
{
    uart_setup();
    /* 9-bit word, parity on, even (PS=0), enabled, RX interrupts, no OVER8 at 19.2k */
    CHECK_EQ(usart.CR1, USART_CR1_M | USART_CR1_PCE | USART_CR1_UE | USART_CR1_TE |
                            USART_CR1_RE | USART_CR1_RXNEIE | USART_CR1_PEIE);
    CHECK_EQ(usart.CR2, 0);         /* 1 stop bit */
    CHECK_EQ(usart.CR3, USART_CR3_EIE);
    CHECK_EQ(usart.BRR, 4375u);
    CHECK_EQ(gpio_a.BSRR, 1u << (8 + 16)); /* DE low */
    /* baud search: 6 Mbit/s needs OVER8, 12 Mbit/s is refused, the rate stays */
    CHECK_EQ(rs485_uart_set_baud(&u, 6000000u), 0);
    CHECK((usart.CR1 & USART_CR1_OVER8) != 0u);
    CHECK((usart.CR1 & USART_CR1_UE) != 0u);
    CHECK_EQ(usart.BRR, 0x16u);
    CHECK_EQ(rs485_uart_set_baud(&u, 12000000u), -1);
    CHECK_EQ(u.baud, 6000000u);
    CHECK_EQ(u.baud_refused, 1);
    CHECK_EQ(rs485_uart_set_baud(&u, 1500000u), 0);
    CHECK((usart.CR1 & USART_CR1_OVER8) == 0u);
    CHECK_EQ(usart.BRR, 56u);
}

static void test_uart_rx_flags(void)
{
    uart_setup();
    usart.SR = USART_SR_RXNE;
    usart.DR = 0x168u; /* parity bit (bit 8) is not data */
    rs485_uart_isr(&u);
    /* the fake keeps RXNE: the driver takes at most 4 characters per interrupt, into its ring;
     * the core sees them only when the lower-priority context drains it */
    CHECK_EQ(rxl.n, 0);
    CHECK_EQ(rxl.pending, 1);
    CHECK_EQ(rs485_uart_rx_drain(&u), 4u);
    CHECK_EQ(rxl.n, 4);
    CHECK_EQ(rxl.byte[0], 0x68);
    CHECK_EQ(rxl.flags[0], 0);
    memset(&rxl, 0, sizeof rxl);
    usart.SR = USART_SR_RXNE | USART_SR_PE | USART_SR_FE | USART_SR_ORE;
    usart.DR = 0x10u;
    rs485_uart_isr(&u);
    (void)rs485_uart_rx_drain(&u);
    CHECK_EQ(rxl.flags[0], HAL_UART_RX_PARITY_ERR | HAL_UART_RX_FRAMING_ERR |
                               HAL_UART_RX_OVERRUN_ERR);
    CHECK_EQ(u.rx_parity_errors, 4);
    memset(&rxl, 0, sizeof rxl);
    usart.SR = 0;
    unsigned pending = rxl.pending;
    rs485_uart_isr(&u);
    CHECK_EQ(rs485_uart_rx_drain(&u), 0u);
    CHECK_EQ(rxl.n, 0);
    CHECK_EQ(rxl.pending, pending); /* nothing stored, nothing to do */
}

/* The main loop holds the drain off (BASEPRI) while it polls the card: characters keep their
 * own times and order; past RS485_RX_RING the next stored one carries an overrun flag. */
static void test_uart_rx_ring(void)
{
    uart_setup();
    usart.SR = USART_SR_RXNE;
    for (unsigned k = 0; k < RS485_RX_RING / 4u; k++) {
        usart.DR = k;
        rs485_uart_isr(&u);
    }
    CHECK_EQ(rxl.n, 0);
    CHECK_EQ(u.rx_ring_overflows, 0);
    usart.DR = 0x99u; /* the ring is full: these four are lost */
    rs485_uart_isr(&u);
    CHECK_EQ(u.rx_ring_overflows, 4);
    CHECK_EQ(u.rx_chars, RS485_RX_RING + 4u);
    CHECK_EQ(rs485_uart_rx_drain(&u), RS485_RX_RING);
    CHECK_EQ(rxl.n, RS485_RX_RING);
    bool in_order = true;
    for (unsigned i = 0; i < RS485_RX_RING; i++) {
        in_order = in_order && rxl.byte[i] == (uint8_t)(i / 4u) && rxl.flags[i] == 0u &&
                   rxl.t[i] == 1000u + i; /* the time the interrupt took each one */
    }
    CHECK(in_order);
    usart.DR = 0x68u;
    rs485_uart_isr(&u);
    CHECK_EQ(rs485_uart_rx_drain(&u), 4u);
    CHECK_EQ(rxl.flags[RS485_RX_RING], HAL_UART_RX_OVERRUN_ERR); /* the loss is told */
    CHECK_EQ(rxl.flags[RS485_RX_RING + 1u], 0u);
    CHECK_EQ(rxl.byte[RS485_RX_RING], 0x68);
    CHECK_EQ(rs485_uart_rx_drain(&u), 0u);
    /* head and tail run on across many laps of the ring, and across the wrap of the 32-bit
     * indices; every character comes out as it went in */
    atomic_store(&u.rx_head, 0xFFFFFF00u);
    atomic_store(&u.rx_tail, 0xFFFFFF00u);
    bool laps_ok = true;
    for (unsigned lap = 0; lap < 3u * RS485_RX_RING; lap++) {
        usart.DR = (uint8_t)(lap * 7u);
        rxl.n = 0;
        rs485_uart_isr(&u);
        laps_ok = laps_ok && rs485_uart_rx_drain(&u) == 4u && rxl.n == 4u &&
                  rxl.byte[0] == (uint8_t)(lap * 7u) && rxl.byte[3] == (uint8_t)(lap * 7u) &&
                  rxl.flags[3] == 0u;
    }
    CHECK(laps_ok);
    CHECK(atomic_load(&u.rx_head) < 0x1000u); /* the indices wrapped */
    CHECK_EQ(u.rx_ring_overflows, 4);
    /* a full ring: nothing stored, nobody woken */
    for (unsigned k = 0; k < RS485_RX_RING / 4u; k++) {
        rs485_uart_isr(&u);
    }
    unsigned pending = rxl.pending;
    rs485_uart_isr(&u);
    CHECK_EQ(rxl.pending, pending);
    CHECK_EQ(u.rx_ring_overflows, 8);
}

/* A reply the drain produces late, with characters after its request already waiting (the
 * master's retry), is not sent: it would collide with them. */
static void test_uart_no_stale_reply(void)
{
    uart_setup();
    static const uint8_t frame[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
    usart.SR = USART_SR_RXNE;
    usart.DR = 0x10u;
    rs485_uart_isr(&u); /* four characters waiting */
    usart.SR = USART_SR_TXE | USART_SR_TC;
    CHECK_EQ(rs485_uart_transmit(&u, frame, sizeof frame, 0u), -1);
    CHECK_EQ(u.tx_stale, 1);
    CHECK(!u.tx_busy);
    CHECK_EQ(gpio_a.BSRR, 1u << (8 + 16)); /* DE stayed low */
    CHECK((usart.CR1 & USART_CR1_RE) != 0u);
    (void)rs485_uart_rx_drain(&u);
    CHECK_EQ(rs485_uart_transmit(&u, frame, sizeof frame, 0u), 0);
    CHECK_EQ(u.tx_frames, 1);
}

static void test_uart_transmit(void)
{
    uart_setup();
    static const uint8_t frame[] = {0x68, 0x05, 0x05, 0x68, 0x02, 0x04, 0x3C, 0x00, 0x3E, 0x80, 0x16};
    usart.SR = 0; /* shift register busy: nothing may be written yet */
    now_calls = 0;
    CHECK_EQ(rs485_uart_transmit(&u, frame, sizeof frame, 1010u), 0);
    CHECK(fake_now > 1010u);         /* waited until not_before (min TSDR) */
    CHECK_EQ(gpio_a.BSRR, 1u << 8);  /* DE high */
    CHECK((usart.CR1 & USART_CR1_RE) == 0u); /* own characters not heard */
    CHECK((usart.CR1 & USART_CR1_TXEIE) != 0u);
    CHECK_EQ(u.tx_pos, 0);
    /* a second frame while one is going out is refused, and so is a new rate (the
     * interrupt owns CR1 until TC) */
    CHECK_EQ(rs485_uart_transmit(&u, frame, sizeof frame, 0u), -1);
    uint32_t brr = usart.BRR;
    CHECK_EQ(rs485_uart_set_baud(&u, 1500000u), -1);
    CHECK_EQ(usart.BRR, brr);
    usart.SR = USART_SR_TXE; /* free: the ISR feeds DR */
    rs485_uart_isr(&u);
    CHECK_EQ(u.tx_pos, sizeof frame);
    CHECK_EQ(usart.DR, 0x16);
    CHECK((usart.CR1 & USART_CR1_TXEIE) == 0u);
    CHECK((usart.CR1 & USART_CR1_TCIE) != 0u);
    CHECK(u.tx_busy);
    usart.SR = USART_SR_TXE | USART_SR_TC; /* last stop bit out */
    rs485_uart_isr(&u);
    CHECK(!u.tx_busy);
    CHECK_EQ(gpio_a.BSRR, 1u << (8 + 16)); /* DE low */
    CHECK((usart.CR1 & (USART_CR1_RE | USART_CR1_TCIE)) == USART_CR1_RE);
    /* QEMU-like USART (TXE and TC at once): the whole frame leaves inside transmit() */
    usart.SR = USART_SR_TXE | USART_SR_TC;
    CHECK_EQ(rs485_uart_transmit(&u, frame, 3, 0u), 0);
    CHECK(!u.tx_busy);
    CHECK_EQ(usart.DR, 0x05);
    /* a not_before far away is a clock mix-up: no 35-minute spin */
    CHECK_EQ(rs485_uart_transmit(&u, frame, 3, fake_now + 1000000u), 0);
    CHECK_EQ(u.tx_clock_mixups, 1);
    CHECK_EQ(rs485_uart_transmit(&u, frame, 0, 0u), -1);
    CHECK_EQ(rs485_uart_transmit(&u, frame, RS485_TX_MAX + 1u, 0u), -1);
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
static void test_timebase(void)
{
    systick_regs_t st = {0};
    volatile uint32_t icsr = 0;
    timebase_t tb;
    timebase_init(&tb, &st, &icsr, 168000000u);
    CHECK_EQ(st.LOAD, 167999u);
    CHECK_EQ(st.CTRL, SYSTICK_CTRL_CLKSOURCE | SYSTICK_CTRL_TICKINT | SYSTICK_CTRL_ENABLE);
    st.VAL = 167999u;
    CHECK_EQ(timebase_now_us(&tb), 0);
    st.VAL = 167999u - 168u * 250u; /* 250 µs into the first millisecond */
    CHECK_EQ(timebase_now_us(&tb), 250);
    timebase_tick(&tb);
    timebase_tick(&tb);
    CHECK_EQ(timebase_now_us(&tb), 2250);
    /* wrapped but the tick not taken yet (read with interrupts masked): still monotonic */
    icsr = SCB_ICSR_PENDSTSET;
    st.VAL = 167999u - 168u * 3u;
    CHECK_EQ(timebase_now_us(&tb), 3003);
    icsr = 0;
    /* deadline: fires in the first tick at or after it */
    timebase_set_deadline(&tb, 4500u);
    timebase_tick(&tb); /* 3 ms */
    timebase_tick(&tb); /* 4 ms */
    CHECK(!timebase_deadline_hit(&tb));
    timebase_tick(&tb); /* 5 ms */
    CHECK(timebase_deadline_hit(&tb));
    CHECK(!timebase_deadline_hit(&tb));
    /* 32-bit wrap of the µs count is continuous */
    tb.ms = 4294967u; /* 4294967000 µs */
    st.VAL = 167999u - 168u * 295u;
    CHECK_EQ(timebase_now_us(&tb), 4294967295u);
    timebase_tick(&tb);
    st.VAL = 167999u;
    CHECK_EQ(timebase_now_us(&tb), (uint32_t)(4294968000ull));
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

/* ---- clock and fault record ----------------------------------------------------------------- */
static void test_clock_and_fault(void)
{
    rcc_regs_t rcc = {0};
    flash_regs_t fl = {0};
    board_clocks_t c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_NOT_MODELLED);
    CHECK_EQ(c.hclk_hz, 168000000u);
    CHECK_EQ(c.pclk2_hz, 84000000u);
    /* silicon out of reset, but no crystal and a PLL that never locks */
    rcc.CR = RCC_CR_HSION | RCC_CR_HSIRDY;
    c = board_clock_init(&rcc, &fl);
    CHECK_EQ(c.source, BOARD_CLOCK_HSI_ONLY);
    CHECK_EQ(c.hclk_hz, 16000000u);
    CHECK_EQ(rcc.PLLCFGR & 0x3Fu, 16u);          /* PLLM from HSI */
    CHECK_EQ((rcc.PLLCFGR >> 6) & 0x1FFu, 336u); /* PLLN */
    CHECK_EQ(fl.ACR & 7u, 5u);                   /* 5 wait states */

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
}

int main(void)
{
    RUN_TEST(test_brr);
    RUN_TEST(test_uart_init_and_baud);
    RUN_TEST(test_uart_rx_flags);
    RUN_TEST(test_uart_rx_ring);
    RUN_TEST(test_uart_no_stale_reply);
    RUN_TEST(test_uart_transmit);
    RUN_TEST(test_bxcan);
    RUN_TEST(test_timebase);
    RUN_TEST(test_leds_dip);
    RUN_TEST(test_clock_and_fault);
    return check_report();
}
