/* Bus captures, read one record at a time so memory stays flat however long the file is.
 *
 * Formats (docs/captures.md):
 *   pcap and pcapng, read with libpcap: LINKTYPE_PROFIBUS_DL (257) or LINKTYPE_USER0 (147, what
 *     the Wireshark Lua dissector sees), µs or ns timestamps; pcapng's if_speed gives the baud
 *     rate and its epb_flags the direction when present;
 *   text: one telegram per line (capture/text_import.h has the accepted shapes);
 *   LCM event logs (lcm-logger) holding dfp_lcm telegram messages.
 *
 * A record is what the file holds for one telegram. The reader checks whether its octets form
 * exactly one valid FDL telegram and says why not in `problem`, but hands the octets over either
 * way: a replay feeds them to the card as they were on the wire, damaged or not. What makes a
 * file unreadable from some point on (a truncated record, an unknown link type, a record header
 * that is garbage) ends the reading with an error that names the position. */
#ifndef CAPTURE_CAPTURE_H
#define CAPTURE_CAPTURE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "capture/pcap_writer.h" /* PCAP_LINKTYPE_PROFIBUS_DL, PCAP_LINKTYPE_USER0 */
#include "capture/record.h"
#include "capture/text_import.h"

/* Octets a classic pcap file is read in at a time: a few hundred telegram records. */
#define CAP_PCAP_CHUNK 16384u

typedef struct cap_reader {
    cap_format_t format;
    uint32_t linktype; /* pcap/pcapng: 257 or 147; 0 for text and LCM */
    char path[512];
    uint64_t records;
    uint64_t file_size;  /* for progress; 0 when unknown (a pipe) */
    uint64_t file_pos;   /* bytes consumed so far (approximately, for progress) */
    char error[1024];
    /* Backend state. */
    void *pcap;     /* pcap_t */
    FILE *file;     /* text */
    void *lcm_log;  /* lcm_eventlog_t */
    uint64_t line;  /* text: current line number */
    uint32_t if_baud; /* pcapng if_speed of the (single) interface, 0 when absent */
    /* LCM logs: the channel whose telegram_t messages are the capture ("" = every channel),
     * and what the reader chose and why when it was not told (for the report). */
    char lcm_channel[64];
    char lcm_note[240];
    text_import_state_t text;
    char line_buf[TEXT_IMPORT_MAX_LINE + 2];
    /* Classic pcap records read a chunk at a time (src/cap_pcap.c). */
    struct {
        bool on;
        bool big_endian;
        bool nano;
        size_t len;
        size_t pos;
        uint8_t buf[CAP_PCAP_CHUNK];
    } chunk;
} cap_reader_t;

/* Opens path in the given format (AUTO: by content). Returns 0, or -1 with a one-line reason in
 * err ("dump.pcap: link type 1 (ETHERNET) is not PROFIBUS: expected 257 or 147"). */
int cap_reader_open(cap_reader_t *r, const char *path, cap_format_t format, char *err,
                    size_t errlen);
/* The same, naming the LCM channel to read (other formats ignore it). NULL: inferred — a log
 * that holds the card's telemetry (DFP_TELEGRAM) besides other telegram channels (a segment's
 * frames, recorded by the same logger) is read on DFP_TELEGRAM alone, since the others repeat
 * the same telegrams from the senders' side; otherwise every channel. "*": every channel. A
 * named channel the log has no telegram on is an error that lists the ones it has. */
#define CAP_LCM_TELEMETRY_CHANNEL "DFP_TELEGRAM"
int cap_reader_open_channel(cap_reader_t *r, const char *path, cap_format_t format,
                            const char *lcm_channel, char *err, size_t errlen);
/* 1: rec holds the next record; 0: end of file; -1: the rest of the file cannot be read,
 * r->error says why and at which position ("record 12 at byte 456: truncated: 9 of 20
 * octets"). Records read before stay valid. */
int cap_reader_next(cap_reader_t *r, cap_record_t *rec);
void cap_reader_close(cap_reader_t *r);
const char *cap_format_name(cap_format_t f);
/* v when it is one of the ten PROFIBUS rates (hal_uart_bauds), else 0: a rate read from a file
 * is only believed when the bus can have run at it. */
uint32_t cap_profibus_rate(uint64_t v);
/* What cap_record_t.position counts in this format: "byte", "line" or "event". */
const char *cap_position_unit(cap_format_t f);
/* "pcap", "pcapng", "text", "lcm" (and "auto"); false for anything else. */
bool cap_format_parse(const char *name, cap_format_t *out);

/* ---- writing ------------------------------------------------------------------------------ */

typedef struct cap_writer_options {
    cap_format_t format;  /* PCAP (default when AUTO), PCAPNG or TEXT */
    uint32_t linktype;    /* pcap/pcapng: 257 (default when 0) or 147 */
    bool nanosecond;      /* pcap: ns magic; pcapng: if_tsresol 9 (else 6) */
    uint32_t baud;        /* pcapng: if_speed; 0 = not written */
} cap_writer_options_t;

typedef struct cap_writer {
    FILE *f;
    cap_writer_options_t opt;
    uint64_t base_ns; /* added to every record's time (e.g. the wall clock at start) */
    uint64_t records;
    char path[512];
} cap_writer_t;

/* Format AUTO picks by extension: .pcapng → pcapng, .txt → text, else pcap. Returns 0, or -1
 * with a one-line reason in err. */
int cap_writer_open(cap_writer_t *w, const char *path, const cap_writer_options_t *opt,
                    uint64_t base_ns, char *err, size_t errlen);
int cap_writer_frame(cap_writer_t *w, uint64_t t_ns, const uint8_t *frame, size_t len,
                     cap_dir_t dir);
/* Flushes and closes; -1 if anything could not be written. */
int cap_writer_close(cap_writer_t *w);

#endif
