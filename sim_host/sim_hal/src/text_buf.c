#include "sim_hal/text_buf.h"

#include <stdarg.h>
#include <stdio.h>

void text_buf_put(text_buf_t *b, const char *fmt, ...)
{
    if (b->max == 0u || b->n >= b->max - 1u) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->n, b->max - b->n, fmt, ap);
    va_end(ap);
    if (k > 0) {
        b->n += (size_t)k;
        if (b->n >= b->max) {
            b->n = b->max - 1u; /* vsnprintf cut it */
        }
    }
}
