/* Time as the protocol core sees it: a free-running microsecond counter that wraps.
 *
 * The core never reads a clock. Every event (a received character, a poll) carries the time it
 * happened, so tests, replay and fuzzing can run at any speed. 32 bits of microseconds wrap after
 * 71 minutes; all comparisons go through hal_time_diff() so a wrap is harmless as long as no two
 * compared instants are more than 35 minutes apart (the longest DP watchdog is 650 s). */
#ifndef HAL_TIME_H
#define HAL_TIME_H

#include <stdbool.h>
#include <stdint.h>

typedef uint32_t hal_time_us_t;

/* Signed distance a - b, correct across one wrap of the counter. */
static inline int32_t hal_time_diff(hal_time_us_t a, hal_time_us_t b)
{
    return (int32_t)(a - b);
}

static inline bool hal_time_reached(hal_time_us_t now, hal_time_us_t deadline)
{
    return hal_time_diff(now, deadline) >= 0;
}

/* The earlier of two deadlines: how every poll function merges the deadlines of its parts into
 * the one it returns. */
static inline hal_time_us_t hal_time_earlier(hal_time_us_t a, hal_time_us_t b)
{
    return hal_time_diff(a, b) <= 0 ? a : b;
}

/* Returned by poll functions that have no pending deadline. */
#define HAL_TIME_NO_DEADLINE_US 0x7FFFFFFFu

#endif
