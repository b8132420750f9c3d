/* The error texts the host backends hand back to their callers: formatted into the caller's
 * buffer, truncated to it, nothing written when there is no buffer. */
#ifndef SIM_HAL_ERROR_TEXT_H
#define SIM_HAL_ERROR_TEXT_H

#include <stddef.h>

void sim_error_text(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* text for a terminal, into out (cut to n octets, always terminated): control characters shown
 * as "\xNN" (C0, DEL, C1 in UTF-8 and as a lone octet), every other octet of text kept. Log and
 * error lines carry strings from the wire and from files (LCM channel names, a drive's or a
 * capture's texts): unescaped, their sender could clear the screen, fake lines or, with OSC 52,
 * write the clipboard of whoever reads them. */
void sim_text_visible(const char *text, char *out, size_t n);

#endif
