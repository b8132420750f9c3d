#include "board/timebase.h"

void timebase_init(timebase_t *tb, systick_regs_t *st, uint32_t hclk_hz,
                   const volatile uint32_t *us)
{
    tb->us = us;
    tb->deadline_armed = false;
    tb->deadline_hit = false;
    st->CTRL = 0;
    st->LOAD = hclk_hz / 1000u - 1u;
    st->VAL = 0;
    st->CTRL = SYSTICK_CTRL_CLKSOURCE | SYSTICK_CTRL_TICKINT | SYSTICK_CTRL_ENABLE;
}

void timebase_tick(timebase_t *tb)
{
    if (tb->deadline_armed && hal_time_reached(*tb->us, tb->deadline)) {
        tb->deadline_armed = false;
        tb->deadline_hit = true;
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
