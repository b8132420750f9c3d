/* µs time base and deadline.
 *
 * now_us is a free-running 32-bit counter at 1 MHz (TIM2 with its prescaler set by the board),
 * read in one instruction, so the UART interrupt can stamp every character and it wraps like
 * hal_time_us_t. SysTick interrupts once per millisecond and checks the deadline there: main-loop
 * deadlines (watchdog, baud search, C2 supervision, MOVILINK timeouts) have 1 ms resolution,
 * which every one of them tolerates (the shortest is the 1 ms WD base). The reply's min TSDR is
 * waited in the UART driver instead. */
#ifndef BOARD_TIMEBASE_H
#define BOARD_TIMEBASE_H

#include <stdbool.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "hal/hal_time.h"

typedef struct timebase {
    const volatile uint32_t *us; /* the 1 MHz counter */
    volatile hal_time_us_t deadline;
    volatile bool deadline_armed;
    volatile bool deadline_hit;
} timebase_t;

/* Starts SysTick at 1 kHz from HCLK; us is the running 1 MHz counter. */
void timebase_init(timebase_t *tb, systick_regs_t *st, uint32_t hclk_hz,
                   const volatile uint32_t *us);
static inline hal_time_us_t timebase_now_us(const timebase_t *tb) { return *tb->us; }
/* The prescaler that makes a timer clocked at timer_hz count microseconds (PSC register). */
static inline uint32_t timebase_prescaler(uint32_t timer_hz) { return timer_hz / 1000000u - 1u; }
/* From the SysTick handler: fires the deadline. */
void timebase_tick(timebase_t *tb);
void timebase_set_deadline(timebase_t *tb, hal_time_us_t t);
/* True once (clears) when the deadline passed. */
bool timebase_deadline_hit(timebase_t *tb);

#endif
