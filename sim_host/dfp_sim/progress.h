/* A progress line on stderr while a long replay or record runs, only when stderr is a terminal:
 * the first at once, then five times a second, cleared at the end. */
#ifndef DFP_SIM_PROGRESS_H
#define DFP_SIM_PROGRESS_H

#include <stdbool.h>
#include <stdint.h>

typedef struct progress {
    bool on; /* stderr is a terminal */
    const char *what;
    uint64_t t0;
    uint64_t last;
    bool shown;
} progress_t;

void progress_begin(progress_t *p, const char *what);
/* Fits replay_progress_t: records read, position and size of the file (0: unknown). */
void progress_show(void *ctx, uint64_t records, uint64_t pos, uint64_t size);
void progress_end(progress_t *p);

#endif
