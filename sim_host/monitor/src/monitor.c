/* The monitor's telegram path: what each telegram on the line says about the stations, the
 * request waiting for its answer, the token ring, and the events (monitor.h). What answers say
 * about a DP slave is mon_dp.c's. */
#include "monitor/monitor.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "fdl_active/fdl_active.h"
#include "mon_internal.h"

#define NS_PER_S 1000000000ull
/* Without the line's own timing (a PTY, a USB adapter) an answer may arrive this late and still
 * be an answer: the kernel and the adapter batch characters for milliseconds. */
#define MON_UNTIMED_ANSWER_NS 200000000ull
/* A silence of this many slot times before a token: the token was lost and claimed (the
 * lost-token time-out TTO is 6 slot times plus 2 per address of the claiming station). */
#define MON_LOST_TOKEN_SLOTS 6u

void mon_init(mon_t *m, const mon_cfg_t *cfg)
{
    memset(m, 0, sizeof *m);
    m->cfg = *cfg;
    if (m->cfg.storm_repeats == 0u) {
        m->cfg.storm_repeats = 10u;
    }
    if (m->cfg.tsl_bits == 0u && m->cfg.baud != 0u) {
        fdl_bus_params_t p;
        fdl_bus_params_default(&p, m->cfg.baud, FDL_BUS_PROFILE_DP);
        m->cfg.tsl_bits = p.tsl_bits;
    }
    m->slot_ns = m->cfg.baud != 0u ? (uint64_t)m->cfg.tsl_bits * NS_PER_S / m->cfg.baud : 0u;
    m->holder = 0xFFu;
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        m->st[a].master = MON_NO_MASTER;
        m->st[a].owner = MON_NO_MASTER;
    }
}

uint64_t mon_bits(const mon_t *m, uint64_t ns)
{
    return m->cfg.baud != 0u ? ns * m->cfg.baud / NS_PER_S : 0u;
}

void mon_emit(mon_t *m, uint64_t t_ns, mon_event_type_t type, mon_level_t level, uint8_t station,
              uint8_t other, uint32_t value, const char *fmt, ...)
{
    mon_event_t *ev = &m->events[m->events_total % MON_EVENTS];
    memset(ev, 0, sizeof *ev);
    ev->seq = m->events_total++;
    ev->t_ns = t_ns;
    ev->type = type;
    ev->level = level;
    ev->station = station;
    ev->other = other;
    ev->value = value;
    va_list ap;
    va_start(ap, fmt);
    /* va_start is above; clang 14's analyzer says otherwise when the file is compiled into
     * a test as well (as for cli.c's cli_error). */
    // NOLINTNEXTLINE(clang-analyzer-valist.Uninitialized)
    (void)vsnprintf(ev->text, sizeof ev->text, fmt, ap);
    va_end(ap);
    if (m->cfg.on_event != NULL) {
        m->cfg.on_event(m->cfg.ctx, ev);
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

void mon_span_add(mon_span_t *s, uint64_t ns)
{
    if (s->n == 0u || ns < s->min_ns) {
        s->min_ns = ns;
    }
    if (ns > s->max_ns) {
        s->max_ns = ns;
    }
    s->n++;
    s->sum_ns += ns;
}

uint64_t mon_span_mean(const mon_span_t *s)
{
    return s->n != 0u ? s->sum_ns / s->n : 0u;
}

/* A station sent a telegram: it exists. */
void mon_heard(mon_t *m, uint8_t a, mon_role_t role, uint64_t t_ns)
{
    mon_station_t *s = &m->st[a];
    bool first = !s->seen;
    if (first) {
        s->seen = true;
        s->first_ns = t_ns;
    }
    s->last_ns = t_ns;
    if (role == MON_ROLE_ACTIVE || s->role == MON_ROLE_UNKNOWN) {
        s->role = role;
    }
    if (first) {
        mon_emit(m, t_ns, MON_EV_NEW_STATION, MON_LEVEL_INFO, a, 0, 0,
                 "station %u heard for the first time (%s)", a, mon_role_name(s->role));
    }
}

/* The pending request got no answer. */
static void unanswered(mon_t *m, uint64_t t_ns)
{
    if (!m->pending) {
        return;
    }
    m->pending = false;
    mon_station_t *to = &m->st[m->pend_da];
    bool gap_probe = (m->pend_fc & FDL_FC_CODE_MASK) == FDL_REQ_FDL_STATUS && !to->seen;
    to->last_req_unanswered = true;
    if (gap_probe) {
        return; /* GAP maintenance asks every free address: silence is the normal answer */
    }
    m->line.unanswered++;
    m->st[m->pend_sa].unanswered_sent++;
    to->missing++;
    to->missing_in_a_row++;
    if (to->missing_in_a_row == MON_MISSING_IN_A_ROW) {
        mon_emit(m, t_ns, MON_EV_NO_ANSWER, MON_LEVEL_WARN, m->pend_da, m->pend_sa,
                 MON_MISSING_IN_A_ROW, "station %u does not answer master %u (%u requests)",
                 m->pend_da, m->pend_sa, MON_MISSING_IN_A_ROW);
        mon_dp_gone(m, m->pend_da, t_ns);
    }
}

static uint32_t request_hash(const uint8_t *f, size_t len)
{
    uint32_t h = 2166136261u; /* FNV-1a */
    for (size_t i = 0; i < len; i++) {
        h = (h ^ f[i]) * 16777619u;
    }
    return h;
}

static void retry_storm(mon_t *m, uint8_t da, uint64_t t_ns)
{
    mon_station_t *s = &m->st[da];
    if (s->storm_count == 0u || t_ns - s->storm_window_ns >= NS_PER_S) {
        if (s->storm_count < m->cfg.storm_repeats) {
            s->storm = false; /* a quiet second re-arms the event */
        }
        s->storm_window_ns = t_ns;
        s->storm_count = 0u;
    }
    s->storm_count++;
    if (s->storm_count >= m->cfg.storm_repeats && !s->storm) {
        s->storm = true;
        mon_emit(m, t_ns, MON_EV_RETRY_STORM, MON_LEVEL_WARN, da, s->last_req_sa, s->storm_count,
                 "retry storm: %u repeats to station %u within a second", s->storm_count, da);
    }
}

/* FCB repeats: the same FCB from the same master again after no answer, or the same octets. */
static void count_repeat(mon_t *m, const fdl_msg_t *msg, const uint8_t *f, size_t len,
                         uint64_t t_ns)
{
    mon_station_t *to = &m->st[msg->da];
    uint32_t h = request_hash(f, len);
    bool fcv = (msg->fc & FDL_FC_FCV) != 0u;
    bool fcb = (msg->fc & FDL_FC_FCB) != 0u;
    bool same_master = to->last_fcb_known && to->last_req_sa == msg->sa;
    bool repeat = fcv && same_master && to->last_fcb == fcb &&
                  (to->last_req_unanswered || to->last_req_hash == h);
    if (repeat) {
        to->repeats_received++;
        m->st[msg->sa].repeats_sent++;
        retry_storm(m, msg->da, t_ns);
    }
    to->last_req_sa = msg->sa;
    to->last_req_hash = h;
    to->last_req_unanswered = false;
    if (fcv) {
        to->last_fcb_known = true;
        to->last_fcb = fcb;
    }
}

static bool expects_answer(const fdl_msg_t *msg)
{
    uint8_t code = msg->fc & FDL_FC_CODE_MASK;
    return msg->da != FDL_ADDR_BROADCAST && code != FDL_REQ_SDN_LOW && code != FDL_REQ_SDN_HIGH;
}

static void request(mon_t *m, const fdl_msg_t *msg, const uint8_t *f, size_t len, uint64_t t0,
                    uint64_t t1)
{
    /* A request while another waits for its answer: that one got none (a master's retry after
     * the slot time comes before any mon_idle need say so). */
    unanswered(m, t0);
    m->line.requests++;
    mon_heard(m, msg->sa, MON_ROLE_ACTIVE, t0);
    m->st[msg->sa].requests_sent++;
    if (msg->da == FDL_ADDR_BROADCAST) {
        m->line.broadcasts++;
    } else {
        mon_station_t *to = &m->st[msg->da];
        to->requests_received++;
        if ((msg->fc & FDL_FC_CODE_MASK) != FDL_REQ_FDL_STATUS) {
            to->addressed = true;
        }
        count_repeat(m, msg, f, len, t0);
    }
    mon_dp_request(m, msg, t0);
    if (!expects_answer(msg)) {
        return;
    }
    m->pending = true;
    m->pend_sa = msg->sa;
    m->pend_da = msg->da;
    m->pend_fc = msg->fc;
    m->pend_saps = msg->has_dsap;
    m->pend_dsap = msg->has_dsap ? msg->dsap : 0u;
    m->pend_ssap = msg->has_ssap ? msg->ssap : 0u;
    m->pend_du_len = (uint8_t)(msg->data_len < MON_IO_MAX ? msg->data_len : MON_IO_MAX);
    memcpy(m->pend_du, msg->data, m->pend_du_len);
    m->pend_end_ns = t1;
}

static void station_delay(mon_t *m, uint64_t t0)
{
    mon_station_t *s = &m->st[m->pend_da];
    if (!m->cfg.timing || t0 < m->pend_end_ns) {
        return;
    }
    uint64_t ns = t0 - m->pend_end_ns;
    mon_span_add(&s->tsdr, ns);
    if (m->cfg.baud == 0u) {
        return;
    }
    /* Whole bit times, rounded to the nearest: the times carry the rounding of their source. */
    uint64_t bits = (ns * m->cfg.baud + NS_PER_S / 2u) / NS_PER_S;
    if (s->min_tsdr_bits != 0u && bits < s->min_tsdr_bits) {
        s->tsdr_below_min++;
    }
    if (s->max_tsdr_bits != 0u && bits > s->max_tsdr_bits) {
        s->tsdr_over_max++;
    }
    if (m->slot_ns != 0u && ns > m->slot_ns) {
        s->tsdr_over_slot++;
        if (s->late_event_ns == 0u || t0 - s->late_event_ns >= NS_PER_S) {
            s->late_event_ns = t0;
            mon_emit(m, t0, MON_EV_LATE_ANSWER, MON_LEVEL_WARN, m->pend_da, m->pend_sa,
                     (uint32_t)bits, "station %u answered after %llu bit times (slot time %u)",
                     m->pend_da, (unsigned long long)bits, m->cfg.tsl_bits);
        }
    }
}

/* An answer (SD1/SD2/SD3 response, or SC with msg NULL). */
static void answer(mon_t *m, const fdl_msg_t *msg, uint64_t t0)
{
    m->line.answers++;
    if (msg == NULL) {
        m->line.short_acks++;
    }
    bool matches = m->pending &&
                   (msg == NULL || (msg->sa == m->pend_da && msg->da == m->pend_sa));
    if (!matches) {
        unanswered(m, t0);
        if (msg != NULL) {
            mon_heard(m, msg->sa, MON_ROLE_PASSIVE, t0);
            m->st[msg->sa].answers++;
        }
        return;
    }
    m->pending = false;
    mon_station_t *s = &m->st[m->pend_da];
    uint8_t fc = msg != NULL ? msg->fc : FDL_RSP_OK;
    bool fdl_status = (m->pend_fc & FDL_FC_CODE_MASK) == FDL_REQ_FDL_STATUS;
    mon_role_t role = MON_ROLE_PASSIVE;
    if (fdl_status && msg != NULL) {
        s->fdl_status_known = true;
        s->fdl_status = fc & FDL_FC_STATION_MASK;
        role = s->fdl_status != 0u ? MON_ROLE_ACTIVE : MON_ROLE_PASSIVE;
    }
    mon_heard(m, m->pend_da, role, t0);
    s->answers++;
    s->missing_in_a_row = 0u;
    switch (fc & FDL_FC_CODE_MASK) {
    case FDL_RSP_UE: s->ue++; break;
    case FDL_RSP_RR: s->rr++; break;
    case FDL_RSP_RS: s->rs++; break;
    default: break;
    }
    station_delay(m, t0);
    mon_dp_answer(m, msg, t0);
}

/* Whether sa's pass closes a rotation that judges the others: since its previous pass the token
 * went round and came back from another station, or sa kept it for a whole rotation of its own
 * (alone: two passes to itself). A pass that follows a failed pass (the token never left sa), or
 * a claim after a lost token (the ring starts afresh), closes none. */
static bool closes_rotation(const mon_t *m, uint8_t sa, uint8_t da, uint8_t prev_ns)
{
    const mon_station_t *s = &m->st[sa];
    uint64_t since = s->prev_token_ns;
    if (since == 0u) {
        return false;
    }
    return s->token_received_ns > since || (prev_ns == sa && da == sa && since > m->claim_ns);
}

/* Whether a garbled run came at or after t_ns: a token the monitor could not read may have
 * been in it. */
static bool garbled_since(const mon_t *m, uint64_t t_ns)
{
    return m->line.garbled != 0u && m->last_garbled_ns >= t_ns;
}

static void ring_check_members(mon_t *m, uint8_t sa, uint64_t t0)
{
    uint64_t since = m->st[sa].prev_token_ns;
    if (garbled_since(m, since)) {
        return; /* a member's pass may be among what the monitor could not read */
    }
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        mon_station_t *s = &m->st[a];
        if (a != sa && s->in_ring && s->last_token_ns < since) {
            s->in_ring = false;
            mon_emit(m, t0, MON_EV_RING_LEAVE, MON_LEVEL_WARN, (uint8_t)a, sa, 0,
                     "master %u left the token ring (no token from it for a rotation)", a);
        }
    }
}

static void token(mon_t *m, uint8_t da, uint8_t sa, uint64_t t0)
{
    m->line.tokens++;
    unanswered(m, t0);
    mon_station_t *s = &m->st[sa];
    /* A token to itself is never a repeat: no successor failed to take it (a lone master with
     * nothing to send passes to itself again and again; a claim is two such tokens). */
    if (m->last_was_token && m->last_token_sa == sa && m->last_token_da == da && da != sa) {
        s->token_repeats++;
        return;
    }
    bool ring_known = false;
    for (unsigned a = 0; a < MON_STATIONS && !ring_known; a++) {
        ring_known = m->st[a].in_ring;
    }
    uint64_t silence = t0 > m->last_end_ns ? t0 - m->last_end_ns : 0u;
    /* A claim comes from a station that did not hold the token (the holder went silent); a
     * lone master that holds the token through a pause and passes it on claims nothing. */
    bool lost = ring_known && m->slot_ns != 0u && m->line.telegrams > 1u && sa != m->holder &&
                silence >= MON_LOST_TOKEN_SLOTS * m->slot_ns;
    if (lost) {
        m->line.lost_tokens++;
        mon_emit(m, t0, MON_EV_LOST_TOKEN, MON_LEVEL_WARN, sa, da, (uint32_t)(silence / 1000u),
                 "token lost: the line was silent for %llu us, master %u claimed it",
                 (unsigned long long)(silence / 1000u), sa);
    } else if (m->holder != 0xFFu && sa != m->holder && sa != m->last_token_sa &&
               !garbled_since(m, m->st[m->last_token_sa].last_token_ns)) {
        /* Not after a garbled run: the holder may have passed a token the monitor missed. */
        mon_emit(m, t0, MON_EV_DUPLICATE_TOKEN, MON_LEVEL_WARN, sa, m->holder, 0,
                 "master %u passed a token while master %u held it", sa, m->holder);
    }
    if (lost) {
        m->claim_ns = t0;
    }
    mon_heard(m, sa, MON_ROLE_ACTIVE, t0);
    s->tokens_sent++;
    uint8_t prev_ns = s->next_station;
    s->next_station = da;
    if (s->last_token_ns != 0u) {
        uint64_t rot = t0 - s->last_token_ns;
        mon_span_add(&s->rotation, rot);
        if (m->cfg.ttr_bits != 0u && mon_bits(m, rot) > m->cfg.ttr_bits) {
            s->rotations_over_ttr++;
        }
    }
    s->prev_token_ns = s->last_token_ns;
    s->last_token_ns = t0;
    if (!s->in_ring) {
        s->in_ring = true;
        mon_emit(m, t0, MON_EV_RING_ENTER, MON_LEVEL_INFO, sa, da, 0,
                 "master %u is in the token ring (passes to %u)", sa, da);
    }
    if (!lost && closes_rotation(m, sa, da, prev_ns)) {
        ring_check_members(m, sa, t0);
    }
    if (!lost && da != sa) {
        m->st[da].token_received_ns = t0;
    }
    m->holder = da;
    m->last_token_sa = sa;
    m->last_token_da = da;
}

static void illegal(mon_t *m, const uint8_t *f, size_t len, uint64_t t0, const char *why)
{
    m->line.illegal++;
    unanswered(m, t0);
    char hex[3 * 12 + 4];
    size_t n = 0;
    for (size_t i = 0; i < len && i < 12u; i++) {
        n += (size_t)snprintf(hex + n, sizeof hex - n, "%s%02X", i != 0u ? " " : "", f[i]);
    }
    if (len > 12u) {
        (void)snprintf(hex + n, sizeof hex - n, " ...");
    }
    /* the source address: after DA (SD1, SD3, SD4), after LE, LEr, SD2 and DA (SD2) */
    size_t sa_at = f[0] == FDL_SD2 ? 5u : 2u;
    uint8_t sa = len > sa_at ? (uint8_t)(f[sa_at] & 0x7Fu) : 0u;
    mon_emit(m, t0, MON_EV_ILLEGAL, MON_LEVEL_WARN, sa, 0, 0, "%s: %s", why, hex);
}

/* A valid frame: which kind it is, and whether its addresses and function are legal. */
static void valid_frame(mon_t *m, const uint8_t *f, size_t len, const fdl_msg_t *msg,
                        uint64_t t0, uint64_t t1)
{
    if (f[0] == FDL_SC) {
        answer(m, NULL, t0);
        return;
    }
    if (f[0] == FDL_SD4) {
        uint8_t da = f[1];
        uint8_t sa = f[2];
        if (da > 126u || sa > 126u) {
            illegal(m, f, len, t0, da == FDL_ADDR_BROADCAST || sa == FDL_ADDR_BROADCAST
                                       ? "token with address 127" : "token with an address above 127");
            return;
        }
        token(m, da, sa, t0);
        return;
    }
    if (msg->sa == FDL_ADDR_BROADCAST) {
        illegal(m, f, len, t0, "source address 127 (the broadcast address)");
        return;
    }
    if ((msg->fc & FDL_FC_REQUEST) != 0u) {
        uint8_t code = msg->fc & FDL_FC_CODE_MASK;
        if (code == 0x1u || code == 0x2u || code == 0x8u || code == 0xAu || code == 0xBu) {
            illegal(m, f, len, t0, "request with a reserved function code");
            return;
        }
        request(m, msg, f, len, t0, t1);
        return;
    }
    answer(m, msg, t0);
}

void mon_telegram(mon_t *m, const uint8_t *f, size_t len, uint64_t t_start_ns, uint64_t t_end_ns)
{
    fdl_msg_t msg;
    memset(&msg, 0, sizeof msg);
    if (len == 0u) {
        return;
    }
    if (fdl_check(f, len, NULL, &msg) != FDL_CHECK_OK) {
        mon_garbled(m, f, len, t_start_ns);
        return;
    }
    if (m->cfg.on_frame != NULL) {
        m->cfg.on_frame(m->cfg.ctx, f, len, t_start_ns, false);
    }
    if (m->line.telegrams == 0u && m->line.garbled == 0u) {
        m->line.first_ns = t_start_ns;
    }
    m->line.telegrams++;
    m->line.octets += len;
    m->line.last_ns = t_end_ns;
    m->line.busy_ns += t_end_ns >= t_start_ns ? t_end_ns - t_start_ns : 0u;
    valid_frame(m, f, len, &msg, t_start_ns, t_end_ns);
    m->last_was_token = f[0] == FDL_SD4;
    m->last_end_ns = t_end_ns;
}

void mon_garbled(mon_t *m, const uint8_t *f, size_t len, uint64_t t_ns)
{
    if (m->line.telegrams == 0u && m->line.garbled == 0u) {
        m->line.first_ns = t_ns;
    }
    m->line.garbled++;
    m->line.octets += len;
    m->line.last_ns = t_ns;
    m->last_garbled_ns = t_ns;
    if (m->cfg.on_frame != NULL && len != 0u) {
        m->cfg.on_frame(m->cfg.ctx, f, len, t_ns, true);
    }
    fdl_msg_t msg;
    memset(&msg, 0, sizeof msg);
    if (len > 0u && fdl_parse_damaged(f, len, &msg) && msg.sa < FDL_ADDR_BROADCAST) {
        m->st[msg.sa].garbled++;
    }
    unanswered(m, t_ns);
    m->last_was_token = false;
    m->last_end_ns = t_ns;
}

void mon_idle(mon_t *m, uint64_t now_ns)
{
    uint64_t wait = m->slot_ns;
    if (m->cfg.answer_wait_ns != 0u) {
        wait = m->cfg.answer_wait_ns;
    } else if (!m->cfg.timing && wait < MON_UNTIMED_ANSWER_NS) {
        wait = MON_UNTIMED_ANSWER_NS;
    }
    if (m->pending && wait != 0u && now_ns > m->pend_end_ns + wait) {
        unanswered(m, now_ns);
    }
    mon_dp_idle(m, now_ns);
}

const char *mon_role_name(mon_role_t r)
{
    switch (r) {
    case MON_ROLE_ACTIVE: return "active";
    case MON_ROLE_PASSIVE: return "passive";
    default: return "unknown";
    }
}

const char *mon_dp_state_name(mon_dp_state_t s)
{
    switch (s) {
    case MON_DP_WAIT_PRM: return "Wait_Prm";
    case MON_DP_WAIT_CFG: return "Wait_Cfg";
    case MON_DP_DATA_EXCH: return "Data_Exch";
    default: return "-";
    }
}

const char *mon_event_name(mon_event_type_t t)
{
    static const char *const names[MON_EV_COUNT] = {
        "new_station", "ring_enter", "ring_leave", "lost_token", "dx_enter", "dx_leave",
        "master_change", "stat_diag", "diag_change", "prm_fault", "retry_storm", "late_answer",
        "no_answer", "illegal", "duplicate_token",
    };
    return (unsigned)t < MON_EV_COUNT ? names[t] : "?";
}
