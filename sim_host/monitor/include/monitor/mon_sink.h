/* Where the monitor's text goes (a report file, a buffer the HTTP API serves, a screen). */
#ifndef MONITOR_MON_SINK_H
#define MONITOR_MON_SINK_H

#include <stddef.h>

typedef struct mon_sink {
    void (*put)(void *ctx, const char *s, size_t n);
    void *ctx;
} mon_sink_t;

/* printf into the sink (at most 1024 characters per call; longer output is cut). */
void mon_printf(const mon_sink_t *out, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A sink into a fixed buffer: what does not fit is dropped and overflow set. */
typedef struct mon_buf {
    char *buf;
    size_t cap;
    size_t len;
    int overflow;
} mon_buf_t;
mon_sink_t mon_buf_sink(mon_buf_t *b);

#endif
