#include <stdio.h>
#include <stdlib.h>

#include "dp_master/dp_master.h"
#include "dp_slave/dp_wire.h"
#include "http_internal.h"
#include "rig/rig_log.h"

static void add_hex(cJSON *o, const char *key, const uint8_t *d, size_t n)
{
    char text[2u * 256u + 1u];
    size_t k = 0;
    for (size_t i = 0; i < n && k + 2u < sizeof text; i++) {
        k += (size_t)snprintf(text + k, sizeof text - k, "%02X", d[i]);
    }
    text[k] = '\0';
    cJSON_AddStringToObject(o, key, text);
}

static void add_words(cJSON *o, const char *key, const uint16_t *w, unsigned n)
{
    cJSON *a = cJSON_AddArrayToObject(o, key);
    for (unsigned i = 0; i < n; i++) {
        cJSON_AddItemToArray(a, cJSON_CreateNumber(w[i]));
    }
}

static void add_opt_string(cJSON *o, const char *key, const char *v)
{
    if (v != NULL && v[0] != '\0') {
        cJSON_AddStringToObject(o, key, v);
    } else {
        cJSON_AddNullToObject(o, key);
    }
}

static const char *dp_state_text(uint8_t st)
{
    return dp_state_name((dp_state_t)st);
}

static const char *baud_state_text(uint8_t st)
{
    switch (st) {
    case DP_BAUD_SEARCH: return "search";
    case DP_BAUD_CONTROL: return "control";
    default: return "fixed";
    }
}

static const char *led_text(uint8_t mode)
{
    return mode == HAL_LED_ON ? "on" : mode == HAL_LED_BLINK ? "blink" : "off";
}

static cJSON *json_drive(const rig_snap_card_t *c)
{
    cJSON *d = cJSON_CreateObject();
    char text[200];
    cJSON_AddNumberToObject(d, "control_word", c->control_word);
    movidrive_control_word_text(c->control_word, text, sizeof text);
    cJSON_AddStringToObject(d, "control_text", text);
    cJSON_AddNumberToObject(d, "status_word", c->status_word);
    movidrive_status_word_text(c->status_word, text, sizeof text);
    cJSON_AddStringToObject(d, "status_text", text);
    cJSON_AddBoolToObject(d, "enabled", c->enabled);
    cJSON_AddNumberToObject(d, "fault", c->fault);
    const char *fname = movidrive_fault_name(c->fault);
    cJSON_AddStringToObject(d, "fault_name", fname != NULL ? fname : "unknown fault");
    cJSON_AddNumberToObject(d, "speed_setpoint_rpm", c->setpoint_mrpm / 1000.0);
    cJSON_AddNumberToObject(d, "speed_actual_rpm", c->speed_mrpm / 1000.0);
    cJSON_AddNumberToObject(d, "current_pct", c->current_mpct / 1000.0);
    cJSON_AddNumberToObject(d, "ramp_up_ms", c->ramp_up_ms);
    cJSON_AddNumberToObject(d, "ramp_down_ms", c->ramp_down_ms);
    cJSON *in = cJSON_AddObjectToObject(d, "inputs");
    cJSON_AddBoolToObject(in, "DI00", c->di00);
    return d;
}

static void add_opt_number(cJSON *o, const char *key, bool present, double v)
{
    if (present) {
        cJSON_AddNumberToObject(o, key, v);
    } else {
        cJSON_AddNullToObject(o, key);
    }
}

/* The diagnosis octets with their reading; "ext" is what follows the six standard octets. */
static void add_diag(cJSON *dp, const rig_snap_card_t *c)
{
    char text[300];
    cJSON *diag = cJSON_AddObjectToObject(dp, "diag");
    add_hex(diag, "hex", c->diag, c->diag_len);
    rig_diag_text(c->diag, c->diag_len, text, sizeof text);
    cJSON_AddStringToObject(diag, "text", text);
    if (c->diag_len <= DP_DIAG_STD_LEN) {
        cJSON_AddNullToObject(diag, "ext");
        cJSON_AddNullToObject(diag, "ext_text");
        return;
    }
    const uint8_t *ext = c->diag + DP_DIAG_STD_LEN;
    add_hex(diag, "ext", ext, c->diag_len - DP_DIAG_STD_LEN);
    if (c->diag_len - DP_DIAG_STD_LEN >= 2u && ext[0] == 0x02u) {
        const char *fname = movidrive_fault_name(ext[1]);
        (void)snprintf(text, sizeof text, "fault %u (%s)", ext[1],
                       fname != NULL ? fname : "unknown fault");
        cJSON_AddStringToObject(diag, "ext_text", text);
    } else {
        cJSON_AddNullToObject(diag, "ext_text");
    }
}

static void add_dp(cJSON *o, const rig_snap_card_t *c)
{
    cJSON *dp = cJSON_AddObjectToObject(o, "dp");
    cJSON_AddStringToObject(dp, "state", dp_state_text(c->dp_state));
    add_opt_number(dp, "baud", c->baud != 0u, c->baud);
    cJSON_AddStringToObject(dp, "baud_state", baud_state_text(c->baud_state));
    add_opt_number(dp, "master", c->master >= 0, c->master);
    cJSON_AddNumberToObject(dp, "watchdog_ms", c->watchdog_ms);
    add_hex(dp, "config", c->cfg, c->cfg_len);
    add_diag(dp, c);
}

static void add_monitor(cJSON *o, const rig_snap_card_t *c)
{
    cJSON *mon = cJSON_AddObjectToObject(o, "monitor");
    cJSON_AddStringToObject(mon, "P090", c->p090);
    cJSON_AddNumberToObject(mon, "P092", c->baud);
    cJSON_AddNumberToObject(mon, "P093", c->address);
    add_words(mon, "po", c->po, c->pd_words != 0u ? c->pd_words : 3u);
    add_words(mon, "pi", c->pi, c->pd_words != 0u ? c->pd_words : 3u);
    cJSON_AddNumberToObject(mon, "P819", c->p819_ms);
}

static void add_dpv1(cJSON *o, const rig_snap_card_t *c)
{
    cJSON *v1 = cJSON_AddObjectToObject(o, "dpv1");
    cJSON_AddBoolToObject(v1, "enabled", c->dpv1_enabled);
    cJSON_AddBoolToObject(v1, "msac1", c->msac1_open);
    cJSON *m2 = cJSON_AddArrayToObject(v1, "msac2");
    for (unsigned i = 0; i < 2u; i++) {
        cJSON *e = cJSON_CreateObject();
        cJSON_AddBoolToObject(e, "open", c->msac2_open[i]);
        add_opt_number(e, "master", c->msac2_master[i] >= 0, c->msac2_master[i]);
        cJSON_AddItemToArray(m2, e);
    }
}

cJSON *http_json_card(const rig_snap_card_t *c)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "address", c->address);
    cJSON *dip = cJSON_AddObjectToObject(o, "dip");
    cJSON_AddNumberToObject(dip, "address", c->address);
    cJSON_AddNumberToObject(dip, "next_address", c->next_address);
    cJSON_AddBoolToObject(o, "cable", c->cable);
    cJSON_AddBoolToObject(o, "on_bus", c->on_bus);
    add_dp(o, c);
    cJSON *leds = cJSON_AddObjectToObject(o, "leds");
    cJSON_AddStringToObject(leds, "run", led_text(c->led[HAL_LED_RUN]));
    cJSON_AddStringToObject(leds, "bus_fault", led_text(c->led[HAL_LED_BUS_FAULT]));
    add_monitor(o, c);
    add_dpv1(o, c);
    cJSON *nvm = cJSON_AddObjectToObject(o, "nvm");
    add_opt_string(nvm, "eeprom", c->eeprom_path);
    add_opt_string(nvm, "card_nvm", c->card_nvm_path);
    add_opt_string(nvm, "note", c->nvm_note);
    if (c->has_drive) {
        cJSON_AddItemToObject(o, "drive", json_drive(c));
    } else {
        cJSON_AddNullToObject(o, "drive");
    }
    return o;
}

/* Stable identifiers for scripts; dp_master_phase_name() is the log's wording. */
static const char *phase_id(uint8_t p)
{
    static const char *const ids[] = {"BACKOFF", "FDL_STATUS", "DIAG_1",    "SET_PRM",
                                      "CHK_CFG", "DIAG_2",     "DATA_EXCH", "DIAG_DX"};
    return p < sizeof ids / sizeof ids[0] ? ids[p] : "?";
}

static void slave_words(const uint8_t *d, uint16_t len, bool param_channel, cJSON *o,
                        const char *key)
{
    uint16_t w[DFP21B_MAX_PD];
    unsigned n = 0;
    for (size_t k = param_channel ? ML_TELEGRAM_LEN : 0u; k + 1u < len && n < DFP21B_MAX_PD;
         k += 2u) {
        w[n++] = (uint16_t)(d[k] << 8 | d[k + 1u]);
    }
    add_words(o, key, w, n);
}

static cJSON *json_master(const rig_snapshot_t *s)
{
    cJSON *m = cJSON_CreateObject();
    cJSON_AddNumberToObject(m, "address", s->master_address);
    cJSON_AddBoolToObject(m, "running", s->master_running);
    cJSON_AddNumberToObject(m, "baud", s->master_baud);
    cJSON *a = cJSON_AddArrayToObject(m, "slaves");
    for (unsigned i = 0; i < s->num_slaves; i++) {
        const rig_snap_slave_t *sl = &s->slaves[i];
        cJSON *e = cJSON_CreateObject();
        cJSON_AddNumberToObject(e, "address", sl->address);
        cJSON_AddStringToObject(e, "phase", phase_id(sl->phase));
        cJSON_AddNumberToObject(e, "cycles", sl->cycles);
        slave_words(sl->outputs, sl->out_len, sl->param_channel, e, "po");
        slave_words(sl->inputs, sl->in_len, sl->param_channel, e, "pi");
        add_hex(e, "outputs", sl->outputs, sl->out_len);
        add_hex(e, "inputs", sl->inputs, sl->in_len);
        cJSON_AddBoolToObject(e, "param_channel", sl->param_channel);
        add_hex(e, "diag", sl->diag, sl->diag_len);
        cJSON_AddItemToArray(a, e);
    }
    return m;
}

static const char *medium_kind(uint8_t m)
{
    return m == RIG_MEDIUM_MEMBUS ? "membus" : m == RIG_MEDIUM_TTY ? "tty" : "lcm";
}

cJSON *http_json_state(rig_ctl_t *ctl, const rig_snapshot_t *s)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "t_us", (double)s->t_us);
    cJSON_AddStringToObject(o, "mode", ctl->mode);
    cJSON_AddBoolToObject(o, "read_only", ctl->read_only);
    cJSON *med = cJSON_AddObjectToObject(o, "medium");
    cJSON_AddStringToObject(med, "kind", medium_kind(s->medium));
    cJSON_AddStringToObject(med, "name", s->medium_name);
    cJSON_AddNumberToObject(med, "baud", s->medium_baud);
    cJSON *cards = cJSON_AddArrayToObject(o, "cards");
    for (unsigned i = 0; i < s->num_cards; i++) {
        cJSON_AddItemToArray(cards, http_json_card(&s->cards[i]));
    }
    if (s->has_master) {
        cJSON_AddItemToObject(o, "master", json_master(s));
    } else {
        cJSON_AddNullToObject(o, "master");
    }
    cJSON *ev = cJSON_AddObjectToObject(o, "events");
    cJSON_AddNumberToObject(ev, "next_seq", (double)rig_ctl_next_seq(ctl));
    return o;
}

rig_snapshot_t *http_snapshot(rig_ctl_t *ctl)
{
    rig_snapshot_t *s = malloc(sizeof *s);
    if (s != NULL) {
        rig_ctl_snapshot(ctl, s);
    }
    return s;
}

cJSON *http_json_event(const rig_ctl_event_t *e)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "seq", (double)e->seq);
    cJSON_AddNumberToObject(o, "t_us", (double)e->t_us);
    cJSON_AddStringToObject(o, "source", e->source);
    cJSON_AddStringToObject(o, "level", rig_log_level_name(e->level));
    cJSON_AddStringToObject(o, "kind", e->kind);
    cJSON_AddStringToObject(o, "text", e->text);
    return o;
}

cJSON *http_json_param_info(const movidrive_param_info_t *p)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "p_number", p->p_number);
    cJSON_AddNumberToObject(o, "index", p->index);
    cJSON_AddStringToObject(o, "name", p->name);
    cJSON_AddStringToObject(o, "unit", p->unit);
    cJSON_AddBoolToObject(o, "read_only", p->read_only);
    cJSON *en = cJSON_AddArrayToObject(o, "enums");
    for (unsigned i = 0; i < p->num_enums; i++) {
        cJSON *e = cJSON_CreateObject();
        cJSON_AddNumberToObject(e, "value", p->enums[i].value);
        cJSON_AddStringToObject(e, "text", p->enums[i].text);
        cJSON_AddItemToArray(en, e);
    }
    return o;
}

