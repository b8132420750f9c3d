/* The monitor's full-screen view: see mon_view.h. Everything is written into the caller's grid
 * through put_text, which clips at the right edge, so no size can write out of bounds; a row
 * is built whole in a local buffer first and then clipped. */
#include "monitor/mon_view.h"

#include "monitor/mon_decode.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define NS_PER_S 1000000000ull
#define TEXT_MAX 1024u

typedef struct grid {
    char *s;
    unsigned rows;
    unsigned cols;
} grid_t;

/* Where each part of the screen is (rows), for this size and station count. */
typedef struct layout {
    unsigned header_h;
    unsigned table_row;
    unsigned table_h; /* the column headings and the station rows */
    unsigned pane_row;
    unsigned pane_h;  /* the pane's title and its lines */
    unsigned help_row;
    bool help;
} layout_t;

static void put_text(const grid_t *g, unsigned row, unsigned col, const char *t)
{
    if (row >= g->rows) {
        return;
    }
    char *line = g->s + (size_t)row * g->cols;
    for (; *t != '\0' && col < g->cols; t++, col++) {
        /* The grid goes to a terminal as it is: a control character would move its cursor. */
        line[col] = '?';
        if (*t >= ' ' && *t <= '~') {
            line[col] = *t;
        }
    }
}

__attribute__((format(printf, 4, 5))) static void put_fmt(const grid_t *g, unsigned row,
                                                          unsigned col, const char *fmt, ...)
{
    char text[TEXT_MAX];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (n >= 0) {
        put_text(g, row, col, text);
    }
}

/* A count in at most width characters: 1234567 in 5 is "1234k". */
static void fmt_count(char *out, size_t n, unsigned width, uint64_t v)
{
    static const char suffix[] = " kMGTPE";
    unsigned s = 0;
    int len = snprintf(out, n, "%llu", (unsigned long long)v);
    while (len > (int)width && s + 1u < sizeof suffix - 1u) {
        v /= 1000u;
        s++;
        len = snprintf(out, n, "%llu%c", (unsigned long long)v, suffix[s]);
    }
}

/* Milliseconds with one decimal. */
static void fmt_ms(char *out, size_t n, uint64_t ns)
{
    snprintf(out, n, "%llu.%llu", (unsigned long long)(ns / 1000000u),
             (unsigned long long)(ns / 100000u % 10u));
}

/* h:mm:ss, and .mmm when millis. */
static void fmt_clock(char *out, size_t n, uint64_t ns, bool millis)
{
    uint64_t s = ns / NS_PER_S;
    int len = snprintf(out, n, "%llu:%02u:%02u", (unsigned long long)(s / 3600u),
                       (unsigned)(s / 60u % 60u), (unsigned)(s % 60u));
    if (millis && len > 0 && (size_t)len < n) {
        snprintf(out + len, n - (size_t)len, ".%03u", (unsigned)(ns / 1000000u % 1000u));
    }
}

/* 1500000 is "1.5 Mbit/s", 45450 "45.45 kbit/s". */
static void fmt_baud(char *out, size_t n, uint32_t baud)
{
    if (baud == 0u) {
        snprintf(out, n, "rate unknown");
        return;
    }
    uint32_t unit = baud >= 1000000u ? 1000000u : 1000u;
    const char *name = unit == 1000000u ? "Mbit/s" : "kbit/s";
    if (baud < 1000u) {
        snprintf(out, n, "%u bit/s", (unsigned)baud);
        return;
    }
    char frac[16] = "";
    if (baud % unit != 0u) {
        snprintf(frac, sizeof frac, ".%0*u", unit == 1000000u ? 6 : 3, (unsigned)(baud % unit));
        size_t end = strlen(frac);
        while (end > 0u && frac[end - 1u] == '0') {
            frac[--end] = '\0';
        }
    }
    snprintf(out, n, "%u%s %s", (unsigned)(baud / unit), frac, name);
}

static void fmt_hex(char *out, size_t n, const uint8_t *p, unsigned len)
{
    size_t at = 0;
    out[0] = '\0';
    for (unsigned i = 0; i < len && at + 4u < n; i++) {
        at += (size_t)snprintf(out + at, n - at, i == 0u ? "%02X" : " %02X", p[i]);
    }
}

/* Times are shown from the line's first telegram. */
static uint64_t since_start(const mon_t *m, uint64_t t_ns)
{
    return t_ns >= m->line.first_ns ? t_ns - m->line.first_ns : 0u;
}

static uint64_t span_mean(const mon_span_t *s)
{
    return s->n == 0u ? 0u : s->sum_ns / s->n;
}

static const char *state_name(const mon_t *m, unsigned a)
{
    const mon_station_t *s = &m->st[a];
    if (s->role == MON_ROLE_ACTIVE) {
        return m->holder == a ? "holder" : s->in_ring ? "in ring" : "-";
    }
    switch (s->dp_state) {
    case MON_DP_WAIT_PRM:
        return "Wait_Prm";
    case MON_DP_WAIT_CFG:
        return "Wait_Cfg";
    case MON_DP_DATA_EXCH:
        return "Data_Exch";
    default:
        return "-";
    }
}

/* Worth a look: gone quiet, retrying, not in data exchange, diagnosis, late answers. */
static bool station_warning(const mon_station_t *s)
{
    return s->missing_in_a_row >= MON_MISSING_IN_A_ROW || s->storm ||
           (s->dp && s->dp_state != MON_DP_DATA_EXCH) ||
           (s->diag_len >= 2u && (s->diag[1] & 0x02u) != 0u) || s->tsdr_over_slot > 0u ||
           s->tsdr_over_max > 0u;
}

/* The stations a row is shown for, by address (127 is broadcast, not a station). */
static unsigned station_list(const mon_t *m, uint8_t *list)
{
    unsigned n = 0;
    for (unsigned a = 0; a + 1u < MON_STATIONS; a++) {
        if (m->st[a].seen || m->st[a].addressed) {
            list[n++] = (uint8_t)a;
        }
    }
    return n;
}

/* The clock the figures are shown at, and the rates since the last sample. */
static uint64_t view_clock(const mon_t *m, mon_view_t *v, uint64_t now_ns)
{
    if (v->paused) {
        if (!v->frozen) {
            v->frozen = true;
            v->frozen_ns = now_ns;
        }
        return v->frozen_ns;
    }
    v->frozen = false;
    if (!v->have_prev || now_ns < v->prev_ns || m->line.telegrams < v->prev_telegrams ||
        m->line.busy_ns < v->prev_busy_ns) {
        v->have_prev = true; /* the first sample, or a monitor started again */
    } else if (now_ns - v->prev_ns >= MON_VIEW_RATE_NS) {
        uint64_t dt = now_ns - v->prev_ns;
        uint64_t busy = m->line.busy_ns - v->prev_busy_ns;
        v->telegrams_per_s = (m->line.telegrams - v->prev_telegrams) * NS_PER_S / dt;
        v->load_permille = busy >= dt ? 1000u : (uint32_t)(busy * 1000u / dt);
        v->have_rate = true;
    } else {
        return now_ns;
    }
    v->prev_ns = now_ns;
    v->prev_telegrams = m->line.telegrams;
    v->prev_busy_ns = m->line.busy_ns;
    return now_ns;
}

static layout_t make_layout(const mon_view_t *v, unsigned rows, unsigned stations)
{
    layout_t l = {0};
    l.header_h = rows >= 8u ? 2u : 1u;
    l.help = v->help && rows >= 2u;
    l.help_row = rows - 1u;
    unsigned body = rows - (rows >= 1u ? l.header_h : 0u) - (l.help ? 1u : 0u);
    if (rows <= l.header_h) {
        body = 0;
    }
    unsigned pane_min = 0;
    if (body >= 12u) {
        pane_min = body / 3u > 5u ? body / 3u : 5u;
    }
    unsigned want = (stations > 0u ? stations : 1u) + 1u;
    l.table_row = l.header_h;
    l.table_h = pane_min == 0u ? body : (want < body - pane_min ? want : body - pane_min);
    l.pane_row = l.table_row + l.table_h;
    l.pane_h = pane_min == 0u ? 0u : body - l.table_h;
    return l;
}

static void draw_header(const mon_t *m, const mon_view_t *v, const grid_t *g, const layout_t *l,
                        uint64_t now_ns)
{
    char rate[32];
    char up[32] = "0:00:00";
    fmt_baud(rate, sizeof rate, v->baud);
    if ((m->line.telegrams > 0u || m->line.garbled > 0u) && now_ns >= m->line.first_ns) {
        fmt_clock(up, sizeof up, now_ns - m->line.first_ns, false);
    }
    char left[TEXT_MAX];
    int len = snprintf(left, sizeof left, "%s  %s  up %s%s", v->source ? v->source : "monitor",
                       rate, up, v->paused ? "  PAUSED" : "");
    put_text(g, 0, 0, left);
    static const char keys[] = "? help  q quit";
    if (len > 0 && (unsigned)len + 2u + (sizeof keys - 1u) <= g->cols) {
        put_text(g, 0, g->cols - (unsigned)(sizeof keys - 1u), keys);
    }
    if (l->header_h < 2u) {
        return;
    }
    unsigned heard = 0;
    char ring[MON_STATIONS * 4u + 8u] = "";
    size_t at = 0;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        heard += m->st[a].seen ? 1u : 0u;
        if (m->st[a].in_ring) {
            at += (size_t)snprintf(ring + at, sizeof ring - at, at == 0u ? "%u" : ",%u", a);
        }
    }
    char tps[24] = "-";
    char load[16] = "-";
    if (v->have_rate) {
        fmt_count(tps, sizeof tps, 7, v->telegrams_per_s);
        snprintf(load, sizeof load, "%u.%u%%", (unsigned)(v->load_permille / 10u),
                 (unsigned)(v->load_permille % 10u));
    }
    char holder[8] = "-";
    if (m->holder < MON_STATIONS) {
        snprintf(holder, sizeof holder, "%u", (unsigned)m->holder);
    }
    put_fmt(g, 1, 0, "tel/s %s  load %s  heard %u  garbled %llu  events %llu  ring %s  holder %s",
            tps, load, heard, (unsigned long long)m->line.garbled,
            (unsigned long long)m->events_total, at == 0u ? "-" : ring, holder);
}

/* One station's row; the headings use the same widths (draw_table). */
static void station_row(const mon_t *m, unsigned a, char *out, size_t n)
{
    const mon_station_t *s = &m->st[a];
    bool active = s->role == MON_ROLE_ACTIVE;
    const char *role = active ? "master" : s->role == MON_ROLE_PASSIVE ? "slave" : "-";
    char master[8] = "-";
    char ident[8] = "-";
    char dx_mean[16] = "-";
    char dx_max[16] = "-";
    char tsdr[16] = "-";
    char req[16];
    char rep[16];
    char miss[16];
    char diag[16];
    if (s->dp && s->master != MON_NO_MASTER) {
        snprintf(master, sizeof master, "%u", (unsigned)s->master);
    }
    if (s->ident_known) {
        snprintf(ident, sizeof ident, "0x%04X", (unsigned)s->ident);
    }
    if (s->dx_cycle.n > 0u) {
        fmt_ms(dx_mean, sizeof dx_mean, span_mean(&s->dx_cycle));
        fmt_ms(dx_max, sizeof dx_max, s->dx_cycle.max_ns);
    }
    if (!m->cfg.timing) {
        snprintf(tsdr, sizeof tsdr, "n/m");
    } else if (s->tsdr.n > 0u) {
        fmt_count(tsdr, sizeof tsdr, 6, span_mean(&s->tsdr) / 1000u);
    }
    fmt_count(req, sizeof req, 7, active ? s->requests_sent : s->requests_received);
    fmt_count(rep, sizeof rep, 5, active ? s->repeats_sent : s->repeats_received);
    fmt_count(miss, sizeof miss, 5, active ? s->unanswered_sent : s->missing);
    fmt_count(diag, sizeof diag, 4, s->diag_changes);
    snprintf(out, n, "%c%3u %-6s %-9s %4s %-6s %6s %6s %6s %7s %5s %5s %4s",
             station_warning(s) ? '!' : ' ', a, role, state_name(m, a), master, ident, dx_mean,
             dx_max, tsdr, req, rep, miss, diag);
}

/* The selected row after the keys' moves, and the table scrolled so that it shows. */
static unsigned select_row(mon_view_t *v, const uint8_t *list, unsigned n, unsigned visible)
{
    if (n == 0u) {
        v->move = 0;
        return 0;
    }
    int32_t at = 0;
    if (v->selected_known) {
        /* A station that vanished (never: stations stay) or a new one above keeps the same
         * station selected, not the same row. */
        at = (int32_t)n - 1;
        for (unsigned i = 0; i < n; i++) {
            if (list[i] >= v->selected) {
                at = (int32_t)i;
                break;
            }
        }
    }
    at += v->move;
    at = at < 0 ? 0 : at >= (int32_t)n ? (int32_t)n - 1 : at;
    v->move = 0;
    unsigned sel = (unsigned)at;
    v->selected = list[sel];
    v->selected_known = true;
    if (sel < v->top) {
        v->top = sel;
    }
    if (visible > 0u && sel >= v->top + visible) {
        v->top = sel - visible + 1u;
    }
    unsigned max_top = n > visible ? n - visible : 0u;
    if (v->top > max_top) {
        v->top = max_top;
    }
    return sel;
}

static void draw_table(const mon_t *m, mon_view_t *v, const grid_t *g, const layout_t *l)
{
    uint8_t list[MON_STATIONS];
    unsigned n = station_list(m, list);
    unsigned visible = l->table_h > 0u ? l->table_h - 1u : 0u;
    v->page = visible > 0u ? visible : 1u;
    unsigned sel = select_row(v, list, n, visible);
    if (l->table_h == 0u) {
        return;
    }
    put_fmt(g, l->table_row, 0, "%c%3s %-6s %-9s %4s %-6s %6s %6s %6s %7s %5s %5s %4s", ' ',
            "ADR", "ROLE", "STATE", "MSTR", "IDENT", "DXmean", "DXmax", "TSDRus", "REQ", "REP",
            "MISS", "DIAG");
    v->attr[l->table_row] = MON_ATTR_HEADING;
    if (n == 0u && visible > 0u) {
        put_text(g, l->table_row + 1u, 0, "    no station heard yet");
    }
    for (unsigned i = 0; i < visible && v->top + i < n; i++) {
        unsigned row = l->table_row + 1u + i;
        unsigned a = list[v->top + i];
        char text[TEXT_MAX];
        station_row(m, a, text, sizeof text);
        put_text(g, row, 0, text);
        v->attr[row] = (uint8_t)((station_warning(&m->st[a]) ? MON_ATTR_WARNING : 0u) |
                                 (v->top + i == sel ? MON_ATTR_SELECTED : 0u));
    }
}

/* The pane's lines, filled from the top until it is full. */
typedef struct pane {
    const grid_t *g;
    unsigned row;
    unsigned end;
} pane_t;

__attribute__((format(printf, 2, 3))) static void pane_line(pane_t *p, const char *fmt, ...)
{
    if (p->row >= p->end) {
        return;
    }
    char text[TEXT_MAX];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (n >= 0) {
        put_text(p->g, p->row, 0, text);
    }
    p->row++;
}

static void pane_hex(pane_t *p, const char *name, const uint8_t *data, unsigned len)
{
    char hex[TEXT_MAX];
    fmt_hex(hex, sizeof hex, data, len);
    pane_line(p, "%s (%u): %s", name, len, len == 0u ? "-" : hex);
}

static void details_dp(const mon_t *m, const mon_station_t *s, pane_t *p)
{
    char mean[16];
    char min[16];
    char max[16];
    if (s->diag_len != 0u) {
        char text[TEXT_MAX];
        (void)mon_decode_diag(s->diag, s->diag_len, mon_prm_dpv1(s->prm, s->prm_len), text,
                              sizeof text);
        pane_line(p, "diag: %s", text);
    }
    pane_hex(p, "diag", s->diag, s->diag_len);
    if (mon_is_dfp21b(s)) {
        mon_dfp21b_t d;
        mon_decode_dfp21b_station(s, &d);
        pane_line(p, "DFP21B: %s%s", d.pd_config, d.cfg_valid ? "" : " (not accepted)");
        if (d.has_control) {
            pane_line(p, "PO1 control 0x%04X: %s", d.control_word, d.control_text);
        }
        if (d.has_status) {
            pane_line(p, "PI1 status 0x%04X: %s", d.status_word, d.status_text);
        }
        if (d.param_request[0] != '\0') {
            pane_line(p, "channel: %s -> %s", d.param_request, d.param_answer);
        }
    }
    pane_hex(p, "prm", s->prm, s->prm_len);
    pane_hex(p, "cfg", s->cfg, s->cfg_len);
    pane_hex(p, "out", s->outputs, s->out_len);
    pane_hex(p, "in", s->inputs, s->in_len);
    fmt_ms(min, sizeof min, s->dx_cycle.min_ns);
    fmt_ms(mean, sizeof mean, span_mean(&s->dx_cycle));
    fmt_ms(max, sizeof max, s->dx_cycle.max_ns);
    pane_line(p, "data exchange %llu, cycle min/mean/max %s/%s/%s ms, diag changes %llu, "
                 "Stat_Diag %llu, watchdog %u ms",
              (unsigned long long)s->dx_count, min, mean, max,
              (unsigned long long)s->diag_changes, (unsigned long long)s->stat_diag,
              (unsigned)s->watchdog_ms);
    if (!m->cfg.timing) {
        pane_line(p, "TSDR not measurable (the source's times are not the line's)");
        return;
    }
    pane_line(p, "TSDR min/mean/max %llu/%llu/%llu us (%llu answers), below min %llu, over max "
                 "%llu, over slot %llu",
              (unsigned long long)(s->tsdr.min_ns / 1000u),
              (unsigned long long)(span_mean(&s->tsdr) / 1000u),
              (unsigned long long)(s->tsdr.max_ns / 1000u), (unsigned long long)s->tsdr.n,
              (unsigned long long)s->tsdr_below_min, (unsigned long long)s->tsdr_over_max,
              (unsigned long long)s->tsdr_over_slot);
}

static void details_ring(const mon_station_t *s, pane_t *p)
{
    char mean[16];
    char min[16];
    char max[16];
    fmt_ms(min, sizeof min, s->rotation.min_ns);
    fmt_ms(mean, sizeof mean, span_mean(&s->rotation));
    fmt_ms(max, sizeof max, s->rotation.max_ns);
    pane_line(p, "ring: %s, next station %u, tokens %llu, token repeats %llu, rotation "
                 "min/mean/max %s/%s/%s ms, over TTR %llu",
              s->in_ring ? "in" : "out", (unsigned)s->next_station,
              (unsigned long long)s->tokens_sent, (unsigned long long)s->token_repeats, min, mean,
              max, (unsigned long long)s->rotations_over_ttr);
}

static void draw_details(const mon_t *m, const mon_view_t *v, pane_t *p)
{
    if (!v->selected_known || v->selected >= MON_STATIONS) {
        pane_line(p, "no station selected");
        return;
    }
    unsigned a = v->selected;
    const mon_station_t *s = &m->st[a];
    if (s->seen) {
        char first[32];
        char last[32];
        fmt_clock(first, sizeof first, since_start(m, s->first_ns), true);
        fmt_clock(last, sizeof last, since_start(m, s->last_ns), true);
        pane_line(p, "heard first at %s, last at %s", first, last);
    } else {
        pane_line(p, "never heard, only addressed");
    }
    if (s->fdl_status_known) {
        pane_line(p, "FDL status 0x%02X", (unsigned)s->fdl_status);
    }
    if (s->role == MON_ROLE_ACTIVE) {
        details_ring(s, p);
    }
    if (s->dp) {
        details_dp(m, s, p);
    }
    pane_line(p, "requests sent %llu (repeats %llu, unanswered %llu), received %llu (repeats "
                 "%llu, missing %llu), answers %llu, RS %llu, RR %llu, UE %llu, garbled %llu",
              (unsigned long long)s->requests_sent, (unsigned long long)s->repeats_sent,
              (unsigned long long)s->unanswered_sent, (unsigned long long)s->requests_received,
              (unsigned long long)s->repeats_received, (unsigned long long)s->missing,
              (unsigned long long)s->answers, (unsigned long long)s->rs,
              (unsigned long long)s->rr, (unsigned long long)s->ue,
              (unsigned long long)s->garbled);
}

static const mon_event_t *held_event(const mon_t *m, uint64_t seq)
{
    if (seq >= m->events_total || m->events_total - seq > MON_EVENTS) {
        return NULL;
    }
    const mon_event_t *ev = &m->events[seq % MON_EVENTS];
    return ev->seq == seq ? ev : NULL;
}

static void draw_events(const mon_t *m, mon_view_t *v, pane_t *p)
{
    if (m->events_total == 0u) {
        pane_line(p, "no event yet");
        return;
    }
    for (uint64_t seq = m->events_total; seq > 0u && p->row < p->end; seq--) {
        const mon_event_t *ev = held_event(m, seq - 1u);
        if (ev == NULL) {
            break;
        }
        char at[32];
        fmt_clock(at, sizeof at, since_start(m, ev->t_ns), true);
        if (ev->level != MON_LEVEL_INFO) {
            v->attr[p->row] = MON_ATTR_WARNING;
        }
        pane_line(p, "%s %c %.*s", at, ev->level == MON_LEVEL_ERROR ? 'E'
                                        : ev->level == MON_LEVEL_WARN ? 'W'
                                                                      : ' ',
                  (int)MON_EVENT_TEXT, ev->text);
    }
}

static void draw_pane(const mon_t *m, mon_view_t *v, const grid_t *g, const layout_t *l)
{
    if (l->pane_h == 0u) {
        return;
    }
    pane_t p = {g, l->pane_row, l->pane_row + l->pane_h};
    v->attr[l->pane_row] = MON_ATTR_HEADING;
    if (v->pane == MON_PANE_DETAILS) {
        if (v->selected_known && v->selected < MON_STATIONS) {
            mon_role_t r = m->st[v->selected].role;
            const char *role = r == MON_ROLE_ACTIVE    ? "master"
                               : r == MON_ROLE_PASSIVE ? "slave"
                                                       : "not heard";
            pane_line(&p, "station %u: %s, %s (e: events)", (unsigned)v->selected, role,
                      state_name(m, v->selected));
        } else {
            pane_line(&p, "details (e: events)");
        }
        draw_details(m, v, &p);
        return;
    }
    pane_line(&p, "events, newest first: %llu, %llu no longer held (d: details)",
              (unsigned long long)m->events_total,
              (unsigned long long)(m->events_total > MON_EVENTS ? m->events_total - MON_EVENTS
                                                                : 0u));
    draw_events(m, v, &p);
}

void mon_view_render(const mon_t *m, mon_view_t *v, uint64_t now_ns, char *screen,
                     unsigned rows, unsigned cols)
{
    if (rows == 0u || cols == 0u) {
        return;
    }
    memset(screen, ' ', (size_t)rows * cols);
    memset(v->attr, 0, sizeof v->attr);
    grid_t g = {screen, rows > MON_VIEW_MAX_ROWS ? MON_VIEW_MAX_ROWS : rows, cols};
    uint64_t shown_ns = view_clock(m, v, now_ns);
    uint8_t list[MON_STATIONS];
    layout_t l = make_layout(v, g.rows, station_list(m, list));
    draw_header(m, v, &g, &l, shown_ns);
    draw_table(m, v, &g, &l);
    draw_pane(m, v, &g, &l);
    if (l.help) {
        memset(screen + (size_t)l.help_row * cols, ' ', cols);
        put_text(&g, l.help_row, 0,
                 "keys: up/down j/k PgUp/PgDn Home/End select  Enter/d details  e events  "
                 "p pause  ? help  q quit");
        v->attr[l.help_row] = MON_ATTR_HEADING;
    }
}

static int32_t clamp_move(int32_t move)
{
    const int32_t limit = (int32_t)MON_STATIONS;
    return move < -limit ? -limit : move > limit ? limit : move;
}

mon_view_result_t mon_view_key(mon_view_t *v, int key)
{
    int32_t page = v->page > 0u ? (int32_t)v->page : 1;
    switch (key) {
    case MON_KEY_UP:
    case 'k':
        v->move = clamp_move(v->move - 1);
        return MON_VIEW_CHANGED;
    case MON_KEY_DOWN:
    case 'j':
        v->move = clamp_move(v->move + 1);
        return MON_VIEW_CHANGED;
    case MON_KEY_PGUP:
        v->move = clamp_move(v->move - page);
        return MON_VIEW_CHANGED;
    case MON_KEY_PGDN:
        v->move = clamp_move(v->move + page);
        return MON_VIEW_CHANGED;
    case MON_KEY_HOME:
        v->move = -(int32_t)MON_STATIONS;
        return MON_VIEW_CHANGED;
    case MON_KEY_END:
        v->move = (int32_t)MON_STATIONS;
        return MON_VIEW_CHANGED;
    case '\r':
    case '\n':
    case 'd':
        v->pane = MON_PANE_DETAILS;
        return MON_VIEW_CHANGED;
    case 'e':
        v->pane = MON_PANE_EVENTS;
        return MON_VIEW_CHANGED;
    case 'p':
        v->paused = !v->paused;
        return MON_VIEW_CHANGED;
    case '?':
        v->help = !v->help;
        return MON_VIEW_CHANGED;
    case MON_KEY_ESC:
        if (!v->help) {
            return MON_VIEW_IGNORED;
        }
        v->help = false;
        return MON_VIEW_CHANGED;
    case 'q':
    case 'Q':
    case MON_KEY_CTRL_C:
    case MON_KEY_CTRL_BACKSLASH:
        return MON_VIEW_QUIT;
    default:
        return MON_VIEW_IGNORED;
    }
}
