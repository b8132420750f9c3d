/* The FDL active station (fdl_active.h): the ring's rules, each named after its clause's term. */
#include <string.h>

#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "fdl_active/fdl_active.h"

#define NO_ADDRESS 0xFFu
/* Station type in the FC of an FDL status answer (bits 5..4). */
#define FC_TYPE_PASSIVE 0x00u
#define FC_TYPE_NOT_READY 0x10u
#define FC_TYPE_READY 0x20u
#define FC_TYPE_IN_RING 0x30u

static bool bit_get(const uint8_t *set, uint8_t a)
{
    return (set[a >> 3] & (1u << (a & 7u))) != 0u;
}

static void bit_put(uint8_t *set, uint8_t a, bool on)
{
    if (on) {
        set[a >> 3] = (uint8_t)(set[a >> 3] | (1u << (a & 7u)));
    } else {
        set[a >> 3] = (uint8_t)(set[a >> 3] & ~(1u << (a & 7u)));
    }
}

static uint32_t us(const fdl_active_t *s, uint32_t bits)
{
    return fdl_bus_us(&s->cfg.bus, bits);
}

/* One character, rounded up: a first character that started within TSL ends up to this much
 * later, and that is when the receiver sees it. */
static uint32_t char_us(const fdl_active_t *s)
{
    return hal_uart_char_ns(s->cfg.bus.baud) / 1000u + 1u;
}

static uint8_t ts(const fdl_active_t *s)
{
    return s->cfg.address;
}

static void emit(fdl_active_t *s, fdl_active_event_t ev)
{
    if (s->cfg.event != NULL) {
        s->cfg.event(s->cfg.event_ctx, &ev);
    }
}

static void set_state(fdl_active_t *s, fdl_mac_state_t next, hal_time_us_t t)
{
    if (next == s->state) {
        return;
    }
    fdl_mac_state_t old = s->state;
    s->state = next;
    emit(s, (fdl_active_event_t){.type = FDL_EV_STATE, .t = t, .old_state = old, .state = next,
                                 .address = ts(s)});
}

static void las_put(fdl_active_t *s, uint8_t a, bool on, hal_time_us_t t)
{
    if (a > FDL_ACTIVE_HSA_MAX || bit_get(s->las, a) == on) {
        return;
    }
    bit_put(s->las, a, on);
    emit(s, (fdl_active_event_t){.type = FDL_EV_LAS, .t = t, .state = s->state, .address = a,
                                 .kind = on ? FDL_STATION_IN_RING : FDL_STATION_NONE});
}

static void live_put(fdl_active_t *s, uint8_t a, fdl_station_kind_t k, hal_time_us_t t)
{
    if (s->live[a] == (uint8_t)k) {
        return;
    }
    s->live[a] = (uint8_t)k;
    emit(s, (fdl_active_event_t){.type = FDL_EV_LIVE, .t = t, .state = s->state, .address = a,
                                 .kind = k});
}

/* The address after a, counting 0..HSA round (the ring's order of addresses). */
static uint8_t next_address(const fdl_active_t *s, uint8_t a)
{
    uint8_t top = s->cfg.bus.hsa > ts(s) ? s->cfg.bus.hsa : ts(s);
    return a >= top ? 0u : (uint8_t)(a + 1u);
}

/* The next station of the LAS after a (TS itself when a is the only other one). */
static uint8_t las_next(const fdl_active_t *s, uint8_t a)
{
    uint8_t b = a;
    for (unsigned k = 0; k < FDL_ACTIVE_ADDRESSES; k++) {
        b = b >= FDL_ACTIVE_HSA_MAX ? 0u : (uint8_t)(b + 1u);
        if (b == ts(s) || bit_get(s->las, b)) {
            return b;
        }
    }
    return ts(s);
}

/* The GAP: the addresses after TS up to (not including) NS, at most HSA. */
static bool in_gap(const fdl_active_t *s, uint8_t a)
{
    if (a == ts(s) || a == s->ns || a > s->cfg.bus.hsa) {
        return false;
    }
    if (s->ns == ts(s)) {
        return true;
    }
    if (s->ns > ts(s)) {
        return a > ts(s) && a < s->ns;
    }
    return a > ts(s) || a < s->ns;
}

static void transmit(fdl_active_t *s, const uint8_t *f, size_t len, hal_time_us_t now,
                     bool reply)
{
    if (s->cfg.uart.ops != NULL && s->cfg.uart.ops->transmit != NULL) {
        (void)s->cfg.uart.ops->transmit(s->cfg.uart.ctx, f, len, now);
    }
    hal_time_us_t end =
        now + (uint32_t)(((uint64_t)hal_uart_char_ns(s->cfg.bus.baud) * len + 999u) / 1000u);
    fdl_active_sent(s, now, end, reply);
}

void fdl_active_init(fdl_active_t *s, const fdl_active_cfg_t *cfg, hal_time_us_t now)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->state = FDL_MAC_OFFLINE;
    s->ns = ts(s);
    s->ps = ts(s);
    s->foreign_ps = NO_ADDRESS;
    s->listen_started = false;
    s->last_activity = now;
    s->line_free = now;
    s->deadline = now + HAL_TIME_NO_DEADLINE_US;
}

static hal_time_us_t tto_end(const fdl_active_t *s)
{
    return s->last_activity + us(s, fdl_bus_tto_bits(&s->cfg.bus, ts(s)));
}

void fdl_active_start(fdl_active_t *s, hal_time_us_t now)
{
    memset(s->las, 0, sizeof s->las);
    memset(s->listen_set, 0, sizeof s->listen_set);
    memset(s->listen_prev, 0, sizeof s->listen_prev);
    s->listen_started = false;
    s->listen_rotations = 0;
    s->in_ring = false;
    s->leaving = false;
    s->have_token_t = false;
    s->ns = ts(s);
    s->ps = ts(s);
    s->last_activity = now;
    s->line_free = now;
    set_state(s, FDL_MAC_LISTEN_TOKEN, now);
}

void fdl_active_leave(fdl_active_t *s, hal_time_us_t now)
{
    s->leaving = true;
    s->gap_pending = false;
    s->answer_pending = false;
    if (s->state == FDL_MAC_USE_TOKEN) {
        s->pass_to = s->ns;
        s->pass_tries = 0;
        set_state(s, FDL_MAC_PASS_TOKEN, now);
    } else if (s->state != FDL_MAC_PASS_TOKEN && s->state != FDL_MAC_AWAIT_STATUS_RESPONSE) {
        fdl_active_stop(s, now);
    }
}

void fdl_active_stop(fdl_active_t *s, hal_time_us_t now)
{
    s->in_ring = false;
    s->answer_pending = false;
    set_state(s, FDL_MAC_OFFLINE, now);
}

bool fdl_active_holds_token(const fdl_active_t *s)
{
    return s->state == FDL_MAC_USE_TOKEN;
}

hal_time_us_t fdl_active_line_free(const fdl_active_t *s)
{
    return s->line_free;
}

bool fdl_active_may_start(const fdl_active_t *s, hal_time_us_t now, bool high)
{
    if (s->state != FDL_MAC_USE_TOKEN || !hal_time_reached(now, s->line_free)) {
        return false;
    }
    if (s->late) {
        return high && !s->high_done; /* a late token: one high-priority message cycle */
    }
    return !hal_time_reached(now, s->tth_end); /* TTH > 0 */
}

void fdl_active_cycle(fdl_active_t *s, bool high)
{
    if (s->late && high) {
        s->high_done = true;
    }
}

void fdl_active_sent(fdl_active_t *s, hal_time_us_t start, hal_time_us_t end, bool reply)
{
    s->tx_start = start;
    s->reply_expected = reply;
    s->last_activity = end;
    s->line_free = end + (reply ? 0u : us(s, fdl_bus_tid2_bits(&s->cfg.bus)));
}

bool fdl_active_in_las(const fdl_active_t *s, uint8_t address)
{
    return address == ts(s) ? s->in_ring : address <= FDL_ACTIVE_HSA_MAX &&
                                               bit_get(s->las, address);
}

fdl_station_kind_t fdl_active_station(const fdl_active_t *s, uint8_t address)
{
    return address < FDL_ACTIVE_ADDRESSES ? (fdl_station_kind_t)s->live[address]
                                          : FDL_STATION_UNKNOWN;
}

/* ---- the token arrives ------------------------------------------------------------------ */

/* A GAP sweep: the addresses after TS, one per token visit (the Siemens and IEC reading of the
 * GAP update factor: G rotations without, then one address each time the token comes until the
 * whole GAP has been asked). */
static void gap_sweep_start(fdl_active_t *s)
{
    s->gap_sweep = true;
    s->gap_rotations = 0;
    s->gap_next = next_address(s, ts(s));
}

/* Token receipt: TRR from the last receipt, TTH = TTR - TRR, one more rotation towards G. */
static void take_token(fdl_active_t *s, uint8_t from, hal_time_us_t t)
{
    uint32_t ttr = us(s, s->cfg.bus.ttr_bits);
    uint32_t trr = s->have_token_t ? (uint32_t)hal_time_diff(t, s->token_t) : 0u;
    s->have_token_t = true;
    s->token_t = t;
    s->visit++;
    s->stats.tokens_received++;
    s->stats.trr_us = trr;
    if (trr > s->stats.trr_max_us) {
        s->stats.trr_max_us = trr;
    }
    s->late = trr >= ttr;
    s->high_done = false;
    s->tth_end = t + (s->late ? 0u : ttr - trr);
    if (s->late) {
        s->stats.late_tokens++;
        emit(s, (fdl_active_event_t){.type = FDL_EV_LATE_TOKEN, .t = t, .state = s->state,
                                     .address = ts(s), .trr_us = trr});
    }
    s->ps = from;
    s->foreign_ps = NO_ADDRESS;
    /* NS is the next station of the LAS: the LAS changed since we last held the token (a station
     * entered the ring after us, or one was skipped). */
    s->ns = las_next(s, ts(s));
    s->gap_asked_this_visit = false;
    if (!s->gap_sweep && ++s->gap_rotations >= s->cfg.bus.gap_factor) {
        gap_sweep_start(s);
    }
    s->line_free = t + us(s, fdl_bus_tid1_bits(&s->cfg.bus));
    if (!s->in_ring) {
        s->in_ring = true;
        emit(s, (fdl_active_event_t){.type = FDL_EV_IN_RING, .t = t, .state = s->state,
                                     .address = ts(s)});
    }
    set_state(s, FDL_MAC_USE_TOKEN, t);
}

/* Token passing seen from outside: sa passed to da, so the stations between them are not (or no
 * longer) in the ring, and sa is. */
static void token_seen(fdl_active_t *s, uint8_t sa, uint8_t da, hal_time_us_t t)
{
    las_put(s, sa, true, t);
    if (sa == da) {
        /* A station alone (after its claim): its ring is itself, so this station is out of it
         * and enters again through sa's GAP ("ready", not "in ring"). */
        for (unsigned a = 0; a <= FDL_ACTIVE_HSA_MAX; a++) {
            if (a != sa && a != ts(s)) {
                las_put(s, (uint8_t)a, false, t);
            }
        }
        if (s->in_ring && s->state == FDL_MAC_ACTIVE_IDLE) {
            s->in_ring = false;
        }
        return;
    }
    for (uint8_t a = sa == FDL_ACTIVE_HSA_MAX ? 0u : (uint8_t)(sa + 1u); a != da;
         a = a >= FDL_ACTIVE_HSA_MAX ? 0u : (uint8_t)(a + 1u)) {
        if (a == ts(s)) {
            if (s->in_ring && s->state == FDL_MAC_ACTIVE_IDLE) {
                s->in_ring = false; /* skipped: back in through the GAP of our PS */
            }
            continue;
        }
        las_put(s, a, false, t);
    }
}

/* Listen_Token: the LAS is complete after two identical rotations. */
static void listen_token(fdl_active_t *s, uint8_t sa, uint8_t da, hal_time_us_t t)
{
    bit_put(s->listen_set, sa, true);
    if (da > sa) {
        return;
    }
    /* A token to a lower address (or to itself) ends a rotation, whoever passes it, so a
     * station that leaves while we listen cannot keep us listening. The first such token only
     * starts the count: what was heard before it is part of a rotation. */
    if (!s->listen_started) {
        s->listen_started = true;
        memset(s->listen_set, 0, sizeof s->listen_set);
        return;
    }
    bool same = memcmp(s->listen_set, s->listen_prev, sizeof s->listen_set) == 0;
    if (s->listen_rotations >= 1u && same) {
        memset(s->las, 0, sizeof s->las);
        for (unsigned a = 0; a <= FDL_ACTIVE_HSA_MAX; a++) {
            if (bit_get(s->listen_set, (uint8_t)a)) {
                las_put(s, (uint8_t)a, true, t); /* each one told: the ring as found */
            }
        }
        s->ns = las_next(s, ts(s));
        set_state(s, FDL_MAC_ACTIVE_IDLE, t);
        return;
    }
    memcpy(s->listen_prev, s->listen_set, sizeof s->listen_prev);
    memset(s->listen_set, 0, sizeof s->listen_set);
    s->listen_rotations++;
}

static bool holding(const fdl_active_t *s)
{
    return s->state == FDL_MAC_USE_TOKEN || s->state == FDL_MAC_AWAIT_STATUS_RESPONSE ||
           s->state == FDL_MAC_PASS_TOKEN || s->state == FDL_MAC_CLAIM_TOKEN;
}

/* Another station transmitted a request or a token while we held ours: two tokens are on the
 * bus; the holder that notices drops its own. */
static void double_token(fdl_active_t *s, uint8_t sa, hal_time_us_t t)
{
    s->stats.double_tokens++;
    emit(s, (fdl_active_event_t){.type = FDL_EV_DOUBLE_TOKEN, .t = t, .state = s->state,
                                 .address = sa});
    set_state(s, FDL_MAC_ACTIVE_IDLE, t);
}

static void token_frame(fdl_active_t *s, uint8_t da, uint8_t sa, hal_time_us_t t)
{
    if (holding(s) && sa != ts(s)) {
        double_token(s, sa, t);
    }
    if (s->state == FDL_MAC_LISTEN_TOKEN) {
        listen_token(s, sa, da, t);
        return;
    }
    if (s->state == FDL_MAC_OFFLINE) {
        return;
    }
    token_seen(s, sa, da, t);
    if (da != ts(s) || s->state != FDL_MAC_ACTIVE_IDLE) {
        return;
    }
    /* A token from a station other than the PS is refused once, taken when repeated: the ring
     * changed (IEC 61158-4-3, token receipt in Active_Idle). */
    if (s->in_ring && sa != s->ps && sa != s->foreign_ps) {
        s->foreign_ps = sa;
        return;
    }
    take_token(s, sa, t);
}

/* An answer to our GAP request. */
static void status_answer(fdl_active_t *s, uint8_t sa, uint8_t fc, hal_time_us_t t)
{
    fdl_station_kind_t k = FDL_STATION_PASSIVE;
    switch (fc & FDL_FC_STATION_MASK) {
    case FC_TYPE_NOT_READY:
        k = FDL_STATION_NOT_READY;
        break;
    case FC_TYPE_READY:
        k = FDL_STATION_READY;
        break;
    case FC_TYPE_IN_RING:
        k = FDL_STATION_IN_RING;
        break;
    default:
        break;
    }
    live_put(s, sa, k, t);
    if (k == FDL_STATION_READY) {
        s->ns = sa; /* it enters the ring: the token goes to it now */
        s->pass_to = sa;
        emit(s, (fdl_active_event_t){.type = FDL_EV_NEW_SUCCESSOR, .t = t, .state = s->state,
                                     .address = sa});
    }
    s->state = FDL_MAC_PASS_TOKEN;
    s->gap_pending = false;
}

static uint8_t own_status_fc(const fdl_active_t *s)
{
    if (s->state == FDL_MAC_LISTEN_TOKEN || s->state == FDL_MAC_OFFLINE) {
        return FC_TYPE_NOT_READY;
    }
    return s->in_ring ? FC_TYPE_IN_RING : FC_TYPE_READY;
}

/* A telegram from our own address that we did not send: another station has it. */
static void duplicate_address(fdl_active_t *s, hal_time_us_t t)
{
    emit(s, (fdl_active_event_t){.type = FDL_EV_DUPLICATE_ADDRESS, .t = t, .state = s->state,
                                 .address = ts(s)});
    fdl_active_stop(s, t);
}

void fdl_active_activity(fdl_active_t *s, hal_time_us_t t)
{
    /* Holding the token, a character is only expected as the answer to our request. One that
     * comes when no answer is due is another station on the line: two holders (after a claim
     * race, say) whose telegrams collide never hear a valid one from each other, so this is how
     * they find out. (A character during our own request cannot be told from an early answer
     * on a PTY or LCM segment, whose line is faster than its nominal rate: not judged.) */
    if (holding(s) && !s->reply_expected && hal_time_diff(t, s->tx_start) > 0) {
        double_token(s, NO_ADDRESS, t);
    }
    s->last_activity = t;
    s->activity_seen = true;
    if (s->state == FDL_MAC_CHECK_TOKEN_PASS) {
        /* The successor's first character within TSL: the token pass worked. A leaving
         * station waits for this too: a successor that refuses a new PS's first token needs
         * the repeat. */
        s->stats.tokens_passed++;
        if (s->leaving) {
            fdl_active_stop(s, t);
        } else {
            set_state(s, FDL_MAC_ACTIVE_IDLE, t);
        }
    }
}

void fdl_active_frame(fdl_active_t *s, const uint8_t *f, size_t len, hal_time_us_t first_t,
                      hal_time_us_t end_t)
{
    (void)first_t;
    s->last_activity = end_t;
    s->line_free = end_t + us(s, fdl_bus_tid1_bits(&s->cfg.bus));
    s->reply_expected = false;
    if (len == 0u || f[0] == FDL_SC || s->state == FDL_MAC_OFFLINE) {
        return;
    }
    if (f[0] == FDL_SD4) {
        if (len < FDL_SD4_LEN) {
            return;
        }
        uint8_t da = f[1] & FDL_ADDR_MASK;
        uint8_t sa = f[2] & FDL_ADDR_MASK;
        if (sa == ts(s)) {
            duplicate_address(s, end_t);
            return;
        }
        token_frame(s, da, sa, end_t);
        return;
    }
    fdl_msg_t msg = {0};
    if (fdl_parse(f, len, &msg) != FDL_PARSE_OK) {
        return;
    }
    if (msg.sa == ts(s)) {
        duplicate_address(s, end_t);
        return;
    }
    bool request = (msg.fc & FDL_FC_REQUEST) != 0u;
    if (request && holding(s)) {
        double_token(s, msg.sa, end_t);
    }
    if (request && msg.da == ts(s) && (msg.fc & FDL_FC_CODE_MASK) == FDL_REQ_FDL_STATUS) {
        s->answer_pending = true;
        s->answer_to = msg.sa;
        s->answer_at = end_t + us(s, s->cfg.bus.min_tsdr_bits);
        return;
    }
    if (!request && s->state == FDL_MAC_AWAIT_STATUS_RESPONSE && msg.da == ts(s) &&
        msg.sa == s->gap_asked) {
        status_answer(s, msg.sa, msg.fc, end_t);
    }
}

void fdl_active_release(fdl_active_t *s, hal_time_us_t now)
{
    if (s->state != FDL_MAC_USE_TOKEN) {
        return;
    }
    /* GAP maintenance, only with time left on the token (TTH > 0): in a sweep one address per
     * visit; past the GAP's end (NS, or HSA round to TS) the sweep is over and the next starts
     * G rotations later. */
    s->gap_pending = false;
    if (s->gap_sweep && !s->late && !hal_time_reached(now, s->tth_end)) {
        while (!in_gap(s, s->gap_next) && s->gap_next > s->cfg.bus.hsa &&
               s->gap_next != ts(s)) {
            s->gap_next = next_address(s, s->gap_next); /* above HSA: round to 0 */
        }
        if (in_gap(s, s->gap_next)) {
            s->gap_pending = true;
        } else {
            s->gap_sweep = false;
            s->gap_rotations = 0;
        }
    }
    s->pass_to = s->ns;
    s->pass_tries = 0;
    set_state(s, FDL_MAC_PASS_TOKEN, now);
}

/* ---- the station's own transmissions ----------------------------------------------------- */

static void send_token(fdl_active_t *s, uint8_t to, hal_time_us_t now)
{
    uint8_t f[FDL_SD4_LEN] = {FDL_SD4, to, ts(s)};
    transmit(s, f, sizeof f, now, false);
    /* The successor may start right after the token; TID2 applies to those who have nothing. */
    s->line_free = s->last_activity + us(s, fdl_bus_tid1_bits(&s->cfg.bus));
}

static void send_status_request(fdl_active_t *s, hal_time_us_t now)
{
    uint8_t f[8];
    uint8_t g = s->gap_next;
    size_t n = fdl_encode(f, g, ts(s), FDL_FC_REQUEST | FDL_REQ_FDL_STATUS, false, 0, 0,
                          NULL, 0);
    s->gap_asked = g;
    s->gap_asked_this_visit = true;
    s->gap_next = next_address(s, g);
    s->stats.gap_requests++;
    transmit(s, f, n, now, true);
    s->activity_seen = false;
    s->deadline = s->last_activity + us(s, s->cfg.bus.tsl_bits) + char_us(s);
    s->state = FDL_MAC_AWAIT_STATUS_RESPONSE;
}

static void send_status_answer(fdl_active_t *s, hal_time_us_t now)
{
    uint8_t f[8];
    size_t n = fdl_encode(f, s->answer_to, ts(s), own_status_fc(s), false, 0, 0, NULL, 0);
    s->answer_pending = false;
    s->stats.status_answers++;
    transmit(s, f, n, now, false);
    s->line_free = s->last_activity;
}

/* PASS_TOKEN: the GAP request first if one is due, then the token. */
static hal_time_us_t pass_token(fdl_active_t *s, hal_time_us_t now)
{
    if (!hal_time_reached(now, s->line_free)) {
        return s->line_free;
    }
    if (s->gap_pending && !s->leaving) {
        s->gap_pending = false;
        send_status_request(s, now);
        return s->deadline;
    }
    uint8_t to = s->pass_to;
    if (s->leaving && to == ts(s)) {
        fdl_active_stop(s, now); /* alone: nobody to hand the token to */
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    send_token(s, to, now);
    if (to == ts(s)) {
        s->stats.tokens_to_self++;
        take_token(s, ts(s), s->last_activity);
        return s->line_free;
    }
    s->activity_seen = false;
    s->deadline = s->last_activity + us(s, s->cfg.bus.tsl_bits) + char_us(s);
    s->state = FDL_MAC_CHECK_TOKEN_PASS;
    return s->deadline;
}

/* No character from the successor within TSL: the token again, FDL_TOKEN_PASS_REPEATS times
 * whatever the message retry limit (a successor that refuses a new PS's first token must get the
 * second), then the next station of the LAS; with none left the station passes to itself. */
static hal_time_us_t token_pass_failed(fdl_active_t *s, hal_time_us_t now)
{
    if (s->pass_tries < FDL_TOKEN_PASS_REPEATS) {
        s->pass_tries++;
        s->stats.token_retries++;
    } else {
        uint8_t gone = s->pass_to;
        s->stats.stations_skipped++;
        emit(s, (fdl_active_event_t){.type = FDL_EV_PASS_FAILED, .t = now, .state = s->state,
                                     .address = gone});
        las_put(s, gone, false, now);
        live_put(s, gone, FDL_STATION_NONE, now);
        s->pass_to = las_next(s, gone);
        s->ns = s->pass_to;
        s->pass_tries = 0;
        emit(s, (fdl_active_event_t){.type = FDL_EV_NEW_SUCCESSOR, .t = now, .state = s->state,
                                     .address = s->ns});
    }
    s->state = FDL_MAC_PASS_TOKEN;
    return pass_token(s, now);
}

/* Claim_Token: the bus was silent for TTO. The ring starts again from this station alone (two
 * tokens to itself), GAP maintenance at once to find the others. */
static hal_time_us_t claim_token(fdl_active_t *s, hal_time_us_t now)
{
    if (!hal_time_reached(now, s->line_free)) {
        return s->line_free;
    }
    send_token(s, ts(s), now);
    if (++s->claim_tokens < 2u) {
        return s->line_free;
    }
    gap_sweep_start(s); /* the ring is rebuilt by GAP maintenance at once */
    s->have_token_t = false;
    take_token(s, ts(s), s->last_activity);
    return s->line_free;
}

static hal_time_us_t idle_poll(fdl_active_t *s, hal_time_us_t now)
{
    if (s->answer_pending) {
        if (!hal_time_reached(now, s->answer_at)) {
            return s->answer_at;
        }
        send_status_answer(s, now);
    }
    hal_time_us_t lost = tto_end(s);
    if (!hal_time_reached(now, lost)) {
        return lost;
    }
    s->stats.claims++;
    emit(s, (fdl_active_event_t){.type = FDL_EV_CLAIM, .t = now, .state = s->state,
                                 .address = ts(s)});
    memset(s->las, 0, sizeof s->las);
    s->ns = ts(s);
    s->claim_tokens = 0;
    set_state(s, FDL_MAC_CLAIM_TOKEN, now);
    return claim_token(s, now);
}

hal_time_us_t fdl_active_poll(fdl_active_t *s, hal_time_us_t now)
{
    hal_time_us_t far = now + HAL_TIME_NO_DEADLINE_US;
    switch (s->state) {
    case FDL_MAC_OFFLINE:
        return far;
    case FDL_MAC_LISTEN_TOKEN:
    case FDL_MAC_ACTIVE_IDLE:
        return idle_poll(s, now);
    case FDL_MAC_CLAIM_TOKEN:
        return claim_token(s, now);
    case FDL_MAC_USE_TOKEN:
        return far; /* the user's turn: it releases the token */
    case FDL_MAC_AWAIT_STATUS_RESPONSE:
        if (!hal_time_reached(now, s->deadline)) {
            return s->deadline;
        }
        if (s->activity_seen && hal_time_diff(now, s->last_activity) < (int32_t)char_us(s)) {
            /* an answer is coming in: give its characters their time */
            s->deadline = now + char_us(s);
            return s->deadline;
        }
        live_put(s, s->gap_asked, FDL_STATION_NONE, now);
        s->state = FDL_MAC_PASS_TOKEN;
        return pass_token(s, now);
    case FDL_MAC_PASS_TOKEN:
        return pass_token(s, now);
    case FDL_MAC_CHECK_TOKEN_PASS:
        if (!hal_time_reached(now, s->deadline)) {
            return s->deadline;
        }
        return token_pass_failed(s, now);
    }
    return far;
}

const char *fdl_mac_state_name(fdl_mac_state_t st)
{
    static const char *const names[] = {
        "Offline",   "Listen_Token", "Active_Idle", "Claim_Token",
        "Use_Token", "Await_Status_Response", "Pass_Token", "Check_Token_Pass",
    };
    return (unsigned)st < sizeof names / sizeof names[0] ? names[st] : "?";
}

const char *fdl_station_kind_name(fdl_station_kind_t k)
{
    static const char *const names[] = {"unknown", "none", "passive", "master not ready",
                                        "master ready", "master in ring"};
    return (unsigned)k < sizeof names / sizeof names[0] ? names[k] : "?";
}
