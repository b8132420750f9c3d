/* The host's monotonic clock in nanoseconds: what every host program measures real time with
 * (pacing a simulation to wall time, benchmarks, the tty backend's character timing). The
 * protocol core never calls it; it receives hal_time_us_t values derived from it. */
#ifndef SIM_HAL_HOST_CLOCK_H
#define SIM_HAL_HOST_CLOCK_H

#include <stdint.h>
#include <time.h>

static inline uint64_t host_clock_mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

#endif
