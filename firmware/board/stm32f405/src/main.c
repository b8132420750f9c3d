/* The DFP21B card on the STM32F405 reference board.
 *
 * Interrupt context: USART1 (each character into the telegram collector, finished telegrams
 * into the driver's queue; the transmit steps), PendSV (the receive-to-reply path: each queued
 * telegram into dfp21b_rx_telegram, which checks, answers and hands the reply to the UART driver
 * at once), SysTick (deadlines, LED patterns), CAN1 RX0 (frames into a ring). Time is TIM2, a
 * free-running 1 MHz counter.
 * Main loop: dfp21b_poll (timers, outputs to the inverter, MOVILINK, data set 47, inputs for the
 * next reply) and the SBus link, with PendSV and CAN masked (BASEPRI) while they run, so the
 * core is never entered twice; the USART keeps receiving and sending meanwhile. Then sleep until
 * a telegram ended, a CAN frame came, or the deadline passed.
 *
 * Build variants (CMake targets, firmware/board/stm32f405/CMakeLists.txt):
 *   card image   automatic baud search, strict timing, address from the DIP switches
 *   QEMU image   DFP_BOARD_FIXED_BAUD, relaxed timing, DFP_BOARD_DIP_OVERRIDE, semihosting:
 *                prints a summary and exits with a verdict after DFP_BOARD_EXIT_SILENCE_MS
 *                without a character, once it has been in Data_Exch
 *   fault image  DFP_BOARD_FAULT_TEST: runs into a bus fault on purpose, then resets once more
 *                (fault record test: the record is shown by the next start only) */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "board/board.h"
#include "board/board_io.h"
#include "board/bxcan.h"
#ifdef DFP_BOARD_LOOPBACK_INVERTER
#include "board/loop_inverter.h"
#endif
#include "board/rs485_uart.h"
#include "board/timebase.h"
#include "dfp21b/dfp21b.h"
#include "movilink/sbus.h"

#ifndef DFP_BOARD_FIXED_BAUD
#define DFP_BOARD_FIXED_BAUD 0u
#endif
#ifndef DFP_BOARD_STRICT_TIMING
#define DFP_BOARD_STRICT_TIMING 1
#endif
#ifndef DFP_BOARD_DIP_OVERRIDE
#define DFP_BOARD_DIP_OVERRIDE (-1)
#endif
#ifndef DFP_BOARD_SBUS_ADDRESS
#define DFP_BOARD_SBUS_ADDRESS 0u /* P813 of the inverter the card sits in */
#endif
#ifndef DFP_BOARD_SBUS_BITRATE
#define DFP_BOARD_SBUS_BITRATE 500000u
#endif
/* TIM2's kernel clock from the clocks clock.c set up (board.h); QEMU's model counts at 1 GHz
 * whatever RCC says. */
#ifndef DFP_BOARD_TIM2_HZ
#define DFP_BOARD_TIM2_HZ board_tim2_hz(&clocks)
#endif
#define FW_VERSION_MAJOR 0u
#define FW_VERSION_MINOR 6u
#define FW_VERSION_BUGFIX 0u

static timebase_t tb;
static rs485_uart_t uart;
static board_leds_t leds = {.port = {GPIOB, GPIOB}, .pin = {0u, 1u}};
static board_dip_t dip = {.port = GPIOC, .first_pin = 0u, .active_low = true,
                          .override = DFP_BOARD_DIP_OVERRIDE};
static bxcan_t can;
static sbus_card_link_t sbus;
static bool sbus_up; /* the card talks SBus (bxCAN or the stand-in loop) */
#ifdef DFP_BOARD_LOOPBACK_INVERTER
static loop_inverter_t loop;
#endif
static dfp21b_t card;
static board_clocks_t clocks;
static volatile bool poll_request;
static uint32_t data_exch_entries;

static hal_time_us_t now_us(void)
{
    return timebase_now_us(&tb);
}

/* ---- interrupts ------------------------------------------------------------------------------ */

void SysTick_Handler(void);
void USART1_IRQHandler(void);
void PendSV_Handler(void);
void CAN1_RX0_IRQHandler(void);

void SysTick_Handler(void)
{
    timebase_tick(&tb);
    board_leds_tick(&leds);
}

static void uart_rx(void *ctx, const fdl_rx_telegram_t *tg)
{
    dfp21b_rx_telegram(ctx, tg);
    poll_request = true; /* a telegram ended (or was dropped): the main loop's turn */
}

void USART1_IRQHandler(void)
{
    /* Clear the pending bit before draining DR: a character that arrives while we drain
     * raises it again instead of being stranded (tooling notes, "RX interrupt pitfall"). */
    NVIC_ICPR[IRQ_USART1 / 32u] = 1u << (IRQ_USART1 % 32u);
    rs485_uart_isr(&uart);
}

static void uart_rx_pending(void *ctx)
{
    (void)ctx;
    SCB_ICSR = SCB_ICSR_PENDSVSET;
}

/* Tail-chains to the USART interrupt unless the main loop is inside the core (BASEPRI): then
 * right after it, with the telegrams' own times. */
void PendSV_Handler(void)
{
    (void)rs485_uart_rx_drain(&uart);
}

void CAN1_RX0_IRQHandler(void)
{
    bxcan_rx_isr(&can);
    poll_request = true;
}

/* ---- the inverter over SBus ---------------------------------------------------------------- */

static void can_rx(void *ctx, const hal_can_frame_t *f)
{
    (void)ctx;
    sbus_card_link_rx(&sbus, f, now_us());
}

static void sbus_param_response(void *c, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    dfp21b_inverter_param_response(c, channel, rsp);
}

static void sbus_process_inputs(void *c, const uint16_t *pi, uint8_t n)
{
    dfp21b_inverter_process_inputs(c, pi, n);
}

static void card_event(void *ctx, const dp_event_t *ev)
{
    (void)ctx;
    if (ev->type == DP_EV_STATE && ev->new_state == DP_STATE_DATA_EXCH) {
        data_exch_entries++;
    }
}

/* ---- set-up ---------------------------------------------------------------------------------- */

/* The interrupt's priority was set by board_irq_priorities in board_init. */
static void nvic_enable(uint32_t irq)
{
    NVIC_ICPR[irq / 32u] = 1u << (irq % 32u);
    NVIC_ISER[irq / 32u] = 1u << (irq % 32u);
}

static void board_init(void)
{
    clocks = board_clock_init(RCC, FLASH_IF);
    RCC->AHB1ENR |= RCC_AHB1ENR_GPIOA | RCC_AHB1ENR_GPIOB | RCC_AHB1ENR_GPIOC;
    RCC->APB2ENR |= RCC_APB2ENR_USART1;
    RCC->APB1ENR |= RCC_APB1ENR_CAN1 | RCC_APB1ENR_TIM2;
    TIM2->PSC = timebase_prescaler(DFP_BOARD_TIM2_HZ);
    TIM2->ARR = 0xFFFFFFFFu;
    TIM2->EGR = TIM_EGR_UG; /* the prescaler is buffered: load it now */
    TIM2->CR1 = TIM_CR1_CEN;
    /* Before SysTick starts: USART1 above SysTick, whose handler would otherwise delay the
     * TIM2 stamp of a character by up to ~0.9 µs (board.h). */
    board_irq_priorities(NVIC_IPR, &SCB_SHPR3);
    SCB_SHCSR |= (1u << 16) | (1u << 17) | (1u << 18); /* MemManage, BusFault, UsageFault */
    timebase_init(&tb, SYSTICK, clocks.hclk_hz, &TIM2->CNT);
    board_leds_init(&leds);
    for (uint8_t i = 0; i < 7u; i++) {
        gpio_config(GPIOC, i, GPIO_MODE_INPUT, GPIO_PULL_UP, 0);
    }
    gpio_config(GPIOA, 8u, GPIO_MODE_OUTPUT, GPIO_PULL_DOWN, 0);   /* DE */
    gpio_config(GPIOA, 9u, GPIO_MODE_AF, GPIO_PULL_NONE, 7u);      /* USART1 TX */
    gpio_config(GPIOA, 10u, GPIO_MODE_AF, GPIO_PULL_UP, 7u);       /* USART1 RX */
    gpio_config(GPIOB, 8u, GPIO_MODE_AF, GPIO_PULL_UP, 9u);        /* CAN1 RX */
    gpio_config(GPIOB, 9u, GPIO_MODE_AF, GPIO_PULL_NONE, 9u);      /* CAN1 TX */
}

#ifdef DFP_BOARD_EXIT_SILENCE_MS
static char *put_u32(char *p, uint32_t v)
{
    char tmp[11];
    unsigned n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    while (n > 0u) {
        *p++ = tmp[--n];
    }
    return p;
}

static char *put_s(char *p, const char *s)
{
    while (*s != '\0') {
        *p++ = *s++;
    }
    return p;
}

/* One line for the test's log, then the verdict: 0 = it served a master in Data_Exch without a
 * character error, a fault or a stack overflow. */
static void report_and_exit(void)
{
    uint32_t rx_err = uart.rx_parity_errors + uart.rx_framing_errors + uart.rx_overruns;
    uint32_t stack = board_stack_used();
    char line[256];
    char *p = line;
    p = put_s(p, "dfp21b-qemu: address ");
    p = put_u32(p, card.address);
    p = put_s(p, ", data exchange entered ");
    p = put_u32(p, data_exch_entries);
    p = put_s(p, "x, telegrams for me ");
    p = put_u32(p, card.dp.telegrams_for_me);
    p = put_s(p, ", rx telegrams ");
    p = put_u32(p, uart.rx_telegrams);
    p = put_s(p, ", rx errors ");
    p = put_u32(p, rx_err);
    p = put_s(p, ", no buffer free ");
    p = put_u32(p, uart.rx_buffer_overflows);
    p = put_s(p, ", frames sent ");
    p = put_u32(p, uart.tx_frames);
    p = put_s(p, " (late, not sent: ");
    p = put_u32(p, uart.tx_stale);
    p = put_s(p, ")");
    p = put_s(p, ", stack ");
    p = put_u32(p, stack);
    p = put_s(p, "/");
    p = put_u32(p, board_stack_size());
    p = put_s(p, " B, clock ");
    p = put_s(p, board_clock_source_name(clocks.source));
    p = put_s(p, ", inverter ");
    p = put_s(p, can.up ? "SBus (bxCAN)" : sbus_up ? "stand-in on an SBus memory loop"
                                                : "none (no CAN controller answered)");
    p = put_s(p, "\n");
    *p = '\0';
    semihost_write0(line);
    bool ok = data_exch_entries > 0u && rx_err == 0u && stack < board_stack_size();
    semihost_exit(ok ? 0u : 1u);
}
#endif

/* A fault handler's record from before the reset (RAM kept over it): shown once, by the start
 * the fault's reset caused; printed under test. */
__attribute__((noinline)) static bool take_previous_fault(void)
{
    bool had_fault = board_fault.magic == BOARD_FAULT_MAGIC;
#ifdef BOARD_SEMIHOSTING
    if (had_fault) {
        char line[320];
        board_fault_format(&board_fault, line, sizeof line);
        semihost_write0("previous ");
        semihost_write0(line);
        semihost_write0("\n");
    }
#endif
    board_fault_mark_shown(&board_fault);
    return had_fault;
}

#ifdef DFP_BOARD_FAULT_TEST
/* Three starts in one QEMU run, each after a SYSRESETREQ, which keeps RAM (QEMU reloads only
 * the image's contents, not its NOLOAD sections): 1 faults on purpose, 2 must show the record
 * and resets as NRST or a debugger would, 3 must not show it. */
#define FAULT_TEST_MAGIC 0x7E57FA17u
static struct {
    uint32_t magic;
    uint32_t starts;
} fault_test __attribute__((section(".noinit")));

static void fault_test_step(bool pattern)
{
    if (fault_test.magic != FAULT_TEST_MAGIC) {
        fault_test.magic = FAULT_TEST_MAGIC;
        fault_test.starts = 0;
    }
    fault_test.starts++;
    char line[] = "fault test: start 0, fault pattern ";
    line[18] = (char)('0' + fault_test.starts % 10u);
    semihost_write0(line);
    semihost_write0(pattern ? "on\n" : "off\n");
    if (fault_test.starts == 1u) {
        semihost_write0("fault test: reading 0xFFFFFFF0\n");
        (void)*(volatile uint32_t *)0xFFFFFFF0u;
    }
    if (fault_test.starts == 2u) {
        __asm volatile("dsb" ::: "memory");
        SCB_AIRCR = 0x05FA0004u; /* SYSRESETREQ, RAM kept */
        for (;;) {
        }
    }
    if (board_fault.magic == BOARD_FAULT_SHOWN && board_fault.bfar == 0xFFFFFFF0u) {
        semihost_write0("fault test: the shown record is kept for a debugger\n");
    }
    semihost_exit(pattern || fault_test.starts != 3u ? 1u : 0u);
}
#endif

/* The card <-> inverter link: SBus on bxCAN, or the stand-in loop in test images. Without a
 * CAN controller (QEMU) or transceiver the card runs without inverter: PI words echo PO words
 * and parameter services answer "no response" (class 6 code 2). */
__attribute__((noinline)) static ml_link_t start_inverter_link(void)
{
    bxcan_cfg_t ccfg = {.regs = CAN1, .pclk_hz = clocks.pclk1_hz,
                        .bitrate = DFP_BOARD_SBUS_BITRATE, .rx = can_rx, .rx_ctx = NULL};
    ml_link_t inverter = {0};
    sbus_card_link_cfg_t scfg = {.address = DFP_BOARD_SBUS_ADDRESS,
                                 .param_response = sbus_param_response,
                                 .process_inputs = sbus_process_inputs, .card = &card};
    if (bxcan_init(&can, &ccfg) == 0) {
        scfg.can = bxcan_hal(&can);
        sbus_up = true;
        nvic_enable(IRQ_CAN1_RX0);
    }
#ifdef DFP_BOARD_LOOPBACK_INVERTER
    else {
        loop_inverter_init(&loop, DFP_BOARD_SBUS_ADDRESS);
        scfg.can = loop_inverter_card_can(&loop);
        sbus_up = true;
    }
#endif
    if (sbus_up) {
        sbus_card_link_init(&sbus, &scfg);
        inverter = sbus_card_link(&sbus);
    }
    return inverter;
}

/* The main loop's sections inside the core: PendSV (the USART's deferred work, the reply path)
 * and CAN are held off between core_enter and core_leave. Out of line so that
 * tools/reply_path_count.py finds every section's bounds by these two names. */
__attribute__((noinline)) static void core_enter(void)
{
    board_basepri(BOARD_PRIO_CORE);
}

__attribute__((noinline)) static void core_leave(void)
{
    board_basepri(0);
}

/* dfp21b's preemption point between two bounded pieces of main-loop work: a reply that became
 * due meanwhile is served here, not after the whole pass. */
static void core_preempt(void *ctx)
{
    (void)ctx;
    core_leave();
    core_enter();
}

#ifdef DFP_BOARD_LOOPBACK_INVERTER
/* The stand-in inverter's half of an exchange is not the card's work: the card's half (taking
 * the delivered frame) runs in a section of its own. */
static void loop_rx(void *ctx, const hal_can_frame_t *f)
{
    core_preempt(NULL);
    can_rx(ctx, f);
}
#endif

/* Out of line, as start_inverter_link: their configuration structs are then not part of main's
 * frame, which is on every interrupt's stack chain (tools/stack_report.py). */
__attribute__((noinline)) static void start_card(ml_link_t inverter)
{
    rs485_uart_cfg_t ucfg = {.regs = USART1, .de_port = GPIOA, .de_pin = 8u,
                             .pclk_hz = clocks.pclk2_hz,
                             .baud = DFP_BOARD_FIXED_BAUD != 0u ? DFP_BOARD_FIXED_BAUD : 6000000u,
                             .strict_timing = DFP_BOARD_STRICT_TIMING != 0,
                             .clock_us = &TIM2->CNT, .rx = uart_rx, .rx_ctx = &card,
                             .rx_pending = uart_rx_pending};
    (void)rs485_uart_init(&uart, &ucfg);
    dfp21b_cfg_t cfg = {
        .uart = rs485_uart_hal(&uart),
        .led = board_leds_hal(&leds),
        .dip = board_dip_hal(&dip),
        .fixed_baud = DFP_BOARD_FIXED_BAUD,
        .strict_timing = DFP_BOARD_STRICT_TIMING != 0,
        .inverter = inverter,
        .serial = "STM32F405-0001",
        .hardware_revision = 1,
        .software_revision = {FW_VERSION_MAJOR, FW_VERSION_MINOR, FW_VERSION_BUGFIX},
        .event = card_event,
        .preempt = core_preempt,
    };
    /* Not a core section: the USART interrupt is enabled only after it. */
    board_basepri(BOARD_PRIO_CORE);
    dfp21b_init(&card, &cfg, now_us());
    board_basepri(0);
    nvic_enable(IRQ_USART1);
}

#ifdef DFP_BOARD_EXIT_SILENCE_MS
/* Test images end themselves once the master has gone quiet after Data_Exch. Returns the next
 * deadline, no later than the next look at the silence (100 ms). */
typedef struct silence_watch {
    uint32_t last_telegrams;
    hal_time_us_t last_activity;
} silence_watch_t;

static hal_time_us_t exit_on_silence(silence_watch_t *w, hal_time_us_t now, hal_time_us_t next)
{
    if (uart.rx_telegrams != w->last_telegrams) {
        w->last_telegrams = uart.rx_telegrams;
        w->last_activity = now;
    } else if (data_exch_entries > 0u &&
               hal_time_diff(now, w->last_activity) >
                   (int32_t)(DFP_BOARD_EXIT_SILENCE_MS * 1000u)) {
        report_and_exit();
    }
    if (hal_time_diff(next, now + 100000u) > 0) {
        next = now + 100000u;
    }
    return next;
}
#endif

int main(void)
{
    board_init();
    bool had_fault = take_previous_fault();
    if (board_reset_by_iwdg(RCC)) {
        had_fault = true; /* the main loop hung: shown like a fault */
#ifdef BOARD_SEMIHOSTING
        semihost_write0("previous reset by the independent watchdog\n");
#endif
    }
    leds.fault_pattern = had_fault; /* BUS FAULT at 4 Hz until the card is in Data_Exch (below) */
#ifdef DFP_BOARD_FAULT_TEST
    fault_test_step(leds.fault_pattern);
#endif
    DBGMCU_APB1_FZ |= DBGMCU_APB1_FZ_IWDG_STOP; /* a debugger's halt is no hang */
    board_iwdg_start(IWDG, BOARD_IWDG_TIMEOUT_MS);
    start_card(start_inverter_link());
#ifdef DFP_BOARD_EXIT_SILENCE_MS
    silence_watch_t silence = {.last_telegrams = 0, .last_activity = now_us()};
#endif

    for (;;) {
        board_iwdg_refresh(IWDG);
        poll_request = false;
        hal_time_us_t now = now_us();
        /* The core's work, in sections that hold the USART's deferred work (PendSV) off; the
         * longest section is the "main-loop section" of docs/performance.md, counted by
         * tools/reply_path_count.py. */
        core_enter();
        if (can.up) {
            (void)bxcan_drain(&can);
        }
#ifdef DFP_BOARD_LOOPBACK_INVERTER
        if (!can.up && sbus_up) {
            (void)loop_inverter_poll(&loop, now, loop_rx, NULL, core_preempt);
            core_preempt(NULL);
        }
#endif
        hal_time_us_t next = dfp21b_poll(&card, now);
#ifdef DFP_BOARD_LOOPBACK_INVERTER
        if (!can.up && sbus_up) {
            core_preempt(NULL);
        }
        if (!can.up && sbus_up && loop_inverter_poll(&loop, now, loop_rx, NULL, core_preempt) != 0u) {
            poll_request = true; /* the stand-in answered within this pass: take it now */
        }
#endif
        if (sbus_up) {
            core_preempt(NULL);
            next = hal_time_earlier(next, sbus_card_link_poll(&sbus, now));
        }
        core_leave();
        if (had_fault && dp_slave_state(&card.dp) == DP_STATE_DATA_EXCH) {
            leds.fault_pattern = false;
        }
#ifdef DFP_BOARD_EXIT_SILENCE_MS
        next = exit_on_silence(&silence, now, next);
#endif
        timebase_set_deadline(&tb, next);
        /* Sleep unless something is pending; masked, so a wake-up between the check and the
         * wfi is not lost (the interrupt stays pending and ends the wfi). */
        __asm volatile("cpsid i" ::: "memory");
        if (!poll_request && !tb.deadline_hit && hal_time_diff(next, now_us()) > 0) {
            __asm volatile("wfi");
        }
        __asm volatile("cpsie i" ::: "memory");
        (void)timebase_deadline_hit(&tb);
    }
}
