/* Human-readable output of dfp-sim: a timeline of card and master events, decoded diagnosis,
 * and the --capture file. */
#ifndef DFP_SIM_REPORT_H
#define DFP_SIM_REPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "capture/capture.h"
#include "cli_table.h"
#include "dfp21b/dfp21b.h"
#include "dp_master/dp_master.h"
#include "hal/hal_led.h"

typedef struct report {
    const char *time_unit_note;
    uint64_t (*now_ns)(void *ctx); /* time shown at the start of each line */
    void *now_ctx;
    dfp21b_t *card; /* for monitor values in the lines; may be NULL */
    bool show_inputs;
    bool show_addressed;
    bool slave_silent; /* unanswered polls of a silent address are reported once */
    uint32_t baud_steps; /* the card's baud search: told when it starts and ends */
    cap_writer_t capture;
    bool capturing;
    bool capture_direction; /* mark frames of the local station TX, others RX (tty sessions) */
    bool capture_failed;
    uint64_t frames_captured;
} report_t;

void report_line(report_t *r, const char *who, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void report_card_event(void *ctx, const dp_event_t *ev);
void report_master_event(void *ctx, const dp_master_event_t *ev);
/* Formats the standard diagnosis bits, e.g. "Station_Not_Ready Prm_Req | Master_Add 2". */
void report_diag_text(const uint8_t *d, size_t len, char *out, size_t max);
const char *report_baud_text(uint32_t baud);
/* The --capture options every command that writes captures shares. */
typedef struct capture_opts {
    const char *path;
    cap_writer_options_t w;
} capture_opts_t;

/* --capture FILE, --capture-format pcap|pcapng|text, --capture-linktype profibus|user0,
 * --capture-ns into a capture_opts_t. */
extern const cli_opt_t capture_options[4];
/* The words of --capture-format and --capture-linktype (convert's --format and --linktype). */
extern const cli_choice_t capture_format_words[4];
extern const cli_choice_t capture_linktype_words[5];
/* Opens o->path (if set) with times counted from base_ns (wall clock at start); false after
 * reporting why. */
bool report_open_capture(report_t *r, const capture_opts_t *o, uint64_t base_ns);
/* 0, or 1 after reporting that the capture is incomplete. */
int report_close_capture(report_t *r);
/* sim_frame_tap_t for --capture. */
void report_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len, bool local,
                uint32_t baud);

#endif
