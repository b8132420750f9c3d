/* What the answers of a DP slave say about it: its master, its state, its parameters,
 * configuration and diagnosis (IEC 61158-6-3, the DP slave state machine seen from the line).
 *
 * The state follows the services the slave accepted: a positive answer to a locking Set_Prm
 * puts it in Wait_Cfg, one with Unlock_Req in Wait_Prm, a diagnosis that asks for parameters
 * (Prm_Req) or reports a fault in Wait_Prm, a diagnosis without Station_Not_Ready and without
 * Stat_Diag, or a Data_Exchange answered with data, in Data_Exch.
 * A Set_Prm from another master while the slave exchanges data is refused by a locked slave
 * even where its FDL layer acknowledges it, so it changes nothing here either. */
#include <stdio.h>
#include <string.h>

#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"
#include "mon_internal.h"

static void set_state(mon_t *m, uint8_t a, mon_dp_state_t to, uint64_t t_ns, const char *why)
{
    mon_station_t *s = &m->st[a];
    mon_dp_state_t from = s->dp_state;
    s->dp_state = to;
    if (to == MON_DP_DATA_EXCH) {
        m->wd_due_ns = 0u; /* a watchdog to watch: the next mon_idle scans again */
    }
    if (from == to) {
        return;
    }
    if (from == MON_DP_DATA_EXCH) {
        mon_emit(m, t_ns, MON_EV_DX_LEAVE, MON_LEVEL_WARN, a, s->master, (uint32_t)to,
                 "slave %u left data exchange: %s", a, why);
    } else if (to == MON_DP_DATA_EXCH) {
        mon_emit(m, t_ns, MON_EV_DX_ENTER, MON_LEVEL_INFO, a, s->master, 0,
                 "slave %u in data exchange with master %u", a, s->master);
    }
}

static void set_master(mon_t *m, uint8_t a, uint8_t master, uint64_t t_ns)
{
    mon_station_t *s = &m->st[a];
    s->master = master;
    /* A slave between two parameterisations says "no master" in its diagnosis; only a new
     * owner is worth an event. */
    if (master == MON_NO_MASTER || master == s->owner) {
        return;
    }
    uint8_t before = s->owner;
    s->owner = master;
    if (before == MON_NO_MASTER) {
        mon_emit(m, t_ns, MON_EV_MASTER_CHANGE, MON_LEVEL_INFO, a, master, 0,
                 "slave %u belongs to master %u", a, master);
    } else {
        mon_emit(m, t_ns, MON_EV_MASTER_CHANGE, MON_LEVEL_WARN, a, master, before,
                 "slave %u changed master: %u, was %u", a, master, before);
    }
}

/* The slave's ident, from its Set_Prm or diagnosis, and the max TSDR its GSD gives. */
static void set_ident(mon_t *m, uint8_t a, uint16_t ident)
{
    mon_station_t *s = &m->st[a];
    s->ident_known = true;
    s->ident = ident;
    for (size_t k = 0; k < m->cfg.n_gsd && k < MON_MAX_GSD; k++) {
        if (m->cfg.gsd[k].ident == ident) {
            s->max_tsdr_bits = m->cfg.gsd[k].max_tsdr_bits;
        }
    }
}

static bool positive(const fdl_msg_t *rsp)
{
    if (rsp == NULL) {
        return true; /* SC */
    }
    /* RDL/RDH: data in the answer, only the request's data was not taken (no resource) */
    uint8_t code = rsp->fc & FDL_FC_CODE_MASK;
    return code == FDL_RSP_OK || code == FDL_RSP_DL || code == FDL_RSP_NR || code == FDL_RSP_DH ||
           code == FDL_RSP_RDL || code == FDL_RSP_RDH;
}

static const char *refusal_name(const fdl_msg_t *rsp)
{
    switch (rsp != NULL ? rsp->fc & FDL_FC_CODE_MASK : FDL_RSP_OK) {
    case FDL_RSP_UE: return "UE (user error)";
    case FDL_RSP_RR: return "RR (no resource)";
    case FDL_RSP_RS: return "RS (service not activated)";
    default: return "a refusal";
    }
}

static void copy_du(uint8_t *dst, uint8_t *len, const uint8_t *src, size_t n, size_t max)
{
    *len = (uint8_t)(n < max ? n : max);
    if (*len != 0u) {
        memcpy(dst, src, *len);
    }
}

/* The request came from another master than the slave's own: a locked slave refuses it (RS)
 * and goes on with its owner, so a refusal says nothing about its state. */
static bool locked_out(const mon_t *m, const mon_station_t *s)
{
    return s->master != MON_NO_MASTER && s->master != m->pend_sa;
}

static void data_exchange(mon_t *m, const fdl_msg_t *rsp, uint64_t t_ns)
{
    uint8_t a = m->pend_da;
    mon_station_t *s = &m->st[a];
    if (!positive(rsp)) {
        if (s->dp_state == MON_DP_DATA_EXCH && !locked_out(m, s)) {
            char why[64];
            (void)snprintf(why, sizeof why, "Data_Exchange answered with %s", refusal_name(rsp));
            set_state(m, a, MON_DP_WAIT_PRM, t_ns, why);
        }
        return;
    }
    copy_du(s->outputs, &s->out_len, m->pend_du, m->pend_du_len, MON_IO_MAX);
    if (rsp != NULL) {
        copy_du(s->inputs, &s->in_len, rsp->data, rsp->data_len, MON_IO_MAX);
    } else {
        s->in_len = 0u;
    }
    if (s->last_dx_ns != 0u && t_ns > s->last_dx_ns) {
        mon_span_add(&s->dx_cycle, t_ns - s->last_dx_ns);
    }
    s->last_dx_ns = t_ns;
    s->dx_count++;
    set_master(m, a, m->pend_sa, t_ns);
    set_state(m, a, MON_DP_DATA_EXCH, t_ns, "");
}

/* min TSDR as dp_slave.c adopts it: 0 keeps the one the slave has (the default before any),
 * less than the default counts as the default. */
static void take_min_tsdr(mon_station_t *s, uint8_t bits)
{
    if (bits != 0u) {
        s->min_tsdr_bits = bits > FDL_MIN_TSDR_DEFAULT_BITS ? bits : FDL_MIN_TSDR_DEFAULT_BITS;
    } else if (s->min_tsdr_bits == 0u) {
        s->min_tsdr_bits = FDL_MIN_TSDR_DEFAULT_BITS;
    }
}

/* A locking Set_Prm: the slave takes all of it and the master owns it. */
static void adopt_prm(mon_t *m, uint8_t a, uint64_t t_ns)
{
    mon_station_t *s = &m->st[a];
    const uint8_t *p = m->pend_du;
    copy_du(s->prm, &s->prm_len, p, m->pend_du_len, MON_PRM_MAX);
    take_min_tsdr(s, p[DP_PRM_MIN_TSDR]);
    set_ident(m, a, (uint16_t)((p[DP_PRM_IDENT_HIGH] << 8) | p[DP_PRM_IDENT_LOW]));
    uint32_t base = DP_WD_BASE_MS;
    if (m->pend_du_len >= DP_PRM_LEN_DPV1 &&
        (p[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_WD_BASE_1MS) != 0u) {
        base = DP_WD_BASE_1MS_MS;
    }
    s->watchdog_ms = (p[DP_PRM_STATION_STATUS] & DP_PRM_WD_ON) != 0u
                         ? (uint32_t)p[DP_PRM_WD_FACT_1] * p[DP_PRM_WD_FACT_2] * base
                         : 0u;
    set_master(m, a, m->pend_sa, t_ns);
    char why[48];
    (void)snprintf(why, sizeof why, "new Set_Prm from master %u", m->pend_sa);
    set_state(m, a, MON_DP_WAIT_CFG, t_ns, why);
}

/* Set_Prm answered. The slave acknowledges every Set_Prm it does not refuse for a lock (a fault
 * shows in its next diagnosis); what it does follows Lock_Req and Unlock_Req (dp_slave.c
 * svc_set_prm): Unlock (01, 11) releases it to Wait_Prm, 00 changes only the min TSDR, 10
 * parameterises it. */
static void set_prm(mon_t *m, const fdl_msg_t *rsp, uint64_t t_ns)
{
    uint8_t a = m->pend_da;
    mon_station_t *s = &m->st[a];
    if (!positive(rsp)) {
        if (!locked_out(m, s)) {
            set_state(m, a, MON_DP_WAIT_PRM, t_ns, "Set_Prm refused");
        }
        return;
    }
    if (s->dp_state == MON_DP_DATA_EXCH && locked_out(m, s)) {
        return; /* locked by its master: another master's parameters are not taken */
    }
    const uint8_t *p = m->pend_du;
    if (m->pend_du_len < DP_PRM_LEN_STANDARD) {
        set_master(m, a, MON_NO_MASTER, t_ns);
        set_state(m, a, MON_DP_WAIT_PRM, t_ns, "Set_Prm too short (Prm_Fault)");
        return;
    }
    uint8_t status = p[DP_PRM_STATION_STATUS];
    if ((status & DP_PRM_UNLOCK_REQ) != 0u) {
        char why[64];
        (void)snprintf(why, sizeof why, "master %u released it (Unlock_Req)", m->pend_sa);
        set_master(m, a, MON_NO_MASTER, t_ns);
        set_state(m, a, MON_DP_WAIT_PRM, t_ns, why);
        return;
    }
    if ((status & DP_PRM_LOCK_REQ) == 0u) {
        take_min_tsdr(s, p[DP_PRM_MIN_TSDR]);
        return;
    }
    adopt_prm(m, a, t_ns);
}

static void diag_events(mon_t *m, uint8_t a, const uint8_t *d, size_t n, bool changed,
                        uint64_t t_ns)
{
    mon_station_t *s = &m->st[a];
    if (changed && s->diag_len != 0u) {
        s->diag_changes++;
        char hex[3 * 8 + 4];
        size_t k = 0;
        for (size_t i = 0; i < n && i < 8u; i++) {
            k += (size_t)snprintf(hex + k, sizeof hex - k, "%s%02X", i != 0u ? " " : "", d[i]);
        }
        mon_emit(m, t_ns, MON_EV_DIAG_CHANGE, MON_LEVEL_INFO, a, d[DP_DIAG_MASTER_ADD], 0,
                 "slave %u diagnosis changed: %s%s", a, hex, n > 8u ? " ..." : "");
    }
    bool stat = (d[DP_DIAG_STATUS_2] & DP_DIAG2_STAT_DIAG) != 0u;
    bool was_stat = s->diag_len > DP_DIAG_STATUS_2 &&
                    (s->diag[DP_DIAG_STATUS_2] & DP_DIAG2_STAT_DIAG) != 0u;
    if (stat) {
        s->stat_diag++;
        if (!was_stat) {
            mon_emit(m, t_ns, MON_EV_STAT_DIAG, MON_LEVEL_WARN, a, d[DP_DIAG_MASTER_ADD], 0,
                     "slave %u reports Stat_Diag: its master keeps reading diagnosis", a);
        }
    }
    uint8_t faults = d[DP_DIAG_STATUS_1] & (DP_DIAG1_PRM_FAULT | DP_DIAG1_CFG_FAULT);
    if (faults != 0u && changed) {
        mon_emit(m, t_ns, MON_EV_PRM_FAULT, MON_LEVEL_ERROR, a, d[DP_DIAG_MASTER_ADD], faults,
                 "slave %u refused its %s", a,
                 faults == DP_DIAG1_CFG_FAULT ? "configuration (Cfg_Fault)"
                                              : "parameters (Prm_Fault)");
    }
}

static void slave_diag(mon_t *m, const fdl_msg_t *rsp, uint64_t t_ns)
{
    if (rsp == NULL || rsp->data_len < DP_DIAG_STD_LEN) {
        return;
    }
    uint8_t a = m->pend_da;
    mon_station_t *s = &m->st[a];
    const uint8_t *d = rsp->data;
    size_t n = rsp->data_len < MON_DIAG_MAX ? rsp->data_len : MON_DIAG_MAX;
    bool changed = n != s->diag_len || memcmp(d, s->diag, n) != 0;
    diag_events(m, a, d, n, changed, t_ns);
    copy_du(s->diag, &s->diag_len, d, n, MON_DIAG_MAX);
    set_ident(m, a, (uint16_t)((d[DP_DIAG_IDENT_HIGH] << 8) | d[DP_DIAG_IDENT_LOW]));
    set_master(m, a, d[DP_DIAG_MASTER_ADD], t_ns);
    uint8_t b1 = d[DP_DIAG_STATUS_1];
    if ((d[DP_DIAG_STATUS_2] & DP_DIAG2_PRM_REQ) != 0u) {
        set_state(m, a, MON_DP_WAIT_PRM, t_ns, "diagnosis asks for parameters (Prm_Req)");
    } else if ((b1 & (DP_DIAG1_PRM_FAULT | DP_DIAG1_CFG_FAULT)) != 0u) {
        set_state(m, a, MON_DP_WAIT_PRM, t_ns, "diagnosis reports Prm_Fault or Cfg_Fault");
    } else if ((b1 & DP_DIAG1_STATION_NOT_READY) == 0u &&
               (d[DP_DIAG_STATUS_2] & DP_DIAG2_STAT_DIAG) == 0u) {
        /* Ready, and not holding its master in diagnosis (Stat_Diag): the master goes on to
         * Data_Exchange. */
        set_state(m, a, MON_DP_DATA_EXCH, t_ns, "");
    } else if ((b1 & DP_DIAG1_STATION_NOT_READY) != 0u && s->dp_state == MON_DP_DATA_EXCH) {
        /* Stat_Diag alone is no state of the slave's: one in data exchange stays there. */
        set_state(m, a, MON_DP_WAIT_CFG, t_ns, "diagnosis says Station_Not_Ready");
    }
}

void mon_dp_request(mon_t *m, const fdl_msg_t *req, uint64_t t_ns)
{
    (void)t_ns;
    if (req->da == FDL_ADDR_BROADCAST || !req->has_dsap) {
        return;
    }
    /* The DP SAPs (49..62) make the addressed station a DP slave even before it answers. */
    if (req->dsap >= DP_SAP_MSAC2_RM && req->dsap <= DP_SAP_CHK_CFG) {
        m->st[req->da].dp = true;
    }
}

void mon_dp_answer(mon_t *m, const fdl_msg_t *rsp, uint64_t t_ns)
{
    uint8_t code = m->pend_fc & FDL_FC_CODE_MASK;
    if (code != FDL_REQ_SRD_LOW && code != FDL_REQ_SRD_HIGH) {
        return;
    }
    mon_station_t *s = &m->st[m->pend_da];
    if (!m->pend_saps) {
        s->dp = true;
        data_exchange(m, rsp, t_ns);
        return;
    }
    switch (m->pend_dsap) {
    case DP_SAP_SET_PRM: set_prm(m, rsp, t_ns); break;
    case DP_SAP_CHK_CFG:
        if (positive(rsp)) {
            copy_du(s->cfg, &s->cfg_len, m->pend_du, m->pend_du_len, MON_CFG_MAX);
            if (s->dp_state == MON_DP_UNKNOWN) {
                s->dp_state = MON_DP_WAIT_CFG;
            }
        }
        break;
    case DP_SAP_SLAVE_DIAG: slave_diag(m, rsp, t_ns); break;
    case DP_SAP_GET_CFG:
        if (rsp != NULL && s->cfg_len == 0u) {
            copy_du(s->cfg, &s->cfg_len, rsp->data, rsp->data_len, MON_CFG_MAX);
        }
        break;
    default: break;
    }
}

void mon_dp_gone(mon_t *m, uint8_t a, uint64_t t_ns)
{
    if (m->st[a].dp_state == MON_DP_DATA_EXCH) {
        set_state(m, a, MON_DP_UNKNOWN, t_ns, "no answer to its master");
    }
}

void mon_dp_idle(mon_t *m, uint64_t now_ns)
{
    /* Expiries only move later (each answer restarts a watchdog), so the earliest one found by
     * the last scan is a safe time for the next: mon_idle may run for every telegram. */
    if (now_ns <= m->wd_due_ns) {
        return;
    }
    uint64_t next = UINT64_MAX;
    for (unsigned a = 0; a < FDL_ADDR_BROADCAST; a++) {
        mon_station_t *s = &m->st[a];
        if (s->dp_state != MON_DP_DATA_EXCH || s->watchdog_ms == 0u) {
            continue;
        }
        /* Its last answer: a request reached it then and restarted its watchdog. */
        uint64_t expiry = s->last_ns + (uint64_t)s->watchdog_ms * 1000000u;
        if (now_ns > expiry) {
            char why[64];
            (void)snprintf(why, sizeof why, "its watchdog (%u ms) expired", s->watchdog_ms);
            set_state(m, (uint8_t)a, MON_DP_WAIT_PRM, expiry, why);
        } else if (expiry < next) {
            next = expiry;
        }
    }
    m->wd_due_ns = next;
}
