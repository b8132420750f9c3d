/* Text captures: one telegram per line, as bus analysers, pyprofibus and people write them.
 *
 * Accepted line shapes (docs/captures.md is the user-facing list, with examples):
 *   plain hex            "68 05 05 68 84 02 5D 00 00 E3 16", "6805056884025D0000E316",
 *                        "0x68,0x05,...", "68:05:05:..."
 *   time and direction   "0.001234 TX 10 84 02 49 CF 16", "[12.345678] < E5",
 *                        "12:34:56.789012 RX ...", "1700000000.123456789 -> ...",
 *                        markers TX/RX, >/<, ->/<-, M>/S< (master sends / slave answers)
 *   dfp-sim's own export "<seconds>.<9 digits> TX|RX|-- <hex>" (text_export_line below)
 *   pyprofibus PHY debug "PHY-serial: TX   10 02 01 49 4C 16", "PHY-serial: RX   E5"
 *                        ("RX (fragment)" lines are skipped: they are octets pyprofibus threw
 *                        away as no telegram, and may be only part of what was on the wire)
 *   pyprofibus profisniff "FdlTelegram(sd=SD2, haveLE=True, da=0x02, sa=0x01, fc=0x5D,
 *                        dae=Empty, sae=Empty, du=00 00, haveFCS=True, ed=0x16)": the frame is
 *                        rebuilt with its FCS
 *   ProSoft AN-X-PBCAPT  "46: a 3.040,029 g 0,027 ...  |........SD2 120<0 SRDH 8a 8a": rebuilt
 *                        where the line has what a frame needs (docs/captures.md says what is
 *                        lost, e.g. FCB/FCV)
 * Any of these may follow a time and direction ("10:00:00.5 PHY-serial: RX   E5"). Blank lines
 * and comments ('#', '//', ';' first on the line; '#', '//' after hex octets) are skipped
 * silently. Anything else is a bad line: reported with its number, never fatal.
 *
 * Pure functions over one line at a time: no I/O, no allocation, bounded work per line. */
#ifndef CAPTURE_TEXT_IMPORT_H
#define CAPTURE_TEXT_IMPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/record.h"

/* Lines longer than this are bad lines (the rest of such a line is skipped by the reader). */
#define TEXT_IMPORT_MAX_LINE 4096u

typedef struct text_import_state {
    uint64_t line;        /* number of the line last given (1-based), for messages */
    uint64_t last_t_ns;   /* time of the last timed record; a later line may be earlier (kept as
                             written: replay deals with it) */
    bool seen_time;
    uint32_t shape_seen;  /* TEXT_SHAPE_* of the records read so far (for the summary) */
} text_import_state_t;

/* Bits of shape_seen. */
#define TEXT_SHAPE_HEX 0x01u        /* hex octets, with or without time and direction */
#define TEXT_SHAPE_EXPORT 0x02u     /* dfp-sim's own export (text_export_line) */
#define TEXT_SHAPE_PHY 0x04u        /* pyprofibus PHY debug lines */
#define TEXT_SHAPE_PROFISNIFF 0x08u /* pyprofibus profisniff FdlTelegram(...) */
#define TEXT_SHAPE_PROSOFT 0x10u    /* ProSoft AN-X-PBCAPT */

/* "hex", "dfp-sim export", "pyprofibus PHY", "pyprofibus profisniff", "ProSoft AN-X-PBCAPT";
 * "?" for anything that is not exactly one TEXT_SHAPE_* bit. */
const char *text_shape_name(uint32_t shape);

typedef enum text_line_result {
    TEXT_LINE_SKIP = 0, /* blank, comment (a header written as a comment), a pyprofibus
                           "RX (fragment)" line */
    TEXT_LINE_RECORD,   /* rec filled: data, len, orig_len, has_time/t_ns, dir, problem ("" or
                           what is wrong with the telegram, e.g. a bad FCS as written) */
    TEXT_LINE_BAD,      /* not a telegram: rec->problem says why, e.g. "not hex: 'zz'"; rec->len
                           is 0 */
} text_line_result_t;

void text_import_init(text_import_state_t *st);
/* line: one line without its line ending (a trailing '\r' is ignored); len may exceed
 * TEXT_IMPORT_MAX_LINE (then the result is TEXT_LINE_BAD). Sets rec->position = st->line. */
text_line_result_t text_import_line(text_import_state_t *st, const char *line, size_t len,
                                    cap_record_t *rec);

/* One line in dfp-sim's own shape, without the newline; text_import_line reads it back to the
 * same record (time, direction, octets). Returns the length written (out is always
 * terminated), or 0 when max is too small. */
size_t text_export_line(char *out, size_t max, uint64_t t_ns, cap_dir_t dir,
                        const uint8_t *data, size_t len);

#endif
