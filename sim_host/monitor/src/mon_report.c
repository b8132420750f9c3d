/* What the reports share (mon_report_priv.h), the verdicts, and the terminal summary. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "monitor/mon_decode.h"
#include "mon_report_priv.h"

#define NS_PER_S 1e9
#define NS_PER_MS 1e6
#define NS_PER_US 1e3
/* FDL status answer: the station type in FC bits 5..4 (protocol.md §A1). */
#define FDL_STATION_SHIFT 4u
#define FDL_STATION_MASK 0x03u

double mon_rel_s(const mon_report_info_t *info, uint64_t t_ns)
{
    return t_ns > info->t_start_ns ? (double)(t_ns - info->t_start_ns) / NS_PER_S : 0.0;
}

void mon_hex(const uint8_t *p, size_t len, char *out)
{
    static const char digits[] = "0123456789ABCDEF";
    size_t i = 0;
    for (; i < len && i < MON_IO_MAX; i++) {
        out[2u * i] = digits[p[i] >> 4];
        out[2u * i + 1u] = digits[p[i] & 0x0Fu];
    }
    out[2u * i] = '\0';
}

/* Octets of the well-formed UTF-8 sequence at s (Unicode's table 3-7), 0 when there is none. */
static size_t utf8_len(const unsigned char *s)
{
    unsigned char c = s[0];
    size_t n = c >= 0xC2u && c <= 0xDFu ? 2u
             : c >= 0xE0u && c <= 0xEFu ? 3u
             : c >= 0xF0u && c <= 0xF4u ? 4u : 0u;
    /* no overlong forms, no surrogates, nothing above U+10FFFF */
    unsigned char lo = c == 0xE0u ? 0xA0u : c == 0xF0u ? 0x90u : 0x80u;
    unsigned char hi = c == 0xEDu ? 0x9Fu : c == 0xF4u ? 0x8Fu : 0xBFu;
    if (n == 0u || s[1] < lo || s[1] > hi) {
        return 0u;
    }
    for (size_t i = 2; i < n; i++) {
        if ((s[i] & 0xC0u) != 0x80u) {
            return 0u;
        }
    }
    return n;
}

/* Escapes go out in runs: plain text in one put, each escape in its own. JSON and XML are
 * UTF-8: an octet that begins no UTF-8 sequence (a file named in Latin-1) becomes U+FFFD in
 * JSON, '?' in XML. */
static void escaped(const mon_sink_t *out, const char *s, bool json)
{
    const char *run = s;
    for (; *s != '\0'; s++) {
        unsigned char c = (unsigned char)*s;
        char esc[8];
        esc[0] = '\0';
        if (c >= 0x80u) {
            size_t n = utf8_len((const unsigned char *)s);
            if (n != 0u) {
                s += n - 1u; /* the sequence stays in the run */
                continue;
            }
            (void)snprintf(esc, sizeof esc, "%s", json ? "\\ufffd" : "?");
        } else if (json && (c == '"' || c == '\\')) {
            (void)snprintf(esc, sizeof esc, "\\%c", c);
        } else if (json && c < 0x20u) {
            (void)snprintf(esc, sizeof esc, "\\u%04x", c);
        } else if (!json && (c == '&' || c == '<' || c == '>' || c == '"' || c == '\'')) {
            const char *e = c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;"
                          : c == '"' ? "&quot;" : "&apos;";
            (void)snprintf(esc, sizeof esc, "%s", e);
        } else if (!json && c < 0x20u && c != '\n' && c != '\t') {
            /* XML 1.0 has no way to carry these: a visible stand-in */
            (void)snprintf(esc, sizeof esc, "?");
        }
        if (esc[0] != '\0') {
            out->put(out->ctx, run, (size_t)(s - run));
            out->put(out->ctx, esc, strlen(esc));
            run = s + 1;
        }
    }
    out->put(out->ctx, run, (size_t)(s - run));
}

void mon_json_str(const mon_sink_t *out, const char *s)
{
    out->put(out->ctx, "\"", 1);
    escaped(out, s != NULL ? s : "", true);
    out->put(out->ctx, "\"", 1);
}

void mon_xml_text(const mon_sink_t *out, const char *s)
{
    escaped(out, s != NULL ? s : "", false);
}

uint64_t mon_first_listed(const mon_t *m, unsigned last_events)
{
    uint64_t first = m->events_total > last_events ? m->events_total - last_events : 0u;
    uint64_t oldest_held = mon_events_dropped(m);
    return first > oldest_held ? first : oldest_held;
}

const char *mon_fdl_status_name(uint8_t fdl_status)
{
    static const char *const names[4] = {"passive", "not ready", "ready", "in ring"};
    return names[(fdl_status >> FDL_STATION_SHIFT) & FDL_STATION_MASK];
}

/* ---- verdicts ----------------------------------------------------------------------------- */

static void set_case(mon_case_t *c, unsigned addr, const char *what, mon_verdict_t v,
                     const char *fmt, ...) __attribute__((format(printf, 5, 6)));
static void set_case(mon_case_t *c, unsigned addr, const char *what, mon_verdict_t v,
                     const char *fmt, ...)
{
    (void)snprintf(c->name, sizeof c->name, "%u %s", addr, what);
    c->verdict = v;
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(c->message, sizeof c->message, fmt, ap);
    va_end(ap);
}

static bool expected(const mon_report_opts_t *o, unsigned addr)
{
    for (size_t i = 0; o != NULL && i < o->n_expect; i++) {
        if (o->expect[i] == addr) {
            return true;
        }
    }
    return false;
}

static void dx_case(const mon_station_t *st, unsigned a, mon_case_t *c)
{
    if (!st->seen) {
        set_case(c, a, "data exchange", MON_FAIL, "slave %u never heard", a);
    } else if (!st->dp) {
        set_case(c, a, "data exchange", MON_FAIL, "station %u: no DP service to it seen", a);
    } else if (st->dp_state != MON_DP_DATA_EXCH) {
        set_case(c, a, "data exchange", MON_FAIL, "slave %u in %s at the end, not Data_Exch", a,
                 mon_dp_state_name(st->dp_state));
    } else {
        set_case(c, a, "data exchange", MON_PASS, "%llu Data_Exchange answers",
                 (unsigned long long)st->dx_count);
    }
}

static void tsdr_case(const mon_t *m, const mon_station_t *st, unsigned a, mon_case_t *c)
{
    const mon_span_t *s = &st->tsdr;
    if (!m->cfg.timing) {
        set_case(c, a, "station delay", MON_SKIP,
                 "not measurable: the telegram times are not the line's");
    } else if (s->n == 0u) {
        set_case(c, a, "station delay", MON_SKIP, "no answer timed");
    } else if (st->tsdr_over_max > 0u || st->tsdr_below_min > 0u) {
        set_case(c, a, "station delay", MON_FAIL,
                 "%llu answers later than max TSDR %u bit times, %llu sooner than min TSDR %u "
                 "bit times (TSDR %.1f..%.1f us)",
                 (unsigned long long)st->tsdr_over_max, (unsigned)st->max_tsdr_bits,
                 (unsigned long long)st->tsdr_below_min, (unsigned)st->min_tsdr_bits,
                 (double)s->min_ns / NS_PER_US, (double)s->max_ns / NS_PER_US);
    } else {
        set_case(c, a, "station delay", MON_PASS, "TSDR %.1f..%.1f us",
                 (double)s->min_ns / NS_PER_US, (double)s->max_ns / NS_PER_US);
    }
}

static void rotation_case(const mon_t *m, const mon_station_t *st, unsigned a, mon_case_t *c)
{
    if (m->cfg.ttr_bits == 0u) {
        set_case(c, a, "token rotation", MON_SKIP, "no TTR given: rotations not judged");
    } else if (st->rotations_over_ttr > 0u) {
        set_case(c, a, "token rotation", MON_FAIL,
                 "%llu of %llu rotations over TTR %u bit times (longest %.3f ms)",
                 (unsigned long long)st->rotations_over_ttr,
                 (unsigned long long)st->rotation.n, (unsigned)m->cfg.ttr_bits,
                 (double)st->rotation.max_ns / NS_PER_MS);
    } else {
        set_case(c, a, "token rotation", MON_PASS, "%llu rotations within TTR",
                 (unsigned long long)st->rotation.n);
    }
}

unsigned mon_station_cases(const mon_t *m, const mon_report_opts_t *opts, unsigned addr,
                           mon_case_t cases[MON_CASES_PER_STATION])
{
    const mon_station_t *st = &m->st[addr];
    uint64_t max_rep = opts != NULL ? opts->max_repeats : 0u;
    uint64_t max_miss = opts != NULL ? opts->max_missing : 0u;
    unsigned n = 0;
    if (st->dp || expected(opts, addr)) {
        dx_case(st, addr, &cases[n++]);
        set_case(&cases[n++], addr, "retries",
                 st->repeats_received > max_rep ? MON_FAIL : MON_PASS,
                 "%llu repeats received, at most %llu allowed",
                 (unsigned long long)st->repeats_received, (unsigned long long)max_rep);
        set_case(&cases[n++], addr, "missing answers",
                 st->missing > max_miss ? MON_FAIL : MON_PASS,
                 "%llu requests unanswered, at most %llu allowed",
                 (unsigned long long)st->missing, (unsigned long long)max_miss);
        tsdr_case(m, st, addr, &cases[n++]);
    }
    if (st->tokens_sent > 0u) {
        rotation_case(m, st, addr, &cases[n++]);
    }
    return n;
}

bool mon_report_ok(const mon_t *m, const mon_report_opts_t *opts)
{
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        mon_case_t cases[MON_CASES_PER_STATION];
        unsigned n = mon_station_cases(m, opts, a, cases);
        for (unsigned i = 0; i < n; i++) {
            if (cases[i].verdict == MON_FAIL) {
                return false;
            }
        }
    }
    return true;
}

/* ---- the terminal summary ----------------------------------------------------------------- */

static void span_ms(const mon_span_t *s, char *out, size_t max)
{
    if (s->n == 0u) {
        (void)snprintf(out, max, "-");
    } else {
        (void)snprintf(out, max, "%.3f", (double)mon_span_mean(s) / NS_PER_MS);
    }
}

static void station_row(const mon_t *m, unsigned a, const mon_sink_t *out)
{
    const mon_station_t *st = &m->st[a];
    char master[8] = "-";
    char ident[8] = "-";
    char tsdr[16] = "-";
    char cycle[16];
    if (st->dp && st->master != MON_NO_MASTER) {
        (void)snprintf(master, sizeof master, "%u", st->master);
    }
    if (st->ident_known) {
        (void)snprintf(ident, sizeof ident, "%04X", st->ident);
    }
    if (m->cfg.timing && st->tsdr.n > 0u) {
        (void)snprintf(tsdr, sizeof tsdr, "%.1f", (double)mon_span_mean(&st->tsdr) / NS_PER_US);
    }
    span_ms(&st->dx_cycle, cycle, sizeof cycle);
    mon_printf(out, "%4u %-7s %-4s %-9s %6s %5s %9llu %9llu %7llu %7llu %8s %8s\n", a,
               mon_role_name(st->role), st->in_ring ? "ring" : "-",
               st->dp ? mon_dp_state_name(st->dp_state) : "-", master, ident,
               (unsigned long long)st->requests_received, (unsigned long long)st->answers,
               (unsigned long long)st->missing, (unsigned long long)st->repeats_received, tsdr,
               cycle);
}

static void text_events(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    mon_printf(out, "events: %llu (%llu no longer held)\n", (unsigned long long)m->events_total,
               (unsigned long long)mon_events_dropped(m));
    for (uint64_t s = mon_first_listed(m, info->last_events); s < m->events_total; s++) {
        const mon_event_t *e = mon_event(m, s);
        if (e != NULL) {
            static const char *const levels[3] = {"info", "warn", "error"};
            mon_printf(out, "  %12.6f %-5s %s\n", mon_rel_s(info, e->t_ns),
                       levels[e->level <= MON_LEVEL_ERROR ? e->level : MON_LEVEL_ERROR], e->text);
        }
    }
}

void mon_report_text(const mon_t *m, const mon_report_info_t *info, const mon_sink_t *out)
{
    const mon_line_t *l = &m->line;
    mon_printf(out, "monitor %s: %.3f s, %llu telegrams, %llu tokens, %llu garbled, "
               "%llu illegal, %llu unanswered, %llu lost tokens\n",
               info->source != NULL ? info->source : "", mon_rel_s(info, info->t_now_ns),
               (unsigned long long)l->telegrams, (unsigned long long)l->tokens,
               (unsigned long long)l->garbled, (unsigned long long)l->illegal,
               (unsigned long long)l->unanswered, (unsigned long long)l->lost_tokens);
    mon_printf(out, "%4s %-7s %-4s %-9s %6s %5s %9s %9s %7s %7s %8s %8s\n", "addr", "role",
               "ring", "DP state", "master", "ident", "requests", "answers", "missing",
               "repeats", "TSDR us", "DX ms");
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        if (m->st[a].seen || m->st[a].addressed) {
            station_row(m, a, out);
        }
    }
    text_events(m, info, out);
}
