/* Stand-ins for the monitor core's accessors (src/monitor.c), linked into the report tests only
 * while the core is not in the tree (report.cmake checks): the tests fill a mon_t by hand and
 * need no telegram handling, only what the reports call. */
#include <string.h>

#include "monitor/monitor.h"

void mon_init(mon_t *m, const mon_cfg_t *cfg)
{
    memset(m, 0, sizeof *m);
    m->cfg = *cfg;
    m->holder = 255u;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        m->st[a].master = MON_NO_MASTER;
    }
}

const mon_event_t *mon_event(const mon_t *m, uint64_t seq)
{
    if (seq >= m->events_total || m->events_total - seq > MON_EVENTS) {
        return NULL;
    }
    return &m->events[seq % MON_EVENTS];
}

uint64_t mon_events_dropped(const mon_t *m)
{
    return m->events_total > MON_EVENTS ? m->events_total - MON_EVENTS : 0u;
}

const char *mon_role_name(mon_role_t r)
{
    return r == MON_ROLE_ACTIVE ? "active" : r == MON_ROLE_PASSIVE ? "passive" : "unknown";
}

const char *mon_dp_state_name(mon_dp_state_t s)
{
    static const char *const names[] = {"-", "Wait_Prm", "Wait_Cfg", "Data_Exch"};
    return (unsigned)s < 4u ? names[s] : "-";
}

const char *mon_event_name(mon_event_type_t t)
{
    static const char *const names[MON_EV_COUNT] = {
        "new_station", "ring_enter",  "ring_leave", "lost_token",    "dx_enter",
        "dx_leave",    "master_change", "stat_diag", "diag_change",  "prm_fault",
        "retry_storm", "late_answer", "no_answer",  "illegal",       "duplicate_token"};
    return (unsigned)t < MON_EV_COUNT ? names[t] : "?";
}

uint64_t mon_span_mean(const mon_span_t *s)
{
    return s->n > 0u ? s->sum_ns / s->n : 0u;
}
