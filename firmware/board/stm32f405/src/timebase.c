#include "board/timebase.h"

void timebase_init(timebase_t *tb, systick_regs_t *st, volatile uint32_t *icsr, uint32_t hclk_hz)
{
    tb->st = st;
    tb->icsr = icsr;
    tb->ticks_per_us = hclk_hz / 1000000u;
    tb->load = hclk_hz / 1000u - 1u;
    tb->ms = 0;
    tb->deadline_armed = false;
    tb->deadline_hit = false;
    st->CTRL = 0;
    st->LOAD = tb->load;
    st->VAL = 0;
    st->CTRL = SYSTICK_CTRL_CLKSOURCE | SYSTICK_CTRL_TICKINT | SYSTICK_CTRL_ENABLE;
}

hal_time_us_t timebase_now_us(const timebase_t *tb)
{
    uint32_t m;
    uint32_t v;
    do {
        m = tb->ms;
        v = tb->st->VAL;
    } while (m != tb->ms); /* the tick preempted us: read again */
    if ((*tb->icsr & SCB_ICSR_PENDSTSET) != 0u) {
        /* wrapped, tick not taken yet (we run at its priority or masked): count it */
        v = tb->st->VAL;
        m++;
    }
    uint32_t elapsed = tb->load - (v > tb->load ? tb->load : v);
    return (hal_time_us_t)(m * 1000u + elapsed / tb->ticks_per_us);
}

void timebase_tick(timebase_t *tb)
{
    tb->ms = tb->ms + 1u;
    if (tb->deadline_armed) {
        hal_time_us_t now = (hal_time_us_t)(tb->ms * 1000u);
        if (hal_time_reached(now, tb->deadline)) {
            tb->deadline_armed = false;
            tb->deadline_hit = true;
        }
    }
}

void timebase_set_deadline(timebase_t *tb, hal_time_us_t t)
{
    tb->deadline_hit = false;
    tb->deadline = t;
    tb->deadline_armed = true;
}

bool timebase_deadline_hit(timebase_t *tb)
{
    if (tb->deadline_hit) {
        tb->deadline_hit = false;
        return true;
    }
    return false;
}
