/* The FDL station: everything layer 2 does before and after the DP slave machine. A telegram's
 * way: character -> fdl_rx -> baud found -> address and FC checks (TSYN) -> FDL status / SDN /
 * SRD -> FCB retry cache -> dp_slave_request() -> reply encoding -> HAL transmit at end of
 * request + min TSDR (protocol.md §A1.4, §A1.5, §A2.1, §A2.3). */
#include <string.h>

#include "dp_slave/fdl_wire.h"
#include "dp_slave_internal.h"

uint32_t dp_baud_search_dwell_us(uint32_t baud)
{
    /* Two telegrams of the maximum 255 characters, but never below 20 ms: a master that
     * repeats its requests every few milliseconds is heard on every rate it might use. */
    uint64_t us = (2ull * FDL_FRAME_MAX * FDL_CHAR_BITS * HAL_US_PER_S) / baud;
    return us < DP_BAUD_SEARCH_DWELL_MIN_US ? DP_BAUD_SEARCH_DWELL_MIN_US : (uint32_t)us;
}

void fdl_station_timing_changed(dp_slave_t *s)
{
    /* min TSDR counts from the request's last stop bit, but the request's end is known only as
     * a microsecond timestamp, up to a microsecond before the true end: at 1.5 Mbit/s and above
     * that is more than a bit time, and an answer timed from the timestamp alone came before
     * min TSDR (IEC 61158-4-3: a responder waits at least min TSDR). */
    s->min_tsdr_us = hal_uart_bits_us(s->baud, s->min_tsdr_bits) + FDL_TIMESTAMP_RESOLUTION_US;
}

/* Returns false when the UART cannot make the rate; the station then keeps its old one. */
static bool select_baud(dp_slave_t *s, uint32_t baud)
{
    if (s->cfg.uart.ops != NULL && s->cfg.uart.ops->set_baud != NULL &&
        s->cfg.uart.ops->set_baud(s->cfg.uart.ctx, baud) != 0) {
        return false;
    }
    s->baud = baud;
    fdl_station_timing_changed(s);
    fdl_rx_set_baud(&s->rx, baud);
    return true;
}

/* The next rate of the search, from hal_uart_bauds[from] on, that the UART can make. A refused
 * rate is passed over: left in place, the UART would go on listening at the old rate, and a
 * telegram heard there would make the refused rate the line's (its timing, P092). */
static void search_from(dp_slave_t *s, uint8_t from, hal_time_us_t now)
{
    uint8_t i = from;
    for (unsigned tries = 0; tries < HAL_UART_NUM_BAUDS; tries++) {
        if (select_baud(s, hal_uart_bauds[i])) {
            break;
        }
        i = (uint8_t)((i + 1u) % HAL_UART_NUM_BAUDS);
    }
    s->baud_index = i;
    s->baud_deadline = now + dp_baud_search_dwell_us(s->baud);
    dp_slave_emit(s, DP_EV_BAUD_SET, now, s->baud, 0);
}

void fdl_station_watchdog_changed(dp_slave_t *s)
{
    uint32_t ms = s->cfg.baud_control_ms != 0u ? s->cfg.baud_control_ms : DP_BAUD_CONTROL_MS_DEFAULT;
    s->baud_control_base_us = ms * 1000u;
    if (s->wd_on && s->wd_time_ms * 2u > ms) {
        ms = s->wd_time_ms * 2u; /* never lose the rate before the DP watchdog could expire */
    }
    s->baud_control_us = ms * 1000u;
}

void fdl_station_start_baud(dp_slave_t *s, hal_time_us_t now)
{
    if (s->cfg.fixed_baud != 0u) {
        s->baud_state = DP_BAUD_FIXED;
        /* A fixed rate the UART refuses leaves the station deaf; its rate is still the one
         * configured, so P092 and the timing say what was asked for. */
        if (!select_baud(s, s->cfg.fixed_baud)) {
            s->baud = s->cfg.fixed_baud;
            fdl_station_timing_changed(s);
            fdl_rx_set_baud(&s->rx, s->baud);
        }
    } else {
        s->baud_state = DP_BAUD_SEARCH;
        search_from(s, 0u, now);
    }
}

hal_time_us_t fdl_station_poll(dp_slave_t *s, hal_time_us_t now)
{
    hal_time_us_t next = fdl_rx_poll(&s->rx, now);
    if (s->baud_state != DP_BAUD_SEARCH && s->baud_state != DP_BAUD_CONTROL) {
        return next;
    }
    if (hal_time_reached(now, s->baud_deadline)) {
        uint8_t from = 0u;
        if (s->baud_state == DP_BAUD_CONTROL) {
            s->baud_state = DP_BAUD_SEARCH;
            s->line_active = false;
            s->addressed_reported = false;
            dp_slave_emit(s, DP_EV_BAUD_LOST, now, s->baud, 0);
        } else {
            from = (uint8_t)((s->baud_index + 1u) % HAL_UART_NUM_BAUDS);
        }
        search_from(s, from, now);
    }
    return hal_time_earlier(next, s->baud_deadline);
}

/* ---- replies ------------------------------------------------------------------------------ */

static const uint8_t short_ack = FDL_SC;

void fdl_station_reply_sc(dp_slave_t *s)
{
    s->tx = &short_ack;
    s->tx_len = FDL_SC_LEN;
}

/* A reply whose DU lies at buf + FDL_TX_HEADROOM with the octet sum du_sum. */
void fdl_station_reply_framed(dp_slave_t *s, const fdl_msg_t *m, uint8_t code, bool saps,
                              uint8_t *buf, size_t du_len, uint8_t du_sum)
{
    size_t len;
    s->tx = fdl_frame_in_place(buf, du_len, du_sum, m->sa, s->cfg.address, code, saps, m->ssap,
                               m->dsap, &len);
    s->tx_len = (uint16_t)len;
}

static void reply_copied(dp_slave_t *s, const fdl_msg_t *m, uint8_t code, bool saps,
                         const uint8_t *data, size_t len)
{
    uint8_t *du = &s->tx_buf[FDL_TX_HEADROOM];
    if (len > 0u) {
        memcpy(du, data, len);
    }
    fdl_station_reply_framed(s, m, code, saps, s->tx_buf, len, fdl_fcs(du, len));
}

/* A reply without SAP octets: RS/RR/UE status or Data_Exchange data. */
void fdl_station_reply_plain(dp_slave_t *s, const fdl_msg_t *m, uint8_t code,
                             const uint8_t *data, size_t len)
{
    reply_copied(s, m, code, false, data, len);
}

/* A reply to a SAP request: SAPs swapped. */
void fdl_station_reply_sap(dp_slave_t *s, const fdl_msg_t *m, const uint8_t *data, size_t len)
{
    reply_copied(s, m, FDL_RSP_DL, true, data, len);
}

void fdl_station_reply_rs(dp_slave_t *s, const fdl_msg_t *m)
{
    fdl_station_reply_framed(s, m, FDL_RSP_RS, false, s->tx_buf, 0, 0);
}

/* ---- FCB retry cache (protocol.md §A1.5) -------------------------------------------------- */

/* The master's slot, or the least recently used one taken over for it (fcb_victim, worked out
 * after the reply by fdl_station_prepare()). The clock ticks when the master served changes, not
 * per request, so the usual case (one owner polling) is a single comparison; a slot's age is the
 * clock minus its stamp, which survives the clock's wrap. */
static fdl_fcb_slot_t *fcb_slot(dp_slave_t *s, uint8_t master)
{
    fdl_fcb_slot_t *take = &s->fcb[s->fcb_last];
    if (take->master == master) {
        return take;
    }
    uint8_t i = 0;
    while (i < FDL_FCB_SLOTS && s->fcb[i].master != master) {
        i++; /* a master switching back (class 1 and class 2 in turn) */
    }
    if (i == FDL_FCB_SLOTS) {
        i = s->fcb_victim;
        take = &s->fcb[i];
        take->master = master;
        take->fcb_valid = false;
        take->reply_len = 0;
    }
    take = &s->fcb[i];
    take->stamp = ++s->fcb_clock;
    s->fcb_last = i;
    s->fcb_victim_stale = true;
    return take;
}

void fdl_station_prepare(dp_slave_t *s)
{
    if (!s->fcb_victim_stale) {
        return;
    }
    /* A free slot (master FDL_FCB_FREE, stamp 0) is older than any used one until the clock
     * first wraps, and no slot is free by then. */
    uint32_t now = s->fcb_clock;
    uint8_t victim = 0;
    for (uint8_t i = 1; i < FDL_FCB_SLOTS; i++) {
        if (now - s->fcb[i].stamp > now - s->fcb[victim].stamp) {
            victim = i;
        }
    }
    s->fcb_victim = victim;
    s->fcb_victim_stale = false;
}

bool fdl_station_references(dp_slave_t *s, const uint8_t *buf, bool forget)
{
    bool found = false;
    for (fdl_fcb_slot_t *e = &s->fcb[0]; e < &s->fcb[FDL_FCB_SLOTS]; e++) {
        if (e->reply_len > 0u && (uintptr_t)e->reply - (uintptr_t)buf < FDL_TX_HEADROOM) {
            found = true;
            if (forget) {
                e->reply_len = 0;
            }
        }
    }
    return found;
}

/* ---- receive path ------------------------------------------------------------------------- */

static void transmit(dp_slave_t *s, const uint8_t *frame, size_t len, hal_time_us_t request_end)
{
    if (len == 0u || s->cfg.uart.ops == NULL || s->cfg.uart.ops->transmit == NULL) {
        return;
    }
    hal_time_us_t not_before = request_end + s->min_tsdr_us;
    s->tx_last = frame;
    (void)s->cfg.uart.ops->transmit(s->cfg.uart.ctx, frame, len, not_before);
}

/* Any error-free data telegram, for whomever, proves the rate: the baud search ends. */
static void note_line_activity(dp_slave_t *s, uint8_t sd, hal_time_us_t t)
{
    if (sd != FDL_SD1 && sd != FDL_SD2 && sd != FDL_SD3) {
        return;
    }
    s->line_active = true;
    if (s->baud_state == DP_BAUD_SEARCH) {
        s->baud_state = DP_BAUD_CONTROL;
        s->baud_deadline = t + s->baud_control_us;
        dp_slave_emit(s, DP_EV_BAUD_FOUND, t, s->baud, 0);
    }
}

/* TSYN: a request must follow at least 33 idle bits (protocol.md §A2.1), checked only where the
 * medium lets the receiver measure the gap (strict timing). */
static bool tsyn_violated(const dp_slave_t *s)
{
    /* idle_before_ns is UINT32_MAX when unknown, never below the threshold */
    return s->rx.strict && s->rx.idle_before_ns < s->rx.tsyn_short_ns;
}

/* Parses the telegram and keeps it if it is a request for this station or a broadcast. */
static bool accept_request(dp_slave_t *s, fdl_msg_t *m, hal_time_us_t t, bool *first)
{
    if (fdl_parse(s->rx.frame, s->rx.frame_len, m) != FDL_PARSE_OK) {
        return false;
    }
    if ((m->fc & FDL_FC_REQUEST) == 0u) {
        return false; /* a response between other stations */
    }
    bool broadcast = m->da == FDL_ADDR_BROADCAST;
    if (m->da != s->cfg.address && !broadcast) {
        return false;
    }
    if (m->sa == FDL_ADDR_BROADCAST) {
        /* 127 is the global address, a destination only (protocol.md §A1.3): served, such a
         * telegram would lock the slave to "master 127" and be answered to everyone. */
        return false;
    }
    if (tsyn_violated(s)) {
        s->rx.error_count[FDL_RX_ERR_TSYN]++;
        dp_slave_emit(s, DP_EV_RX_ERROR, t, FDL_RX_ERR_TSYN, m->sa);
        return false;
    }
    if (!broadcast) {
        s->telegrams_for_me++;
        if (s->baud_state == DP_BAUD_CONTROL) {
            s->baud_deadline = t + s->baud_control_us;
        }
        if (!s->addressed_reported) {
            s->addressed_reported = true;
            *first = true; /* reported after the reply, which does not wait for the LEDs */
        }
    }
    /* The DP watchdog counts any telegram of the owning master, whatever its service. */
    if (s->wd_on && s->state != DP_STATE_WAIT_PRM && m->sa == s->master_add) {
        s->wd_deadline = t + s->wd_time_us;
    }
    return true;
}

/* SRD: a retry (same FCB, FCV set) gets the cached reply and is not executed again; anything
 * else runs and its reply is cached, by reference, for the next retry. */
static void serve_srd(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    bool fcv = (m->fc & FDL_FC_FCV) != 0u;
    uint8_t fcb = (m->fc & FDL_FC_FCB) != 0u ? 1u : 0u;
    fdl_fcb_slot_t *slot = fcb_slot(s, m->sa);
    if (fcv && slot->fcb_valid && slot->fcb == fcb && slot->reply_len > 0u &&
        (slot->guard == NULL || *slot->guard == slot->guard_value)) {
        transmit(s, slot->reply, slot->reply_len, t);
        dp_slave_emit(s, DP_EV_FCB_REPEAT, t, m->fc, m->sa); /* after: the reply does not wait */
        return;
    }
    slot->reply_len = 0; /* its buffer is about to be written */
    s->tx_buf = slot->buf;
    s->tx_guard = NULL;
    s->tx_sent = false;
    dp_slave_request(s, m, false, t);
    slot->fcb_valid = fcv || fcb != 0u;
    slot->fcb = fcb;
    slot->reply = s->tx;
    slot->reply_len = s->tx_len;
    slot->guard = s->tx_guard;
    slot->guard_value = s->tx_guard_value;
    if (!s->tx_sent) {
        transmit(s, s->tx, s->tx_len, t);
    }
}

void fdl_station_send_now(dp_slave_t *s, hal_time_us_t request_end)
{
    if (s->tx_buf == s->tx_scratch) {
        return; /* an SDN: nothing is answered */
    }
    s->tx_sent = true;
    transmit(s, s->tx, s->tx_len, request_end);
}

void fdl_station_frame(dp_slave_t *s)
{
    hal_time_us_t t = s->rx.frame_end_t;
    note_line_activity(s, s->rx.frame[0], t);
    fdl_msg_t m;
    bool first = false;
    if (!accept_request(s, &m, t, &first)) {
        return;
    }
    bool broadcast = m.da == FDL_ADDR_BROADCAST;
    switch ((uint8_t)(m.fc & FDL_FC_CODE_MASK)) {
    case FDL_REQ_FDL_STATUS:
        if (!broadcast) {
            fdl_station_reply_framed(s, &m, FDL_RSP_OK, false, s->tx_scratch, 0, 0);
            transmit(s, s->tx, s->tx_len, t);
        }
        break;
    case FDL_REQ_SDN_LOW:
    case FDL_REQ_SDN_HIGH:
        s->tx_buf = s->tx_scratch; /* an SDN has no reply; nothing may be built in a slot */
        dp_slave_request(s, &m, true, t);
        break;
    case FDL_REQ_SRD_LOW:
    case FDL_REQ_SRD_HIGH:
        if (!broadcast) { /* a request with reply cannot go to everybody */
            serve_srd(s, &m, t);
        }
        break;
    default:
        if (!broadcast) {
            s->tx_buf = s->tx_scratch;
            fdl_station_reply_rs(s, &m);
            transmit(s, s->tx, s->tx_len, t);
        }
        break;
    }
    if (first) {
        dp_slave_emit(s, DP_EV_ADDRESSED, t, m.fc, m.sa);
    }
}
