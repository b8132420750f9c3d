/* The error texts the host backends hand back to their callers: formatted into the caller's
 * buffer, truncated to it, nothing written when there is no buffer. */
#ifndef SIM_HAL_ERROR_TEXT_H
#define SIM_HAL_ERROR_TEXT_H

#include <stddef.h>

void sim_error_text(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
