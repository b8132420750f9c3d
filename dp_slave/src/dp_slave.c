/* The DP slave machine (DP-V0, IEC 61158-6-3): the service table of dp_services.h applied to
 * every request the FDL station (fdl_station.c) lets through, the DDLM services themselves, the
 * diagnosis and the watchdog (protocol.md §A3). */
#include "dp_slave/dp_slave.h"

#include <string.h>

#include "dp_slave/dp_services.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "dp_slave_internal.h"

/* x * 0x01010101 adds the four octets of x into the top octet (carries leave it). */
#define OCTET_SUM_MULTIPLIER 0x01010101u
#define OCTET_SUM_SHIFT 24u

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

void dp_slave_emit(dp_slave_t *s, dp_event_type_t type, hal_time_us_t t, uint32_t value,
                   uint8_t master)
{
    if (s->cfg.hooks.event == NULL) {
        return;
    }
    dp_event_t ev; /* field by field: a zeroing initialiser is a memset call on the reply path */
    ev.type = type;
    ev.t = t;
    ev.old_state = s->state;
    ev.new_state = s->state;
    ev.master = master;
    ev.value = value;
    s->cfg.hooks.event(s->cfg.hooks.ctx, &ev);
}

/* Where the requester's address (DA) sits in a framed reply: behind SD1 or SD2 LE LEr SD2. */
static size_t reply_da_at(const uint8_t *frame)
{
    return frame[0] == FDL_SD2 ? FDL_SD2_HEADER_LEN : FDL_SD1_SD3_HEADER_LEN;
}

/* The Data_Exchange reply for the current inputs and input length, framed with DA and FC 0:
 * the reply path writes the master's address and DL/DH into it and adds them to the check
 * octet, as the ASIC's header insertion does. */
static void frame_inputs(dp_slave_t *s)
{
    /* Into a buffer that neither the newest inputs nor a cached reply (the one a retry or the
     * transmitter may be reading) occupy; three buffers always leave one. */
    uint8_t i = 0;
    bool free_found = false;
    for (uint8_t k = 1; k < DP_DX_BUFFERS && !free_found; k++) {
        i = (uint8_t)((s->dx_current + k) % DP_DX_BUFFERS);
        free_found = !fdl_station_references(s, s->dx[i].buf, false);
    }
    if (!free_found) {
        /* Only masters that owned the slave before point at the others: a retry of theirs runs
         * anew (and is refused) instead of being answered from a buffer about to change. */
        i = (uint8_t)((s->dx_current + 1u) % DP_DX_BUFFERS);
        (void)fdl_station_references(s, s->dx[i].buf, true);
    }
    dp_dx_buffer_t *dx = &s->dx[i];
    /* Only what a reply carries: Chk_Cfg frames again when the length changes. */
    uint8_t *du = &dx->buf[FDL_TX_HEADROOM];
    memcpy(du, s->inputs, s->in_len);
    size_t len;
    const uint8_t *frame = fdl_frame_in_place(dx->buf, s->in_len, fdl_fcs(du, s->in_len), 0u,
                                              s->cfg.address, 0u, false, 0u, 0u, &len);
    dx->start = (uint8_t)(frame - dx->buf);
    dx->len = (uint8_t)len;
    dx->sum_base = frame[len - FDL_TRAILER_LEN];
    s->dx_current = i;
}

static void give_outputs(dp_slave_t *s, const uint8_t *out, size_t len, dp_outputs_reason_t why)
{
    if (s->cfg.hooks.outputs != NULL) {
        s->cfg.hooks.outputs(s->cfg.hooks.ctx, out, len, why);
    }
}

static void clear_outputs(dp_slave_t *s, dp_outputs_reason_t why)
{
    /* Octets past out_len are never given or read, and a new out_len clears again. By words,
     * not memset(): a watchdog expiry does this in a main-loop section with a budget. */
    uint32_t *w = s->outputs_words;
    for (size_t n = (s->out_len + 3u) / 4u; n > 0u; n--) {
        *w++ = 0u;
    }
    s->sync_latched = false; /* latched_outputs is written whole before it is latched again */
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
        s->master_clear = false;
    }
    s->state = next;
    s->diag_framed = false; /* the watchdog's expiry changes the state outside the receive path */
    if (next == DP_STATE_WAIT_PRM) {
        s->wd_on = false;
        s->baud_control_us = s->baud_control_base_us; /* what the rate holds without a watchdog */
        s->dpv1_mode = false;
    }
    if (s->cfg.hooks.event != NULL) {
        dp_event_t ev;
        ev.type = DP_EV_STATE;
        ev.t = t;
        ev.old_state = prev;
        ev.new_state = next;
        ev.master = s->master_add;
        ev.value = 0;
        s->cfg.hooks.event(s->cfg.hooks.ctx, &ev);
    }
}

void dp_slave_init(dp_slave_t *s, const dp_slave_cfg_t *cfg, hal_time_us_t now)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->state = DP_STATE_WAIT_PRM;
    s->master_add = DP_MASTER_ADD_NONE;
    s->min_tsdr_bits = FDL_MIN_TSDR_DEFAULT_BITS;
    for (size_t i = 0; i < FDL_FCB_SLOTS; i++) {
        s->fcb[i].master = FDL_FCB_FREE;
    }
    if (cfg->default_cfg != NULL && cfg->default_cfg_len <= DP_MAX_CFG_LEN) {
        memcpy(s->cfg_data, cfg->default_cfg, cfg->default_cfg_len);
        s->cfg_len = cfg->default_cfg_len;
    }
    /* The diagnosis frames' two delimiters never change: written here, not on every framing. */
    for (size_t i = 0; i < DP_DIAG_BUFFERS; i++) {
        s->diag[i].buf[0] = FDL_SD2;
        s->diag[i].buf[FDL_SD2_HEADER_LEN - 1u] = FDL_SD2;
    }
    fdl_rx_init(&s->rx, cfg->fixed_baud != 0u ? cfg->fixed_baud : hal_uart_bauds[0],
                cfg->strict_timing);
    fdl_station_watchdog_changed(s);
    fdl_station_start_baud(s, now);
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
    dp_slave_emit(s, DP_EV_PRM_FAULT, t, (uint32_t)why, master);
}

/* min TSDR: 0 keeps the current value, below the default 11 bit times counts as 11. */
static void adopt_min_tsdr(dp_slave_t *s, uint8_t min_tsdr)
{
    if (min_tsdr != 0u) {
        s->min_tsdr_bits = min_tsdr < FDL_MIN_TSDR_DEFAULT_BITS ? (uint8_t)FDL_MIN_TSDR_DEFAULT_BITS
                                                                : min_tsdr;
        fdl_station_timing_changed(s);
    }
}

/* The checks of a locking Set_Prm (protocol.md §A3.2), in the order the faults are reported.
 * Fills dpv1 with DPV1_Status_1..3 (zero for a DP-V0 telegram). 0 = accepted. */
static dp_prm_fault_t check_locking_prm(dp_slave_t *s, const uint8_t *p, size_t len,
                                        uint8_t dpv1[3])
{
    uint8_t status = p[DP_PRM_STATION_STATUS];
    if ((status & DP_PRM_STATION_RESERVED) != 0u) {
        return DP_PRM_FAULT_RESERVED_BITS;
    }
    uint16_t ident = (uint16_t)((p[DP_PRM_IDENT_HIGH] << 8) | p[DP_PRM_IDENT_LOW]);
    if (ident != s->cfg.ident) {
        return DP_PRM_FAULT_IDENT;
    }
    uint8_t f1 = p[DP_PRM_WD_FACT_1];
    uint8_t f2 = p[DP_PRM_WD_FACT_2];
    if ((status & DP_PRM_WD_ON) != 0u && (f1 == 0u || f2 == 0u || (f1 == 1u && f2 == 1u))) {
        return DP_PRM_FAULT_WATCHDOG;
    }
    if (len >= DP_PRM_LEN_DPV1) {
        memcpy(dpv1, &p[DP_PRM_DPV1_STATUS_1], 3u);
        if ((dpv1[0] & DP_DPV1_1_RESERVED) != 0u) {
            return DP_PRM_FAULT_RESERVED_BITS;
        }
    }
    bool want_sync = (status & DP_PRM_SYNC_REQ) != 0u;
    bool want_freeze = (status & DP_PRM_FREEZE_REQ) != 0u;
    if ((want_sync && !s->cfg.sync_supported) || (want_freeze && !s->cfg.freeze_supported)) {
        return DP_PRM_FAULT_UNSUPPORTED;
    }
    if (s->cfg.hooks.prm_check != NULL &&
        !s->cfg.hooks.prm_check(s->cfg.hooks.ctx, &p[DP_PRM_LEN_STANDARD],
                                len - DP_PRM_LEN_STANDARD)) {
        return DP_PRM_FAULT_USER;
    }
    return (dp_prm_fault_t)0;
}

/* An accepted locking Set_Prm: the master owns the slave, Wait_Cfg, watchdog armed. */
static void adopt_prm(dp_slave_t *s, const fdl_msg_t *m, const uint8_t dpv1[3], hal_time_us_t t)
{
    const uint8_t *p = m->data;
    uint8_t status = p[DP_PRM_STATION_STATUS];
    bool wd_on = (status & DP_PRM_WD_ON) != 0u;
    s->master_add = m->sa;
    s->station_status = status;
    s->group_ident = p[DP_PRM_GROUP_IDENT];
    memcpy(s->dpv1_status, dpv1, sizeof s->dpv1_status);
    adopt_min_tsdr(s, p[DP_PRM_MIN_TSDR]);
    s->prm_fault = false;
    s->cfg_fault = false;
    s->not_supported = false;
    s->dpv1_mode = m->data_len >= DP_PRM_LEN_DPV1 && (dpv1[0] & DP_DPV1_1_ENABLE) != 0u;
    set_state(s, DP_STATE_WAIT_CFG, t);
    s->wd_on = wd_on;
    uint32_t base_ms = (dpv1[0] & DP_DPV1_1_WD_BASE_1MS) != 0u ? DP_WD_BASE_1MS_MS : DP_WD_BASE_MS;
    s->wd_time_ms = wd_on ? base_ms * p[DP_PRM_WD_FACT_1] * p[DP_PRM_WD_FACT_2] : 0u;
    s->wd_time_us = s->wd_time_ms * 1000u;
    s->wd_deadline = t + s->wd_time_us;
    fdl_station_watchdog_changed(s);
    dp_slave_emit(s, DP_EV_PRM_OK, t, s->wd_time_ms, m->sa);
}

/* DDLM_Set_Prm (SAP 61). */
static void svc_set_prm(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    const uint8_t *p = m->data;
    size_t len = m->data_len;
    fdl_station_reply_sc(s); /* the FDL acknowledges; a rejection is reported through Prm_Fault */

    if (len < DP_PRM_LEN_STANDARD || len > DP_MAX_PRM_LEN) {
        prm_fault(s, DP_PRM_FAULT_LENGTH, m->sa, t);
        return;
    }
    uint8_t status = p[DP_PRM_STATION_STATUS];
    if ((status & DP_PRM_UNLOCK_REQ) != 0u) {
        /* Unlock 01 and 11: the master releases the slave for others. */
        s->master_add = DP_MASTER_ADD_NONE;
        set_state(s, DP_STATE_WAIT_PRM, t);
        return;
    }
    if ((status & DP_PRM_LOCK_REQ) == 0u) {
        /* 00: only min TSDR may be changed; the rest of the telegram is not adopted. */
        adopt_min_tsdr(s, p[DP_PRM_MIN_TSDR]);
        return;
    }
    uint8_t dpv1[3] = {0, 0, 0};
    dp_prm_fault_t fault = check_locking_prm(s, p, len, dpv1);
    if (fault != (dp_prm_fault_t)0) {
        if (fault == DP_PRM_FAULT_UNSUPPORTED) {
            s->not_supported = true;
        }
        prm_fault(s, fault, m->sa, t);
        return;
    }
    adopt_prm(s, m, dpv1, t);
}

/* DDLM_Chk_Cfg (SAP 62), in Wait_Cfg or Data_Exch (the table acknowledges it in Wait_Prm). */
static void svc_chk_cfg(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    /* Always SC, whatever the check finds (a fault shows in the diagnosis), so it goes out
     * before the check and its events run. */
    fdl_station_reply_sc(s);
    fdl_station_send_now(s, t);
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
        dp_slave_emit(s, DP_EV_CFG_FAULT, t, 0, m->sa);
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
        frame_inputs(s);
        if (s->freeze_mode) {
            /* Frozen inputs are read only in freeze mode; a Freeze copies them anew. */
            memset(s->frozen_inputs, 0, sizeof s->frozen_inputs);
        }
        clear_outputs(s, DP_OUTPUTS_CLEAR);
    }
    dp_slave_emit(s, DP_EV_CFG_OK, t, ((uint32_t)out_len << 8) | in_len, m->sa);
    set_state(s, DP_STATE_DATA_EXCH, t);
}

/* Diag.Station_Status_1..3 and Diag.Master_Add in one word (octet 0 in the low byte): the part
 * of the diagnosis that follows the machine, compared whole to tell a framed one still current. */
static uint32_t diag_status_word(const dp_slave_t *s)
{
    uint32_t st1 = 0;
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
    uint32_t st2 = DP_DIAG2_ALWAYS_ONE;
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
    uint32_t st3 = s->ext_diag_overflow ? DP_DIAG3_EXT_DIAG_OVERFLOW : 0u;
    return st1 | (st2 << 8) | (st3 << 16) | ((uint32_t)s->master_add << 24);
}

static void put_diag_status(uint8_t *out, uint32_t status, uint16_t ident)
{
    out[DP_DIAG_STATUS_1] = (uint8_t)status;
    out[DP_DIAG_STATUS_2] = (uint8_t)(status >> 8);
    out[DP_DIAG_STATUS_3] = (uint8_t)(status >> 16);
    out[DP_DIAG_MASTER_ADD] = (uint8_t)(status >> 24);
    out[DP_DIAG_IDENT_HIGH] = (uint8_t)(ident >> 8);
    out[DP_DIAG_IDENT_LOW] = (uint8_t)(ident & 0xFFu);
}

size_t dp_slave_build_diag(const dp_slave_t *s, uint8_t *out, size_t max)
{
    if (max < DP_DIAG_STD_LEN) {
        return 0;
    }
    put_diag_status(out, diag_status_word(s), s->cfg.ident);
    size_t n = DP_DIAG_STD_LEN;
    size_t ext = s->ext_diag_len;
    if (ext > max - n) {
        ext = max - n;
    }
    memcpy(&out[n], s->ext_diag, ext);
    return n + ext;
}

/* Frames the diagnosis with DA and DSAP 0 into the buffer the transmitter is not reading; a
 * retry that pointed there runs anew and reads the diagnosis as it is now. */
static void frame_diag(dp_slave_t *s, uint32_t status)
{
    uint8_t i = (uint8_t)(s->diag_current ^ 1u);
    if (fdl_station_sending_from(s, s->diag[i].buf)) {
        i ^= 1u;
    }
    (void)fdl_station_references(s, s->diag[i].buf, true);
    /* Written directly rather than by fdl_frame_in_place(): a watchdog expiry frames it in the
     * main-loop section that changes the state, which must stay within its budget. SD2 at
     * every length, the bare six octets too (architecture.md, "Data replies are SD2"); its
     * delimiters are in place since dp_slave_init, only LE and LEr change. */
    _Static_assert(FDL_TX_HEADROOM == FDL_SD2_HEADER_LEN + FDL_ADDR_FC_LEN + FDL_SAPS_LEN,
                   "the diagnosis frame starts at buf[0]");
    dp_diag_buffer_t *d = &s->diag[i];
    uint8_t ext = s->ext_diag_len;
    uint8_t *du = &d->buf[FDL_TX_HEADROOM];
    put_diag_status(du, status, s->cfg.ident);
    if (ext > 0u) {
        memcpy(&du[DP_DIAG_STD_LEN], s->ext_diag, ext);
    }
    uint8_t *da = du - FDL_ADDR_FC_LEN - FDL_SAPS_LEN;
    da[0] = FDL_ADDR_EXT; /* DA and DSAP are the requester's, written per request */
    da[1] = (uint8_t)(s->cfg.address | FDL_ADDR_EXT);
    da[FDL_FC_FROM_DA] = FDL_RSP_DL;
    da[FDL_ADDR_FC_LEN] = 0u;
    da[FDL_ADDR_FC_LEN + 1u] = DP_SAP_SLAVE_DIAG;
    uint8_t le = (uint8_t)(FDL_ADDR_FC_LEN + FDL_SAPS_LEN + DP_DIAG_STD_LEN + ext);
    d->buf[1] = le;
    d->buf[2] = le;
    /* The status word's four octets summed by one multiply (into its top octet). */
    uint32_t sum = ((status * OCTET_SUM_MULTIPLIER) >> OCTET_SUM_SHIFT) + (s->cfg.ident >> 8) +
                   (s->cfg.ident & 0xFFu) + s->ext_diag_sum + da[1] + FDL_RSP_DL +
                   DP_SAP_SLAVE_DIAG;
    uint8_t *end = &du[DP_DIAG_STD_LEN + ext];
    end[0] = (uint8_t)(sum + FDL_ADDR_EXT);
    end[1] = FDL_ED;
    d->len = (uint8_t)(le + FDL_SD2_OVERHEAD);
    d->sum_base = (uint8_t)sum;
    s->diag_current = i;
    s->diag_framed = true;
    s->diag_status = status;
}

void dp_slave_prepare(dp_slave_t *s)
{
    fdl_station_prepare(s);
    uint32_t status = diag_status_word(s);
    if (!s->diag_framed || status != s->diag_status) {
        frame_diag(s, status);
    }
}

/* DDLM_Slave_Diag (SAP 60): the framed diagnosis, addressed to the requester. It is current:
 * the receive path frames again after each telegram that changed it, and what changes it
 * elsewhere (set_state, the Ext_Diag and Stat_Diag setters) clears diag_framed. The slot's guard
 * is the DA octet, so a retry of another master is not answered from a frame since addressed
 * to someone else. */
static void svc_slave_diag(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    (void)t;
    if (!s->diag_framed) {
        frame_diag(s, diag_status_word(s));
    }
    dp_diag_buffer_t *d = &s->diag[s->diag_current];
    uint8_t *frame = d->buf;
    uint8_t *da = &d->buf[FDL_SD2_HEADER_LEN];
    uint8_t dsap = (uint8_t)(m->ssap & FDL_AE_SAP_MASK);
    da[0] = (uint8_t)(m->sa | FDL_ADDR_EXT);
    da[FDL_ADDR_FC_LEN] = dsap;
    frame[d->len - FDL_TRAILER_LEN] = (uint8_t)(d->sum_base + da[0] + dsap);
    s->diag_pending = false;
    s->tx = frame;
    s->tx_len = d->len;
    s->tx_guard = da;
    s->tx_guard_value = da[0];
}

/* DDLM_Global_Control (SAP 58, SDN), from the owner in Data_Exch (the table's rule). */
static void svc_global_control(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    if (m->data_len != DP_GC_LEN) {
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
    /* A class-1 master announces Clear or Operate in every Global_Control it sends, at least
     * once per Data_Control_Time (IEC 61158-6-3, the master's operation mode). In Clear it goes
     * on sending a slave without Fail_Safe outputs of full length, every octet 0: substitutes,
     * not its application's data. They are handed over as they come, marked DP_OUTPUTS_CLEAR
     * until the master is back in Operate, so that no device takes them for a request. */
    s->master_clear = (cmd & DP_GC_CLEAR_DATA) != 0u;
    if (s->master_clear) {
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
    dp_slave_emit(s, DP_EV_GLOBAL_CONTROL, t, cmd, m->sa);
}

/* The Data_Exchange reply: the inputs framed ahead (or frozen ones), DH while a diagnosis waits. */
static void reply_inputs(dp_slave_t *s, const fdl_msg_t *m)
{
    uint8_t code = s->diag_pending ? FDL_RSP_DH : FDL_RSP_DL;
    if (s->in_len == 0u) {
        if (s->diag_pending) {
            fdl_station_reply_plain(s, m, code, NULL, 0);
        } else {
            fdl_station_reply_sc(s);
        }
    } else if (s->freeze_mode) {
        fdl_station_reply_plain(s, m, code, s->frozen_inputs, s->in_len);
    } else {
        /* Only the owner exchanges data, but a former owner's retry may still point here:
         * the DA octet guards it. */
        dp_dx_buffer_t *dx = &s->dx[s->dx_current];
        uint8_t *frame = &dx->buf[dx->start];
        uint8_t *da = &frame[reply_da_at(frame)];
        da[0] = m->sa;
        da[FDL_FC_FROM_DA] = code;
        frame[dx->len - FDL_TRAILER_LEN] = (uint8_t)(dx->sum_base + m->sa + code);
        s->tx = frame;
        s->tx_len = dx->len;
        s->tx_guard = da;
        s->tx_guard_value = m->sa;
    }
}

/* DDLM_Data_Exchange (no SAP), from the owner in Data_Exch (the table's rule). The reply does
 * not depend on the outputs, so it goes out before they are taken. */
static void svc_data_exchange(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    bool take = m->data_len == s->out_len && s->out_len > 0u;
    /* Fail-safe masters send an empty telegram in the Clear state. */
    bool clear = m->data_len == 0u && s->out_len > 0u;
    if (!take && !clear && m->data_len != s->out_len) {
        /* The master's configuration does not match what it parameterised: stop exchanging. */
        s->master_add = DP_MASTER_ADD_NONE;
        set_state(s, DP_STATE_WAIT_PRM, t);
        fdl_station_reply_rs(s, m);
        return;
    }
    reply_inputs(s, m);
    fdl_station_send_now(s, t);
    if (take && s->master_clear) {
        /* What a master in Clear sends takes effect at once, Sync or not, and is marked. */
        memcpy(s->outputs, m->data, s->out_len);
        s->sync_latched = false;
        give_outputs(s, s->outputs, s->out_len, DP_OUTPUTS_CLEAR);
    } else if (take && s->sync_mode) {
        memcpy(s->latched_outputs, m->data, s->out_len);
        s->sync_latched = true;
    } else if (take) {
        memcpy(s->outputs, m->data, s->out_len);
        give_outputs(s, s->outputs, s->out_len, DP_OUTPUTS_DATA);
    } else if (clear) {
        clear_outputs(s, DP_OUTPUTS_CLEAR);
    }
}

/* MSAC1S, MSAC2S (SAPs below 55): the device's DP-V1 layer decides, the FDL encodes. */
static void svc_msac(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    if (s->cfg.hooks.sap_request == NULL) {
        fdl_station_reply_rs(s, m);
        return;
    }
    dp_sap_reply_t r = {.buf = s->tx_buf};
    dp_sap_answer_t a = s->cfg.hooks.sap_request(s->cfg.hooks.ctx, m->sa, m->dsap, m->ssap,
                                                 m->data, m->data_len, &r, t);
    switch (a) {
    case DP_SAP_ANSWER_SC:
        fdl_station_reply_sc(s);
        break;
    case DP_SAP_ANSWER_DATA: {
        /* A device that claims more than it may write (into the slave's buffer) is cut short. */
        size_t limit = r.buf == s->tx_buf ? DP_SAP_REPLY_SHORT : DP_SAP_REPLY_MAX;
        bool whole = r.len <= limit;
        size_t len = whole ? r.len : limit;
        uint8_t *du = &r.buf[FDL_TX_HEADROOM];
        uint8_t sum = r.sum_known && whole ? r.sum : fdl_fcs(du, len);
        fdl_station_reply_framed(s, m, FDL_RSP_DL, true, r.buf, len, sum);
        if (r.buf != s->tx_buf) {
            s->tx_guard = r.guard;
            s->tx_guard_value = r.guard_value;
        }
        break;
    }
    case DP_SAP_NOT_SERVED:
    default:
        fdl_station_reply_rs(s, m);
        break;
    }
}

/* DDLM_Get_Cfg (SAP 59): the configuration last accepted (or the device's default). */
static void svc_get_cfg(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    (void)t;
    fdl_station_reply_sap(s, m, s->cfg_data, s->cfg_len);
}

/* DDLM_RD_Inp (SAP 56): the inputs as Data_Exchange would return them. */
static void svc_rd_inp(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    (void)t;
    fdl_station_reply_sap(s, m, s->freeze_mode ? s->frozen_inputs : s->inputs, s->in_len);
}

/* DDLM_RD_Outp (SAP 57). */
static void svc_rd_outp(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t)
{
    (void)t;
    fdl_station_reply_sap(s, m, s->outputs, s->out_len);
}

/* The services that run when the table says DP_RULE_EXECUTE; NULL = never executes. */
typedef void (*dp_service_fn)(dp_slave_t *s, const fdl_msg_t *m, hal_time_us_t t);
static const dp_service_fn service_fn[DP_SERVICE_COUNT] = {
    [DDLM_DATA_EXCHANGE] = svc_data_exchange,
    [DDLM_SET_PRM] = svc_set_prm,
    [DDLM_CHK_CFG] = svc_chk_cfg,
    [DDLM_SLAVE_DIAG] = svc_slave_diag,
    [DDLM_GET_CFG] = svc_get_cfg,
    [DDLM_GLOBAL_CONTROL] = svc_global_control,
    [DDLM_RD_OUTP] = svc_rd_outp,
    [DDLM_RD_INP] = svc_rd_inp,
    [MSAC1S] = svc_msac,
    [MSAC2S] = svc_msac,
};

void dp_slave_request(dp_slave_t *s, const fdl_msg_t *m, bool sdn, hal_time_us_t t)
{
    s->tx_len = 0;
    if (m->has_dsap && !m->has_ssap) {
        if (!sdn) {
            fdl_station_reply_rs(s, m); /* a DSAP needs its SSAP to be answered */
        }
        return;
    }
    dp_service_t svc = dp_service_of(m->has_dsap, m->dsap);
    const dp_service_rule_t *rule = dp_service_rule(svc);
    if (sdn != rule->sdn) {
        /* An SDN to a service with reply is ignored (else a broadcast would reach every slave's
         * Set_Prm); an SRD to the SDN-only Global_Control SAP is "not activated". */
        if (!sdn) {
            fdl_station_reply_rs(s, m);
        }
        return;
    }
    switch (rule->in_state[s->state]) {
    case DP_RULE_EXECUTE:
        break;
    case DP_RULE_SC:
        fdl_station_reply_sc(s);
        return;
    case DP_RULE_IGNORE:
        return;
    case DP_RULE_RS:
    default:
        fdl_station_reply_rs(s, m);
        return;
    }
    if (rule->lock != DP_LOCK_ANY && locked_by_other(s, m->sa)) {
        if (rule->lock == DP_LOCK_OWNER_OR_RS) {
            dp_slave_emit(s, DP_EV_LOCKED_OUT, t, m->has_dsap ? m->dsap : 0u, m->sa);
            fdl_station_reply_rs(s, m);
        }
        return;
    }
    if (service_fn[svc] != NULL) {
        service_fn[svc](s, m, t);
    } else {
        fdl_station_reply_rs(s, m);
    }
}

#if FDL_RX_CHAR_INPUT
void dp_slave_rx_char(dp_slave_t *s, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    fdl_rx_result_t r = fdl_rx_char(&s->rx, byte, flags, t);
    if (r == FDL_RX_FRAME) {
        fdl_station_frame(s);
        dp_slave_prepare(s);
    } else if (r == FDL_RX_ERROR) {
        dp_slave_emit(s, DP_EV_RX_ERROR, t, (uint32_t)s->rx.last_error, 0);
    }
}
#endif

void dp_slave_rx_telegram(dp_slave_t *s, const fdl_rx_telegram_t *tg)
{
    fdl_rx_result_t r = fdl_rx_telegram(&s->rx, tg);
    if (r == FDL_RX_FRAME) {
        fdl_station_frame(s);
        /* After the reply: a master asks for the diagnosis right after the Set_Prm or Chk_Cfg
         * that changed it, sooner than the main loop could frame it at 12 Mbit/s. */
        dp_slave_prepare(s);
    } else if (r == FDL_RX_ERROR) {
        dp_slave_emit(s, DP_EV_RX_ERROR, tg->end_t, (uint32_t)s->rx.last_error, 0);
    }
}

hal_time_us_t dp_slave_poll(dp_slave_t *s, hal_time_us_t now)
{
    hal_time_us_t next = fdl_station_poll(s, now);
    if (s->wd_on && s->state != DP_STATE_WAIT_PRM) {
        if (hal_time_reached(now, s->wd_deadline)) {
            dp_slave_emit(s, DP_EV_WD_EXPIRED, now, s->wd_time_ms, s->master_add);
            s->master_add = DP_MASTER_ADD_NONE;
            s->addressed_reported = false;
            set_state(s, DP_STATE_WAIT_PRM, now);
            /* In the same section as the change: the first request after it may be waiting. */
            dp_slave_prepare(s);
        } else {
            next = hal_time_earlier(next, s->wd_deadline);
        }
    }
    return next;
}

void dp_slave_set_inputs(dp_slave_t *s, const uint8_t *in, size_t len)
{
    if (len > DP_MAX_IO_LEN) {
        len = DP_MAX_IO_LEN;
    }
    memcpy(s->inputs, in, len);
    frame_inputs(s);
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
    s->ext_diag_sum = fdl_fcs(s->ext_diag, len);
    s->ext_diag_overflow = overflow;
    s->diag_framed = false;
    s->diag_pending = true;
}

void dp_slave_set_stat_diag(dp_slave_t *s, bool on)
{
    if (s->stat_diag != on) {
        s->stat_diag = on;
        s->diag_framed = false;
        s->diag_pending = true;
    }
}
