#include "report.h"

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "rig/rig_log.h"

void report_line(report_t *r, const char *who, const char *fmt, ...)
{
    uint64_t ns = r->now_ns != NULL ? r->now_ns(r->now_ctx) : 0u;
    printf("%10.3f ms  %-6s  ", (double)ns / 1e6, who);
    va_list ap;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    fflush(stdout);
}

const char *report_baud_text(uint32_t baud)
{
    return rig_baud_text(baud);
}

void report_diag_text(const uint8_t *d, size_t len, char *out, size_t max)
{
    rig_diag_text(d, len, out, max);
}

void report_card_event(void *ctx, const dp_event_t *ev)
{
    report_t *r = ctx;
    static const dfp21b_t no_card;
    char text[RIG_CTL_TEXT];
    rig_log_level_t level;
    const char *kind;
    if (rig_card_event_text(ev, r->card != NULL ? r->card : &no_card, &r->baud_steps, text,
                            sizeof text, &level, &kind) &&
        level <= RIG_LOG_INFO) {
        report_line(r, "card", "%s", text);
    }
}

void report_master_event(void *ctx, const dp_master_event_t *ev)
{
    report_t *r = ctx;
    char text[RIG_CTL_TEXT];
    if (ev->type == DP_MASTER_EV_INPUTS) {
        if (r->show_inputs) {
            size_t n = 0;
            for (size_t i = 0; i < ev->len && n + 4 < sizeof text; i++) {
                n += (size_t)snprintf(text + n, sizeof text - n, "%02X%s", ev->data[i],
                                      (i % 2u) == 1u ? " " : "");
            }
            text[n] = '\0';
            report_line(r, "master", "slave %u inputs: %s", ev->slave, text);
        }
        return;
    }
    rig_log_level_t level;
    const char *kind;
    if (rig_master_event_text(ev, &r->slave_silent, text, sizeof text, &level, &kind)) {
        report_line(r, "master", "%s", text);
    }
}

void report_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len, bool local,
                uint32_t baud)
{
    (void)baud;
    report_t *r = ctx;
    if (!r->capturing) {
        return;
    }
    cap_dir_t dir = !r->capture_direction ? CAP_DIR_UNKNOWN : local ? CAP_DIR_TX : CAP_DIR_RX;
    if (cap_writer_frame(&r->capture, t_start_ns, frame, len, dir) != 0) {
        r->capture_failed = true;
    }
    r->frames_captured++;
}

const cli_choice_t capture_format_words[4] = {
    {"pcap", CAP_FORMAT_PCAP, false},
    {"pcapng", CAP_FORMAT_PCAPNG, false},
    {"text", CAP_FORMAT_TEXT, false},
    {NULL, 0, false},
};

const cli_choice_t capture_linktype_words[5] = {
    {"profibus", PCAP_LINKTYPE_PROFIBUS_DL, false},
    {"user0", PCAP_LINKTYPE_USER0, false},
    {"257", PCAP_LINKTYPE_PROFIBUS_DL, true},
    {"147", PCAP_LINKTYPE_USER0, true},
    {NULL, 0, false},
};

const cli_opt_t capture_options[4] = {
    {CLI_OPT("--capture", "FILE", CLI_TEXT, offsetof(capture_opts_t, path))},
    {CLI_OPT("--capture-format", "pcap|pcapng|text", CLI_CHOICE,
            offsetof(capture_opts_t, w.format)),
     .choices = capture_format_words,
     .bad = "--capture-format: '%s' is not one of pcap, pcapng, text"},
    {CLI_OPT("--capture-linktype", "profibus|user0", CLI_CHOICE,
            offsetof(capture_opts_t, w.linktype)),
     .choices = capture_linktype_words,
     .bad = "--capture-linktype: '%s' is not profibus (257) or user0 (147)"},
    {CLI_OPT("--capture-ns", NULL, CLI_FLAG, offsetof(capture_opts_t, w.nanosecond))},
};

bool report_open_capture(report_t *r, const capture_opts_t *o, uint64_t base_ns)
{
    if (o->path == NULL) {
        return true;
    }
    char err[700];
    if (cap_writer_open(&r->capture, o->path, &o->w, base_ns, err, sizeof err) != 0) {
        cli_error("%s", err);
        return false;
    }
    r->capturing = true;
    return true;
}

int report_close_capture(report_t *r)
{
    if (!r->capturing) {
        return 0;
    }
    r->capturing = false;
    if (cap_writer_close(&r->capture) != 0 || r->capture_failed) {
        cli_error("could not write the whole capture to %s", r->capture.path);
        return 1;
    }
    return 0;
}
