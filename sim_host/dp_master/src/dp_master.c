#include "dp_master/dp_master.h"
#include "dp_master_internal.h"

#include <stdio.h>
#include <string.h>

#include "dp_master/dpv1_c2.h"

#include "dp_slave/dp_cfg.h"
#include "dp_slave/dp_services.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

static void emit(dp_master_t *m, const dp_master_event_t *ev)
{
    if (m->cfg.event != NULL) {
        m->cfg.event(m->cfg.event_ctx, ev);
    }
}

void dpm_set_phase(dp_master_t *m, unsigned idx, dp_master_phase_t next, hal_time_us_t t)
{
    dp_master_slave_t *s = &m->slaves[idx];
    if (s->phase == next) {
        return;
    }
    dp_master_event_t ev = {.type = DP_MASTER_EV_PHASE, .t = t, .slave = s->cfg.address,
                      .old_phase = s->phase, .new_phase = next};
    s->phase = next;
    emit(m, &ev);
}

/* MSAC1 closes when the slave leaves Data_Exch: a request the card already took is lost. One
 * not sent yet waits for the next Data_Exch. */
static void c1_lost(dp_master_slave_t *s, hal_time_us_t t, const char *why)
{
    s->c1_turn = false;
    if (dp_master_xfer_busy(&s->c1) && s->c1.started) {
        dp_master_xfer_fail(&s->c1, t, "slave %u restarted (%s); the request is lost",
                            s->cfg.address, why);
    }
}

static void restart_slave(dp_master_t *m, unsigned idx, hal_time_us_t t, const char *why)
{
    dp_master_slave_t *s = &m->slaves[idx];
    bool lost = s->phase == DP_MASTER_PHASE_FDL_STATUS;
    (void)snprintf(s->fault, sizeof s->fault, "%s", why);
    dp_master_event_t ev = {.type = DP_MASTER_EV_FAULT, .t = t, .slave = s->cfg.address,
                            .text = s->fault, .old_phase = s->phase,
                            .new_phase = DP_MASTER_PHASE_BACKOFF};
    emit(m, &ev);
    s->restarts++;
    s->fcb_first = true;
    if (lost) {
        /* Nobody answers at this address (yet): ask again at a steady, modest rate, as a
         * master's GAP update does, so a slave still searching for the baud rate hears us. */
        s->due = t + m->cfg.lost_poll_us;
    } else {
        /* The slave answers but refuses: back off so a broken slave is not hammered. */
        s->due = t + s->backoff_us;
        s->backoff_us = s->backoff_us * 2u > m->cfg.backoff_max_us ? m->cfg.backoff_max_us
                                                                   : s->backoff_us * 2u;
    }
    dpm_set_phase(m, idx, DP_MASTER_PHASE_BACKOFF, t);
    c1_lost(s, t, why);
}

void dp_master_init(dp_master_t *m, const dp_master_cfg_t *cfg, hal_time_us_t now)
{
    memset(m, 0, sizeof *m);
    m->cfg = *cfg;
    if (m->cfg.slot_time_us == 0u) {
        uint32_t b = cfg->baud;
        uint32_t bits = b <= 187500u ? 100u : b <= 500000u ? 200u : b <= 1500000u ? 300u
                        : b <= 3000000u ? 400u : b <= 6000000u ? 600u : 1000u;
        m->cfg.slot_time_us = hal_uart_bits_us(b, bits);
    }
    if (cfg->token_ring) {
        dpm_ring_init(m, now);
    }
    if (m->cfg.max_retry == 0u && !cfg->token_ring) m->cfg.max_retry = 1u; /* ring: the bus's */
    if (m->cfg.backoff_min_us == 0u) m->cfg.backoff_min_us = 10000u;
    if (m->cfg.backoff_max_us == 0u) m->cfg.backoff_max_us = 1000000u;
    if (m->cfg.lost_poll_us == 0u) m->cfg.lost_poll_us = 5000u;
    if (m->cfg.c1_timeout_us == 0u) m->cfg.c1_timeout_us = DP_MASTER_C1_TIMEOUT_US_DEFAULT;
    fdl_rx_init(&m->rx, cfg->baud, cfg->strict_timing);
    if (cfg->uart.ops != NULL && cfg->uart.ops->set_baud != NULL) {
        (void)cfg->uart.ops->set_baud(cfg->uart.ctx, cfg->baud);
    }
    m->running = true;
    m->next_send = now;
}

int dp_master_add_slave(dp_master_t *m, const dp_master_slave_cfg_t *sc)
{
    if (m->num_slaves >= DP_MASTER_MAX_SLAVES || sc->prm_len < DP_PRM_LEN_STANDARD) {
        return -1;
    }
    uint16_t out_len;
    uint16_t in_len;
    if (!dp_cfg_io_lengths(sc->cfg, sc->cfg_len, &out_len, &in_len)) {
        return -1;
    }
    dp_master_slave_t *s = &m->slaves[m->num_slaves];
    memset(s, 0, sizeof *s);
    s->cfg = *sc;
    s->out_len = out_len;
    s->in_len = in_len;
    s->fcb_first = true;
    s->phase = DP_MASTER_PHASE_FDL_STATUS;
    s->backoff_us = m->cfg.backoff_min_us;
    /* Due at once. Not 0: on a wall clock 0 can be more than 2^31 us in the past, which the
     * wrapping comparison reads as the future. */
    s->due = m->next_send;
    return m->num_slaves++;
}

int dp_master_reconfigure(dp_master_t *m, unsigned idx, const dp_master_slave_cfg_t *sc,
                          hal_time_us_t now)
{
    uint16_t out_len;
    uint16_t in_len;
    if (idx >= m->num_slaves || sc->prm_len < DP_PRM_LEN_STANDARD ||
        !dp_cfg_io_lengths(sc->cfg, sc->cfg_len, &out_len, &in_len)) {
        return -1;
    }
    dp_master_slave_t *s = &m->slaves[idx];
    s->cfg = *sc;
    s->out_len = out_len;
    s->in_len = in_len;
    s->fcb_first = true;
    s->due = now;
    s->backoff_us = m->cfg.backoff_min_us;
    memset(s->outputs, 0, sizeof s->outputs);
    dpm_set_phase(m, idx, DP_MASTER_PHASE_FDL_STATUS, now);
    c1_lost(s, now, "new parameters");
    return 0;
}

void dp_master_set_outputs(dp_master_t *m, unsigned idx, const uint8_t *out, size_t len)
{
    if (idx >= m->num_slaves) {
        return;
    }
    dp_master_slave_t *s = &m->slaves[idx];
    memcpy(s->outputs, out, len < s->out_len ? len : s->out_len);
}

void dp_master_global_control(dp_master_t *m, uint8_t command, uint8_t group_select)
{
    m->gc_pending = true;
    m->gc_command = command;
    m->gc_group = group_select;
}

void dp_master_stop(dp_master_t *m)
{
    m->running = false;
    m->waiting = false;
    if (m->cfg.token_ring) {
        fdl_active_stop(&m->mac, m->mac.last_activity);
    }
}

void dp_master_start(dp_master_t *m, hal_time_us_t now)
{
    m->running = true;
    m->waiting = false;
    m->next_send = now;
    if (m->cfg.token_ring) {
        fdl_active_start(&m->mac, now);
    }
    /* A class-2 telegram that was on the wire when the master stopped will never be answered:
     * settle it now, or a later Abort waits for that answer for ever (soak finding
     * c2_abort_stuck). */
    for (unsigned k = 0; k < m->num_c2; k++) {
        if (m->c2[k]->on_wire) {
            dp_master_c2_no_answer(m->c2[k], now);
        }
    }
    for (unsigned i = 0; i < m->num_slaves; i++) {
        m->slaves[i].fcb_first = true;
        m->slaves[i].due = now;
        dpm_set_phase(m, i, DP_MASTER_PHASE_FDL_STATUS, now);
        c1_lost(&m->slaves[i], now, "master restarted");
    }
}

/* ---- DP-V1 -------------------------------------------------------------------------------- */

int dp_master_c1_submit(dp_master_t *m, unsigned idx, const uint8_t *pdu, size_t len,
                        dp_master_acyc_done_t done, void *ctx)
{
    if (idx >= m->num_slaves) {
        return -1;
    }
    dp_master_slave_t *s = &m->slaves[idx];
    if (!dp_master_prm_is_dpv1(s->cfg.prm, s->cfg.prm_len)) {
        return -1;
    }
    return dp_master_xfer_start(&s->c1, DPV1_SAP_C1, DPV1_SAP_C1, pdu, len, m->cfg.c1_timeout_us,
                                done, ctx);
}

bool dp_master_c1_busy(const dp_master_t *m, unsigned idx)
{
    return idx < m->num_slaves && dp_master_xfer_busy(&m->slaves[idx].c1);
}

static int c1_port_submit(void *ctx, unsigned idx, const uint8_t *pdu, size_t len,
                          dp_master_acyc_done_t done, void *done_ctx, hal_time_us_t now)
{
    (void)now;
    return dp_master_c1_submit(ctx, idx, pdu, len, done, done_ctx);
}

dp_master_acyc_port_t dp_master_c1_port(dp_master_t *m, unsigned idx)
{
    return (dp_master_acyc_port_t){.submit = c1_port_submit, .ctx = m, .idx = idx};
}

int dp_master_add_c2(dp_master_t *m, struct dp_master_c2 *c)
{
    if (m->num_c2 >= DP_MASTER_MAX_C2) {
        return -1;
    }
    m->c2[m->num_c2++] = c;
    return 0;
}

/* The FCB sequence of one (our address, slave) pair. The slave keeps one FCB per initiator
 * address, whatever the SAP, so class-1 telegrams, DP-V0 services and class-2 connections from
 * the same address to the same slave share one sequence. */
static void pair_fcb(dp_master_t *m, uint8_t own, uint8_t slave, bool **first, bool **fcb)
{
    if (own == m->cfg.address) {
        for (unsigned i = 0; i < m->num_slaves; i++) {
            if (m->slaves[i].cfg.address == slave) {
                *first = &m->slaves[i].fcb_first;
                *fcb = &m->slaves[i].fcb;
                return;
            }
        }
    }
    dp_master_fcb_t *free_slot = NULL;
    for (unsigned i = 0; i < sizeof m->fcbs / sizeof m->fcbs[0]; i++) {
        dp_master_fcb_t *f = &m->fcbs[i];
        if (f->used && f->own == own && f->slave == slave) {
            *first = &f->first;
            *fcb = &f->fcb;
            return;
        }
        if (!f->used && free_slot == NULL) {
            free_slot = f;
        }
    }
    if (free_slot == NULL) {
        free_slot = &m->fcbs[0]; /* more pairs than slots: start that pair afresh */
    }
    *free_slot = (dp_master_fcb_t){.used = true, .own = own, .slave = slave, .first = true};
    *first = &free_slot->first;
    *fcb = &free_slot->fcb;
}

/* ---- sending ------------------------------------------------------------------------------ */

static uint32_t idle_before_request_us(const dp_master_t *m)
{
    /* TSYN (33 bit) is the minimum; TID1 (37 bit) is the usual idle after a reply. One extra
     * microsecond absorbs the rounding of microsecond timestamps at high rates. */
    return hal_uart_bits_us(m->cfg.baud, 37u) + 1u;
}

static void send(dp_master_t *m, hal_time_us_t now, bool expect_reply, unsigned idx)
{
    uint32_t char_ns = hal_uart_char_ns(m->cfg.baud);
    uint32_t tx_us = (uint32_t)(((uint64_t)char_ns * m->request_len + 999u) / 1000u);
    if (m->cfg.uart.ops != NULL && m->cfg.uart.ops->transmit != NULL) {
        (void)m->cfg.uart.ops->transmit(m->cfg.uart.ctx, m->request, m->request_len, now);
    }
    if (m->cfg.token_ring) {
        fdl_active_sent(&m->mac, now, now + tx_us, expect_reply);
    }
    fdl_rx_reset(&m->rx);
    if (expect_reply) {
        m->waiting = true;
        m->waiting_for = (uint8_t)idx;
        m->reply_deadline = now + tx_us + m->cfg.slot_time_us;
    } else {
        m->next_send = now + tx_us + hal_uart_bits_us(m->cfg.baud, 100u); /* TID2 after SDN */
    }
}

static uint8_t fc_with(bool first, bool fcb, bool high)
{
    uint8_t code = high ? FDL_REQ_SRD_HIGH : FDL_REQ_SRD_LOW;
    if (first) {
        return (uint8_t)(FDL_FC_REQUEST | FDL_FC_FCB | code);
    }
    return (uint8_t)(FDL_FC_REQUEST | FDL_FC_FCV | (fcb ? FDL_FC_FCB : 0u) | code);
}

static uint8_t next_fc(dp_master_slave_t *s, bool high)
{
    return fc_with(s->fcb_first, s->fcb, high);
}

/* A reply completed the request: the next one toggles FCB. */
static void fcb_advance(bool *first, bool *fcb)
{
    *fcb = *first ? false : !*fcb;
    *first = false;
}

static void build_request(dp_master_t *m, dp_master_slave_t *s)
{
    uint8_t da = s->cfg.address;
    uint8_t sa = m->cfg.address;
    size_t n = 0;
    switch (s->phase) {
    case DP_MASTER_PHASE_FDL_STATUS:
        n = fdl_encode(m->request, da, sa, FDL_FC_REQUEST | FDL_REQ_FDL_STATUS, false, 0, 0,
                       NULL, 0);
        break;
    case DP_MASTER_PHASE_DIAG_1:
    case DP_MASTER_PHASE_DIAG_2:
    case DP_MASTER_PHASE_DIAG_DX:
        n = fdl_encode(m->request, da, sa, next_fc(s, true), true, DP_SAP_SLAVE_DIAG,
                       DP_SAP_MASTER, NULL, 0);
        break;
    case DP_MASTER_PHASE_SET_PRM:
        n = fdl_encode(m->request, da, sa, next_fc(s, true), true, DP_SAP_SET_PRM, DP_SAP_MASTER,
                       s->cfg.prm, s->cfg.prm_len);
        break;
    case DP_MASTER_PHASE_CHK_CFG:
        n = fdl_encode(m->request, da, sa, next_fc(s, true), true, DP_SAP_CHK_CFG, DP_SAP_MASTER,
                       s->cfg.cfg, s->cfg.cfg_len);
        break;
    case DP_MASTER_PHASE_DATA_EXCH:
        n = fdl_encode(m->request, da, sa, next_fc(s, true), false, 0, 0, s->outputs,
                       s->out_len);
        break;
    case DP_MASTER_PHASE_BACKOFF:
        break;
    }
    m->request_len = (uint16_t)n;
}

/* ---- receiving ---------------------------------------------------------------------------- */

/* A diagnosis in one of the DIAG phases: the first decides whether to parameterise the slave,
 * the later ones whether it is ready for data exchange. */
static void diag_received(dp_master_t *m, unsigned idx, const fdl_msg_t *msg, hal_time_us_t t)
{
    dp_master_slave_t *s = &m->slaves[idx];
    const uint8_t *d = msg->data;
    s->last_diag_len = msg->data_len;
    memcpy(s->last_diag, d, msg->data_len);
    dp_master_event_t ev = {.type = DP_MASTER_EV_DIAG, .t = t, .slave = s->cfg.address, .data = d,
                      .len = msg->data_len, .old_phase = s->phase, .new_phase = s->phase};
    emit(m, &ev);
    if (s->phase == DP_MASTER_PHASE_DIAG_1) {
        uint16_t ident = (uint16_t)((d[DP_DIAG_IDENT_HIGH] << 8) | d[DP_DIAG_IDENT_LOW]);
        uint16_t want = (uint16_t)((s->cfg.prm[DP_PRM_IDENT_HIGH] << 8) |
                                   s->cfg.prm[DP_PRM_IDENT_LOW]);
        if (ident != want) {
            restart_slave(m, idx, t, "ident number differs from the configuration");
        } else if (d[DP_DIAG_MASTER_ADD] != DP_MASTER_ADD_NONE &&
                   d[DP_DIAG_MASTER_ADD] != m->cfg.address &&
                   (d[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ) == 0u) {
            /* The card does not refuse us with RS: its diagnosis names the owner. */
            char why[48];
            (void)snprintf(why, sizeof why, "slave is locked by master %u",
                           (unsigned)d[DP_DIAG_MASTER_ADD]);
            restart_slave(m, idx, t, why);
        } else {
            dpm_set_phase(m, idx, DP_MASTER_PHASE_SET_PRM, t);
        }
        return;
    }
    uint8_t st1 = d[DP_DIAG_STATUS_1];
    uint8_t st2 = d[DP_DIAG_STATUS_2];
    if ((st1 & DP_DIAG1_PRM_FAULT) != 0u) {
        restart_slave(m, idx, t, "Prm_Fault: slave refused the parameters");
    } else if ((st1 & DP_DIAG1_CFG_FAULT) != 0u) {
        restart_slave(m, idx, t, "Cfg_Fault: slave refused the configuration");
    } else if ((st1 & DP_DIAG1_NOT_SUPPORTED) != 0u) {
        restart_slave(m, idx, t, "Not_Supported: slave lacks a requested function");
    } else if ((st2 & DP_DIAG2_PRM_REQ) != 0u || (st1 & DP_DIAG1_STATION_NOT_READY) != 0u) {
        if ((st2 & DP_DIAG2_STAT_DIAG) != 0u && s->stat_diag_repeats < 100u) {
            s->stat_diag_repeats++; /* slave asks to be polled for diagnosis again */
        } else {
            restart_slave(m, idx, t, "slave is not ready for data exchange");
        }
    } else {
        s->stat_diag_repeats = 0;
        s->backoff_us = m->cfg.backoff_min_us;
        dpm_set_phase(m, idx, DP_MASTER_PHASE_DATA_EXCH, t);
    }
}

/* A Data_Exchange answer: the inputs, and a diagnosis request when the slave flags one. */
static void data_exchange_received(dp_master_t *m, unsigned idx, const fdl_msg_t *msg, bool sc,
                                   uint8_t code, hal_time_us_t t)
{
    dp_master_slave_t *s = &m->slaves[idx];
    if (!sc && (code == FDL_RSP_RS || code == FDL_RSP_RR || code == FDL_RSP_UE)) {
        restart_slave(m, idx, t, code == FDL_RSP_RS ? "RS: slave left data exchange"
                                                    : "slave refused Data_Exchange");
        return;
    }
    s->cycles++;
    s->c1_turn = true;
    s->inputs_len = sc ? 0u : msg->data_len;
    if (!sc) {
        memcpy(s->inputs, msg->data, msg->data_len);
    }
    dp_master_event_t ev = {.type = DP_MASTER_EV_INPUTS, .t = t, .slave = s->cfg.address,
                      .data = s->inputs, .len = s->inputs_len, .old_phase = s->phase,
                      .new_phase = s->phase};
    emit(m, &ev);
    if (!sc && (code == FDL_RSP_DH || code == FDL_RSP_RDH)) {
        dpm_set_phase(m, idx, DP_MASTER_PHASE_DIAG_DX, t);
    }
}

/* An acknowledgement (sc: short acknowledgement) moves a Set_Prm or Chk_Cfg phase on. */
static void ack_received(dp_master_t *m, unsigned idx, bool sc, hal_time_us_t t)
{
    bool set_prm = m->slaves[idx].phase == DP_MASTER_PHASE_SET_PRM;
    if (!sc) {
        restart_slave(m, idx, t, set_prm ? "Set_Prm not acknowledged"
                                         : "Chk_Cfg not acknowledged");
        return;
    }
    dpm_set_phase(m, idx, set_prm ? DP_MASTER_PHASE_CHK_CFG : DP_MASTER_PHASE_DIAG_2, t);
}

static void reply_received(dp_master_t *m, unsigned idx, const fdl_msg_t *msg, bool sc,
                           hal_time_us_t t)
{
    dp_master_slave_t *s = &m->slaves[idx];
    if (s->phase != DP_MASTER_PHASE_FDL_STATUS) {
        fcb_advance(&s->fcb_first, &s->fcb);
    }
    uint8_t code = sc ? 0xFFu : (uint8_t)(msg->fc & FDL_FC_CODE_MASK);
    switch (s->phase) {
    case DP_MASTER_PHASE_FDL_STATUS:
        if (sc || (msg->fc & FDL_FC_REQUEST) != 0u) {
            restart_slave(m, idx, t, "unexpected answer to FDL status");
            return;
        }
        dpm_set_phase(m, idx, DP_MASTER_PHASE_DIAG_1, t);
        return;
    case DP_MASTER_PHASE_DIAG_1:
    case DP_MASTER_PHASE_DIAG_2:
    case DP_MASTER_PHASE_DIAG_DX:
        if (sc || code != FDL_RSP_DL || msg->data_len < DP_DIAG_STD_LEN) {
            restart_slave(m, idx, t, "no valid diagnosis");
            return;
        }
        diag_received(m, idx, msg, t);
        return;
    case DP_MASTER_PHASE_SET_PRM:
    case DP_MASTER_PHASE_CHK_CFG:
        ack_received(m, idx, sc, t);
        return;
    case DP_MASTER_PHASE_DATA_EXCH:
        data_exchange_received(m, idx, msg, sc, code, t);
        return;
    case DP_MASTER_PHASE_BACKOFF:
        return;
    }
}

/* The slot time bounds the first character of the answer; once it is coming, give the rest of
 * the telegram the time its characters need. t: a character that left the assembler collecting. */
static void answer_coming(dp_master_t *m, hal_time_us_t t)
{
    hal_time_us_t until = t + 2u * (hal_uart_char_ns(m->cfg.baud) / 1000u + 1u) +
                          (m->cfg.strict_timing ? 0u : m->rx.relaxed_gap_us);
    if (hal_time_diff(until, m->reply_deadline) > 0) {
        m->reply_deadline = until;
    }
}

static void frame_received(dp_master_t *m);

/* Every telegram goes to the ring's rules (tokens, FDL status, the LAS); the answer we wait for
 * also to the master. */
static void heard(dp_master_t *m)
{
    if (m->cfg.token_ring) {
        fdl_active_frame(&m->mac, m->rx.frame, m->rx.frame_len, m->rx.frame_end_t,
                         m->rx.frame_end_t);
    }
    if (m->waiting) {
        frame_received(m);
    }
}

void dp_master_rx_char(dp_master_t *m, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    fdl_rx_result_t r = fdl_rx_char(&m->rx, byte, flags, t);
    if (m->cfg.token_ring) {
        fdl_active_activity(&m->mac, t);
    }
    if (m->waiting && m->rx.collecting) {
        answer_coming(m, t);
    }
    if (r == FDL_RX_FRAME) {
        heard(m);
    }
}

void dp_master_rx_telegram(dp_master_t *m, const dp_master_whole_t *w)
{
    fdl_rx_telegram_t tg = dp_master_whole_take(&m->rx, w);
    if (m->waiting && w->len > 1u) {
        /* rx_char would have moved the deadline at each character but the last; the one before
         * the last moves it furthest */
        answer_coming(m, w->before_last_t);
    }
    if (m->cfg.token_ring) {
        fdl_active_activity(&m->mac, w->first_t);
    }
    if (fdl_rx_telegram(&m->rx, &tg) == FDL_RX_FRAME) {
        heard(m);
    }
}

static void frame_received(dp_master_t *m)
{
    unsigned idx = m->waiting_for;
    const uint8_t *f = m->rx.frame;
    fdl_msg_t msg = {0};
    bool sc = f[0] == FDL_SC;
    if (!sc) {
        if (fdl_parse(f, m->rx.frame_len, &msg) != FDL_PARSE_OK ||
            (msg.fc & FDL_FC_REQUEST) != 0u || msg.da != m->expect_da ||
            msg.sa != m->expect_sa) {
            return; /* not the answer we wait for */
        }
    }
    m->waiting = false;
    m->retries = 0;
    m->next_send = m->rx.frame_end_t + idle_before_request_us(m);
    hal_time_us_t te = m->rx.frame_end_t;
    switch (m->waiting_kind) {
    case DP_MASTER_WAIT_CYCLIC:
        m->c2_turn = true;
        reply_received(m, idx, &msg, sc, te);
        return;
    case DP_MASTER_WAIT_C1: {
        dp_master_slave_t *s = &m->slaves[idx];
        m->c2_turn = true;
        fcb_advance(&s->fcb_first, &s->fcb);
        dp_master_xfer_answer(&s->c1, &msg, sc, te);
        return;
    }
    case DP_MASTER_WAIT_C2: {
        dp_master_c2_t *c = m->c2[m->waiting_c2];
        bool *first;
        bool *fcb;
        pair_fcb(m, m->expect_da, m->expect_sa, &first, &fcb);
        fcb_advance(first, fcb);
        dp_master_c2_answer(c, &msg, sc, te);
        return;
    }
    }
}

/* The next slave to address: *c1 says whether its queued class-1 request (or poll) goes out
 * now, between two Data_Exchange. */
static int pick_slave(dp_master_t *m, hal_time_us_t now, bool *c1)
{
    for (unsigned k = 0; k < m->num_slaves; k++) {
        unsigned idx = (m->next_slave + k) % m->num_slaves;
        dp_master_slave_t *s = &m->slaves[idx];
        if (s->phase == DP_MASTER_PHASE_DATA_EXCH && s->c1_turn && dp_master_xfer_busy(&s->c1)) {
            *c1 = true;
            m->next_slave = (uint8_t)((idx + 1u) % m->num_slaves);
            return (int)idx;
        }
        if (!hal_time_reached(now, s->due)) {
            continue;
        }
        *c1 = false;
        if (s->phase == DP_MASTER_PHASE_BACKOFF) {
            dpm_set_phase(m, idx, DP_MASTER_PHASE_FDL_STATUS, now);
        }
        m->next_slave = (uint8_t)((idx + 1u) % m->num_slaves);
        return (int)idx;
    }
    return -1;
}

/* One telegram of an attached class-2 connection that has something to send, round robin. */
bool dpm_send_c2(dp_master_t *m, hal_time_us_t now)
{
    for (unsigned k = 0; k < m->num_c2; k++) {
        unsigned i = (m->next_c2 + k) % m->num_c2;
        dp_master_c2_t *c = m->c2[i];
        if (!dp_master_c2_ready(c, now)) {
            continue;
        }
        uint8_t dsap = 0;
        const uint8_t *du = NULL;
        size_t n = dp_master_c2_telegram(c, now, &dsap, &du);
        bool *first;
        bool *fcb;
        pair_fcb(m, c->cfg.address, c->cfg.slave, &first, &fcb);
        m->request_len = (uint16_t)fdl_encode(m->request, c->cfg.slave, c->cfg.address,
                                              fc_with(*first, *fcb, true), true, dsap,
                                              c->cfg.ssap, du, n);
        m->next_c2 = (uint8_t)((i + 1u) % m->num_c2);
        m->waiting_kind = DP_MASTER_WAIT_C2;
        m->waiting_c2 = (uint8_t)i;
        m->expect_da = c->cfg.address;
        m->expect_sa = c->cfg.slave;
        m->c2_turn = false;
        m->acyclic_telegrams++;
        send(m, now, true, 0);
        return true;
    }
    return false;
}

/* The answer did not come within the slot time: the same frame again, or after the last retry
 * the connection's or the slave's failure. Returns true when a retry is on its way. */
static bool reply_timed_out(dp_master_t *m, hal_time_us_t now)
{
    m->timeouts++;
    unsigned idx = m->waiting_for;
    m->waiting = false;
    /* A repeat is part of the message cycle, but only for a master that still holds the token
     * (one that found a second holder has given it up). */
    bool may_repeat = !m->cfg.token_ring || fdl_active_holds_token(&m->mac);
    if (m->retries < m->cfg.max_retry && may_repeat) {
        m->retries++;
        m->total_retries++;
        if (m->waiting_kind != DP_MASTER_WAIT_C2) {
            dp_master_event_t ev = {.type = DP_MASTER_EV_RETRY, .t = now,
                              .slave = m->slaves[idx].cfg.address,
                              .old_phase = m->slaves[idx].phase,
                              .new_phase = m->slaves[idx].phase};
            emit(m, &ev);
        } else {
            m->c2[m->waiting_c2]->x.telegrams++;
        }
        send(m, now, true, idx); /* same frame, same FCB */
        return true;
    }
    m->retries = 0;
    m->next_send = now;
    if (m->waiting_kind == DP_MASTER_WAIT_C2) {
        bool *first;
        bool *fcb;
        pair_fcb(m, m->expect_da, m->expect_sa, &first, &fcb);
        *first = true;
        dp_master_c2_no_answer(m->c2[m->waiting_c2], now);
    } else {
        restart_slave(m, idx, now, "no answer");
    }
    return false;
}

/* A pending Global_Control goes out as a broadcast SDN (no answer). */
void dpm_send_global_control(dp_master_t *m, hal_time_us_t now)
{
    m->gc_pending = false;
    uint8_t du[2] = {m->gc_command, m->gc_group};
    m->request_len = (uint16_t)fdl_encode(m->request, FDL_ADDR_BROADCAST, m->cfg.address,
                                          FDL_FC_REQUEST | FDL_REQ_SDN_HIGH, true,
                                          DP_SAP_GLOBAL_CONTROL, DP_SAP_MASTER, du, 2);
    send(m, now, false, 0);
    dp_master_event_t ev = {.type = DP_MASTER_EV_GLOBAL_CONTROL_SENT, .t = now, .data = du,
                            .len = 2};
    emit(m, &ev);
}

/* Nothing to send now: the earliest instant something will be. */
hal_time_us_t dpm_idle_until(dp_master_t *m, hal_time_us_t now)
{
    hal_time_us_t next = now + HAL_TIME_NO_DEADLINE_US;
    for (unsigned i = 0; i < m->num_slaves; i++) {
        next = hal_time_earlier(next, m->slaves[i].due);
        hal_time_us_t d = dp_master_xfer_check_timeout(&m->slaves[i].c1, now);
        next = hal_time_earlier(next, d);
    }
    for (unsigned i = 0; i < m->num_c2; i++) {
        hal_time_us_t d = dp_master_c2_next_deadline(m->c2[i], now);
        next = hal_time_earlier(next, d);
    }
    return next;
}

/* The slave's next telegram: a class-1 acyclic one (c1) or its phase's cyclic one. */
void dpm_send_to_slave(dp_master_t *m, unsigned idx, bool c1, hal_time_us_t now)
{
    dp_master_slave_t *s = &m->slaves[idx];
    m->expect_da = m->cfg.address;
    m->expect_sa = s->cfg.address;
    if (c1) {
        const uint8_t *du = NULL;
        size_t n = dp_master_xfer_telegram(&s->c1, now, &du);
        m->request_len = (uint16_t)fdl_encode(m->request, s->cfg.address, m->cfg.address,
                                              next_fc(s, true), true, DPV1_SAP_C1, DPV1_SAP_C1,
                                              du, n);
        s->c1_turn = false;
        m->waiting_kind = DP_MASTER_WAIT_C1;
        m->acyclic_telegrams++;
        send(m, now, true, idx);
        return;
    }
    build_request(m, s);
    if (s->phase == DP_MASTER_PHASE_DATA_EXCH) {
        s->due = now + m->cfg.cycle_us;
    }
    m->waiting_kind = DP_MASTER_WAIT_CYCLIC;
    send(m, now, true, idx);
}

hal_time_us_t dp_master_poll(dp_master_t *m, hal_time_us_t now)
{
    if (!m->running) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    if (m->waiting) {
        if (!hal_time_reached(now, m->reply_deadline)) {
            return m->reply_deadline;
        }
        if (reply_timed_out(m, now)) {
            return m->reply_deadline;
        }
    }
    if (m->cfg.token_ring) {
        return dpm_ring_poll(m, now);
    }
    if (!hal_time_reached(now, m->next_send)) {
        return m->next_send;
    }
    if (m->gc_pending) {
        dpm_send_global_control(m, now);
        return m->next_send;
    }
    /* Class-1 response timers run while their slave is busy with other things. */
    for (unsigned i = 0; i < m->num_slaves; i++) {
        (void)dp_master_xfer_check_timeout(&m->slaves[i].c1, now);
    }
    if (m->c2_turn && dpm_send_c2(m, now)) {
        return m->reply_deadline;
    }
    bool c1 = false;
    int idx = pick_slave(m, now, &c1);
    if (idx < 0) {
        return dpm_send_c2(m, now) ? m->reply_deadline : dpm_idle_until(m, now);
    }
    dpm_send_to_slave(m, (unsigned)idx, c1, now);
    return m->reply_deadline;
}
