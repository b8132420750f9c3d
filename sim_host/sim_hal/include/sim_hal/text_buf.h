/* A line of text built into a caller's fixed buffer, piece by piece: what does not fit is cut,
 * the text always ends in NUL. The decoders (replay, monitor) write their telegram texts so. */
#ifndef SIM_HAL_TEXT_BUF_H
#define SIM_HAL_TEXT_BUF_H

#include <stddef.h>

typedef struct text_buf {
    char *p;
    size_t max; /* the buffer's size, NUL included */
    size_t n;   /* characters written so far (at most max - 1) */
} text_buf_t;

/* printf at the end of the text; once the buffer is full, nothing more. */
void text_buf_put(text_buf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
