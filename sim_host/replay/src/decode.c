#include "replay/decode.h"

#include <stdio.h>
#include <string.h>

#include "dp_master/dpv1_xfer.h"
#include "dp_master/param_channel.h"
#include "dp_slave/dp_services.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "sim_hal/text_buf.h"

/* ---- parsing ------------------------------------------------------------------------------ */

/* The core reads the record (fdl_parse_damaged, protocol.md §A1.2/§A1.3); only the kind is
 * replay's own. */
void replay_frame_parse(const uint8_t *f, size_t len, replay_frame_t *out)
{
    memset(out, 0, sizeof *out);
    fdl_msg_t m;
    bool has_header = fdl_parse_damaged(f, len, &m);
    out->sd = m.sd;
    if (len == 0u || m.sd == FDL_SC) {
        out->kind = len == 0u ? REPLAY_KIND_GARBAGE : REPLAY_KIND_SC;
        return;
    }
    if (m.sd == FDL_SD4) {
        out->kind = REPLAY_KIND_TOKEN;
    } else if (has_header) {
        out->kind = (m.fc & FDL_FC_REQUEST) != 0u ? REPLAY_KIND_REQUEST : REPLAY_KIND_RESPONSE;
    }
    out->has_header = has_header;
    out->da = m.da;
    out->sa = m.sa;
    out->fc = m.fc;
    out->has_dsap = m.has_dsap;
    out->has_ssap = m.has_ssap;
    out->dsap = m.dsap;
    out->ssap = m.ssap;
    if (has_header && m.sd != FDL_SD4) {
        out->du = m.data;
        out->du_len = m.data_len;
    }
}

/* ---- services ----------------------------------------------------------------------------- */

/* The DDLM services are named by the service table (dp_services.h); the rest are replay's own
 * finer kinds (FDL functions, SAPs the card does not serve, DP-V1 by function). */
static bool ddlm_service(replay_service_t s, dp_service_t *out)
{
    switch (s) {
    case REPLAY_SVC_DATA_EXCHANGE: *out = DDLM_DATA_EXCHANGE; return true;
    case REPLAY_SVC_SET_PRM: *out = DDLM_SET_PRM; return true;
    case REPLAY_SVC_CHK_CFG: *out = DDLM_CHK_CFG; return true;
    case REPLAY_SVC_SLAVE_DIAG: *out = DDLM_SLAVE_DIAG; return true;
    case REPLAY_SVC_GET_CFG: *out = DDLM_GET_CFG; return true;
    case REPLAY_SVC_GLOBAL_CONTROL: *out = DDLM_GLOBAL_CONTROL; return true;
    case REPLAY_SVC_RD_INP: *out = DDLM_RD_INP; return true;
    case REPLAY_SVC_RD_OUTP: *out = DDLM_RD_OUTP; return true;
    case REPLAY_SVC_SET_SLAVE_ADD: *out = DDLM_SET_SLAVE_ADD; return true;
    default: return false;
    }
}

static const char *const local_names[REPLAY_SVC_COUNT] = {
    [REPLAY_SVC_FDL_STATUS] = "FDL_Status",
    [REPLAY_SVC_SET_EXT_PRM] = "Set_Ext_Prm",
    [REPLAY_SVC_MSAC1_READ] = "MSAC1 read",
    [REPLAY_SVC_MSAC1_WRITE] = "MSAC1 write",
    [REPLAY_SVC_MSAC1_POLL] = "MSAC1 poll",
    [REPLAY_SVC_MSAC1_ALARM_ACK] = "MSAC1 alarm ack",
    [REPLAY_SVC_MSAC1_OTHER] = "MSAC1 other",
    [REPLAY_SVC_MSAC2_INITIATE] = "MSAC2 initiate",
    [REPLAY_SVC_MSAC2_POLL] = "MSAC2 poll",
    [REPLAY_SVC_MSAC2_READ] = "MSAC2 read",
    [REPLAY_SVC_MSAC2_WRITE] = "MSAC2 write",
    [REPLAY_SVC_MSAC2_TRANSPORT] = "MSAC2 data transport",
    [REPLAY_SVC_MSAC2_IDLE] = "MSAC2 idle",
    [REPLAY_SVC_MSAC2_ABORT] = "MSAC2 abort",
    [REPLAY_SVC_MSAC2_OTHER] = "MSAC2 other",
    [REPLAY_SVC_ALARM_SAP] = "alarm SAP 50",
    [REPLAY_SVC_OTHER_SAP] = "other SAP",
    [REPLAY_SVC_OTHER_FUNCTION] = "other FDL function",
};

const char *replay_service_name(replay_service_t s)
{
    dp_service_t ddlm;
    if (ddlm_service(s, &ddlm)) {
        return dp_service_label(ddlm);
    }
    const char *name = (unsigned)s < REPLAY_SVC_COUNT ? local_names[s] : NULL;
    return name != NULL ? name : "?";
}

bool replay_expects_answer(const replay_frame_t *req)
{
    uint8_t code = req->fc & FDL_FC_CODE_MASK;
    return code != FDL_REQ_SDN_LOW && code != FDL_REQ_SDN_HIGH;
}

static replay_service_t acyclic_service(bool c1, const replay_frame_t *q)
{
    if (q->du_len == 0u) {
        return c1 ? REPLAY_SVC_MSAC1_POLL : REPLAY_SVC_MSAC2_POLL;
    }
    switch (q->du[0]) {
    case DPV1_FN_READ: return c1 ? REPLAY_SVC_MSAC1_READ : REPLAY_SVC_MSAC2_READ;
    case DPV1_FN_WRITE: return c1 ? REPLAY_SVC_MSAC1_WRITE : REPLAY_SVC_MSAC2_WRITE;
    case DPV1_FN_ALARM_ACK: return c1 ? REPLAY_SVC_MSAC1_ALARM_ACK : REPLAY_SVC_MSAC2_OTHER;
    case DPV1_FN_INITIATE: return c1 ? REPLAY_SVC_MSAC1_OTHER : REPLAY_SVC_MSAC2_INITIATE;
    case DPV1_FN_ABORT: return c1 ? REPLAY_SVC_MSAC1_OTHER : REPLAY_SVC_MSAC2_ABORT;
    case DPV1_FN_IDLE: return c1 ? REPLAY_SVC_MSAC1_OTHER : REPLAY_SVC_MSAC2_IDLE;
    case DPV1_FN_DATA_TRANSPORT:
        return c1 ? REPLAY_SVC_MSAC1_OTHER : REPLAY_SVC_MSAC2_TRANSPORT;
    default: return c1 ? REPLAY_SVC_MSAC1_OTHER : REPLAY_SVC_MSAC2_OTHER;
    }
}

replay_service_t replay_service_of(const replay_frame_t *q)
{
    uint8_t code = q->fc & FDL_FC_CODE_MASK;
    if (code == FDL_REQ_FDL_STATUS) {
        return REPLAY_SVC_FDL_STATUS;
    }
    if (code != FDL_REQ_SRD_LOW && code != FDL_REQ_SRD_HIGH && code != FDL_REQ_SDN_LOW &&
        code != FDL_REQ_SDN_HIGH) {
        return REPLAY_SVC_OTHER_FUNCTION;
    }
    if (!q->has_dsap) {
        return REPLAY_SVC_DATA_EXCHANGE;
    }
    switch (q->dsap) {
    case DP_SAP_SET_SLAVE_ADD: return REPLAY_SVC_SET_SLAVE_ADD;
    case DP_SAP_RD_INP: return REPLAY_SVC_RD_INP;
    case DP_SAP_RD_OUTP: return REPLAY_SVC_RD_OUTP;
    case DP_SAP_GLOBAL_CONTROL: return REPLAY_SVC_GLOBAL_CONTROL;
    case DP_SAP_GET_CFG: return REPLAY_SVC_GET_CFG;
    case DP_SAP_SLAVE_DIAG: return REPLAY_SVC_SLAVE_DIAG;
    case DP_SAP_SET_PRM: return REPLAY_SVC_SET_PRM;
    case DP_SAP_CHK_CFG: return REPLAY_SVC_CHK_CFG;
    case 53u: return REPLAY_SVC_SET_EXT_PRM;
    case DPV1_SAP_C1: return acyclic_service(true, q);
    case 50u: return REPLAY_SVC_ALARM_SAP;
    case DPV1_SAP_RM:
        return q->du_len > 0u && q->du[0] == DPV1_FN_INITIATE ? REPLAY_SVC_MSAC2_INITIATE
                                                               : REPLAY_SVC_MSAC2_OTHER;
    default:
        return q->dsap <= 48u ? acyclic_service(false, q) : REPLAY_SVC_OTHER_SAP;
    }
}

/* ---- text --------------------------------------------------------------------------------- */

size_t replay_hex(const uint8_t *p, size_t len, char *out, size_t max)
{
    if (max == 0u) {
        return 0;
    }
    size_t n = 0;
    out[0] = '\0';
    for (size_t i = 0; i < len; i++) {
        if (n + (i > 0u ? 4u : 3u) + 4u > max) {
            if (n + 4u < max) {
                memcpy(out + n, " ...", 5);
                n += 4;
            }
            return n;
        }
        n += (size_t)snprintf(out + n, max - n, i > 0u ? " %02X" : "%02X", p[i]);
    }
    return n;
}

static void put_hex(text_buf_t *b, const uint8_t *p, size_t len)
{
    if (b->max > b->n) {
        b->n += replay_hex(p, len, b->p + b->n, b->max - b->n);
    }
}

static const char *const req_names[16] = {
    "time event", "?1", "?2", "SDA low", "SDN low", "SDA high", "SDN high", "MSRD", "?8",
    "FDL status request", "time event (TE)", "counter event (CE)", "SRD low", "SRD high",
    "Request Ident", "Request LSAP status",
};
static const char *const rsp_names[16] = {
    "OK", "UE (user error)", "RR (no resource)", "RS (service not activated)", "?4", "?5",
    "?6", "?7", "DL", "NR (no response data)", "DH (diagnosis pending)", "?B",
    "RDL (no resource for receive)", "RDH (no resource, diagnosis)", "?E", "?F",
};

size_t replay_fc_text(uint8_t fc, char *out, size_t max)
{
    text_buf_t b = {out, max, 0};
    if (max > 0u) out[0] = '\0';
    if ((fc & FDL_FC_REQUEST) != 0u) {
        text_buf_put(&b, "%s", req_names[fc & FDL_FC_CODE_MASK]);
        if ((fc & FDL_FC_FCV) != 0u) {
            text_buf_put(&b, " FCV=1 FCB=%u", (fc & FDL_FC_FCB) != 0u ? 1u : 0u);
        } else if ((fc & FDL_FC_FCB) != 0u) {
            text_buf_put(&b, " FCV=0 FCB=1 (first)");
        }
    } else {
        text_buf_put(&b, "%s", rsp_names[fc & FDL_FC_CODE_MASK]);
        static const char *const types[4] = {"", " (master not ready)", " (master ready)",
                                             " (master in ring)"};
        text_buf_put(&b, "%s", types[(fc & FDL_FC_STATION_MASK) >> 4]);
    }
    return b.n;
}

static void diag_text(text_buf_t *b, const uint8_t *d, size_t len)
{
    static const char *const st1[8] = {"Station_Non_Existent", "Station_Not_Ready", "Cfg_Fault",
                                       "Ext_Diag", "Not_Supported", "Invalid_Slave_Response",
                                       "Prm_Fault", "Master_Lock"};
    static const char *const st2[8] = {"Prm_Req", "Stat_Diag", NULL, "WD_On", "Freeze_Mode",
                                       "Sync_Mode", NULL, "Deactivated"};
    if (len < DP_DIAG_STD_LEN) {
        text_buf_put(b, "short diagnosis (%zu octets)", len);
        return;
    }
    for (unsigned i = 0; i < 8u; i++) {
        if (((d[0] >> i) & 1u) != 0u) text_buf_put(b, "%s ", st1[i]);
    }
    for (unsigned i = 0; i < 8u; i++) {
        if (((d[1] >> i) & 1u) != 0u && st2[i] != NULL) text_buf_put(b, "%s ", st2[i]);
    }
    if (d[DP_DIAG_MASTER_ADD] == DP_MASTER_ADD_NONE) {
        text_buf_put(b, "| no master");
    } else {
        text_buf_put(b, "| Master_Add %u", d[DP_DIAG_MASTER_ADD]);
    }
    text_buf_put(b, ", ident 0x%02X%02X", d[4], d[5]);
    if (len > DP_DIAG_STD_LEN) {
        text_buf_put(b, ", ext ");
        put_hex(b, d + DP_DIAG_STD_LEN, len - DP_DIAG_STD_LEN);
    }
}

static void movilink_text(text_buf_t *b, const uint8_t *m, bool reply)
{
    uint8_t mg = m[ML_OFF_MANAGEMENT];
    text_buf_put(b, "param channel [");
    put_hex(b, m, ML_TELEGRAM_LEN);
    text_buf_put(b, "] handshake %u, %s", (mg & ML_MGMT_HANDSHAKE) != 0u ? 1u : 0u,
        ml_service_name(mg & ML_MGMT_SERVICE_MASK));
    if ((mg & ML_MGMT_SERVICE_MASK) != ML_SVC_NONE) {
        text_buf_put(b, " index %u", (unsigned)m[ML_OFF_INDEX_HIGH] << 8 | m[ML_OFF_INDEX_LOW]);
    }
    if (reply && (mg & ML_MGMT_ERROR) != 0u) {
        char t[96];
        ml_error_text(m, t, sizeof t);
        text_buf_put(b, ", error: %s", t);
    } else if ((mg & ML_MGMT_SERVICE_MASK) != ML_SVC_NONE) {
        uint32_t v = (uint32_t)m[4] << 24 | (uint32_t)m[5] << 16 | (uint32_t)m[6] << 8 | m[7];
        text_buf_put(b, " data 0x%08X", v);
    }
}

static void io_text(text_buf_t *b, const uint8_t *d, size_t len, const replay_dx_layout_t *lay,
                    bool reply, const char *what)
{
    if (len == 0u) {
        text_buf_put(b, "no %s", what);
        return;
    }
    if (lay != NULL && lay->known && lay->param_channel && len >= ML_TELEGRAM_LEN) {
        movilink_text(b, d, reply);
        d += ML_TELEGRAM_LEN;
        len -= ML_TELEGRAM_LEN;
        if (len == 0u) return;
        text_buf_put(b, "; ");
    }
    text_buf_put(b, "%s", reply ? "PI" : "PO");
    for (size_t i = 0; i + 1u < len; i += 2u) {
        text_buf_put(b, " %02X%02X", d[i], d[i + 1u]);
    }
    if ((len & 1u) != 0u) {
        text_buf_put(b, " %02X", d[len - 1u]);
    }
}

static void prm_text(text_buf_t *b, const uint8_t *d, size_t len)
{
    if (len < DP_PRM_LEN_STANDARD) {
        text_buf_put(b, "%zu octets (too short): ", len);
        put_hex(b, d, len);
        return;
    }
    uint8_t st = d[DP_PRM_STATION_STATUS];
    text_buf_put(b, "%s%s%s%s%s", (st & DP_PRM_LOCK_REQ) ? "Lock " : "",
        (st & DP_PRM_UNLOCK_REQ) ? "Unlock " : "", (st & DP_PRM_SYNC_REQ) ? "Sync " : "",
        (st & DP_PRM_FREEZE_REQ) ? "Freeze " : "", (st & DP_PRM_WD_ON) ? "WD_On " : "");
    bool base_1ms = len > DP_PRM_DPV1_STATUS_1 &&
                    (d[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_WD_BASE_1MS) != 0u;
    text_buf_put(b, "WD %u x %u x %s, min TSDR %u, ident 0x%02X%02X, group 0x%02X", d[1], d[2],
        base_1ms ? "1 ms" : "10 ms", d[3], d[4], d[5], d[6]);
    if (len > DP_PRM_LEN_STANDARD) {
        text_buf_put(b, ", then ");
        put_hex(b, d + DP_PRM_LEN_STANDARD, len - DP_PRM_LEN_STANDARD);
    }
}

static void gc_text(text_buf_t *b, const uint8_t *d, size_t len)
{
    if (len < DP_GC_LEN) {
        text_buf_put(b, "%zu octets (too short)", len);
        return;
    }
    uint8_t c = d[0];
    if ((c & ~(unsigned)DP_GC_RESERVED) == 0u) text_buf_put(b, "Operate ");
    if (c & DP_GC_CLEAR_DATA) text_buf_put(b, "Clear_Data ");
    if (c & DP_GC_UNFREEZE) text_buf_put(b, "Unfreeze ");
    if (c & DP_GC_FREEZE) text_buf_put(b, "Freeze ");
    if (c & DP_GC_UNSYNC) text_buf_put(b, "Unsync ");
    if (c & DP_GC_SYNC) text_buf_put(b, "Sync ");
    if (c & DP_GC_RESERVED) text_buf_put(b, "reserved bits 0x%02X ", c & DP_GC_RESERVED);
    text_buf_put(b, "(0x%02X), group 0x%02X", c, d[1]);
}

static const char *fn_name(uint8_t fn)
{
    switch (fn & 0x7Fu) {
    case DPV1_FN_IDLE: return "Idle";
    case DPV1_FN_DATA_TRANSPORT: return "Data_Transport";
    case DPV1_FN_RM: return "RM";
    case DPV1_FN_INITIATE: return "Initiate";
    case DPV1_FN_ABORT: return "Abort";
    case DPV1_FN_ALARM_ACK: return "Alarm_Ack";
    case DPV1_FN_READ: return "Read";
    case DPV1_FN_WRITE: return "Write";
    default: return NULL;
    }
}

/* A DP-V1 PDU (request or response). */
static void dpv1_text(text_buf_t *b, const uint8_t *d, size_t len, bool reply)
{
    if (len == 0u) {
        text_buf_put(b, reply ? "empty" : "poll (no data)");
        return;
    }
    const char *name = fn_name(d[0]);
    if (name == NULL) {
        text_buf_put(b, "function 0x%02X: ", d[0]);
        put_hex(b, d, len);
        return;
    }
    const char *dir = reply ? ".res" : ".req";
    if ((d[0] & DPV1_FN_ERROR) != 0u && d[0] != DPV1_FN_ERROR) {
        text_buf_put(b, "%s negative", name);
        if (len >= 4u) {
            text_buf_put(b, ": decode 0x%02X, code 0x%02X (%s), 0x%02X", d[1], d[2],
                dp_master_v1_error_text(d[2]), d[3]);
        }
        return;
    }
    switch (d[0]) {
    case DPV1_FN_READ:
    case DPV1_FN_WRITE:
        text_buf_put(b, "%s%s", name, dir);
        if (len >= 4u) {
            text_buf_put(b, " slot %u index %u length %u", d[1], d[2], d[3]);
            if (len > 4u) {
                text_buf_put(b, ": ");
                put_hex(b, d + 4, len - 4u);
            }
        }
        return;
    case DPV1_FN_RM:
        text_buf_put(b, "resource manager: connection SAP %u", len > 1u ? d[1] : 0u);
        return;
    case DPV1_FN_INITIATE:
        text_buf_put(b, "Initiate%s", dir);
        if (!reply && len >= 6u) {
            text_buf_put(b, " Send_Timeout %u", (unsigned)d[4] << 8 | d[5]);
        } else if (reply && len >= 2u) {
            text_buf_put(b, " Max_Len_Data_Unit %u", d[1]);
        }
        return;
    case DPV1_FN_ABORT:
        text_buf_put(b, "Abort");
        if (len >= 3u) {
            text_buf_put(b, " subnet %u, instance 0x%02X, reason %u", d[1], d[2] & 0xF0u, d[2] & 0x0Fu);
        }
        return;
    default:
        text_buf_put(b, "%s%s: ", name, dir);
        put_hex(b, d + 1, len - 1u);
        return;
    }
}

/* What follows the header of a request, by its service. */
static void request_data_text(text_buf_t *b, replay_service_t s, const replay_frame_t *m,
                              const replay_dx_layout_t *lay)
{
    switch (s) {
    case REPLAY_SVC_DATA_EXCHANGE:
        text_buf_put(b, ": ");
        io_text(b, m->du, m->du_len, lay, false, "outputs");
        break;
    case REPLAY_SVC_SET_PRM:
        text_buf_put(b, ": ");
        prm_text(b, m->du, m->du_len);
        break;
    case REPLAY_SVC_CHK_CFG:
    case REPLAY_SVC_SET_SLAVE_ADD:
    case REPLAY_SVC_SET_EXT_PRM:
    case REPLAY_SVC_OTHER_SAP:
    case REPLAY_SVC_OTHER_FUNCTION:
        if (m->du_len > 0u) {
            text_buf_put(b, ": ");
            put_hex(b, m->du, m->du_len);
        }
        break;
    case REPLAY_SVC_GLOBAL_CONTROL:
        text_buf_put(b, ": ");
        gc_text(b, m->du, m->du_len);
        break;
    case REPLAY_SVC_FDL_STATUS:
    case REPLAY_SVC_SLAVE_DIAG:
    case REPLAY_SVC_GET_CFG:
    case REPLAY_SVC_RD_INP:
    case REPLAY_SVC_RD_OUTP:
        break;
    default: /* DP-V1 */
        text_buf_put(b, ": ");
        dpv1_text(b, m->du, m->du_len, false);
        break;
    }
}

static void request_text(text_buf_t *b, const replay_frame_t *m, const replay_dx_layout_t *lay)
{
    char fc[64];
    replay_service_t s = replay_service_of(m);
    replay_fc_text(m->fc, fc, sizeof fc);
    text_buf_put(b, "%s %u -> %u (%s", replay_service_name(s), m->sa, m->da, fc);
    if (m->has_dsap || m->has_ssap) {
        text_buf_put(b, ", SAPs %u/%u", m->has_dsap ? m->dsap : 0u, m->has_ssap ? m->ssap : 0u);
    }
    text_buf_put(b, ")");
    request_data_text(b, s, m, lay);
}

/* An answer without SAPs: FDL status, Data_Exchange data or a bare response code. */
static void plain_response_text(text_buf_t *b, const replay_frame_t *m, const char *fc,
                                const replay_dx_layout_t *lay)
{
    uint8_t code = m->fc & FDL_FC_CODE_MASK;
    if (m->sd == FDL_SD1 && code == FDL_RSP_OK) {
        text_buf_put(b, "FDL status reply %u -> %u: %s", m->sa, m->da, fc);
    } else if (code == FDL_RSP_DL || code == FDL_RSP_DH) {
        text_buf_put(b, "reply %u -> %u %s: ", m->sa, m->da, fc);
        io_text(b, m->du, m->du_len, lay, true, "inputs");
    } else {
        text_buf_put(b, "reply %u -> %u: %s", m->sa, m->da, fc);
        if (m->du_len > 0u) {
            text_buf_put(b, ": ");
            put_hex(b, m->du, m->du_len);
        }
    }
}

/* An answer from a service SAP (DP-V0 services, DP-V1 connections, anything else). */
static void sap_response_text(text_buf_t *b, const replay_frame_t *m, const char *fc)
{
    unsigned dsap = m->has_dsap ? m->dsap : 0u;
    switch (m->ssap) {
    case DP_SAP_SLAVE_DIAG:
        text_buf_put(b, "Slave_Diag reply %u -> %u (%s): ", m->sa, m->da, fc);
        diag_text(b, m->du, m->du_len);
        break;
    case DP_SAP_GET_CFG:
        text_buf_put(b, "Get_Cfg reply %u -> %u (%s): ", m->sa, m->da, fc);
        put_hex(b, m->du, m->du_len);
        break;
    case DP_SAP_RD_INP:
    case DP_SAP_RD_OUTP:
        text_buf_put(b, "%s reply %u -> %u (%s): ", m->ssap == DP_SAP_RD_INP ? "Rd_Inp" : "Rd_Outp",
            m->sa, m->da, fc);
        put_hex(b, m->du, m->du_len);
        break;
    default:
        if (m->ssap == DPV1_SAP_C1 || m->ssap <= DPV1_SAP_RM) {
            text_buf_put(b, "%s reply %u -> %u (%s, SAPs %u/%u): ",
                m->ssap == DPV1_SAP_C1 ? "MSAC1" : "MSAC2", m->sa, m->da, fc, dsap, m->ssap);
            dpv1_text(b, m->du, m->du_len, true);
        } else {
            text_buf_put(b, "reply %u -> %u (%s, SAPs %u/%u)", m->sa, m->da, fc, dsap, m->ssap);
            if (m->du_len > 0u) {
                text_buf_put(b, ": ");
                put_hex(b, m->du, m->du_len);
            }
        }
        break;
    }
}

static void response_text(text_buf_t *b, const replay_frame_t *m, const replay_dx_layout_t *lay)
{
    char fc[64];
    replay_fc_text(m->fc, fc, sizeof fc);
    if (m->has_ssap) {
        sap_response_text(b, m, fc);
    } else {
        plain_response_text(b, m, fc, lay);
    }
}

size_t replay_describe(const uint8_t *f, size_t len, const replay_dx_layout_t *lay, char *out,
                       size_t max)
{
    text_buf_t b = {out, max, 0};
    if (max > 0u) out[0] = '\0';
    replay_frame_t m;
    replay_frame_parse(f, len, &m);
    switch (m.kind) {
    case REPLAY_KIND_SC:
        text_buf_put(&b, len == 1u ? "SC (short acknowledgement)" : "SC followed by %zu octets",
            len - 1u);
        break;
    case REPLAY_KIND_TOKEN:
        if (m.has_header) {
            text_buf_put(&b, "token %u -> %u", m.sa, m.da);
        } else {
            text_buf_put(&b, "token (cut: %zu octets)", len);
        }
        break;
    case REPLAY_KIND_GARBAGE: text_buf_put(&b, "not a telegram (%zu octets)", len); break;
    case REPLAY_KIND_REQUEST: request_text(&b, &m, lay); break;
    case REPLAY_KIND_RESPONSE: response_text(&b, &m, lay); break;
    }
    return b.n;
}
