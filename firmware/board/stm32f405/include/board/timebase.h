/* µs time base and deadline from SysTick (a Cortex-M core timer, so QEMU models it exactly:
 * netduinoplus2 clocks it at 168 MHz of virtual time).
 *
 * SysTick counts down from LOAD = HCLK/1000 - 1 and interrupts once per millisecond; now_us =
 * ms * 1000 + elapsed ticks / (HCLK / 1 MHz). A tick that is pending but not yet taken (read
 * from an interrupt of equal priority or with interrupts masked) is accounted through ICSR.
 * The deadline is checked in the tick: main-loop deadlines (watchdog, baud search, C2
 * supervision, MOVILINK timeouts) have 1 ms resolution, which every one of them tolerates (the
 * shortest is the 1 ms WD base). The reply's min TSDR is waited in the UART driver instead. */
#ifndef BOARD_TIMEBASE_H
#define BOARD_TIMEBASE_H

#include <stdbool.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "hal/hal_time.h"

typedef struct timebase {
    systick_regs_t *st;
    volatile uint32_t *icsr;
    uint32_t ticks_per_us;
    uint32_t load;
    volatile uint32_t ms;
    volatile hal_time_us_t deadline;
    volatile bool deadline_armed;
    volatile bool deadline_hit;
} timebase_t;

void timebase_init(timebase_t *tb, systick_regs_t *st, volatile uint32_t *icsr, uint32_t hclk_hz);
hal_time_us_t timebase_now_us(const timebase_t *tb);
/* From the SysTick handler: counts the millisecond, fires the deadline. */
void timebase_tick(timebase_t *tb);
void timebase_set_deadline(timebase_t *tb, hal_time_us_t t);
/* True once (clears) when the deadline passed. */
bool timebase_deadline_hit(timebase_t *tb);

#endif
