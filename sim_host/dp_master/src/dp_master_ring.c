/* The master as an FDL active station (fdl_active.h): what it sends while it holds the token. */
#include "dp_master/dp_master.h"
#include "dp_master_internal.h"

static void ring_event(void *ctx, const fdl_active_event_t *ev)
{
    dp_master_t *m = ctx;
    if (m->cfg.ring_event != NULL) {
        m->cfg.ring_event(m->cfg.event_ctx, ev);
    }
}

/* The bus parameters decide the reply deadline (TSL, plus the first character's own time) and
 * the retry limit. */
void dpm_ring_init(dp_master_t *m, hal_time_us_t now)
{
    if (m->cfg.bus.baud == 0u) {
        fdl_bus_params_default(&m->cfg.bus, m->cfg.baud, FDL_BUS_PROFILE_DP);
    }
    m->cfg.bus.baud = m->cfg.baud;
    m->cfg.slot_time_us = fdl_bus_us(&m->cfg.bus, m->cfg.bus.tsl_bits) +
                          hal_uart_char_ns(m->cfg.baud) / 1000u + 1u;
    if (m->cfg.max_retry == 0u) {
        m->cfg.max_retry = m->cfg.bus.max_retry;
    }
    fdl_active_cfg_t ac = {.address = m->cfg.address, .bus = m->cfg.bus, .uart = m->cfg.uart,
                           .event = ring_event, .event_ctx = m};
    fdl_active_init(&m->mac, &ac, now);
    fdl_active_start(&m->mac, now);
}

/* ---- as an FDL active station ----------------------------------------------------------- */

/* The next slave for this token visit: each slave at most one cyclic telegram per visit, and
 * only what the token's time allows. Data_Exchange is high priority; start-up, diagnosis and
 * acyclic telegrams are low priority and wait for an early token. */
static int pick_slave_ring(dp_master_t *m, hal_time_us_t now, bool *c1, bool *high)
{
    bool low_ok = fdl_active_may_start(&m->mac, now, false);
    bool high_ok = fdl_active_may_start(&m->mac, now, true);
    for (unsigned k = 0; k < m->num_slaves; k++) {
        unsigned idx = (m->next_slave + k) % m->num_slaves;
        dp_master_slave_t *s = &m->slaves[idx];
        if (low_ok && s->phase == DP_MASTER_PHASE_DATA_EXCH && s->c1_turn &&
            dp_master_xfer_busy(&s->c1)) {
            *c1 = true;
            *high = false;
            m->next_slave = (uint8_t)((idx + 1u) % m->num_slaves);
            return (int)idx;
        }
        if (!hal_time_reached(now, s->due) || s->served_visit == m->mac.visit) {
            continue;
        }
        *high = s->phase == DP_MASTER_PHASE_DATA_EXCH;
        if (!(*high ? high_ok : low_ok)) {
            continue;
        }
        *c1 = false;
        s->served_visit = m->mac.visit;
        if (s->phase == DP_MASTER_PHASE_BACKOFF) {
            dpm_set_phase(m, idx, DP_MASTER_PHASE_FDL_STATUS, now);
        }
        m->next_slave = (uint8_t)((idx + 1u) % m->num_slaves);
        return (int)idx;
    }
    return -1;
}

/* A master alone in its ring with nothing due keeps the token on an idle line until its next
 * slave is due, but never for 3 slot times: a station listening to join must not take the
 * silence for a lost token (its TTO is at least 6 slot times). Passing the token to itself at
 * once would fill the line with tokens between two cycles (e.g. 40 per 2 ms at 1.5 Mbit/s)
 * that say nothing another station could use. */
static hal_time_us_t alone_hold_until(dp_master_t *m, hal_time_us_t now)
{
    if (m->mac.ns != m->cfg.address) {
        return now;
    }
    for (unsigned i = 0; i < m->num_slaves; i++) {
        if (hal_time_reached(now, m->slaves[i].due)) {
            return now; /* served in this visit, due again: the next visit is for it */
        }
    }
    hal_time_us_t limit = m->mac.last_activity +
                          3u * fdl_bus_us(&m->cfg.bus, m->cfg.bus.tsl_bits);
    return hal_time_earlier(dpm_idle_until(m, now), limit);
}

/* Holding the token: Global_Control, then the slaves' telegrams and the class-2 connections'
 * in turn while the token's time lasts; then the token goes on. */
hal_time_us_t dpm_ring_poll(dp_master_t *m, hal_time_us_t now)
{
    for (unsigned i = 0; i < m->num_slaves; i++) {
        (void)dp_master_xfer_check_timeout(&m->slaves[i].c1, now);
    }
    if (m->leaving) {
        if (m->mac.state != FDL_MAC_OFFLINE && !m->mac.leaving) {
            fdl_active_leave(&m->mac, now);
        }
        return fdl_active_poll(&m->mac, now);
    }
    hal_time_us_t mac_next = fdl_active_poll(&m->mac, now);
    if (!fdl_active_holds_token(&m->mac)) {
        return mac_next; /* nothing to send before the token comes, and it comes by a telegram */
    }
    hal_time_us_t from = m->next_send;
    if (hal_time_diff(fdl_active_line_free(&m->mac), from) > 0) {
        from = fdl_active_line_free(&m->mac);
    }
    if (!hal_time_reached(now, from)) {
        return from;
    }
    if (m->gc_pending && fdl_active_may_start(&m->mac, now, true)) {
        fdl_active_cycle(&m->mac, true);
        dpm_send_global_control(m, now);
        return m->next_send;
    }
    if (m->c2_turn && fdl_active_may_start(&m->mac, now, false) && dpm_send_c2(m, now)) {
        return m->reply_deadline;
    }
    bool c1 = false;
    bool high = false;
    int idx = pick_slave_ring(m, now, &c1, &high);
    if (idx >= 0) {
        fdl_active_cycle(&m->mac, high);
        dpm_send_to_slave(m, (unsigned)idx, c1, now);
        return m->reply_deadline;
    }
    if (fdl_active_may_start(&m->mac, now, false) && dpm_send_c2(m, now)) {
        return m->reply_deadline;
    }
    hal_time_us_t hold = alone_hold_until(m, now);
    if (!hal_time_reached(now, hold)) {
        return hold;
    }
    fdl_active_release(&m->mac, now);
    return fdl_active_poll(&m->mac, now);
}

void dp_master_leave(dp_master_t *m)
{
    m->leaving = m->cfg.token_ring && m->running;
}

bool dp_master_left(const dp_master_t *m)
{
    return !m->leaving || m->mac.state == FDL_MAC_OFFLINE;
}
