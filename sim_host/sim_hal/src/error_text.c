#include "sim_hal/error_text.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

void sim_error_text(char *err, size_t errlen, const char *fmt, ...)
{
    if (err == NULL || errlen == 0u) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* Octets in the UTF-8 sequence that starts at p (1 when it is not one: shown escaped). */
static size_t utf8_length(const unsigned char *p)
{
    size_t len = p[0] >= 0xF0u && p[0] <= 0xF4u   ? 4u
                 : p[0] >= 0xE0u && p[0] <= 0xEFu ? 3u
                 : p[0] >= 0xC2u && p[0] <= 0xDFu ? 2u
                                                  : 1u;
    for (size_t i = 1; i < len; i++) {
        if ((p[i] & 0xC0u) != 0x80u) {
            return 1u;
        }
    }
    return len;
}

void sim_text_visible(const char *text, char *out, size_t n)
{
    if (out == NULL || n == 0u) {
        return;
    }
    const unsigned char *p = (const unsigned char *)text;
    size_t used = 0;
    while (*p != '\0') {
        size_t len = *p < 0x80u ? 1u : utf8_length(p);
        unsigned code = len == 2u ? ((p[0] & 0x1Fu) << 6) | (p[1] & 0x3Fu) : p[0];
        bool control = (len == 1u && (*p < 0x20u || *p >= 0x7Fu)) ||
                       (len == 2u && code >= 0x80u && code <= 0x9Fu);
        size_t need = control ? 4u : len;
        if (used + need >= n) {
            break;
        }
        if (control) {
            (void)snprintf(out + used, n - used, "\\x%02x", code);
        } else {
            memcpy(out + used, p, len);
        }
        used += need;
        p += len;
    }
    out[used] = '\0';
}
