/* The STM32F405 reference board: pin map, clocks, interrupt priorities, and the services the
 * main loop uses. Pins are this project's choice for a DFP21B-like card built around an
 * STM32F405 (the real card's MCU is not documented); change them here for another layout.
 *
 *   USART1  TX PA9, RX PA10 (AF7)   RS-485 transceiver; DE (driver enable) PA8, active high
 *   CAN1    RX PB8, TX PB9 (AF9)    SBus to the inverter, 500 kbit/s (P816 default)
 *   LEDs    RUN PB0, BUS FAULT PB1  active high
 *   DIP     PC0..PC6 = 2^0..2^6     switch ON pulls to ground (internal pull-ups)
 *
 * Interrupt priorities (4 bits, lower = more urgent; board_irq_priorities() writes them):
 *   0  MemManage, BusFault, UsageFault (their reset value): a fault in any handler below is
 *      recorded as itself instead of escalating to HardFault
 *   1  USART1: characters into the driver's collector, transmit steps. Never masked, so no
 *      character is lost and no reply stalls mid-frame; and nothing preempts it, because each
 *      character is stamped with TIM2 in its handler and strict timing leaves 1 to 2 µs of
 *      stamp jitter (docs/porting.md), most of which a SysTick handler would take
 *   2  SysTick: deadline flag and LED patterns; a few µs late is harmless (time is TIM2)
 *   3  PendSV: the core's receive-to-reply path (the queue into dfp21b_rx_telegram)
 *   4  CAN1 RX0
 * The main loop masks priority >= 3 with BASEPRI while it runs the core's poll, so the reply
 * path and the main loop never work on the card at the same time (the core has no locks; see
 * docs/porting.md). */
#ifndef BOARD_BOARD_H
#define BOARD_BOARD_H

#include <stdbool.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"

#define BOARD_HSE_HZ 8000000u
#define BOARD_HCLK_HZ 168000000u
#define BOARD_PCLK1_HZ 42000000u
#define BOARD_PCLK2_HZ 84000000u
#define BOARD_HSI_HZ 16000000u

#define BOARD_PRIO_FAULT 0u /* SHPR1's reset value, left as it is */
#define BOARD_PRIO_USART 1u
#define BOARD_PRIO_SYSTICK 2u
#define BOARD_PRIO_CORE 3u /* PendSV, and the BASEPRI of the main loop's core sections */
#define BOARD_PRIO_CAN 4u
#define BOARD_PRIO_SHIFT 4u /* the F405 implements the top 4 bits of each priority byte */

/* Writes the priorities above: USART1's and CAN1 RX0's NVIC_IPR bytes, SysTick's and PendSV's
 * bytes of SCB_SHPR3 (PM0214 §4.3.7, §4.4.8); the other bytes are kept. */
void board_irq_priorities(volatile uint8_t *nvic_ipr, volatile uint32_t *scb_shpr3);

typedef enum board_clock_source {
    BOARD_CLOCK_PLL_HSE = 0, /* 8 MHz crystal -> PLL 168 MHz */
    BOARD_CLOCK_PLL_HSI,     /* no crystal: HSI 16 MHz -> PLL 168 MHz (UART rates within 1 %) */
    BOARD_CLOCK_HSI_ONLY,    /* PLL did not lock: HSI 16 MHz, AHB and APBs /1; the card runs slowly */
    BOARD_CLOCK_NOT_MODELLED, /* RCC reads as zero (QEMU): the machine's fixed 168 MHz */
} board_clock_source_t;

typedef struct board_clocks {
    board_clock_source_t source;
    uint32_t hclk_hz;
    uint32_t pclk1_hz;
    uint32_t pclk2_hz;
} board_clocks_t;

/* TIM2's kernel clock (RM0090 §7.2): PCLK1 when APB1 runs undivided, 2 x PCLK1 when it is
 * divided (the HSI-only fallback runs it /1, the PLL set-up /4). Derived, not stored: RAM. */
static inline uint32_t board_tim2_hz(const board_clocks_t *c)
{
    return c->pclk1_hz < c->hclk_hz ? 2u * c->pclk1_hz : c->pclk1_hz;
}

board_clocks_t board_clock_init(rcc_regs_t *rcc, flash_regs_t *flash);

/* The independent watchdog: started before the card, reloaded by every pass of the main loop
 * (which passes at least once a millisecond: SysTick wakes it), so a main loop that hangs, in a
 * core section or anywhere else, resets the card instead of leaving it answering on the bus with
 * stale data or dead. Its clock is the LSI, 17..47 kHz (RM0090 datasheet, 32 kHz typical): the
 * timeout is set for the typical clock and lies between 0.68 and 1.88 times it. */
#define BOARD_IWDG_TIMEOUT_MS 100u
#define BOARD_IWDG_LSI_HZ 32000u
/* RLR for timeout_ms at /32 (1 ms a count at 32 kHz), within 1..0xFFF. */
uint32_t board_iwdg_reload(uint32_t timeout_ms);
void board_iwdg_start(iwdg_regs_t *iwdg, uint32_t timeout_ms);
static inline void board_iwdg_refresh(iwdg_regs_t *iwdg)
{
    iwdg->KR = IWDG_KEY_RELOAD;
}
/* Whether the last reset came from the watchdog; clears the reset flags for the next start. */
bool board_reset_by_iwdg(rcc_regs_t *rcc);
const char *board_clock_source_name(board_clock_source_t s);

/* Fault record: survives a reset (.noinit RAM), readable with a debugger (`p board_fault`) or
 * at the next start, which shows it (BUS FAULT pattern) and marks it shown: only the reset the
 * fault caused shows it, a later NRST or debugger reset does not. A shown record keeps its
 * fields for the debugger (magic BOARD_FAULT_SHOWN) until the next fault overwrites it. */
#define BOARD_FAULT_MAGIC 0xFA017EC0u
#define BOARD_FAULT_SHOWN 0xFA017EC1u
typedef struct board_fault_record {
    uint32_t magic;
    uint32_t count;       /* faults since a start last took the record: 1, more if faults came
                           * back before main got to it (in board_init, say) */
    uint32_t exception;   /* 3 HardFault, 4 MemManage, 5 BusFault, 6 UsageFault, 16+ IRQ */
    uint32_t r0, r1, r2, r3, r12, lr, pc, xpsr; /* the stacked frame */
    uint32_t sp;          /* stack pointer before the exception */
    uint32_t exc_return;
    uint32_t cfsr, hfsr, mmfar, bfar;
} board_fault_record_t;

extern board_fault_record_t board_fault;
/* A start has taken the record for display: mark it shown (a record that is not a fresh one is
 * left as it is). */
void board_fault_mark_shown(board_fault_record_t *r);
/* Formats the record as one line of text ("fault: HardFault pc=0x... lr=... cfsr=..."). */
unsigned board_fault_format(const board_fault_record_t *r, char *out, unsigned max);

/* Semihosting (test images under QEMU with -semihosting-config enable=on): */
void semihost_write0(const char *s);
__attribute__((noreturn)) void semihost_exit(uint32_t code);

/* Stack: painted at reset, measured later. */
uint32_t board_stack_size(void);
uint32_t board_stack_used(void);

static inline void board_basepri(uint32_t prio)
{
#ifndef BOARD_HOST_TEST
    uint32_t v = prio << BOARD_PRIO_SHIFT;
    __asm volatile("msr basepri, %0" ::"r"(v) : "memory");
#else
    (void)prio;
#endif
}

#endif
