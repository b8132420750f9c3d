/* One record of a bus capture, whatever file it came from (capture/capture.h reads them). */
#ifndef CAPTURE_RECORD_H
#define CAPTURE_RECORD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The longest FDL telegram is 255 octets (SD2 with 244 data units + 11); a record holds a little
 * more so that garbage around a telegram stays visible. Longer records are cut (orig_len says). */
#define CAP_MAX_RECORD 512u

typedef enum cap_format {
    CAP_FORMAT_AUTO = 0, /* open: from the first octets of the file */
    CAP_FORMAT_PCAP,
    CAP_FORMAT_PCAPNG,
    CAP_FORMAT_TEXT,
    CAP_FORMAT_LCM,
} cap_format_t;

/* Direction as the recording tool marked it, relative to the station that recorded. Replay does
 * not need it (an FDL frame says whether it is a request), it is kept for display and export. */
typedef enum cap_dir {
    CAP_DIR_UNKNOWN = 0,
    CAP_DIR_RX, /* received by the recording station ("RX", "<", pcapng inbound) */
    CAP_DIR_TX, /* sent by the recording station ("TX", ">", pcapng outbound) */
} cap_dir_t;

typedef struct cap_record {
    uint64_t index;    /* 1 for the first record of the file */
    uint64_t position; /* byte offset of the record (pcap, pcapng), line number (text), event
                          number (LCM log) */
    bool has_time;     /* false for text lines without a timestamp */
    uint64_t t_ns;     /* pcap/pcapng/LCM: since the Unix epoch; text: as written (seconds of
                          day, seconds since start, ...); only differences matter */
    uint32_t baud;     /* 0 when the format does not say */
    uint16_t error_flags; /* HAL_UART_ERR_* of a received telegram as recorded (LCM), else 0 */
    cap_dir_t dir;
    size_t len;      /* octets in data */
    size_t orig_len; /* octets the record had (> len when cut) */
    char problem[96]; /* "" when data is exactly one valid telegram; else why not, e.g. "bad
                         FCS (0x12, computed 0x34)", "9 octets after the end delimiter" */
    uint8_t data[CAP_MAX_RECORD];
} cap_record_t;

/* Checks that frame[0..len) is exactly one valid FDL telegram (SD1, SD2, SD3, SD4 or SC, FCS and
 * end delimiter right, SD2 length octets equal). Returns true, or false with the reason in
 * problem. */
bool cap_check_telegram(const uint8_t *frame, size_t len, char *problem, size_t max);

#endif
