/* The progress line of replay and record on a terminal (progress.h). */
#include "progress.h"

#include <stdio.h>
#include <unistd.h>

#include "sim_hal/host_clock.h"

void progress_show(void *ctx, uint64_t records, uint64_t pos, uint64_t size)
{
    progress_t *p = ctx;
    if (!p->on) {
        return;
    }
    uint64_t now = host_clock_mono_ns();
    if (p->shown && now - p->last < 200000000u) {
        return; /* the first call shows at once, then five times a second */
    }
    p->last = now;
    double s = (double)(now - p->t0) / 1e9;
    if (size > 0u) {
        fprintf(stderr, "\r%s: %llu records (%.0f %%), %.0f telegrams/s\033[K", p->what,
                (unsigned long long)records, 100.0 * (double)pos / (double)size,
                s > 0 ? (double)records / s : 0.0);
    } else {
        fprintf(stderr, "\r%s: %llu records, %.0f telegrams/s\033[K", p->what,
                (unsigned long long)records, s > 0 ? (double)records / s : 0.0);
    }
    p->shown = true;
}

void progress_end(progress_t *p)
{
    if (p->shown) {
        fputs("\r\033[K", stderr);
        p->shown = false;
    }
}

void progress_begin(progress_t *p, const char *what)
{
    p->on = isatty(STDERR_FILENO) != 0;
    p->what = what;
    p->t0 = host_clock_mono_ns();
    p->last = p->t0;
    p->shown = false;
}
