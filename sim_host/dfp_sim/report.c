#include "report.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "rig/rig_log.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_rx.h"
#include "sim_hal/sim_board.h"

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

static const char *prm_fault_text(uint32_t why)
{
    switch (why) {
    case DP_PRM_FAULT_LENGTH: return "wrong length";
    case DP_PRM_FAULT_IDENT: return "wrong ident number";
    case DP_PRM_FAULT_WATCHDOG: return "invalid watchdog factors";
    case DP_PRM_FAULT_RESERVED_BITS: return "reserved bits set";
    case DP_PRM_FAULT_USER: return "user parameters not 00 00 00 06 81 00 00 01 0x";
    case DP_PRM_FAULT_UNSUPPORTED: return "requested function not supported";
    default: return "?";
    }
}

void report_card_event(void *ctx, const dp_event_t *ev)
{
    report_t *r = ctx;
    char p090[16] = "";
    if (r->card != NULL) {
        dfp21b_p090_text(&r->card->pd, p090, sizeof p090);
    }
    switch (ev->type) {
    case DP_EV_STATE:
        report_line(r, "card", "%s -> %s", dp_state_name(ev->old_state),
                    dp_state_name(ev->new_state));
        break;
    case DP_EV_BAUD_SET:
        report_line(r, "card", "baud search: listening at %s", report_baud_text(ev->value));
        break;
    case DP_EV_BAUD_FOUND:
        report_line(r, "card", "baud rate found: %s (P092)", report_baud_text(ev->value));
        break;
    case DP_EV_BAUD_LOST:
        report_line(r, "card", "no telegram for this station within the baud control time: "
                               "searching again");
        break;
    case DP_EV_WD_EXPIRED:
        report_line(r, "card", "DP watchdog expired (%u ms without the master): outputs "
                               "cleared, inverter performs the P831 fieldbus timeout reaction",
                    ev->value);
        break;
    case DP_EV_PRM_OK:
        report_line(r, "card", "Set_Prm from master %u accepted; watchdog %u ms (P819)",
                    ev->master, ev->value);
        break;
    case DP_EV_PRM_FAULT:
        report_line(r, "card", "Set_Prm from master %u refused: %s -> Prm_Fault", ev->master,
                    prm_fault_text(ev->value));
        break;
    case DP_EV_CFG_OK:
        report_line(r, "card", "Chk_Cfg accepted: %u octets out, %u in; P090 = %s",
                    ev->value >> 8, ev->value & 0xFFu, p090);
        break;
    case DP_EV_CFG_FAULT:
        report_line(r, "card", "Chk_Cfg refused -> Cfg_Fault; P090 = 0PD");
        break;
    case DP_EV_GLOBAL_CONTROL:
        report_line(r, "card", "Global_Control 0x%02X from master %u", ev->value, ev->master);
        break;
    case DP_EV_LOCKED_OUT:
        report_line(r, "card", "request from master %u refused (RS): locked by master %u",
                    ev->master, r->card != NULL ? dp_slave_master(&r->card->dp) : 0u);
        break;
    case DP_EV_RX_ERROR:
        break; /* during a baud search these are expected by the thousand */
    case DP_EV_FCB_REPEAT:
        report_line(r, "card", "repeated request from master %u (same FCB): cached reply sent",
                    ev->master);
        break;
    case DP_EV_ADDRESSED:
        break;
    }
}

void report_led(void *ctx, hal_led_id_t led, hal_led_mode_t mode)
{
    report_t *r = ctx;
    report_line(r, "card", "LED %-9s %s", sim_led_name(led), hal_led_mode_name(mode));
}

void report_master_event(void *ctx, const dpm_event_t *ev)
{
    report_t *r = ctx;
    char text[256];
    switch (ev->type) {
    case DPM_EV_PHASE:
        if (r->slave_silent && (ev->new_phase == DPM_PHASE_FDL_STATUS ||
                                ev->new_phase == DPM_PHASE_BACKOFF)) {
            break;
        }
        if (ev->new_phase > DPM_PHASE_FDL_STATUS) {
            r->slave_silent = false;
        }
        if (ev->new_phase == DPM_PHASE_DATA_EXCH) {
            report_line(r, "master", "slave %u is in data exchange", ev->slave);
        } else if (ev->new_phase != DPM_PHASE_BACKOFF) {
            report_line(r, "master", "slave %u: %s", ev->slave, dpm_phase_name(ev->new_phase));
        }
        break;
    case DPM_EV_DIAG:
        report_diag_text(ev->data, ev->len, text, sizeof text);
        report_line(r, "master", "slave %u diagnosis: %s", ev->slave, text);
        break;
    case DPM_EV_FAULT:
        if (ev->old_phase == DPM_PHASE_FDL_STATUS) {
            if (!r->slave_silent) {
                report_line(r, "master", "slave %u: no answer; asking again every few ms "
                                         "until it answers", ev->slave);
            }
            r->slave_silent = true;
            break;
        }
        report_line(r, "master", "slave %u: %s; start-up again later", ev->slave, ev->text);
        break;
    case DPM_EV_RETRY:
        if (!r->slave_silent && ev->old_phase != DPM_PHASE_FDL_STATUS) {
            report_line(r, "master", "slave %u: no answer, retry", ev->slave);
        }
        break;
    case DPM_EV_INPUTS:
        if (r->show_inputs) {
            size_t n = 0;
            for (size_t i = 0; i < ev->len && n + 4 < sizeof text; i++) {
                n += (size_t)snprintf(text + n, sizeof text - n, "%02X%s", ev->data[i],
                                      (i % 2u) == 1u ? " " : "");
            }
            text[n] = '\0';
            report_line(r, "master", "slave %u inputs: %s", ev->slave, text);
        }
        break;
    case DPM_EV_GLOBAL_CONTROL_SENT:
        report_line(r, "master", "Global_Control 0x%02X to group 0x%02X (broadcast)",
                    ev->data[0], ev->data[1]);
        break;
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

int capture_option(int argc, char **argv, int *i, capture_opts_t *o)
{
    const char *opt = argv[*i];
    if (strcmp(opt, "--capture") == 0) {
        return (o->path = cli_value(argc, argv, i)) != NULL ? 1 : -1;
    }
    if (strcmp(opt, "--capture-ns") == 0) {
        o->w.nanosecond = true;
        return 1;
    }
    if (strcmp(opt, "--capture-format") == 0) {
        const char *v = cli_value(argc, argv, i);
        if (v == NULL) {
            return -1;
        }
        if (!cap_format_parse(v, &o->w.format) || o->w.format == CAP_FORMAT_LCM ||
            o->w.format == CAP_FORMAT_AUTO) {
            cli_error("--capture-format: '%s' is not one of pcap, pcapng, text", v);
            return -1;
        }
        return 1;
    }
    if (strcmp(opt, "--capture-linktype") == 0) {
        const char *v = cli_value(argc, argv, i);
        if (v == NULL) {
            return -1;
        }
        if (strcmp(v, "profibus") == 0 || strcmp(v, "257") == 0) {
            o->w.linktype = PCAP_LINKTYPE_PROFIBUS_DL;
        } else if (strcmp(v, "user0") == 0 || strcmp(v, "147") == 0) {
            o->w.linktype = PCAP_LINKTYPE_USER0;
        } else {
            cli_error("--capture-linktype: '%s' is not profibus (257) or user0 (147)", v);
            return -1;
        }
        return 1;
    }
    return 0;
}

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
