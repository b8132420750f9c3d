#include "dfp_http/http_server.h"

#include <arpa/inet.h>
#include <cjson/cJSON.h>
#include <errno.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "dp_master/dp_master.h"
#include "dp_slave/dp_wire.h"
#include "movidrive/md_names.h"
#include "rig/rig_log.h"
#include "dfp_http/www_files.h"

#define BODY_MAX 16384u
#define ACTION_TIMEOUT_MS 2000u
#define SERVICE_TIMEOUT_MS 7000u
#define STATE_EVERY_MS 100u
#define LOG_LIMIT_DEFAULT 500u
#define MAX_CONNECTIONS 64u

struct http_server {
    struct MHD_Daemon *daemon;
    rig_ctl_t *ctl;
    int listen_fd;
    uint16_t port;
    volatile int stopping;
};

typedef struct request {
    char body[BODY_MAX + 1u];
    size_t len;
    bool too_large;
} request_t;

/* ---- responses ---------------------------------------------------------------------------- */

static enum MHD_Result send_text(struct MHD_Connection *conn, unsigned status, const char *type,
                                 const char *text, size_t len, bool copy)
{
    void *buf; /* MHD takes a non-const pointer but only reads a PERSISTENT or copied buffer */
    memcpy(&buf, &text, sizeof buf);
    struct MHD_Response *r = MHD_create_response_from_buffer(
        len, buf, copy ? MHD_RESPMEM_MUST_COPY : MHD_RESPMEM_PERSISTENT);
    if (r == NULL) {
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    MHD_add_response_header(r, "Cache-Control", "no-store");
    enum MHD_Result rc = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return rc;
}

static enum MHD_Result send_json(struct MHD_Connection *conn, unsigned status, cJSON *obj)
{
    char *text = cJSON_PrintUnformatted(obj);
    cJSON_Delete(obj);
    if (text == NULL) {
        return MHD_NO;
    }
    enum MHD_Result rc = send_text(conn, status, "application/json", text, strlen(text), true);
    cJSON_free(text);
    return rc;
}

static enum MHD_Result send_error(struct MHD_Connection *conn, unsigned status, const char *fmt,
                                  ...) __attribute__((format(printf, 3, 4)));
static enum MHD_Result send_error(struct MHD_Connection *conn, unsigned status, const char *fmt,
                                  ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", msg);
    return send_json(conn, status, o);
}

/* ---- state as JSON ------------------------------------------------------------------------- */

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
    md_control_word_text(c->control_word, text, sizeof text);
    cJSON_AddStringToObject(d, "control_text", text);
    cJSON_AddNumberToObject(d, "status_word", c->status_word);
    md_status_word_text(c->status_word, text, sizeof text);
    cJSON_AddStringToObject(d, "status_text", text);
    cJSON_AddBoolToObject(d, "enabled", c->enabled);
    cJSON_AddNumberToObject(d, "fault", c->fault);
    const char *fname = md_fault_name(c->fault);
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

static cJSON *json_card(const rig_snap_card_t *c)
{
    cJSON *o = cJSON_CreateObject();
    char text[300];
    cJSON_AddNumberToObject(o, "address", c->address);
    cJSON *dip = cJSON_AddObjectToObject(o, "dip");
    cJSON_AddNumberToObject(dip, "address", c->address);
    cJSON_AddNumberToObject(dip, "next_address", c->next_address);
    cJSON_AddBoolToObject(o, "cable", c->cable);
    cJSON_AddBoolToObject(o, "on_bus", c->on_bus);

    cJSON *dp = cJSON_AddObjectToObject(o, "dp");
    cJSON_AddStringToObject(dp, "state", dp_state_text(c->dp_state));
    if (c->baud != 0u) {
        cJSON_AddNumberToObject(dp, "baud", c->baud);
    } else {
        cJSON_AddNullToObject(dp, "baud");
    }
    cJSON_AddStringToObject(dp, "baud_state", baud_state_text(c->baud_state));
    if (c->master >= 0) {
        cJSON_AddNumberToObject(dp, "master", c->master);
    } else {
        cJSON_AddNullToObject(dp, "master");
    }
    cJSON_AddNumberToObject(dp, "watchdog_ms", c->watchdog_ms);
    add_hex(dp, "config", c->cfg, c->cfg_len);
    cJSON *diag = cJSON_AddObjectToObject(dp, "diag");
    add_hex(diag, "hex", c->diag, c->diag_len);
    rig_diag_text(c->diag, c->diag_len, text, sizeof text);
    cJSON_AddStringToObject(diag, "text", text);
    if (c->diag_len > DP_DIAG_STD_LEN) {
        add_hex(diag, "ext", c->diag + DP_DIAG_STD_LEN, c->diag_len - DP_DIAG_STD_LEN);
        const uint8_t *ext = c->diag + DP_DIAG_STD_LEN;
        if (c->diag_len - DP_DIAG_STD_LEN >= 2u && ext[0] == 0x02u) {
            const char *fname = md_fault_name(ext[1]);
            snprintf(text, sizeof text, "fault %u (%s)", ext[1],
                     fname != NULL ? fname : "unknown fault");
            cJSON_AddStringToObject(diag, "ext_text", text);
        } else {
            cJSON_AddNullToObject(diag, "ext_text");
        }
    } else {
        cJSON_AddNullToObject(diag, "ext");
        cJSON_AddNullToObject(diag, "ext_text");
    }

    cJSON *leds = cJSON_AddObjectToObject(o, "leds");
    cJSON_AddStringToObject(leds, "run", led_text(c->led[HAL_LED_RUN]));
    cJSON_AddStringToObject(leds, "bus_fault", led_text(c->led[HAL_LED_BUS_FAULT]));

    cJSON *mon = cJSON_AddObjectToObject(o, "monitor");
    cJSON_AddStringToObject(mon, "P090", c->p090);
    cJSON_AddNumberToObject(mon, "P092", c->baud);
    cJSON_AddNumberToObject(mon, "P093", c->address);
    add_words(mon, "po", c->po, c->pd_words != 0u ? c->pd_words : 3u);
    add_words(mon, "pi", c->pi, c->pd_words != 0u ? c->pd_words : 3u);
    cJSON_AddNumberToObject(mon, "P819", c->p819_ms);

    cJSON *v1 = cJSON_AddObjectToObject(o, "dpv1");
    cJSON_AddBoolToObject(v1, "enabled", c->dpv1_enabled);
    cJSON_AddBoolToObject(v1, "msac1", c->msac1_open);
    cJSON *m2 = cJSON_AddArrayToObject(v1, "msac2");
    for (unsigned i = 0; i < 2u; i++) {
        cJSON *e = cJSON_CreateObject();
        cJSON_AddBoolToObject(e, "open", c->msac2_open[i]);
        if (c->msac2_master[i] >= 0) {
            cJSON_AddNumberToObject(e, "master", c->msac2_master[i]);
        } else {
            cJSON_AddNullToObject(e, "master");
        }
        cJSON_AddItemToArray(m2, e);
    }

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

/* Stable identifiers for scripts; dpm_phase_name() is the log's wording. */
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

static cJSON *json_state(rig_ctl_t *ctl, const rig_snapshot_t *s)
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
        cJSON_AddItemToArray(cards, json_card(&s->cards[i]));
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

static rig_snapshot_t *snapshot(rig_ctl_t *ctl)
{
    rig_snapshot_t *s = malloc(sizeof *s);
    if (s != NULL) {
        rig_ctl_snapshot(ctl, s);
    }
    return s;
}

static cJSON *json_event(const rig_ctl_event_t *e)
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

static cJSON *json_param_info(const md_param_info_t *p)
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

/* ---- the event stream ---------------------------------------------------------------------- */

typedef struct stream {
    http_server_t *srv;
    uint64_t next_seq;
    uint64_t last_state_ms;
    char *pending;
    size_t pending_len;
    size_t pending_off;
} stream_t;

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static void append(stream_t *st, const char *text)
{
    size_t n = strlen(text);
    char *p = realloc(st->pending, st->pending_len + n + 1u);
    if (p == NULL) {
        return;
    }
    st->pending = p;
    memcpy(p + st->pending_len, text, n + 1u);
    st->pending_len += n;
}

static void append_event(stream_t *st, const char *event, const char *id, cJSON *data)
{
    char *json = cJSON_PrintUnformatted(data);
    cJSON_Delete(data);
    if (json == NULL) {
        return;
    }
    char head[64];
    snprintf(head, sizeof head, "event: %s\n", event);
    append(st, head);
    if (id != NULL) {
        snprintf(head, sizeof head, "id: %s\n", id);
        append(st, head);
    }
    append(st, "data: ");
    append(st, json);
    append(st, "\n\n");
    cJSON_free(json);
}

/* Fills the pending text with what is new: log events (or a `lost` notice), and a state event
 * every STATE_EVERY_MS. Waits at most that long for something to say. */
static void stream_collect(stream_t *st)
{
    rig_ctl_t *ctl = st->srv->ctl;
    uint64_t now = mono_ms();
    uint64_t wait_ms = st->last_state_ms + STATE_EVERY_MS > now
                           ? st->last_state_ms + STATE_EVERY_MS - now
                           : 0u;
    if (wait_ms > 0u) {
        rig_ctl_wait(ctl, st->next_seq, (unsigned)wait_ms);
    }
    static const size_t batch = 64u;
    rig_ctl_event_t *ev = malloc(batch * sizeof *ev);
    if (ev != NULL) {
        uint64_t lost = 0;
        size_t n = rig_ctl_events(ctl, st->next_seq, ev, batch, &lost);
        if (lost > 0u) {
            cJSON *o = cJSON_CreateObject();
            char text[96];
            snprintf(text, sizeof text, "this client fell behind: %llu events not sent",
                     (unsigned long long)lost);
            cJSON_AddNumberToObject(o, "seq", (double)st->next_seq);
            cJSON_AddStringToObject(o, "source", "sim");
            cJSON_AddStringToObject(o, "level", "warn");
            cJSON_AddStringToObject(o, "kind", "lost");
            cJSON_AddStringToObject(o, "text", text);
            append_event(st, "log", NULL, o);
            st->next_seq += lost;
        }
        for (size_t i = 0; i < n; i++) {
            char id[24];
            snprintf(id, sizeof id, "%llu", (unsigned long long)ev[i].seq);
            append_event(st, "log", id, json_event(&ev[i]));
            st->next_seq = ev[i].seq + 1u;
        }
        free(ev);
    }
    now = mono_ms();
    if (now >= st->last_state_ms + STATE_EVERY_MS) {
        st->last_state_ms = now;
        rig_snapshot_t *s = snapshot(ctl);
        if (s != NULL) {
            append_event(st, "state", NULL, json_state(ctl, s));
            free(s);
        }
    }
}

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    stream_t *st = cls;
    while (st->pending_off >= st->pending_len) {
        if (st->srv->stopping || st->srv->ctl->closing) {
            return MHD_CONTENT_READER_END_OF_STREAM;
        }
        free(st->pending);
        st->pending = NULL;
        st->pending_len = 0;
        st->pending_off = 0;
        stream_collect(st);
    }
    size_t n = st->pending_len - st->pending_off;
    if (n > max) {
        n = max;
    }
    memcpy(buf, st->pending + st->pending_off, n);
    st->pending_off += n;
    return (ssize_t)n;
}

static void stream_free(void *cls)
{
    stream_t *st = cls;
    free(st->pending);
    free(st);
}

static enum MHD_Result serve_events(http_server_t *srv, struct MHD_Connection *conn)
{
    stream_t *st = calloc(1, sizeof *st);
    if (st == NULL) {
        return MHD_NO;
    }
    st->srv = srv;
    uint64_t next = rig_ctl_next_seq(srv->ctl);
    const char *last = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Last-Event-ID");
    if (last != NULL) {
        char *end;
        unsigned long long v = strtoull(last, &end, 10);
        if (end != last && *end == '\0' && v < next) {
            next = v + 1u;
        }
    }
    st->next_seq = next;
    struct MHD_Response *r =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, stream_read, st, stream_free);
    if (r == NULL) {
        stream_free(st);
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", "text/event-stream");
    MHD_add_response_header(r, "Cache-Control", "no-store");
    enum MHD_Result rc = MHD_queue_response(conn, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return rc;
}

/* ---- request bodies ------------------------------------------------------------------------ */

/* Parses the body as a JSON object whose keys are all in `allowed`; NULL with a message sent. */
static cJSON *parse_body(struct MHD_Connection *conn, const request_t *req,
                         const char *const *allowed, enum MHD_Result *rc)
{
    if (req->too_large) {
        *rc = send_error(conn, 413, "request body over %u octets", BODY_MAX);
        return NULL;
    }
    const char *end = NULL;
    cJSON *o = cJSON_ParseWithLengthOpts(req->body, req->len, &end, false);
    if (o == NULL || !cJSON_IsObject(o)) {
        cJSON_Delete(o);
        *rc = send_error(conn, 400, "the body must be a JSON object%s",
                         req->len == 0u ? " (it is empty)" : "");
        return NULL;
    }
    for (const cJSON *f = o->child; f != NULL; f = f->next) {
        bool ok = false;
        for (const char *const *a = allowed; *a != NULL; a++) {
            if (strcmp(*a, f->string) == 0) {
                ok = true;
            }
        }
        if (!ok) {
            *rc = send_error(conn, 400, "unknown field '%s'", f->string);
            cJSON_Delete(o);
            return NULL;
        }
    }
    return o;
}

static bool get_bool(const cJSON *o, const char *key, bool required, bool *out, char *err,
                     size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (v == NULL) {
        if (required) {
            snprintf(err, n, "'%s' is required (true or false)", key);
        }
        return !required;
    }
    if (!cJSON_IsBool(v)) {
        snprintf(err, n, "'%s' must be true or false", key);
        return false;
    }
    *out = cJSON_IsTrue(v);
    return true;
}

static bool get_int(const cJSON *o, const char *key, bool required, long lo, long hi, long *out,
                    char *err, size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (v == NULL) {
        if (required) {
            snprintf(err, n, "'%s' is required (an integer %ld..%ld)", key, lo, hi);
        }
        return !required;
    }
    double d = cJSON_GetNumberValue(v);
    if (!cJSON_IsNumber(v) || d != (double)(long)d || d < (double)lo || d > (double)hi) {
        snprintf(err, n, "'%s' must be an integer %ld..%ld", key, lo, hi);
        return false;
    }
    *out = (long)d;
    return true;
}

/* A parameter value: a number or a text the parameter knows ("FIELDBUS", "300.5"). */
static bool get_value(const cJSON *o, const md_param_info_t *p, int32_t *raw, char *err,
                      size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, "value");
    if (v == NULL) {
        snprintf(err, n, "'value' is required (a number, or a text such as \"FIELDBUS\")");
        return false;
    }
    if (cJSON_IsNumber(v)) {
        double d = cJSON_GetNumberValue(v);
        if (d != (double)(long long)d || d < -2147483648.0 || d > 4294967295.0) {
            snprintf(err, n, "'value' must be an integer that fits 32 bits");
            return false;
        }
        *raw = (int32_t)(uint32_t)(long long)d;
        return true;
    }
    if (cJSON_IsString(v) && p != NULL) {
        return md_value_parse(p, v->valuestring, raw, err, n);
    }
    snprintf(err, n, "'value' must be a number or a text");
    return false;
}

static const md_param_info_t *find_param(const char *text, char *err, size_t n)
{
    return md_param_find(text, err, n);
}

/* ---- actions ------------------------------------------------------------------------------- */

static enum MHD_Result submit(http_server_t *srv, struct MHD_Connection *conn, rig_cmd_t *cmd,
                              unsigned timeout_ms)
{
    rig_ctl_submit(srv->ctl, cmd, timeout_ms);
    if (cmd->status != 200) {
        return send_error(conn, (unsigned)cmd->status, "%s", cmd->error);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "ok", true);
    return send_json(conn, 200, o);
}

static enum MHD_Result param_answer(http_server_t *srv, struct MHD_Connection *conn,
                                    rig_cmd_t *cmd, const md_param_info_t *p, unsigned timeout)
{
    rig_ctl_submit(srv->ctl, cmd, timeout);
    if (cmd->status != 200) {
        return send_error(conn, (unsigned)cmd->status, "%s", cmd->error);
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "ok", !cmd->refused);
    cJSON_AddStringToObject(o, "p_number", p->p_number);
    cJSON_AddNumberToObject(o, "index", p->index);
    cJSON_AddStringToObject(o, "name", p->name);
    if (cmd->refused) {
        char msg[240];
        snprintf(msg, sizeof msg, "MOVILINK error: %s", cmd->error);
        cJSON_AddStringToObject(o, "error", msg);
    } else {
        char text[128];
        md_value_text(p, cmd->result, text, sizeof text);
        cJSON_AddNumberToObject(o, "value", cmd->result);
        cJSON_AddStringToObject(o, "text", text);
    }
    unsigned status = cmd->refused && !(cmd->type == RIG_CMD_MASTER_PARAM) ? 400u : 200u;
    return send_json(conn, status, o);
}

static enum MHD_Result card_action(http_server_t *srv, struct MHD_Connection *conn,
                                   uint8_t address, const char *what, const request_t *req)
{
    enum MHD_Result rc = MHD_NO;
    char err[200] = "";
    rig_cmd_t cmd = {.card = address};
    cJSON *o = NULL;
    if (strcmp(what, "inputs") == 0) {
        static const char *const allowed[] = {"DI00", NULL};
        if ((o = parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_INPUTS;
        if (!get_bool(o, "DI00", true, &cmd.flag, err, sizeof err)) goto bad;
    } else if (strcmp(what, "fault") == 0) {
        static const char *const allowed[] = {"fault", NULL};
        if ((o = parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        long v = 0;
        cmd.type = RIG_CMD_FAULT;
        if (!get_int(o, "fault", true, 1, 255, &v, err, sizeof err)) goto bad;
        cmd.value = (int32_t)v;
    } else if (strcmp(what, "cable") == 0) {
        static const char *const allowed[] = {"connected", NULL};
        if ((o = parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_CABLE;
        if (!get_bool(o, "connected", true, &cmd.flag, err, sizeof err)) goto bad;
    } else if (strcmp(what, "power-cycle") == 0) {
        static const char *const allowed[] = {NULL};
        if ((o = parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        cmd.type = RIG_CMD_POWER_CYCLE;
    } else if (strcmp(what, "dip") == 0) {
        static const char *const allowed[] = {"address", NULL};
        if ((o = parse_body(conn, req, allowed, &rc)) == NULL) return rc;
        long v = 0;
        cmd.type = RIG_CMD_DIP;
        if (!get_int(o, "address", true, 0, 127, &v, err, sizeof err)) goto bad;
        cmd.value = (int32_t)v;
    } else {
        return send_error(conn, 404, "no action '%s' for a card", what);
    }
    cJSON_Delete(o);
    return submit(srv, conn, &cmd, ACTION_TIMEOUT_MS);
bad:
    cJSON_Delete(o);
    return send_error(conn, 400, "%s", err);
}

static bool card_exists(http_server_t *srv, uint8_t address)
{
    rig_snapshot_t *s = snapshot(srv->ctl);
    bool found = false;
    for (unsigned i = 0; s != NULL && i < s->num_cards; i++) {
        found = found || s->cards[i].address == address;
    }
    free(s);
    return found;
}

static enum MHD_Result card_param(http_server_t *srv, struct MHD_Connection *conn,
                                  uint8_t address, const char *name, const char *method,
                                  const request_t *req)
{
    char err[300];
    const md_param_info_t *p = find_param(name, err, sizeof err);
    if (p == NULL) {
        return send_error(conn, 404, "%s", err);
    }
    rig_cmd_t cmd = {.card = address, .index = p->index, .type = RIG_CMD_PARAM_READ};
    if (strcmp(method, "PUT") == 0) {
        static const char *const allowed[] = {"value", "volatile", NULL};
        enum MHD_Result rc = MHD_NO;
        cJSON *o = parse_body(conn, req, allowed, &rc);
        if (o == NULL) {
            return rc;
        }
        cmd.type = RIG_CMD_PARAM_WRITE;
        bool ok = get_value(o, p, &cmd.value, err, sizeof err) &&
                  get_bool(o, "volatile", false, &cmd.flag, err, sizeof err);
        cJSON_Delete(o);
        if (!ok) {
            return send_error(conn, 400, "%s", err);
        }
    }
    return param_answer(srv, conn, &cmd, p, ACTION_TIMEOUT_MS);
}

static bool parse_address(const char *text, size_t len, uint8_t *out)
{
    if (len == 0u || len > 3u) {
        return false;
    }
    unsigned v = 0;
    for (size_t i = 0; i < len; i++) {
        if (text[i] < '0' || text[i] > '9') {
            return false;
        }
        v = v * 10u + (unsigned)(text[i] - '0');
    }
    if (v > 127u) {
        return false;
    }
    *out = (uint8_t)v;
    return true;
}

static enum MHD_Result master_param(http_server_t *srv, struct MHD_Connection *conn,
                                    const request_t *req)
{
    static const char *const allowed[] = {"slave", "op", "param", "value", "via", "volatile",
                                          NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *o = parse_body(conn, req, allowed, &rc);
    if (o == NULL) {
        return rc;
    }
    char err[300] = "";
    long slave = 0;
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_PARAM};
    const md_param_info_t *p = NULL;
    const cJSON *op = cJSON_GetObjectItemCaseSensitive(o, "op");
    const cJSON *param = cJSON_GetObjectItemCaseSensitive(o, "param");
    const cJSON *via = cJSON_GetObjectItemCaseSensitive(o, "via");
    if (!get_int(o, "slave", true, 0, 125, &slave, err, sizeof err)) {
        goto bad;
    }
    cmd.card = (uint8_t)slave;
    if (!cJSON_IsString(op) ||
        (strcmp(op->valuestring, "read") != 0 && strcmp(op->valuestring, "write") != 0)) {
        snprintf(err, sizeof err, "'op' must be \"read\" or \"write\"");
        goto bad;
    }
    cmd.write = strcmp(op->valuestring, "write") == 0;
    if (param != NULL && cJSON_IsNumber(param)) {
        char num[24];
        snprintf(num, sizeof num, "%d", param->valueint);
        p = find_param(num, err, sizeof err);
    } else if (cJSON_IsString(param)) {
        p = find_param(param->valuestring, err, sizeof err);
    } else {
        snprintf(err, sizeof err, "'param' is required: \"P100\", 8461 or a name");
    }
    if (p == NULL) {
        goto bad;
    }
    cmd.index = p->index;
    if (via == NULL || (cJSON_IsString(via) && strcmp(via->valuestring, "channel") == 0)) {
        cmd.via = RIG_VIA_CHANNEL;
    } else if (cJSON_IsString(via) && strcmp(via->valuestring, "ds47") == 0) {
        cmd.via = RIG_VIA_DS47;
    } else {
        snprintf(err, sizeof err, "'via' must be \"channel\" or \"ds47\" (class-2 services: "
                                  "dfp-sim param --via c2)");
        goto bad;
    }
    if (cmd.write && !get_value(o, p, &cmd.value, err, sizeof err)) {
        goto bad;
    }
    if (!cmd.write && cJSON_GetObjectItemCaseSensitive(o, "value") != NULL) {
        snprintf(err, sizeof err, "'value' belongs to \"op\": \"write\"");
        goto bad;
    }
    if (!get_bool(o, "volatile", false, &cmd.flag, err, sizeof err)) {
        goto bad;
    }
    cJSON_Delete(o);
    return param_answer(srv, conn, &cmd, p, SERVICE_TIMEOUT_MS);
bad:
    cJSON_Delete(o);
    return send_error(conn, 400, "%s", err);
}

static enum MHD_Result master_outputs(http_server_t *srv, struct MHD_Connection *conn,
                                      uint8_t address, const request_t *req)
{
    static const char *const allowed[] = {"po", "hex", NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *o = parse_body(conn, req, allowed, &rc);
    if (o == NULL) {
        return rc;
    }
    rig_cmd_t cmd = {.type = RIG_CMD_MASTER_OUTPUTS, .card = address};
    const cJSON *po = cJSON_GetObjectItemCaseSensitive(o, "po");
    const cJSON *hex = cJSON_GetObjectItemCaseSensitive(o, "hex");
    char err[200] = "";
    if ((po == NULL) == (hex == NULL)) {
        snprintf(err, sizeof err, "give either 'po' (a list of words) or 'hex'");
    } else if (po != NULL) {
        int n = cJSON_GetArraySize(po);
        if (!cJSON_IsArray(po) || n < 1 || n > (int)DFP21B_MAX_PD) {
            snprintf(err, sizeof err, "'po' must be a list of 1..%u words", DFP21B_MAX_PD);
        }
        for (int i = 0; err[0] == '\0' && i < n; i++) {
            const cJSON *w = cJSON_GetArrayItem(po, i);
            double d = cJSON_GetNumberValue(w);
            if (!cJSON_IsNumber(w) || d != (double)(long)d || d < -32768.0 || d > 65535.0) {
                snprintf(err, sizeof err, "'po'[%d] must be a word 0..65535 (or -32768..-1)", i);
            } else {
                cmd.words[i] = (uint16_t)(long)d;
            }
        }
        cmd.num_words = (uint8_t)n;
    } else {
        const char *t = cJSON_GetStringValue(hex);
        size_t len = t != NULL ? strlen(t) : 0u;
        if (t == NULL || len % 2u != 0u || len / 2u > sizeof cmd.raw) {
            snprintf(err, sizeof err, "'hex' must be an even number of hex digits (at most %zu "
                     "octets)", sizeof cmd.raw);
        }
        for (size_t i = 0; err[0] == '\0' && i < len; i += 2u) {
            char pair[3] = {t[i], t[i + 1u], 0};
            if (strspn(pair, "0123456789abcdefABCDEF") != 2u) {
                snprintf(err, sizeof err, "'hex': '%s' is not a hex octet", pair);
            } else {
                cmd.raw[i / 2u] = (uint8_t)strtoul(pair, NULL, 16);
            }
        }
        cmd.raw_len = (uint8_t)(len / 2u);
        cmd.raw_given = true;
    }
    cJSON_Delete(o);
    if (err[0] != '\0') {
        return send_error(conn, 400, "%s", err);
    }
    return submit(srv, conn, &cmd, ACTION_TIMEOUT_MS);
}

/* ---- routing ------------------------------------------------------------------------------- */

static bool starts(const char *s, const char *prefix, const char **rest)
{
    size_t n = strlen(prefix);
    if (strncmp(s, prefix, n) != 0) {
        return false;
    }
    *rest = s + n;
    return true;
}

static enum MHD_Result route_card(http_server_t *srv, struct MHD_Connection *conn,
                                  const char *rest, const char *method, const request_t *req)
{
    const char *slash = strchr(rest, '/');
    size_t alen = slash != NULL ? (size_t)(slash - rest) : strlen(rest);
    uint8_t address;
    if (!parse_address(rest, alen, &address)) {
        return send_error(conn, 404, "'%.*s' is not a card address (0..127)", (int)alen, rest);
    }
    if (!card_exists(srv, address)) {
        return send_error(conn, 404, "no card with address %u", address);
    }
    if (slash == NULL || slash[1] == '\0') {
        if (strcmp(method, "GET") != 0) {
            return send_error(conn, 405, "use GET");
        }
        rig_snapshot_t *s = snapshot(srv->ctl);
        if (s == NULL) {
            return MHD_NO;
        }
        cJSON *o = NULL;
        for (unsigned i = 0; i < s->num_cards; i++) {
            if (s->cards[i].address == address) {
                o = json_card(&s->cards[i]);
            }
        }
        free(s);
        return send_json(conn, 200, o);
    }
    const char *what = slash + 1;
    const char *pname;
    if (starts(what, "params/", &pname)) {
        if (strcmp(method, "GET") != 0 && strcmp(method, "PUT") != 0) {
            return send_error(conn, 405, "use GET or PUT");
        }
        if (strcmp(method, "PUT") == 0 && srv->ctl->read_only) {
            return send_error(conn, 403, "this server is read-only");
        }
        return card_param(srv, conn, address, pname, method, req);
    }
    if (strcmp(method, "POST") != 0) {
        return send_error(conn, 405, "use POST");
    }
    if (srv->ctl->read_only) {
        return send_error(conn, 403, "this server is read-only");
    }
    return card_action(srv, conn, address, what, req);
}

static enum MHD_Result route_master(http_server_t *srv, struct MHD_Connection *conn,
                                    const char *rest, const char *method, const request_t *req)
{
    if (strcmp(method, "POST") != 0) {
        return send_error(conn, 405, "use POST");
    }
    if (srv->ctl->read_only) {
        return send_error(conn, 403, "this server is read-only");
    }
    const char *sub;
    if (strcmp(rest, "run") == 0) {
        static const char *const allowed[] = {"running", NULL};
        enum MHD_Result rc = MHD_NO;
        cJSON *o = parse_body(conn, req, allowed, &rc);
        if (o == NULL) {
            return rc;
        }
        char err[120] = "";
        rig_cmd_t cmd = {.type = RIG_CMD_MASTER_RUN};
        bool ok = get_bool(o, "running", true, &cmd.flag, err, sizeof err);
        cJSON_Delete(o);
        return ok ? submit(srv, conn, &cmd, ACTION_TIMEOUT_MS) : send_error(conn, 400, "%s", err);
    }
    if (strcmp(rest, "param") == 0) {
        return master_param(srv, conn, req);
    }
    if (starts(rest, "slaves/", &sub)) {
        const char *slash = strchr(sub, '/');
        uint8_t address;
        if (slash != NULL && strcmp(slash, "/outputs") == 0 &&
            parse_address(sub, (size_t)(slash - sub), &address)) {
            return master_outputs(srv, conn, address, req);
        }
    }
    return send_error(conn, 404, "no such master endpoint");
}

static enum MHD_Result route_api(http_server_t *srv, struct MHD_Connection *conn,
                                 const char *path, const char *method, const request_t *req)
{
    const char *rest;
    if (strcmp(path, "state") == 0 || strcmp(path, "log") == 0 || strcmp(path, "events") == 0 ||
        strcmp(path, "params") == 0) {
        if (strcmp(method, "GET") != 0) {
            return send_error(conn, 405, "use GET");
        }
    }
    if (strcmp(path, "state") == 0) {
        rig_snapshot_t *s = snapshot(srv->ctl);
        if (s == NULL) {
            return MHD_NO;
        }
        cJSON *o = json_state(srv->ctl, s);
        free(s);
        return send_json(conn, 200, o);
    }
    if (strcmp(path, "events") == 0) {
        return serve_events(srv, conn);
    }
    if (strcmp(path, "log") == 0) {
        const char *since = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "since");
        const char *limit = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "limit");
        char *end = NULL;
        unsigned long long from = since != NULL ? strtoull(since, &end, 10) : 0u;
        if (since != NULL && (end == since || *end != '\0')) {
            return send_error(conn, 400, "'since' must be an event number");
        }
        unsigned long lim = limit != NULL ? strtoul(limit, &end, 10) : LOG_LIMIT_DEFAULT;
        if (limit != NULL && (end == limit || *end != '\0' || lim == 0u || lim > 4096u)) {
            return send_error(conn, 400, "'limit' must be 1..4096");
        }
        rig_ctl_event_t *ev = malloc(lim * sizeof *ev);
        if (ev == NULL) {
            return MHD_NO;
        }
        uint64_t lost = 0;
        size_t n = rig_ctl_events(srv->ctl, from, ev, lim, &lost);
        cJSON *a = cJSON_CreateArray();
        for (size_t i = 0; i < n; i++) {
            cJSON_AddItemToArray(a, json_event(&ev[i]));
        }
        free(ev);
        return send_json(conn, 200, a);
    }
    if (strcmp(path, "params") == 0) {
        const char *q = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "q");
        cJSON *a = cJSON_CreateArray();
        for (size_t i = 0; i < md_param_count(); i++) {
            const md_param_info_t *p = md_param_at(i);
            char idx[8];
            snprintf(idx, sizeof idx, "%u", p->index);
            if (q == NULL || q[0] == '\0' || strcasestr(p->p_number, q) != NULL ||
                strcasestr(p->name, q) != NULL || strcmp(idx, q) == 0) {
                cJSON_AddItemToArray(a, json_param_info(p));
            }
        }
        return send_json(conn, 200, a);
    }
    if (starts(path, "cards/", &rest)) {
        return route_card(srv, conn, rest, method, req);
    }
    if (starts(path, "master/", &rest)) {
        return route_master(srv, conn, rest, method, req);
    }
    return send_error(conn, 404, "no such endpoint: /api/v1/%s", path);
}

static enum MHD_Result serve_file(struct MHD_Connection *conn, const char *url)
{
    const char *name = strcmp(url, "/") == 0 ? "index.html" : url + 1;
    for (size_t i = 0; i < www_file_count; i++) {
        if (strcmp(www_files[i].name, name) == 0) {
            return send_text(conn, 200, www_files[i].mime, (const char *)www_files[i].data,
                             www_files[i].size, false);
        }
    }
    return send_error(conn, 404, "no file '%s'", url);
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_size, void **con_cls)
{
    (void)version;
    http_server_t *srv = cls;
    request_t *req = *con_cls;
    if (req == NULL) {
        req = calloc(1, sizeof *req);
        if (req == NULL) {
            return MHD_NO;
        }
        *con_cls = req;
        return MHD_YES;
    }
    if (*upload_size != 0u) {
        if (req->len + *upload_size > BODY_MAX) {
            req->too_large = true;
        } else {
            memcpy(req->body + req->len, upload_data, *upload_size);
            req->len += *upload_size;
        }
        *upload_size = 0;
        return MHD_YES;
    }
    req->body[req->len] = '\0';
    const char *path;
    if (starts(url, "/api/v1/", &path)) {
        return route_api(srv, conn, path, method, req);
    }
    if (strcmp(method, "GET") != 0 && strcmp(method, "HEAD") != 0) {
        return send_error(conn, 405, "use GET");
    }
    return serve_file(conn, url);
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    (void)cls;
    (void)conn;
    (void)toe;
    free(*con_cls);
    *con_cls = NULL;
}

/* ---- start and stop ------------------------------------------------------------------------ */

bool http_parse_listen(const char *text, char *host, size_t hostlen, uint16_t *port, char *err,
                       size_t errlen)
{
    const char *colon = strrchr(text, ':');
    const char *p = colon != NULL ? colon + 1 : text;
    if (colon != NULL) {
        size_t n = (size_t)(colon - text);
        if (n >= 2u && text[0] == '[' && text[n - 1u] == ']') {
            text++;
            n -= 2u;
        }
        if (n == 0u || n >= hostlen) {
            snprintf(err, errlen, "--http '%s': the address before ':' is missing or too long",
                     text);
            return false;
        }
        memcpy(host, text, n);
        host[n] = '\0';
    } else {
        snprintf(host, hostlen, "127.0.0.1");
    }
    char *end;
    unsigned long v = strtoul(p, &end, 10);
    if (end == p || *end != '\0' || v > 65535u || *p < '0' || *p > '9') {
        snprintf(err, errlen, "--http '%s': use [ADDR:]PORT with PORT 0..65535 (e.g. 8080 or "
                 "0.0.0.0:8080)", text);
        return false;
    }
    *port = (uint16_t)v;
    return true;
}

static int open_listener(const char *host, uint16_t port, char *err, size_t errlen,
                         uint16_t *bound)
{
    struct sockaddr_storage ss;
    memset(&ss, 0, sizeof ss);
    socklen_t len;
    struct sockaddr_in *v4 = (struct sockaddr_in *)&ss;
    struct sockaddr_in6 *v6 = (struct sockaddr_in6 *)&ss;
    if (inet_pton(AF_INET, host, &v4->sin_addr) == 1) {
        v4->sin_family = AF_INET;
        v4->sin_port = htons(port);
        len = sizeof *v4;
    } else if (inet_pton(AF_INET6, host, &v6->sin6_addr) == 1) {
        v6->sin6_family = AF_INET6;
        v6->sin6_port = htons(port);
        len = sizeof *v6;
    } else {
        snprintf(err, errlen, "--http: '%s' is not an IPv4 or IPv6 address", host);
        return -1;
    }
    int fd = socket(ss.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(err, errlen, "--http: socket: %s", strerror(errno));
        return -1;
    }
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd, (struct sockaddr *)&ss, len) != 0 || listen(fd, 32) != 0) {
        snprintf(err, errlen, "--http: cannot listen on %s:%u: %s", host, port, strerror(errno));
        close(fd);
        return -1;
    }
    struct sockaddr_storage got;
    memset(&got, 0, sizeof got);
    socklen_t glen = sizeof got;
    if (getsockname(fd, (struct sockaddr *)&got, &glen) != 0) {
        got = ss;
    }
    *bound = ntohs(got.ss_family == AF_INET ? ((struct sockaddr_in *)&got)->sin_port
                                            : ((struct sockaddr_in6 *)&got)->sin6_port);
    return fd;
}

http_server_t *http_server_start(rig_ctl_t *ctl, const char *listen_text, char *err,
                                 size_t errlen)
{
    char host[64];
    uint16_t port;
    if (!http_parse_listen(listen_text, host, sizeof host, &port, err, errlen)) {
        return NULL;
    }
    http_server_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(err, errlen, "--http: out of memory");
        return NULL;
    }
    s->ctl = ctl;
    s->listen_fd = open_listener(host, port, err, errlen, &s->port);
    if (s->listen_fd < 0) {
        free(s);
        return NULL;
    }
    s->daemon = MHD_start_daemon(
        MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION | MHD_USE_ERROR_LOG, 0,
        NULL, NULL, on_request, s, MHD_OPTION_LISTEN_SOCKET, s->listen_fd,
        MHD_OPTION_CONNECTION_LIMIT, (unsigned)MAX_CONNECTIONS, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)60, MHD_OPTION_NOTIFY_COMPLETED, on_completed, NULL, MHD_OPTION_END);
    if (s->daemon == NULL) {
        snprintf(err, errlen, "--http: the HTTP server did not start on %s:%u", host, s->port);
        close(s->listen_fd);
        free(s);
        return NULL;
    }
    return s;
}

uint16_t http_server_port(const http_server_t *s)
{
    return s->port;
}

void http_server_stop(http_server_t *s)
{
    if (s == NULL) {
        return;
    }
    s->stopping = 1;
    pthread_mutex_lock(&s->ctl->lock);
    pthread_cond_broadcast(&s->ctl->changed);
    pthread_mutex_unlock(&s->ctl->lock);
    MHD_stop_daemon(s->daemon); /* closes the listening socket it was given */
    free(s);
}
