/* FDL station + DP-V0 state machine. Layout of this file follows a telegram's way:
 * character -> fdl_rx -> address/FC checks -> FCB/retry cache -> SAP routing -> DP service ->
 * reply encoding -> HAL transmit. Timers live in dp_slave_poll(). */
#include "dp_slave/dp_slave.h"

#include <string.h>

#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

const char *dp_state_name(dp_state_t st)
{
    switch (st) {
    case DP_STATE_WAIT_PRM: return "Wait_Prm";
    case DP_STATE_WAIT_CFG: return "Wait_Cfg";
    case DP_STATE_DATA_EXCH: return "Data_Exch";
    }
    return "?";
}

const char *dp_baud_state_name(dp_baud_state_t st)
{
    switch (st) {
    case DP_BAUD_SEARCH: return "baud search";
    case DP_BAUD_CONTROL: return "baud control";
    case DP_BAUD_FIXED: return "fixed baud";
    }
    return "?";
}

uint32_t dp_baud_search_dwell_us(uint32_t baud)
{
    /* Two telegrams of the maximum 255 characters, but never below 20 ms, so a master that
     * repeats its requests every few milliseconds is heard on every rate it might use. */
    uint64_t us = (2ull * FDL_FRAME_MAX * FDL_CHAR_BITS * 1000000ull) / baud;
    return us < 20000u ? 20000u : (uint32_t)us;
}

static void emit(dp_slave_t *s, dp_event_type_t type, hal_time_us_t t, uint32_t value,
                 uint8_t master)
{
    if (s->cfg.hooks.event == NULL) {
        return;
    }
    dp_event_t ev = {
        .type = type, .t = t, .old_state = s->state, .new_state = s->state,
        .master = master, .value = value,
    };
    s->cfg.hooks.event(s->cfg.hooks.ctx, &ev);
}

static void give_outputs(dp_slave_t *s, const uint8_t *out, size_t len, dp_outputs_reason_t why)
{
    if (s->cfg.hooks.outputs != NULL) {
        s->cfg.hooks.outputs(s->cfg.hooks.ctx, out, len, why);
    }
}

static void clear_outputs(dp_slave_t *s, dp_outputs_reason_t why)
{
    memset(s->outputs, 0, sizeof s->outputs);
    memset(s->latched_outputs, 0, sizeof s->latched_outputs);
    s->sync_latched = false;
    give_outputs(s, s->outputs, s->out_len, why);
}

/* The one place the DP state changes, so every transition is reported and leaving Data_Exch
 * always puts the outputs into their safe state. */
static void set_state(dp_slave_t *s, dp_state_t next, hal_time_us_t t)
{
    dp_state_t prev = s->state;
    if (prev == next) {
        return;
    }
    if (prev == DP_STATE_DATA_EXCH) {
        clear_outputs(s, DP_OUTPUTS_SAFE_STATE);
        s->sync_mode = false;
        s->freeze_mode = false;
    }
    s->state = next;
    if (next == DP_STATE_WAIT_PRM) {
        s->wd_on = false;
        s->dpv1_mode = false;
    }
    if (s->cfg.hooks.event != NULL) {
        dp_event_t ev = {.type = DP_EV_STATE, .t = t, .old_state = prev, .new_state = next,
                         .master = s->master_add, .value = 0};
        s->cfg.hooks.event(s->cfg.hooks.ctx, &ev);
    }
}

static void select_baud(dp_slave_t *s, uint32_t baud)
{
    s->baud = baud;
    fdl_rx_set_baud(&s->rx, baud);
    if (s->cfg.uart.ops != NULL && s->cfg.uart.ops->set_baud != NULL) {
        (void)s->cfg.uart.ops->set_baud(s->cfg.uart.ctx, baud);
    }
}

static uint32_t baud_control_us(const dp_slave_t *s)
{
    uint32_t ms = s->cfg.baud_control_ms != 0u ? s->cfg.baud_control_ms : DP_BAUD_CONTROL_MS_DEFAULT;
    if (s->wd_on && s->wd_time_ms * 2u > ms) {
        ms = s->wd_time_ms * 2u; /* never lose the rate before the DP watchdog could expire */
    }
    return ms * 1000u;
}

void dp_slave_init(dp_slave_t *s, const dp_slave_cfg_t *cfg, hal_time_us_t now)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->state = DP_STATE_WAIT_PRM;
    s->master_add = DP_MASTER_ADD_NONE;
    s->min_tsdr_bits = FDL_MIN_TSDR_DEFAULT_BITS;
    if (cfg->default_cfg != NULL && cfg->default_cfg_len <= DP_MAX_CFG_LEN) {
        memcpy(s->cfg_data, cfg->default_cfg, cfg->default_cfg_len);
        s->cfg_len = cfg->default_cfg_len;
    }
    fdl_rx_init(&s->rx, cfg->fixed_baud != 0u ? cfg->fixed_baud : hal_uart_bauds[0],
                cfg->strict_timing);
    if (cfg->fixed_baud != 0u) {
        s->baud_state = DP_BAUD_FIXED;
        select_baud(s, cfg->fixed_baud);
    } else {
        s->baud_state = DP_BAUD_SEARCH;
        s->baud_index = 0;
        select_baud(s, hal_uart_bauds[0]);
        s->baud_deadline = now + dp_baud_search_dwell_us(s->baud);
        emit(s, DP_EV_BAUD_SET, now, s->baud, 0);
    }
}

/* ---- replies ------------------------------------------------------------------------------ */

static void reply_sc(dp_slave_t *s)
{
    s->reply[0] = FDL_SC;
    s->reply_len = 1;
}

/* A reply without SAP octets: RS/RR/UE status or Data_Exchange data. */
static void reply_plain(dp_slave_t *s, const fdl_msg_t *m, uint8_t code, const uint8_t *data,
                        size_t len)
{
    s->reply_len = (uint16_t)fdl_encode(s->reply, m->sa, s->cfg.address, code, false, 0, 0, data,
                                        len);
}

/* A reply to a SAP request: SAPs swapped. */
static void reply_sap(dp_slave_t *s, const fdl_msg_t *m, const uint8_t *data, size_t len)
{
    s->reply_len = (uint16_t)fdl_encode(s->reply, m->sa, s->cfg.address, FDL_RSP_DL, true,
                                        m->ssap, m->dsap, data, len);
}

static void reply_rs(dp_slave_t *s, const fdl_msg_t *m)
{
    reply_plain(s, m, FDL_RSP_RS, NULL, 0);
}

/* ---- DP services -------------------------------------------------------------------------- */

static bool locked_by_other(const dp_slave_t *s, uint8_t master)
{
    return s->master_add != DP_MASTER_ADD_NONE && s->master_add != master;
}

static void prm_fault(dp_slave_t *s, dp_prm_fault_t why, uint8_t master, hal_time_us_t t)
{
    s->prm_fault = true;
    s->master_add = DP_MASTER_ADD_NONE;
    set_state(s, DP_STATE_WAIT_PRM, t);
    emit(s, DP_EV_PRM_FAULT, t, (uint32_t)why, master);
}

static void svc_set_prm(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    const uint8_t *p = m->data;
    size_t len = m->data_len;
    reply_sc(s); /* the FDL acknowledges; a rejection is reported through Prm_Fault */

    if (len < DP_PRM_LEN_STANDARD || len > DP_MAX_PRM_LEN) {
        prm_fault(s, DP_PRM_FAULT_LENGTH, m->sa, t);
        return;
    }
    uint8_t status = p[DP_PRM_STATION_STATUS];
    bool lock = (status & DP_PRM_LOCK_REQ) != 0u;
    bool unlock = (status & DP_PRM_UNLOCK_REQ) != 0u;
    if (unlock) {
        /* 01 and 11: the master releases the slave for others. */
        s->master_add = DP_MASTER_ADD_NONE;
        set_state(s, DP_STATE_WAIT_PRM, t);
        return;
    }
    if (!lock) {
        /* 00: only min TSDR may be changed; the rest of the telegram is not adopted. */
        if (p[DP_PRM_MIN_TSDR] != 0u) {
            s->min_tsdr_bits = p[DP_PRM_MIN_TSDR] < FDL_MIN_TSDR_DEFAULT_BITS
                                   ? (uint8_t)FDL_MIN_TSDR_DEFAULT_BITS
                                   : p[DP_PRM_MIN_TSDR];
        }
        return;
    }
    if ((status & DP_PRM_STATION_RESERVED) != 0u) {
        prm_fault(s, DP_PRM_FAULT_RESERVED_BITS, m->sa, t);
        return;
    }
    uint16_t ident = (uint16_t)((p[DP_PRM_IDENT_HIGH] << 8) | p[DP_PRM_IDENT_LOW]);
    if (ident != s->cfg.ident) {
        prm_fault(s, DP_PRM_FAULT_IDENT, m->sa, t);
        return;
    }
    bool wd_on = (status & DP_PRM_WD_ON) != 0u;
    uint8_t f1 = p[DP_PRM_WD_FACT_1];
    uint8_t f2 = p[DP_PRM_WD_FACT_2];
    if (wd_on && (f1 == 0u || f2 == 0u || (f1 == 1u && f2 == 1u))) {
        prm_fault(s, DP_PRM_FAULT_WATCHDOG, m->sa, t);
        return;
    }
    uint8_t dpv1[3] = {0, 0, 0};
    if (len >= DP_PRM_LEN_DPV1) {
        memcpy(dpv1, &p[DP_PRM_DPV1_STATUS_1], 3u);
        if ((dpv1[0] & DP_DPV1_1_RESERVED) != 0u) {
            prm_fault(s, DP_PRM_FAULT_RESERVED_BITS, m->sa, t);
            return;
        }
    }
    bool want_sync = (status & DP_PRM_SYNC_REQ) != 0u;
    bool want_freeze = (status & DP_PRM_FREEZE_REQ) != 0u;
    if ((want_sync && !s->cfg.sync_supported) || (want_freeze && !s->cfg.freeze_supported)) {
        s->not_supported = true;
        prm_fault(s, DP_PRM_FAULT_UNSUPPORTED, m->sa, t);
        return;
    }
    if (s->cfg.hooks.prm_check != NULL &&
        !s->cfg.hooks.prm_check(s->cfg.hooks.ctx, &p[DP_PRM_LEN_STANDARD],
                                len - DP_PRM_LEN_STANDARD)) {
        prm_fault(s, DP_PRM_FAULT_USER, m->sa, t);
        return;
    }

    s->master_add = m->sa;
    s->station_status = status;
    s->group_ident = p[DP_PRM_GROUP_IDENT];
    memcpy(s->dpv1_status, dpv1, sizeof dpv1);
    if (p[DP_PRM_MIN_TSDR] != 0u) {
        s->min_tsdr_bits = p[DP_PRM_MIN_TSDR] < FDL_MIN_TSDR_DEFAULT_BITS
                               ? (uint8_t)FDL_MIN_TSDR_DEFAULT_BITS
                               : p[DP_PRM_MIN_TSDR];
    }
    s->prm_fault = false;
    s->cfg_fault = false;
    s->not_supported = false;
    s->dpv1_mode = len >= DP_PRM_LEN_DPV1 && (dpv1[0] & DP_DPV1_1_ENABLE) != 0u;
    set_state(s, DP_STATE_WAIT_CFG, t);
    s->wd_on = wd_on;
    uint32_t base_ms = (dpv1[0] & DP_DPV1_1_WD_BASE_1MS) != 0u ? 1u : 10u;
    s->wd_time_ms = wd_on ? base_ms * f1 * f2 : 0u;
    s->wd_deadline = t + s->wd_time_ms * 1000u;
    emit(s, DP_EV_PRM_OK, t, s->wd_time_ms, m->sa);
}

static void svc_chk_cfg(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    reply_sc(s);
    if (s->state == DP_STATE_WAIT_PRM) {
        return; /* not parameterised: ignored, Prm_Req in the diagnosis tells the master */
    }
    uint8_t out_len = 0;
    uint8_t in_len = 0;
    bool ok = m->data_len >= 1u && m->data_len <= DP_MAX_CFG_LEN &&
              (s->cfg.hooks.cfg_check == NULL ||
               s->cfg.hooks.cfg_check(s->cfg.hooks.ctx, m->data, m->data_len, &out_len,
                                      &in_len)) &&
              out_len <= DP_MAX_IO_LEN && in_len <= DP_MAX_IO_LEN;
    if (!ok) {
        s->cfg_fault = true;
        s->master_add = DP_MASTER_ADD_NONE;
        set_state(s, DP_STATE_WAIT_PRM, t);
        emit(s, DP_EV_CFG_FAULT, t, 0, m->sa);
        return;
    }
    bool changed = m->data_len != s->cfg_len || memcmp(m->data, s->cfg_data, m->data_len) != 0 ||
                   s->state != DP_STATE_DATA_EXCH;
    memcpy(s->cfg_data, m->data, m->data_len);
    s->cfg_len = m->data_len;
    s->cfg_fault = false;
    if (changed) {
        s->out_len = out_len;
        s->in_len = in_len;
        memset(s->frozen_inputs, 0, sizeof s->frozen_inputs);
        clear_outputs(s, DP_OUTPUTS_CLEAR);
    }
    emit(s, DP_EV_CFG_OK, t, ((uint32_t)out_len << 8) | in_len, m->sa);
    set_state(s, DP_STATE_DATA_EXCH, t);
}

size_t dp_slave_build_diag(const dp_slave_t *s, uint8_t *out, size_t max)
{
    if (max < DP_DIAG_STD_LEN) {
        return 0;
    }
    uint8_t st1 = 0;
    if (s->state != DP_STATE_DATA_EXCH) {
        st1 |= DP_DIAG1_STATION_NOT_READY;
    }
    if (s->cfg_fault) {
        st1 |= DP_DIAG1_CFG_FAULT;
    }
    if (s->ext_diag_len > 0u) {
        st1 |= DP_DIAG1_EXT_DIAG;
    }
    if (s->not_supported) {
        st1 |= DP_DIAG1_NOT_SUPPORTED;
    }
    if (s->prm_fault) {
        st1 |= DP_DIAG1_PRM_FAULT;
    }
    uint8_t st2 = DP_DIAG2_ALWAYS_ONE;
    if (s->state == DP_STATE_WAIT_PRM) {
        st2 |= DP_DIAG2_PRM_REQ;
    }
    if (s->stat_diag) {
        st2 |= DP_DIAG2_STAT_DIAG;
    }
    if (s->wd_on) {
        st2 |= DP_DIAG2_WD_ON;
    }
    if (s->freeze_mode) {
        st2 |= DP_DIAG2_FREEZE_MODE;
    }
    if (s->sync_mode) {
        st2 |= DP_DIAG2_SYNC_MODE;
    }
    out[DP_DIAG_STATUS_1] = st1;
    out[DP_DIAG_STATUS_2] = st2;
    out[DP_DIAG_STATUS_3] = s->ext_diag_overflow ? DP_DIAG3_EXT_DIAG_OVERFLOW : 0u;
    out[DP_DIAG_MASTER_ADD] = s->master_add;
    out[DP_DIAG_IDENT_HIGH] = (uint8_t)(s->cfg.ident >> 8);
    out[DP_DIAG_IDENT_LOW] = (uint8_t)(s->cfg.ident & 0xFFu);
    size_t n = DP_DIAG_STD_LEN;
    size_t ext = s->ext_diag_len;
    if (ext > max - n) {
        ext = max - n;
    }
    memcpy(&out[n], s->ext_diag, ext);
    return n + ext;
}

static void svc_slave_diag(dp_slave_t *s, const fdl_msg_t *m)
{
    uint8_t diag[DP_DIAG_STD_LEN + DP_MAX_EXT_DIAG_LEN];
    size_t n = dp_slave_build_diag(s, diag, sizeof diag);
    s->diag_pending = false;
    reply_sap(s, m, diag, n);
}

static void svc_global_control(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    if (s->state != DP_STATE_DATA_EXCH || s->master_add != m->sa || m->data_len != DP_GC_LEN) {
        return;
    }
    uint8_t cmd = m->data[0];
    uint8_t groups = m->data[1];
    if ((cmd & DP_GC_RESERVED) != 0u) {
        return;
    }
    if (groups != 0u && (groups & s->group_ident) == 0u) {
        return;
    }
    if ((cmd & DP_GC_CLEAR_DATA) != 0u) {
        clear_outputs(s, DP_OUTPUTS_CLEAR);
    }
    /* When both a command and its cancellation are set, the cancellation wins. Sync and Freeze
     * are obeyed only when the master asked for them in Set_Prm (Sync_Req, Freeze_Req). */
    if ((cmd & DP_GC_UNSYNC) != 0u) {
        if (s->sync_latched) {
            memcpy(s->outputs, s->latched_outputs, s->out_len);
            give_outputs(s, s->outputs, s->out_len, DP_OUTPUTS_DATA);
        }
        s->sync_latched = false;
        s->sync_mode = false;
    } else if ((cmd & DP_GC_SYNC) != 0u && s->cfg.sync_supported &&
               (s->station_status & DP_PRM_SYNC_REQ) != 0u) {
        if (s->sync_latched) {
            memcpy(s->outputs, s->latched_outputs, s->out_len);
            give_outputs(s, s->outputs, s->out_len, DP_OUTPUTS_DATA);
        }
        s->sync_latched = false;
        s->sync_mode = true;
    }
    if ((cmd & DP_GC_UNFREEZE) != 0u) {
        s->freeze_mode = false;
    } else if ((cmd & DP_GC_FREEZE) != 0u && s->cfg.freeze_supported &&
               (s->station_status & DP_PRM_FREEZE_REQ) != 0u) {
        memcpy(s->frozen_inputs, s->inputs, s->in_len);
        s->freeze_mode = true;
    }
    emit(s, DP_EV_GLOBAL_CONTROL, t, cmd, m->sa);
}

static void svc_data_exchange(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    if (s->state != DP_STATE_DATA_EXCH) {
        reply_rs(s, m);
        return;
    }
    if (s->master_add != m->sa) {
        emit(s, DP_EV_LOCKED_OUT, t, 0, m->sa);
        reply_rs(s, m);
        return;
    }
    if (m->data_len == s->out_len && s->out_len > 0u) {
        if (s->sync_mode) {
            memcpy(s->latched_outputs, m->data, s->out_len);
            s->sync_latched = true;
        } else {
            memcpy(s->outputs, m->data, s->out_len);
            give_outputs(s, s->outputs, s->out_len, DP_OUTPUTS_DATA);
        }
    } else if (m->data_len == 0u && s->out_len > 0u) {
        /* Fail-safe masters send an empty telegram in the Clear state. */
        clear_outputs(s, DP_OUTPUTS_CLEAR);
    } else if (m->data_len != s->out_len) {
        /* The master's configuration does not match what it parameterised: stop exchanging. */
        s->master_add = DP_MASTER_ADD_NONE;
        set_state(s, DP_STATE_WAIT_PRM, t);
        reply_rs(s, m);
        return;
    }
    uint8_t code = s->diag_pending ? FDL_RSP_DH : FDL_RSP_DL;
    if (s->in_len == 0u) {
        if (s->diag_pending) {
            reply_plain(s, m, code, NULL, 0);
        } else {
            reply_sc(s);
        }
        return;
    }
    reply_plain(s, m, code, s->freeze_mode ? s->frozen_inputs : s->inputs, s->in_len);
}

/* DP-V1 and anything else below SAP 55: the device decides, the FDL encodes. */
static void svc_extension(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    uint8_t reply[DP_SAP_REPLY_MAX];
    size_t len = 0;
    dp_sap_answer_t a = s->cfg.hooks.sap_request(s->cfg.hooks.ctx, m->sa, m->dsap, m->ssap,
                                                 m->data, m->data_len, reply, &len, t);
    switch (a) {
    case DP_SAP_ANSWER_SC:
        reply_sc(s);
        break;
    case DP_SAP_ANSWER_DATA:
        reply_sap(s, m, reply, len <= DP_SAP_REPLY_MAX ? len : DP_SAP_REPLY_MAX);
        break;
    case DP_SAP_NOT_SERVED:
    default:
        reply_rs(s, m);
        break;
    }
}

/* Routes one request to its service; leaves the reply (if any) in s->reply. */
static void dp_service(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    s->reply_len = 0;
    if (!m->has_dsap) {
        svc_data_exchange(s, m, t);
        return;
    }
    if (!m->has_ssap) {
        reply_rs(s, m);
        return;
    }
    bool parameterising = m->dsap == DP_SAP_SET_PRM || m->dsap == DP_SAP_CHK_CFG;
    if (parameterising && locked_by_other(s, m->sa)) {
        emit(s, DP_EV_LOCKED_OUT, t, m->dsap, m->sa);
        reply_rs(s, m);
        return;
    }
    switch (m->dsap) {
    case DP_SAP_SET_PRM:
        svc_set_prm(s, m, t);
        break;
    case DP_SAP_CHK_CFG:
        svc_chk_cfg(s, m, t);
        break;
    case DP_SAP_SLAVE_DIAG:
        svc_slave_diag(s, m);
        break;
    case DP_SAP_GET_CFG:
        reply_sap(s, m, s->cfg_data, s->cfg_len);
        break;
    case DP_SAP_RD_INP:
        if (s->state == DP_STATE_DATA_EXCH) {
            reply_sap(s, m, s->freeze_mode ? s->frozen_inputs : s->inputs, s->in_len);
        } else {
            reply_rs(s, m);
        }
        break;
    case DP_SAP_RD_OUTP:
        if (s->state == DP_STATE_DATA_EXCH) {
            reply_sap(s, m, s->outputs, s->out_len);
        } else {
            reply_rs(s, m);
        }
        break;
    case DP_SAP_GLOBAL_CONTROL:
        reply_rs(s, m); /* an SRD to the SDN-only Global_Control SAP: not activated */
        break;
    default:
        if (m->dsap < DP_SAP_SET_SLAVE_ADD && s->cfg.hooks.sap_request != NULL) {
            svc_extension(s, m, t);
        } else {
            /* includes Set_Slave_Add: the address comes from the DIP switches */
            reply_rs(s, m);
        }
        break;
    }
}

/* ---- FDL ---------------------------------------------------------------------------------- */

static fdl_fcb_slot_t *fcb_slot(dp_slave_t *s, uint8_t master, bool create)
{
    fdl_fcb_slot_t *oldest = &s->fcb[0];
    for (size_t i = 0; i < FDL_FCB_SLOTS; i++) {
        fdl_fcb_slot_t *e = &s->fcb[i];
        if (e->used && e->master == master) {
            return e;
        }
        if (!e->used || (oldest->used && e->age > oldest->age)) {
            oldest = e;
        }
    }
    if (!create) {
        return NULL;
    }
    *oldest = (fdl_fcb_slot_t){.used = true, .master = master};
    return oldest;
}

static void fcb_touch(dp_slave_t *s, fdl_fcb_slot_t *e)
{
    for (size_t i = 0; i < FDL_FCB_SLOTS; i++) {
        if (s->fcb[i].used && s->fcb[i].age < UINT8_MAX) {
            s->fcb[i].age++;
        }
    }
    e->age = 0;
}

static void transmit(dp_slave_t *s, const uint8_t *frame, size_t len, hal_time_us_t request_end)
{
    if (len == 0u || s->cfg.uart.ops == NULL || s->cfg.uart.ops->transmit == NULL) {
        return;
    }
    hal_time_us_t not_before = request_end + hal_uart_bits_us(s->baud, s->min_tsdr_bits);
    (void)s->cfg.uart.ops->transmit(s->cfg.uart.ctx, frame, len, not_before);
}

static void handle_frame(dp_slave_t *s)
{
    const uint8_t *frame = s->rx.buf;
    hal_time_us_t t = s->rx.frame_end_t;
    uint8_t sd = frame[0];
    bool data_frame = sd == FDL_SD1 || sd == FDL_SD2 || sd == FDL_SD3;
    if (data_frame) {
        s->line_active = true;
    }
    if (data_frame && s->baud_state == DP_BAUD_SEARCH) {
        s->baud_state = DP_BAUD_CONTROL;
        s->baud_deadline = t + baud_control_us(s);
        emit(s, DP_EV_BAUD_FOUND, t, s->baud, 0);
    }
    fdl_msg_t m;
    if (fdl_parse(frame, s->rx.frame_len, &m) != FDL_PARSE_OK) {
        return;
    }
    if ((m.fc & FDL_FC_REQUEST) == 0u) {
        return; /* a response between other stations */
    }
    bool broadcast = m.da == FDL_ADDR_BROADCAST;
    if (m.da != s->cfg.address && !broadcast) {
        return;
    }
    if (s->rx.strict && s->rx.idle_before_ns != UINT32_MAX &&
        (uint64_t)s->rx.idle_before_ns + FDL_RX_GAP_TOLERANCE_NS <
            (uint64_t)FDL_TSYN_BITS * s->rx.char_ns / FDL_CHAR_BITS) {
        s->rx.error_count[FDL_RX_ERR_TSYN]++;
        emit(s, DP_EV_RX_ERROR, t, FDL_RX_ERR_TSYN, m.sa);
        return;
    }
    if (!broadcast) {
        s->telegrams_for_me++;
        if (s->baud_state == DP_BAUD_CONTROL) {
            s->baud_deadline = t + baud_control_us(s);
        }
        emit(s, DP_EV_ADDRESSED, t, m.fc, m.sa);
    }
    if (s->wd_on && s->state != DP_STATE_WAIT_PRM && m.sa == s->master_add) {
        s->wd_deadline = t + s->wd_time_ms * 1000u;
    }

    uint8_t code = (uint8_t)(m.fc & FDL_FC_CODE_MASK);
    switch (code) {
    case FDL_REQ_FDL_STATUS:
        if (!broadcast) {
            reply_plain(s, &m, FDL_RSP_OK, NULL, 0);
            transmit(s, s->reply, s->reply_len, t);
        }
        return;
    case FDL_REQ_SDN_LOW:
    case FDL_REQ_SDN_HIGH:
        /* Global_Control is the only DP service sent without reply (and the only one a master
         * may broadcast). Set_Prm, Chk_Cfg, Data_Exchange ... as SDN are ignored, or a
         * broadcast would reach every card on the segment. */
        if (m.has_dsap && m.has_ssap && m.dsap == DP_SAP_GLOBAL_CONTROL) {
            svc_global_control(s, &m, t);
        }
        return;
    case FDL_REQ_SRD_LOW:
    case FDL_REQ_SRD_HIGH:
        break;
    default:
        if (!broadcast) {
            reply_rs(s, &m);
            transmit(s, s->reply, s->reply_len, t);
        }
        return;
    }
    if (broadcast) {
        return; /* a request with reply cannot go to everybody */
    }

    bool fcv = (m.fc & FDL_FC_FCV) != 0u;
    uint8_t fcb = (m.fc & FDL_FC_FCB) != 0u ? 1u : 0u;
    fdl_fcb_slot_t *slot = fcb_slot(s, m.sa, false);
    if (fcv && slot != NULL && slot->fcb_valid && slot->fcb == fcb && slot->reply_len > 0u) {
        /* Retry of the previous request: repeat the answer, do not execute it again. */
        fcb_touch(s, slot);
        emit(s, DP_EV_FCB_REPEAT, t, m.fc, m.sa);
        transmit(s, slot->reply, slot->reply_len, t);
        return;
    }
    dp_service(s, &m, t);
    slot = fcb_slot(s, m.sa, true);
    fcb_touch(s, slot);
    slot->fcb_valid = fcv || fcb != 0u;
    slot->fcb = fcb;
    slot->reply_len = s->reply_len;
    memcpy(slot->reply, s->reply, s->reply_len);
    transmit(s, s->reply, s->reply_len, t);
}

void dp_slave_rx_char(dp_slave_t *s, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    fdl_rx_result_t r = fdl_rx_char(&s->rx, byte, flags, t);
    if (r == FDL_RX_FRAME) {
        handle_frame(s);
    } else if (r == FDL_RX_ERROR) {
        emit(s, DP_EV_RX_ERROR, t, (uint32_t)s->rx.last_error, 0);
    }
}

hal_time_us_t dp_slave_poll(dp_slave_t *s, hal_time_us_t now)
{
    hal_time_us_t next = fdl_rx_poll(&s->rx, now);
    if (s->wd_on && s->state != DP_STATE_WAIT_PRM) {
        if (hal_time_reached(now, s->wd_deadline)) {
            emit(s, DP_EV_WD_EXPIRED, now, s->wd_time_ms, s->master_add);
            s->master_add = DP_MASTER_ADD_NONE;
            set_state(s, DP_STATE_WAIT_PRM, now);
        } else {
            next = hal_time_earlier(next, s->wd_deadline);
        }
    }
    if (s->baud_state == DP_BAUD_SEARCH || s->baud_state == DP_BAUD_CONTROL) {
        if (hal_time_reached(now, s->baud_deadline)) {
            if (s->baud_state == DP_BAUD_CONTROL) {
                s->baud_state = DP_BAUD_SEARCH;
                s->baud_index = 0;
                s->line_active = false;
                emit(s, DP_EV_BAUD_LOST, now, s->baud, 0);
            } else {
                s->baud_index = (uint8_t)((s->baud_index + 1u) % HAL_UART_NUM_BAUDS);
            }
            select_baud(s, hal_uart_bauds[s->baud_index]);
            s->baud_deadline = now + dp_baud_search_dwell_us(s->baud);
            emit(s, DP_EV_BAUD_SET, now, s->baud, 0);
        }
        next = hal_time_earlier(next, s->baud_deadline);
    }
    return next;
}

void dp_slave_set_inputs(dp_slave_t *s, const uint8_t *in, size_t len)
{
    if (len > DP_MAX_IO_LEN) {
        len = DP_MAX_IO_LEN;
    }
    memcpy(s->inputs, in, len);
}

void dp_slave_set_ext_diag(dp_slave_t *s, const uint8_t *diag, size_t len)
{
    bool overflow = len > DP_MAX_EXT_DIAG_LEN;
    if (overflow) {
        len = DP_MAX_EXT_DIAG_LEN;
    }
    /* len 0 may come with diag == NULL: memcmp/memcpy must not see it even then (C11 7.24.1). */
    if (len == s->ext_diag_len && overflow == s->ext_diag_overflow &&
        (len == 0u || memcmp(diag, s->ext_diag, len) == 0)) {
        return;
    }
    if (len > 0u) {
        memcpy(s->ext_diag, diag, len);
    }
    s->ext_diag_len = (uint8_t)len;
    s->ext_diag_overflow = overflow;
    s->diag_pending = true;
}

void dp_slave_set_stat_diag(dp_slave_t *s, bool on)
{
    if (s->stat_diag != on) {
        s->stat_diag = on;
        s->diag_pending = true;
    }
}
