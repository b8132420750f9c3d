#include "monitor/mon_sink.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void mon_printf(const mon_sink_t *out, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    /* va_start is above; clang 14's analyzer says otherwise when the file is compiled into
     * a test as well (as for cli.c's cli_error). */
    // NOLINTNEXTLINE(clang-analyzer-valist.Uninitialized)
    int n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n < 0) {
        return;
    }
    size_t len = (size_t)n < sizeof line ? (size_t)n : sizeof line - 1u;
    out->put(out->ctx, line, len);
}

static void buf_put(void *ctx, const char *s, size_t n)
{
    mon_buf_t *b = ctx;
    if (b->len + n + 1u > b->cap) {
        b->overflow = 1;
        return;
    }
    memcpy(b->buf + b->len, s, n);
    b->len += n;
    b->buf[b->len] = '\0';
}

mon_sink_t mon_buf_sink(mon_buf_t *b)
{
    mon_sink_t s = {buf_put, b};
    return s;
}
