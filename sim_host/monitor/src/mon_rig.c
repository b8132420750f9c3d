#include "monitor/mon_rig.h"

#include <stdio.h>

#include "monitor/mon_report.h"
#include "monitor/mon_sink.h"

static rig_log_level_t log_level(mon_level_t level)
{
    switch (level) {
    case MON_LEVEL_ERROR:
        return RIG_LOG_ERROR;
    case MON_LEVEL_WARN:
        return RIG_LOG_WARN;
    case MON_LEVEL_INFO:
        break;
    }
    return RIG_LOG_INFO;
}

#define NS_PER_S 1000000000ull

/* A new second of events begins at t_ns once the last one is over; the events it did not log
 * are told in one line. */
static void next_window(mon_rig_t *l, uint64_t t_ns)
{
    if (t_ns < l->window_ns || t_ns - l->window_ns < NS_PER_S) {
        return;
    }
    if (l->not_logged != 0u) {
        char text[RIG_CTL_TEXT];
        (void)snprintf(text, sizeof text, "%llu more bus events in one second not logged (over "
                       "%u); GET /api/v1/bus has the monitor's counts",
                       (unsigned long long)l->not_logged, MON_RIG_EVENTS_PER_S);
        rig_ctl_event(l->ctl, t_ns / 1000u, RIG_LOG_WARN, "sim", "bus", text);
    }
    l->window_ns = t_ns;
    l->window_n = 0;
    l->not_logged = 0;
}

/* In the loop's thread (inside mon_telegram or mon_idle): rig_ctl_event never waits there. */
static void log_event(void *ctx, const mon_event_t *ev)
{
    mon_rig_t *l = ctx;
    next_window(l, ev->t_ns);
    if (l->window_n >= MON_RIG_EVENTS_PER_S) {
        l->not_logged++;
        return;
    }
    l->window_n++;
    char source[16];
    (void)snprintf(source, sizeof source, "station %u", ev->station);
    rig_ctl_event(l->ctl, ev->t_ns / 1000u, log_level(ev->level), source, "bus", ev->text);
}

void mon_rig_init(mon_rig_t *l, rig_ctl_t *ctl, const mon_cfg_t *cfg, const char *source,
                  uint64_t now_ns)
{
    mon_cfg_t c = *cfg;
    c.on_event = log_event;
    c.ctx = l;
    mon_init(&l->mon, &c);
    rig_doc_init(&l->doc);
    l->ctl = ctl;
    (void)snprintf(l->source, sizeof l->source, "%s", source != NULL ? source : "");
    l->t0_ns = now_ns;
    l->window_ns = now_ns;
    l->window_n = 0;
    l->not_logged = 0;
    l->last_end_ns = now_ns;
    l->idle_ns = now_ns;
    l->last_publish_ns = 0;
    l->published = false;
    ctl->bus = &l->doc;
}

/* The line's rate is only known once telegrams go (a card searching its baud rate, a master
 * added later): a monitor started without one takes the first telegram's. */
static void frame(void *ctx, uint64_t t_start_ns, const uint8_t *f, size_t len, bool local,
                  uint32_t baud)
{
    (void)local;
    mon_rig_t *l = ctx;
    if (l->mon.cfg.baud == 0u && baud != 0u && l->mon.line.octets == 0u) {
        mon_cfg_t c = l->mon.cfg;
        c.baud = baud;
        mon_init(&l->mon, &c);
    }
    /* A wall-clock medium dates a received telegram back to its first character, which may
     * be before the loop's last turn told the monitor that time had passed. */
    if (t_start_ns < l->idle_ns) {
        t_start_ns = l->idle_ns;
    }
    /* 11 bits a character (start, 8 data, parity, stop) */
    uint64_t end = baud != 0u ? t_start_ns + (uint64_t)len * 11u * 1000000000u / baud
                              : t_start_ns;
    mon_telegram(&l->mon, f, len, t_start_ns, end);
    if (end > l->last_end_ns) {
        l->last_end_ns = end;
    }
}

rig_tap_t mon_rig_tap(mon_rig_t *l)
{
    rig_tap_t t = {.ctx = l, .frame = frame};
    return t;
}

void mon_rig_publish(mon_rig_t *l, uint64_t now_ns)
{
    char *buf = rig_doc_begin(&l->doc);
    if (buf == NULL) {
        return;
    }
    mon_buf_t b = {.buf = buf, .cap = RIG_DOC_CAP, .len = 0, .overflow = 0};
    mon_sink_t out = mon_buf_sink(&b);
    mon_report_info_t info = {.source = l->source, .t_start_ns = l->t0_ns, .t_now_ns = now_ns,
                              .last_events = MON_RIG_LAST_EVENTS};
    mon_report_json(&l->mon, &info, &out);
    if (b.overflow != 0) {
        /* The clients keep the last whole document rather than a cut one. */
        rig_doc_abandon(&l->doc);
        if (l->doc.too_large++ == 0u) {
            rig_ctl_event(l->ctl, now_ns / 1000u, RIG_LOG_WARN, "sim", "bus",
                          "the bus monitor's document is over 1 MiB: GET /api/v1/bus keeps the "
                          "last one that fitted");
        }
        return;
    }
    rig_doc_commit(&l->doc, b.len);
    l->published = true;
}

void mon_rig_service(mon_rig_t *l, uint64_t now_ns)
{
    /* The rig's clock at a turn of the loop may lag the end of a telegram the tap saw whole. */
    uint64_t t = now_ns > l->last_end_ns ? now_ns : l->last_end_ns;
    mon_idle(&l->mon, t);
    l->idle_ns = t;
    next_window(l, t);
    if (!l->published || t - l->last_publish_ns >= MON_RIG_PUBLISH_NS) {
        l->last_publish_ns = t;
        mon_rig_publish(l, t);
    }
}
