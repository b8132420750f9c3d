#include "rig/rig_log.h"

#include <string.h>
#include <time.h>

#include "dp_slave/dp_wire.h"
#include "movidrive/movidrive_names.h"
#include "sim_hal/error_text.h"
#include "sim_hal/sim_board.h"

static const char *const level_names[] = {"error", "warn", "info", "debug"};

const char *rig_log_level_name(rig_log_level_t level)
{
    return (unsigned)level < 4u ? level_names[level] : "?";
}

bool rig_log_level_parse(const char *text, rig_log_level_t *level)
{
    for (unsigned i = 0; i < 4u; i++) {
        if (strcmp(text, level_names[i]) == 0) {
            *level = (rig_log_level_t)i;
            return true;
        }
    }
    return false;
}

void rig_log_init(rig_log_t *l, rig_t *r, FILE *out)
{
    memset(l, 0, sizeof *l);
    l->rig = r;
    l->out = out;
    l->level = RIG_LOG_INFO;
}

/* The terminal line: texts carry strings from the wire and from files, so they go out
 * escaped. */
static void print_line(rig_log_t *l, const char *source, uint64_t ns, const char *text)
{
    char shown[4u * RIG_CTL_TEXT];
    sim_text_visible(text, shown, sizeof shown);
    if (l->time == RIG_LOG_TIME_WALL) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        struct tm tm;
        localtime_r(&ts.tv_sec, &tm);
        char stamp[32];
        if (strftime(stamp, sizeof stamp, "%H:%M:%S", &tm) == 0u) {
            stamp[0] = '\0';
        }
        fprintf(l->out, "%s.%03ld  %-7s  %s\n", stamp, ts.tv_nsec / 1000000L, source, shown);
    } else {
        fprintf(l->out, "%10.3f ms  %-7s  %s\n", (double)ns / 1e6, source, shown);
    }
    fflush(l->out);
}

void rig_vlog(rig_log_t *l, rig_log_level_t level, const char *source, const char *kind,
              const char *fmt, va_list ap)
{
    bool print = level <= l->level;
    bool publish = l->ctl != NULL && (level <= RIG_LOG_INFO || print);
    if (!print && !publish) {
        return;
    }
    char text[RIG_CTL_TEXT];
    vsnprintf(text, sizeof text, fmt, ap);
    uint64_t ns = rig_elapsed_ns(l->rig);
    if (publish) {
        rig_ctl_event(l->ctl, ns / 1000u, level, source, kind, text);
    }
    if (print && l->out != NULL) {
        print_line(l, source, ns, text);
    }
}

void rig_log_print(rig_log_t *l, rig_log_level_t level, const char *source, uint64_t t_us,
                   const char *text)
{
    if (level <= l->level && l->out != NULL) {
        print_line(l, source, t_us * 1000u, text);
    }
}

void rig_log(rig_log_t *l, rig_log_level_t level, const char *source, const char *kind,
             const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    rig_vlog(l, level, source, kind, fmt, ap);
    va_end(ap);
}

const char *rig_baud_text(uint32_t baud)
{
    switch (baud) {
    case 12000000u: return "12 Mbit/s";
    case 6000000u: return "6 Mbit/s";
    case 3000000u: return "3 Mbit/s";
    case 1500000u: return "1.5 Mbit/s";
    case 500000u: return "500 kbit/s";
    case 187500u: return "187.5 kbit/s";
    case 93750u: return "93.75 kbit/s";
    case 45450u: return "45.45 kbit/s";
    case 19200u: return "19.2 kbit/s";
    case 9600u: return "9.6 kbit/s";
    default: return "?";
    }
}

void rig_diag_text(const uint8_t *d, size_t len, char *out, size_t max)
{
    static const char *const st1[8] = {"Station_Non_Existent", "Station_Not_Ready", "Cfg_Fault",
                                       "Ext_Diag", "Not_Supported", "Invalid_Slave_Response",
                                       "Prm_Fault", "Master_Lock"};
    static const char *const st2[8] = {"Prm_Req", "Stat_Diag", NULL, "WD_On", "Freeze_Mode",
                                       "Sync_Mode", NULL, "Deactivated"};
    size_t n = 0;
    out[0] = '\0';
    if (len < DP_DIAG_STD_LEN) {
        snprintf(out, max, "(short diagnosis, %zu octets)", len);
        return;
    }
    for (unsigned b = 0; b < 8 && n < max; b++) {
        if ((d[0] >> b) & 1u) n += (size_t)snprintf(out + n, max - n, "%s ", st1[b]);
    }
    for (unsigned b = 0; b < 8 && n < max; b++) {
        if (((d[1] >> b) & 1u) && st2[b] != NULL) {
            n += (size_t)snprintf(out + n, max - n, "%s ", st2[b]);
        }
    }
    if ((d[DP_DIAG_STATUS_3] & DP_DIAG3_EXT_DIAG_OVERFLOW) != 0u && n < max) {
        n += (size_t)snprintf(out + n, max - n, "Ext_Diag_Overflow ");
    }
    if (n < max) {
        if (d[DP_DIAG_MASTER_ADD] == DP_MASTER_ADD_NONE) {
            n += (size_t)snprintf(out + n, max - n, "| no master");
        } else {
            n += (size_t)snprintf(out + n, max - n, "| Master_Add %u", d[DP_DIAG_MASTER_ADD]);
        }
    }
    if (n < max) {
        n += (size_t)snprintf(out + n, max - n, ", ident 0x%02X%02X", d[4], d[5]);
    }
    for (size_t i = DP_DIAG_STD_LEN; i < len && n + 4 < max; i++) {
        n += (size_t)snprintf(out + n, max - n, "%s%02X", i == DP_DIAG_STD_LEN ? ", ext " : " ",
                              d[i]);
    }
}

void rig_pi_text(const uint16_t *pi, unsigned n, char *out, size_t max)
{
    char sw[160] = "";
    if (n > 0u) {
        movidrive_status_word_text(pi[0], sw, sizeof sw);
    }
    snprintf(out, max, "PI1 %s%s%.1f rpm%s%.1f %% I_N", sw, n > 1u ? ", PI2 " : "",
             n > 1u ? (int16_t)pi[1] * 0.2 : 0.0, n > 2u ? ", PI3 " : "",
             n > 2u ? pi[2] * 0.1 : 0.0);
    if (n < 3u) {
        snprintf(out, max, "PI1 %s", sw);
    }
}

void rig_po_text(const uint16_t *po, unsigned n, char *out, size_t max)
{
    char cw[160] = "";
    if (n > 0u) {
        movidrive_control_word_text(po[0], cw, sizeof cw);
    }
    if (n > 1u) {
        snprintf(out, max, "PO1 %s, PO2 %.1f rpm", cw, (int16_t)po[1] * 0.2);
    } else {
        snprintf(out, max, "PO1 %s", cw);
    }
}

/* ---- card --------------------------------------------------------------------------------- */

static void card_source(const rig_log_t *l, unsigned card, char *out, size_t n, const char *what)
{
    const rig_t *r = l->rig;
    if (!l->name_cards && r->num_cards <= 1u && strcmp(what, "card") == 0) {
        snprintf(out, n, "card");
        return;
    }
    snprintf(out, n, "%s %u", what, r->cards[card].cs.card.address);
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

#define SAY(lvl, k, ...) (*level = (lvl), *kind = (k), snprintf(out, n, __VA_ARGS__), true)

bool rig_card_event_text(const dp_event_t *ev, const dfp21b_t *c, uint32_t *baud_steps, char *out,
                         size_t n, rig_log_level_t *level, const char **kind)
{
    char p090[16] = "";
    dfp21b_p090_text(&c->pd, p090, sizeof p090);
    switch (ev->type) {
    case DP_EV_STATE:
        return SAY(RIG_LOG_INFO, "dp_state", "%s -> %s", dp_state_name(ev->old_state),
                   dp_state_name(ev->new_state));
    case DP_EV_BAUD_SET:
        if ((*baud_steps)++ == 0u) {
            return SAY(RIG_LOG_INFO, "baud", "baud search started at %s",
                       rig_baud_text(ev->value));
        }
        return SAY(RIG_LOG_DEBUG, "baud", "baud search: listening at %s",
                   rig_baud_text(ev->value));
    case DP_EV_BAUD_FOUND: {
        uint32_t steps = *baud_steps;
        *baud_steps = 0;
        return SAY(RIG_LOG_INFO, "baud", "baud rate found: %s (P092) after %u search steps",
                   rig_baud_text(ev->value), steps);
    }
    case DP_EV_BAUD_LOST:
        *baud_steps = 0;
        return SAY(RIG_LOG_WARN, "baud", "no telegram for this station within the baud control "
                   "time: searching again");
    case DP_EV_WD_EXPIRED:
        return SAY(RIG_LOG_WARN, "watchdog", "DP watchdog expired (%u ms without the master): "
                   "outputs cleared, inverter performs the P831 fieldbus timeout reaction",
                   ev->value);
    case DP_EV_PRM_OK:
        return SAY(RIG_LOG_INFO, "prm", "Set_Prm from master %u accepted; watchdog %u ms (P819)",
                   ev->master, ev->value);
    case DP_EV_PRM_FAULT:
        return SAY(RIG_LOG_WARN, "prm", "Set_Prm from master %u refused: %s -> Prm_Fault",
                   ev->master, prm_fault_text(ev->value));
    case DP_EV_CFG_OK:
        return SAY(RIG_LOG_INFO, "cfg", "Chk_Cfg accepted: %u octets out, %u in; P090 = %s",
                   ev->value >> 8, ev->value & 0xFFu, p090);
    case DP_EV_CFG_FAULT:
        return SAY(RIG_LOG_WARN, "cfg", "Chk_Cfg refused -> Cfg_Fault; P090 = 0PD");
    case DP_EV_GLOBAL_CONTROL:
        return SAY(RIG_LOG_INFO, "dp_state", "Global_Control 0x%02X from master %u", ev->value,
                   ev->master);
    case DP_EV_LOCKED_OUT:
        return SAY(RIG_LOG_WARN, "prm", "request from master %u refused (RS): locked by master %u",
                   ev->master, dp_slave_master(&c->dp));
    case DP_EV_FCB_REPEAT:
        return SAY(RIG_LOG_INFO, "dp_state", "repeated request from master %u (same FCB): cached "
                   "reply sent", ev->master);
    case DP_EV_RX_ERROR: /* during a baud search these come by the thousand */
    case DP_EV_ADDRESSED:
        break;
    }
    return false;
}

static void log_card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    rig_log_t *l = ctx;
    char src[16];
    card_source(l, card, src, sizeof src, "card");
    char text[RIG_CTL_TEXT];
    rig_log_level_t level;
    const char *kind;
    if (rig_card_event_text(ev, &l->rig->cards[card].cs.card, &l->baud_steps[card], text,
                            sizeof text, &level, &kind)) {
        rig_log(l, level, src, kind, "%s", text);
    }
}

static void log_led(void *ctx, unsigned card, hal_led_id_t led, hal_led_mode_t mode)
{
    rig_log_t *l = ctx;
    char src[16];
    card_source(l, card, src, sizeof src, "card");
    rig_log(l, RIG_LOG_INFO, src, "led", "LED %-9s %s", sim_led_name(led),
            hal_led_mode_name(mode));
}

static const char *channel_text(uint8_t channel)
{
    switch (channel) {
    case DFP21B_CH_CYCLIC: return "cyclic channel";
    case DFP21B_CH_C1: return "data set 47, class 1";
    case DFP21B_CH_C2_FIRST: return "data set 47, class 2 (1)";
    case DFP21B_CH_C2_FIRST + 1u: return "data set 47, class 2 (2)";
    case DFP21B_CH_STATUS_POLL: return "card's status poll";
    default: return "?";
    }
}

static void log_param(void *ctx, unsigned card, uint8_t channel, const uint8_t *req,
                      const uint8_t *rsp)
{
    rig_log_t *l = ctx;
    uint8_t service = req[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK;
    uint16_t index = ml_index(req);
    /* The card reads the drive's status every 100 ms for its diagnosis: not a user's service. */
    rig_log_level_t level = channel == DFP21B_CH_STATUS_POLL ? RIG_LOG_DEBUG : RIG_LOG_INFO;
    char src[16];
    card_source(l, card, src, sizeof src, "drive");
    const movidrive_param_info_t *p = movidrive_param_info(index);
    char name[96];
    if (p != NULL) {
        snprintf(name, sizeof name, "%s %s", p->p_number, p->name);
    } else if (index >= MOVIDRIVE_IDX_IPOS_H0 &&
               index < MOVIDRIVE_IDX_IPOS_H0 + MOVIDRIVE_IPOS_VARS) {
        snprintf(name, sizeof name, "H%u", index - MOVIDRIVE_IDX_IPOS_H0);
    } else {
        snprintf(name, sizeof name, "index %u", index);
    }
    char value[96];
    if ((rsp[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        ml_error_text(rsp, value, sizeof value);
        rig_log(l, level == RIG_LOG_INFO ? RIG_LOG_WARN : level, src, "param",
                "%s %s (%u) -> refused: %s [%s]", ml_service_name(service), name, index, value,
                channel_text(channel));
        return;
    }
    int32_t v = (int32_t)ml_data(rsp);
    if (p != NULL && (service == ML_SVC_READ || service == ML_SVC_WRITE ||
                      service == ML_SVC_WRITE_VOLATILE)) {
        movidrive_value_text(p, v, value, sizeof value);
    } else {
        snprintf(value, sizeof value, "%d", v);
    }
    rig_log(l, level, src, "param", "%s %s (%u) = %s [%s]", ml_service_name(service), name,
            index, value, channel_text(channel));
}

static void log_drive(void *ctx, unsigned card, const rig_drive_event_t *ev)
{
    rig_log_t *l = ctx;
    char src[16];
    card_source(l, card, src, sizeof src, "drive");
    const char *fname = movidrive_fault_name((uint8_t)ev->value);
    double n = ev->speed_mrpm / 1000.0;
    double target = ev->setpoint_mrpm / 1000.0;
    switch (ev->type) {
    case RIG_DRIVE_ENABLED:
        rig_log(l, RIG_LOG_INFO, src, "drive", "enabled: output stage on");
        break;
    case RIG_DRIVE_INHIBITED:
        rig_log(l, RIG_LOG_INFO, src, "drive", "inhibited: output stage off");
        break;
    case RIG_DRIVE_FAULT:
        rig_log(l, RIG_LOG_WARN, src, "fault", "fault F%02u %s", ev->value,
                fname != NULL ? fname : "(unknown fault)");
        break;
    case RIG_DRIVE_FAULT_RESET:
        rig_log(l, RIG_LOG_INFO, src, "fault", "fault F%02u %s reset", ev->value,
                fname != NULL ? fname : "(unknown fault)");
        break;
    case RIG_DRIVE_RAMP:
        rig_log(l, RIG_LOG_INFO, src, "speed", "ramp from %.1f rpm to %.1f rpm", n,
                l->rig->cards[card].w_target_mrpm / 1000.0);
        break;
    case RIG_DRIVE_SPEED:
        if (ev->value == 1u) {
            rig_log(l, RIG_LOG_INFO, src, "speed", "speed %.1f rpm reached", n);
        } else {
            rig_log(l, RIG_LOG_INFO, src, "speed", "speed %.1f rpm (setpoint %.1f rpm)", n,
                    target);
        }
        break;
    case RIG_DRIVE_INPUT:
        rig_log(l, RIG_LOG_INFO, src, "drive", "DI00 /CONTROLLER INHIBIT %s",
                ev->value ? "high (enable)" : "low (controller inhibit)");
        break;
    }
}

static void log_action(void *ctx, unsigned card, rig_action_type_t type, uint32_t value)
{
    rig_log_t *l = ctx;
    char src[16];
    card_source(l, card, src, sizeof src, "card");
    switch (type) {
    case RIG_ACTION_CABLE:
        rig_log(l, RIG_LOG_INFO, src, "action", "bus connector %s",
                value ? "plugged in" : "pulled");
        break;
    case RIG_ACTION_POWER_CYCLE:
        rig_log(l, RIG_LOG_INFO, src, "action", "power cycle: DIP switches read as address %u",
                value);
        break;
    case RIG_ACTION_DIP:
        rig_log(l, RIG_LOG_INFO, src, "action", "DIP switches set to address %u (read at the "
                "next power-up)", value);
        break;
    case RIG_ACTION_FAULT_INJECTED: {
        const char *fname = movidrive_fault_name((uint8_t)value);
        rig_log(l, RIG_LOG_INFO, src, "action", "drive fault F%02u %s injected", value,
                fname != NULL ? fname : "(unknown fault)");
        break;
    }
    }
}

/* ---- master -------------------------------------------------------------------------------- */

static void log_inputs(rig_log_t *l, const dp_master_event_t *ev)
{
    const dp_master_t *m = &l->rig->master;
    unsigned i = 0;
    while (i < m->num_slaves && m->slaves[i].cfg.address != ev->slave) {
        i++;
    }
    if (!l->show_inputs || i >= m->num_slaves) {
        return;
    }
    size_t len = ev->len;
    if (len > DP_MASTER_MAX_IO) {
        len = DP_MASTER_MAX_IO;
    }
    bool same = len == l->last_inputs_len[i] && memcmp(l->last_inputs[i], ev->data, len) == 0;
    if (same) {
        return;
    }
    memcpy(l->last_inputs[i], ev->data, len);
    l->last_inputs_len[i] = (uint16_t)len;
    const dp_master_slave_t *s = &m->slaves[i];
    dfp21b_pd_cfg_t pd;
    char text[400];
    size_t n = 0;
    if (dfp21b_check_cfg(s->cfg.cfg, s->cfg.cfg_len, &pd)) {
        size_t base = pd.param_channel ? ML_TELEGRAM_LEN : 0u;
        uint16_t pi[DFP21B_MAX_PD] = {0};
        unsigned words = 0;
        for (size_t k = base; k + 1u < len && words < DFP21B_MAX_PD; k += 2u) {
            pi[words++] = (uint16_t)(ev->data[k] << 8 | ev->data[k + 1u]);
        }
        if (pd.param_channel && len >= ML_TELEGRAM_LEN) {
            n += (size_t)snprintf(text, sizeof text, "param %02X%02X %02X%02X %02X%02X%02X%02X, ",
                                  ev->data[0], ev->data[1], ev->data[2], ev->data[3],
                                  ev->data[4], ev->data[5], ev->data[6], ev->data[7]);
        }
        rig_pi_text(pi, words, text + n, sizeof text - n);
    } else {
        for (size_t k = 0; k < len && n + 4 < sizeof text; k++) {
            n += (size_t)snprintf(text + n, sizeof text - n, "%02X%s", ev->data[k],
                                  (k % 2u) == 1u ? " " : "");
        }
        text[n] = '\0';
    }
    rig_log(l, RIG_LOG_INFO, "master", "master", "slave %u inputs: %s", s->cfg.address, text);
}

bool rig_master_event_text(const dp_master_event_t *ev, bool *slave_silent, char *out, size_t n,
                           rig_log_level_t *level, const char **kind)
{
    char text[RIG_CTL_TEXT - 32u]; /* the diagnosis with its "slave N diagnosis: " in front fits out */
    switch (ev->type) {
    case DP_MASTER_EV_PHASE:
        if (*slave_silent && (ev->new_phase == DP_MASTER_PHASE_FDL_STATUS ||
                              ev->new_phase == DP_MASTER_PHASE_BACKOFF)) {
            break;
        }
        if (ev->new_phase > DP_MASTER_PHASE_FDL_STATUS) {
            *slave_silent = false;
        }
        if (ev->new_phase == DP_MASTER_PHASE_DATA_EXCH) {
            return SAY(RIG_LOG_INFO, "master", "slave %u is in data exchange", ev->slave);
        }
        if (ev->new_phase != DP_MASTER_PHASE_BACKOFF) {
            return SAY(RIG_LOG_INFO, "master", "slave %u: %s", ev->slave,
                       dp_master_phase_name(ev->new_phase));
        }
        break;
    case DP_MASTER_EV_DIAG:
        rig_diag_text(ev->data, ev->len, text, sizeof text);
        return SAY(RIG_LOG_INFO, "diag", "slave %u diagnosis: %s", ev->slave, text);
    case DP_MASTER_EV_FAULT:
        if (ev->old_phase == DP_MASTER_PHASE_FDL_STATUS) {
            bool first = !*slave_silent;
            *slave_silent = true;
            if (first) {
                return SAY(RIG_LOG_WARN, "master", "slave %u: no answer; asking again every few "
                           "ms until it answers", ev->slave);
            }
            break;
        }
        return SAY(RIG_LOG_WARN, "master", "slave %u: %s; start-up again later", ev->slave,
                   ev->text);
    case DP_MASTER_EV_RETRY:
        if (!*slave_silent && ev->old_phase != DP_MASTER_PHASE_FDL_STATUS) {
            return SAY(RIG_LOG_INFO, "master", "slave %u: no answer, retry", ev->slave);
        }
        break;
    case DP_MASTER_EV_INPUTS: /* every cycle: each printer decides how to show them */
        break;
    case DP_MASTER_EV_GLOBAL_CONTROL_SENT:
        return SAY(RIG_LOG_INFO, "master", "Global_Control 0x%02X to group 0x%02X (broadcast)",
                   ev->data[0], ev->data[1]);
    }
    return false;
}

static void log_master_event(void *ctx, const dp_master_event_t *ev)
{
    rig_log_t *l = ctx;
    if (ev->type == DP_MASTER_EV_INPUTS) {
        log_inputs(l, ev);
        return;
    }
    char text[RIG_CTL_TEXT];
    rig_log_level_t level;
    const char *kind;
    if (rig_master_event_text(ev, &l->slave_silent, text, sizeof text, &level, &kind)) {
        rig_log(l, level, "master", kind, "%s", text);
    }
}

/* What a commissioning engineer wants to know of the ring: who is in it, who the GAP found,
 * and every fault; the token's everyday rounds only at debug. */
static void log_ring_event(void *ctx, const fdl_active_event_t *ev)
{
    rig_log_t *l = ctx;
    switch (ev->type) {
    case FDL_EV_IN_RING:
        rig_log(l, RIG_LOG_INFO, "master", "ring", "token ring: master %u is in the ring",
                ev->address);
        return;
    case FDL_EV_LAS:
        rig_log(l, RIG_LOG_INFO, "master", "ring", "token ring: master %u %s", ev->address,
                ev->kind == FDL_STATION_IN_RING ? "is in the ring" : "left the ring");
        return;
    case FDL_EV_LIVE:
        rig_log(l, ev->kind >= FDL_STATION_NOT_READY ? RIG_LOG_INFO : RIG_LOG_DEBUG, "master",
                "ring", "token ring: GAP: station %u answers: %s", ev->address,
                fdl_station_kind_name(ev->kind));
        return;
    case FDL_EV_CLAIM:
        rig_log(l, RIG_LOG_INFO, "master", "ring",
                "token ring: bus silent for the lost-token time-out: master %u claims the token",
                ev->address);
        return;
    case FDL_EV_PASS_FAILED:
        rig_log(l, RIG_LOG_WARN, "master", "ring",
                "token ring: master %u did not take the token: skipped", ev->address);
        return;
    case FDL_EV_DOUBLE_TOKEN: {
        char who[24] = "another station";
        if (ev->address != FDL_ACTIVE_NO_ADDRESS) {
            (void)snprintf(who, sizeof who, "station %u", ev->address);
        }
        rig_log(l, RIG_LOG_WARN, "master", "ring",
                "token ring: %s transmitted while we held the token%s: ours dropped", who,
                ev->address == FDL_ACTIVE_NO_ADDRESS ? " (a collision)" : "");
        return;
    }
    case FDL_EV_DUPLICATE_ADDRESS:
        rig_log(l, RIG_LOG_ERROR, "master", "ring",
                "token ring: another station uses our address %u: off the bus", ev->address);
        return;
    case FDL_EV_NEW_SUCCESSOR:
        rig_log(l, RIG_LOG_DEBUG, "master", "ring", "token ring: next station %u", ev->address);
        return;
    case FDL_EV_LATE_TOKEN:
        rig_log(l, RIG_LOG_DEBUG, "master", "ring", "token ring: late token (rotation %u us)",
                ev->trr_us);
        return;
    case FDL_EV_STATE:
        rig_log(l, RIG_LOG_DEBUG, "master", "ring", "token ring: %s -> %s",
                fdl_mac_state_name(ev->old_state), fdl_mac_state_name(ev->state));
        return;
    }
}

rig_tap_t rig_log_tap(rig_log_t *l)
{
    return (rig_tap_t){.ctx = l, .card_event = log_card_event, .led = log_led,
                       .param = log_param, .drive = log_drive, .action = log_action,
                       .master_event = log_master_event, .ring_event = log_ring_event};
}
