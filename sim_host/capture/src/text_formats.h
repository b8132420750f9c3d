/* The line shapes of capture/text_import.h, one module each, and what they share with the
 * dispatcher (text_import.c) for finishing a record. Private to the capture library. */
#ifndef CAPTURE_TEXT_FORMATS_H
#define CAPTURE_TEXT_FORMATS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/record.h"
#include "capture/text_import.h"
#include "text_scan.h"

/* ---- finishing a record (text_import.c) ----------------------------------------------------- */

/* A bad line: the reason into rec->problem, no octets. */
text_line_result_t text_bad(cap_record_t *rec, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* The same for a step that reports success as a bool: always false. */
bool text_refuse(cap_record_t *rec, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A bad line for a time that text_parse_time refused with r. */
text_line_result_t text_bad_time(cap_record_t *rec, time_parse_t r, span_t tok);
/* rec holds the line's octets: its problem is set from the telegram check, st learns the time
 * and the shape. TEXT_LINE_BAD when there are no octets. */
text_line_result_t text_record_done(text_import_state_t *st, cap_record_t *rec, uint32_t shape);

/* ---- pyprofibus PHY debug lines (text_phy.c) ------------------------------------------------ */

/* Does the line start with a PHY's prefix ("PHY: ", "PHY-serial: ")? *after: where the
 * message begins. */
bool phy_prefix(span_t line, size_t *after);
/* msg: what follows the prefix. */
text_line_result_t import_phy(text_import_state_t *st, span_t msg, cap_record_t *rec);

/* ---- pyprofibus profisniff (text_profisniff.c) ---------------------------------------------- */

/* body: what follows "FdlTelegram(". */
text_line_result_t import_profisniff(text_import_state_t *st, span_t body, cap_record_t *rec);

/* ---- ProSoft AN-X-PBCAPT (text_prosoft.c) --------------------------------------------------- */

/* Is this line the analyser's (checked before any other shape)? */
bool prosoft_line(span_t line);
text_line_result_t import_prosoft(text_import_state_t *st, span_t line, cap_record_t *rec);

#endif
