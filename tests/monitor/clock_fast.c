/* A preload for long-run tests: CLOCK_MONOTONIC runs 4096 times as fast as it does, from its
 * first reading, so an hour of a program's time passes in about a second. Waits (ppoll) stay
 * real; what a program measures with the clock is what speeds up. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdint.h>
#include <time.h>

#define CLOCK_FAST_FACTOR 4096u
#define NS_PER_S 1000000000u

int clock_gettime(clockid_t id, struct timespec *ts)
{
    static int (*real)(clockid_t, struct timespec *);
    static uint64_t base_ns;
    if (real == NULL) {
        real = (int (*)(clockid_t, struct timespec *))dlsym(RTLD_NEXT, "clock_gettime");
    }
    int rc = real(id, ts);
    if (rc != 0 || id != CLOCK_MONOTONIC) {
        return rc;
    }
    uint64_t ns = (uint64_t)ts->tv_sec * NS_PER_S + (uint64_t)ts->tv_nsec;
    if (base_ns == 0u) {
        base_ns = ns;
    }
    ns = base_ns + (ns - base_ns) * CLOCK_FAST_FACTOR;
    ts->tv_sec = (time_t)(ns / NS_PER_S);
    ts->tv_nsec = (long)(ns % NS_PER_S);
    return 0;
}
