/* The monitor's JSON document (docs/monitor.md "Reports"). Key names are a contract with the
 * front panel and API clients: add keys, never rename one. */
#include <stdio.h>
#include <string.h>

#include "monitor/mon_decode.h"
#include "mon_report_priv.h"

#define NS_PER_S 1e9
#define NS_PER_MS 1e6
#define NS_PER_US 1e3
#define PERCENT 100.0

static void key(const mon_sink_t *out, const char *k)
{
    mon_printf(out, "\"%s\":", k);
}

static void key_str(const mon_sink_t *out, const char *k, const char *v)
{
    key(out, k);
    mon_json_str(out, v);
    out->put(out->ctx, ",", 1);
}

static void key_u64(const mon_sink_t *out, const char *k, uint64_t v)
{
    mon_printf(out, "\"%s\":%llu,", k, (unsigned long long)v);
}

static void key_bool(const mon_sink_t *out, const char *k, bool v)
{
    mon_printf(out, "\"%s\":%s,", k, v ? "true" : "false");
}

/* An address, or null (absent: 255). */
static void key_addr(const mon_sink_t *out, const char *k, bool known, unsigned a)
{
    if (known) {
        mon_printf(out, "\"%s\":%u,", k, a);
    } else {
        mon_printf(out, "\"%s\":null,", k);
    }
}

static void key_span(const mon_sink_t *out, const char *k, const mon_span_t *s, double unit,
                     bool measurable)
{
    if (s->n == 0u || !measurable) {
        mon_printf(out, "\"%s\":null,", k);
        return;
    }
    /* "sum" lets a client take the mean between two documents (sum and n differences): from
     * the rounded means times n it would be off by n times their rounding. */
    mon_printf(out, "\"%s\":{\"n\":%llu,\"min\":%.3f,\"mean\":%.3f,\"max\":%.3f,\"sum\":%.3f},",
               k, (unsigned long long)s->n, (double)s->min_ns / unit,
               (double)mon_span_mean(s) / unit, (double)s->max_ns / unit,
               (double)s->sum_ns / unit);
}

/* A string, or null when there is none. */
static void key_opt(const mon_sink_t *out, const char *k, bool present, const char *v)
{
    if (present) {
        key_str(out, k, v);
    } else {
        mon_printf(out, "\"%s\":null,", k);
    }
}

static void key_hex(const mon_sink_t *out, const char *k, const uint8_t *p, size_t len)
{
    char hex[MON_HEX_MAX];
    mon_hex(p, len, hex);
    key_str(out, k, hex);
}

/* The slot time in bit times as the monitor judges it (the profile's when none was given). */
static uint32_t tsl_bits(const mon_t *m)
{
    if (m->cfg.tsl_bits != 0u || m->cfg.baud == 0u) {
        return m->cfg.tsl_bits;
    }
    return (uint32_t)((m->slot_ns * m->cfg.baud + (uint64_t)(NS_PER_S / 2)) / (uint64_t)NS_PER_S);
}

static void json_monitor(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    mon_printf(out, "{\"monitor\":{\"t_s\":%.6f,", mon_rel_s(info, info->t_now_ns));
    key_u64(out, "baud", m->cfg.baud);
    key_bool(out, "timing", m->cfg.timing);
    key_str(out, "source", info->source);
    key_u64(out, "tsl_bits", tsl_bits(m));
    mon_printf(out, "\"ttr_bits\":%u},\n", (unsigned)m->cfg.ttr_bits);
}

static void json_line(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    const mon_line_t *l = &m->line;
    uint64_t run = info->t_now_ns > info->t_start_ns ? info->t_now_ns - info->t_start_ns : 0u;
    double load = run > 0u ? (double)l->busy_ns * PERCENT / (double)run : 0.0;
    mon_printf(out, "\"line\":{");
    key_u64(out, "telegrams", l->telegrams);
    key_u64(out, "octets", l->octets);
    key_u64(out, "tokens", l->tokens);
    key_u64(out, "requests", l->requests);
    key_u64(out, "answers", l->answers);
    key_u64(out, "short_acks", l->short_acks);
    key_u64(out, "broadcasts", l->broadcasts);
    key_u64(out, "garbled", l->garbled);
    key_u64(out, "illegal", l->illegal);
    key_u64(out, "unanswered", l->unanswered);
    key_u64(out, "lost_tokens", l->lost_tokens);
    mon_printf(out, "\"load_pct\":%.3f},\n", load > PERCENT ? PERCENT : load);
}

static void json_ring(const mon_t *m, const mon_sink_t *out)
{
    mon_printf(out, "\"ring\":{\"members\":[");
    bool first = true;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        if (m->st[a].in_ring) {
            mon_printf(out, first ? "%u" : ",%u", a);
            first = false;
        }
    }
    mon_printf(out, "],");
    if (m->holder != MON_NO_HOLDER) {
        mon_printf(out, "\"holder\":%u},\n", m->holder);
    } else {
        mon_printf(out, "\"holder\":null},\n");
    }
}

/* The DFP21B's names for a slave with ident 0x6003. */
static void json_dfp21b(const mon_station_t *st, const mon_sink_t *out)
{
    mon_dfp21b_t d;
    mon_decode_dfp21b_station(st, &d);
    char cw[8];
    char sw[8];
    (void)snprintf(cw, sizeof cw, "0x%04X", d.control_word);
    (void)snprintf(sw, sizeof sw, "0x%04X", d.status_word);
    mon_printf(out, "\"dfp21b\":{");
    key_str(out, "pd_config", d.pd_config);
    key_u64(out, "pd_words", d.pd_words);
    key_bool(out, "param_channel", d.param_channel);
    key_bool(out, "cfg_valid", d.cfg_valid);
    key_opt(out, "control_word", d.has_control, cw);
    key_opt(out, "control_text", d.has_control, d.control_text);
    key_opt(out, "status_word", d.has_status, sw);
    key_opt(out, "status_text", d.has_status, d.status_text);
    key_opt(out, "param_request", d.param_request[0] != '\0', d.param_request);
    key(out, "param_answer");
    if (d.param_answer[0] != '\0') {
        mon_json_str(out, d.param_answer);
    } else {
        mon_printf(out, "null");
    }
    mon_printf(out, "}");
}

static void json_dp(const mon_station_t *st, const mon_sink_t *out)
{
    char ident[8];
    char text[4u * MON_DECODE_TEXT];
    (void)snprintf(ident, sizeof ident, "0x%04X", st->ident);
    text[0] = '\0';
    if (st->diag_len > 0u) {
        mon_decode_diag(st->diag, st->diag_len, mon_prm_dpv1(st->prm, st->prm_len), text,
                        sizeof text);
    }
    mon_printf(out, "\"dp\":{");
    key_str(out, "state", mon_dp_state_name(st->dp_state));
    key_addr(out, "master", st->master != MON_NO_MASTER, st->master);
    key_opt(out, "ident", st->ident_known, ident);
    key_hex(out, "prm", st->prm, st->prm_len);
    key_hex(out, "cfg", st->cfg, st->cfg_len);
    key_hex(out, "diag", st->diag, st->diag_len);
    key_opt(out, "diag_text", st->diag_len > 0u, text);
    key_u64(out, "diag_changes", st->diag_changes);
    key_u64(out, "stat_diag", st->stat_diag);
    key_hex(out, "outputs", st->outputs, st->out_len);
    key_hex(out, "inputs", st->inputs, st->in_len);
    key_u64(out, "dx_count", st->dx_count);
    key_span(out, "dx_cycle_ms", &st->dx_cycle, NS_PER_MS, true);
    key_u64(out, "min_tsdr_bits", st->min_tsdr_bits);
    key_u64(out, "max_tsdr_bits", st->max_tsdr_bits);
    key_u64(out, "watchdog_ms", st->watchdog_ms);
    if (mon_is_dfp21b(st)) {
        json_dfp21b(st, out);
    } else {
        mon_printf(out, "\"dfp21b\":null");
    }
    mon_printf(out, "}");
}

/* Its token ring figures and its figures as a requester. */
static void json_master_part(const mon_station_t *st, const mon_sink_t *out)
{
    key_opt(out, "fdl_status", st->fdl_status_known, mon_fdl_status_name(st->fdl_status));
    key_addr(out, "next_station", st->tokens_sent > 0u, st->next_station);
    key_u64(out, "tokens_sent", st->tokens_sent);
    key_u64(out, "token_repeats", st->token_repeats);
    key_span(out, "rotation_ms", &st->rotation, NS_PER_MS, true);
    key_u64(out, "rotations_over_ttr", st->rotations_over_ttr);
    key_u64(out, "requests_sent", st->requests_sent);
    key_u64(out, "repeats_sent", st->repeats_sent);
    key_u64(out, "unanswered_sent", st->unanswered_sent);
}

/* Its figures as a responder. */
static void json_responder_part(const mon_t *m, const mon_station_t *st, const mon_sink_t *out)
{
    key_u64(out, "requests_received", st->requests_received);
    key_u64(out, "answers", st->answers);
    key_u64(out, "missing", st->missing);
    key_u64(out, "repeats_received", st->repeats_received);
    key_u64(out, "rs", st->rs);
    key_u64(out, "rr", st->rr);
    key_u64(out, "ue", st->ue);
    key_u64(out, "garbled", st->garbled);
    key_span(out, "tsdr_us", &st->tsdr, NS_PER_US, m->cfg.timing);
    key_u64(out, "tsdr_below_min", st->tsdr_below_min);
    key_u64(out, "tsdr_over_max", st->tsdr_over_max);
    key_u64(out, "tsdr_over_slot", st->tsdr_over_slot);
}

static void json_station(const mon_t *m, const mon_report_info_t *info, unsigned a,
                         const mon_sink_t *out)
{
    const mon_station_t *st = &m->st[a];
    mon_printf(out, "{\"address\":%u,", a);
    key_str(out, "role", mon_role_name(st->role));
    key_bool(out, "seen", st->seen);
    key_bool(out, "addressed", st->addressed);
    key_bool(out, "in_ring", st->in_ring);
    if (st->seen) {
        mon_printf(out, "\"first_s\":%.6f,\"last_s\":%.6f,", mon_rel_s(info, st->first_ns),
                   mon_rel_s(info, st->last_ns));
    } else {
        mon_printf(out, "\"first_s\":null,\"last_s\":null,");
    }
    json_master_part(st, out);
    json_responder_part(m, st, out);
    if (st->dp) {
        json_dp(st, out);
    } else {
        mon_printf(out, "\"dp\":null");
    }
    mon_printf(out, "}");
}

static void json_events(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    static const char *const levels[3] = {"info", "warn", "error"};
    mon_printf(out, "\"events\":{");
    key_u64(out, "total", m->events_total);
    key_u64(out, "dropped", mon_events_dropped(m));
    mon_printf(out, "\"last\":[");
    bool first = true;
    for (uint64_t s = mon_first_listed(m, info->last_events); s < m->events_total; s++) {
        const mon_event_t *e = mon_event(m, s);
        if (e == NULL) {
            continue;
        }
        mon_printf(out, "%s{\"seq\":%llu,\"t_s\":%.6f,", first ? "\n" : ",\n",
                   (unsigned long long)e->seq, mon_rel_s(info, e->t_ns));
        key_str(out, "level", levels[e->level <= MON_LEVEL_ERROR ? e->level : MON_LEVEL_ERROR]);
        key_str(out, "type", mon_event_name(e->type));
        mon_printf(out, "\"station\":%u,\"other\":%u,\"value\":%lu,", e->station, e->other,
                   (unsigned long)e->value);
        key(out, "text");
        mon_json_str(out, e->text);
        mon_printf(out, "}");
        first = false;
    }
    mon_printf(out, "]}");
}

void mon_report_json(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    json_monitor(m, info, out);
    json_line(m, info, out);
    json_ring(m, out);
    mon_printf(out, "\"stations\":[");
    bool first = true;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        if (m->st[a].seen || m->st[a].addressed) {
            mon_printf(out, first ? "\n" : ",\n");
            json_station(m, info, a, out);
            first = false;
        }
    }
    mon_printf(out, "],\n");
    json_events(m, info, out);
    mon_printf(out, "}\n");
}
