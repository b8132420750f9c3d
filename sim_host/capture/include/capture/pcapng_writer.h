/* pcapng files of bus telegrams, written as they come (the bus monitor's record of a line).
 *
 * One section header (shb_userappl), one interface (the link type, if_tsresol 9: times in ns,
 * if_name, if_description, if_speed = the baud rate), then one Enhanced Packet Block per record:
 * a telegram's octets exactly as on the line (LINKTYPE_PROFIBUS_DL, no pseudo-header, as in
 * pcap_writer.h), or a run of octets that formed no telegram, marked with the opt_comment
 * PCAPNG_COMMENT_GARBLED.
 *
 * Blocks are gathered whole in the writer's buffer and the buffer goes to the file whole, so
 * the file only ever holds whole blocks: a process killed at any moment leaves a file every
 * pcapng reader reads to its end, short of what was still in the buffer. pcapng_writer_tick,
 * called as time passes, empties the buffer once a second, which bounds that loss to the last
 * second.
 *
 * A failed write does not end the program: the file is left as it is, later records are
 * dropped (counted), and the reason is handed out once by pcapng_writer_error. */
#ifndef CAPTURE_PCAPNG_WRITER_H
#define CAPTURE_PCAPNG_WRITER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "capture/record.h" /* cap_dir_t */

#define PCAPNG_COMMENT_GARBLED "garbled"
/* Octets kept of one record; a longer run is cut (its original length is in the block). Four
 * times the longest telegram: a garbled run stays visible around a telegram. */
#define PCAPNG_MAX_OCTETS 1024u
/* What the buffer holds before it goes to the file (some 1 500 short telegrams). */
#define PCAPNG_BUFFER 65536u
/* pcapng_writer_tick empties the buffer when this much time has passed since it last did. */
#define PCAPNG_FLUSH_NS 1000000000ull

typedef struct pcapng_writer_opt {
    uint32_t linktype;          /* 0: PCAP_LINKTYPE_PROFIBUS_DL; or PCAP_LINKTYPE_USER0 */
    uint32_t baud;              /* if_speed; 0: not written */
    const char *userappl;       /* shb_userappl; NULL: "dfp-sim" */
    const char *if_name;        /* the source (a tty, "membus", a capture); NULL: not written */
    const char *if_description; /* NULL: not written */
    uint64_t base_ns;           /* added to every record's time (e.g. the wall clock at start) */
} pcapng_writer_opt_t;

typedef struct pcapng_writer {
    FILE *f;
    uint64_t base_ns;
    uint64_t records;       /* records handed to the file (or its buffer) */
    uint64_t dropped;       /* records not written because of a failed write */
    uint64_t last_flush_ns; /* the time pcapng_writer_tick last emptied the buffer */
    bool failed;
    bool error_told;
    char error[600];
    char path[512];
    size_t used;
    uint8_t buf[PCAPNG_BUFFER];
} pcapng_writer_t;

/* Creates path (a symbolic link there is refused) and writes the section header and interface
 * blocks to it at once, so even a capture with no record is a valid file. Returns 0, or -1 with
 * a one-line reason in err. */
int pcapng_writer_open(pcapng_writer_t *w, const char *path, const pcapng_writer_opt_t *opt,
                       char *err, size_t errlen);
/* One record at t_ns (+ base_ns), in ns. comment: an opt_comment, or NULL. Returns 0, or -1
 * when the record is not written (a write failed, now or before). */
int pcapng_writer_packet(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *octets, size_t len,
                         cap_dir_t dir, const char *comment);
/* A valid telegram, and a run of octets that formed none (commented PCAPNG_COMMENT_GARBLED). */
int pcapng_writer_telegram(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *f, size_t len);
int pcapng_writer_garbled(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *f, size_t len);
/* Everything written so far to the file; -1 if that failed (now or before). */
int pcapng_writer_flush(pcapng_writer_t *w);
/* Time passed (the same clock as the records): flushes once PCAPNG_FLUSH_NS went by since the
 * last time it did. Returns what flush returns, 0 when nothing was due. */
int pcapng_writer_tick(pcapng_writer_t *w, uint64_t now_ns);
/* Why writing stopped ("cannot write capture file X: No space left on device"): returned once,
 * after the first failure; NULL before it and after it was returned. */
const char *pcapng_writer_error(pcapng_writer_t *w);
/* Flushes and closes; -1 if anything could not be written. */
int pcapng_writer_close(pcapng_writer_t *w);

#endif
