/* Helpers of the DP state machine cases: requests with their expected answers, the diagnosis
 * bits, Global_Control and the loopback probe (cases_dp_internal.h). */
#include <stdio.h>
#include <string.h>

#include "cases_dp_internal.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

#define READY_POLLS 50u
#define READY_POLL_MS 20u
#define HEX_OCTETS 32u

const char *dpx_hex(const uint8_t *p, size_t n, char *buf, size_t cap)
{
    size_t at = 0;
    buf[0] = '\0';
    for (size_t i = 0; i < n && i < HEX_OCTETS && at + 4u < cap; i++) {
        at += (size_t)snprintf(buf + at, cap - at, i ? " %02X" : "%02X", p[i]);
    }
    if (n > HEX_OCTETS && at + 4u < cap) snprintf(buf + at, cap - at, " ...");
    return buf;
}

static bool is_response(const cf_answer_t *a)
{
    return (a->fc & FDL_FC_REQUEST) == 0u;
}

bool dpx_is_ack(const cf_reply_t *r)
{
    cf_answer_t a;
    if (cf_is_sc(r)) return true;
    if (!cf_answer(r, &a) || !is_response(&a) || a.du_len != 0u) return false;
    uint8_t code = a.fc & FDL_FC_CODE_MASK;
    return code == FDL_RSP_DL || code == FDL_RSP_DH || code == FDL_RSP_NR;
}

bool dpx_is_data(const cf_reply_t *r, cf_answer_t *a)
{
    if (!cf_answer(r, a) || !is_response(a)) return false;
    uint8_t code = a->fc & FDL_FC_CODE_MASK;
    return code == FDL_RSP_DL || code == FDL_RSP_DH;
}

bool dpx_expect_ack(cf_t *cf, const cf_reply_t *r, const char *what)
{
    char t[CF_TEXT_MAX];
    return cf_check(cf, dpx_is_ack(r), "%s: expected SC (acknowledged), got %s", what,
                    cf_reply_text(r, t, sizeof t));
}

bool dpx_expect_rs(cf_t *cf, const cf_reply_t *r, const char *what)
{
    char t[CF_TEXT_MAX];
    return cf_check(cf, cf_rsp_code(r) == (int)FDL_RSP_RS, "%s: expected RS (FC 0x03), got %s",
                    what, cf_reply_text(r, t, sizeof t));
}

void dpx_note(cf_t *cf, const cf_reply_t *r, const char *what)
{
    char t[CF_TEXT_MAX];
    cf_info(cf, "%s: %s", what, cf_reply_text(r, t, sizeof t));
}

bool dpx_diag_from(cf_t *cf, uint8_t sa, uint8_t *d, size_t *len, const char *what)
{
    static const uint8_t none[1] = {0};
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    if (!cf_dp_from(cf, sa, DP_SAP_MASTER, DP_SAP_SLAVE_DIAG, none, 0, &r)) return false;
    if (!cf_check(cf, dpx_is_data(&r, &a) && a.du_len >= DP_DIAG_STD_LEN,
                  "%s: expected DL with at least 6 diagnosis octets, got %s", what,
                  cf_reply_text(&r, t, sizeof t))) {
        return false;
    }
    memcpy(d, a.du, a.du_len);
    *len = a.du_len;
    return true;
}

bool dpx_bits(cf_t *cf, const uint8_t *d, size_t len, size_t octet, uint8_t mask, uint8_t want,
              const char *name, const char *what)
{
    char h[DPX_HEX_MAX];
    uint8_t got = d[octet] & mask;
    return cf_check(cf, got == want, "%s: %s expected 0x%02X, got 0x%02X (diagnosis %s)", what,
                    name, want, got, dpx_hex(d, len, h, sizeof h));
}

/* The bits a slave must show in Wait_Prm whatever happened before: Station_Not_Ready, Prm_Req
 * and the always-one bit; the master-only bits 0; no Freeze/Sync mode; Master_Add none. */
bool dpx_wait_prm_bits(cf_t *cf, const uint8_t *d, size_t n, const char *what)
{
    return dpx_bits(cf, d, n, DP_DIAG_STATUS_1, DP_DIAG1_STATION_NOT_READY,
                    DP_DIAG1_STATION_NOT_READY, "Station_status_1.Station_Not_Ready", what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_1,
                    DP_DIAG1_STATION_NON_EXISTENT | DP_DIAG1_INVALID_SLAVE_RESPONSE |
                        DP_DIAG1_MASTER_LOCK,
                    0, "Station_status_1 master-only bits 0, 5, 7", what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2, DP_DIAG2_PRM_REQ | DP_DIAG2_ALWAYS_ONE,
                    DP_DIAG2_PRM_REQ | DP_DIAG2_ALWAYS_ONE,
                    "Station_status_2.Prm_Req and bit 2 (always 1)", what) &&
           dpx_bits(cf, d, n, DP_DIAG_STATUS_2,
                    DP_DIAG2_FREEZE_MODE | DP_DIAG2_SYNC_MODE | 0x40u | DP_DIAG2_DEACTIVATED, 0,
                    "Station_status_2 Freeze_Mode, Sync_Mode, bit 6, Deactivated", what) &&
           dpx_bits(cf, d, n, DP_DIAG_MASTER_ADD, 0xFFu, DP_MASTER_ADD_NONE, "Master_Add", what);
}

bool dpx_set_prm(cf_t *cf, const uint8_t *prm, size_t len, const char *what)
{
    cf_reply_t r;
    if (!cf_dp(cf, DP_SAP_SET_PRM, prm, len, &r)) return false;
    return dpx_expect_ack(cf, &r, what);
}

bool dpx_chk_cfg(cf_t *cf, const uint8_t *cfg, size_t len, const char *what)
{
    cf_reply_t r;
    if (!cf_dp(cf, DP_SAP_CHK_CFG, cfg, len, &r)) return false;
    return dpx_expect_ack(cf, &r, what);
}

bool dpx_wait_ready(cf_t *cf, uint8_t *d, size_t *len, const char *what)
{
    char h[DPX_HEX_MAX];
    for (unsigned i = 0; i < READY_POLLS; i++) {
        if (!cf_diag(cf, d, len)) return false;
        uint8_t faults = d[DP_DIAG_STATUS_1] & (DP_DIAG1_CFG_FAULT | DP_DIAG1_PRM_FAULT);
        if (!cf_check(cf, faults == 0u, "%s: expected no Cfg_Fault/Prm_Fault, got diagnosis %s",
                      what, dpx_hex(d, *len, h, sizeof h))) {
            return false;
        }
        bool busy = (d[DP_DIAG_STATUS_1] & DP_DIAG1_STATION_NOT_READY) != 0u ||
                    (d[DP_DIAG_STATUS_2] & (DP_DIAG2_PRM_REQ | DP_DIAG2_STAT_DIAG)) != 0u;
        if (!busy) return true;
        if (!cf_pause_ms(cf, READY_POLL_MS)) return false;
    }
    return cf_fail(cf, "%s: expected the slave ready (no Prm_Req, Stat_Diag, Station_Not_Ready) "
                   "within %u polls, got diagnosis %s", what, READY_POLLS,
                   dpx_hex(d, *len, h, sizeof h));
}

bool dpx_dx(cf_t *cf, const uint8_t *out, uint8_t *in, const char *what)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    cf_reply_t r;
    cf_answer_t a;
    char t[CF_TEXT_MAX];
    if (!cf_data_exchange(cf, out != NULL ? out : zeros, cf->out_len, &r)) return false;
    if (cf->in_len == 0u) {
        return cf_check(cf, dpx_is_ack(&r),
                        "%s: Data_Exchange without inputs: expected SC, got %s", what,
                        cf_reply_text(&r, t, sizeof t));
    }
    if (!cf_check(cf, dpx_is_data(&r, &a) && !a.saps && a.du_len == cf->in_len,
                  "%s: Data_Exchange: expected DL with %u input octets, got %s", what,
                  (unsigned)cf->in_len, cf_reply_text(&r, t, sizeof t))) {
        return false;
    }
    if (in != NULL) memcpy(in, a.du, a.du_len);
    return true;
}

bool dpx_dx_refused(cf_t *cf, const char *what)
{
    static const uint8_t zeros[DP_IO_LEN_LIMIT];
    cf_reply_t r;
    if (!cf_data_exchange(cf, zeros, cf->out_len, &r)) return false;
    return dpx_expect_rs(cf, &r, what);
}

bool dpx_gc(cf_t *cf, uint8_t sa, uint8_t command, uint8_t group)
{
    const uint8_t du[DP_GC_LEN] = {command, group};
    uint8_t frame[FDL_FRAME_MAX];
    cf_reply_t r;
    char t[CF_TEXT_MAX];
    size_t n = fdl_encode(frame, FDL_ADDR_BROADCAST, sa, FDL_FC_REQUEST | FDL_REQ_SDN_HIGH, true,
                          DP_SAP_GLOBAL_CONTROL, DP_SAP_MASTER, du, sizeof du);
    if (!cf_exchange_wait(cf, frame, n, cf->link.slot_us, &r)) return false;
    return cf_check(cf, r.len == 0u,
                    "Global_Control %02X %02X (SDN to 127): expected no answer, got %s", command,
                    group, cf_reply_text(&r, t, sizeof t));
}

bool dpx_start_up_with(cf_t *cf, const uint8_t *prm, size_t len)
{
    uint8_t keep[sizeof cf->prm];
    uint8_t keep_len = cf->prm_len;
    memcpy(keep, cf->prm, sizeof keep);
    memcpy(cf->prm, prm, len);
    cf->prm_len = (uint8_t)len;
    bool ok = cf_start_up(cf);
    memcpy(cf->prm, keep, sizeof keep);
    cf->prm_len = keep_len;
    return ok;
}

size_t dpx_prm_with(const cf_t *cf, uint8_t set, uint8_t clear, uint8_t *out)
{
    memcpy(out, cf->prm, cf->prm_len);
    out[DP_PRM_STATION_STATUS] = (uint8_t)((out[DP_PRM_STATION_STATUS] | set) & ~clear);
    return cf->prm_len;
}

uint32_t dpx_watchdog_ms(const cf_t *cf, const uint8_t *prm, size_t len)
{
    if (len < DP_PRM_LEN_STANDARD || (prm[DP_PRM_STATION_STATUS] & DP_PRM_WD_ON) == 0u) return 0;
    uint32_t base = DP_WD_BASE_MS;
    if (cf->dpv1 && len >= DP_PRM_LEN_DPV1 &&
        (prm[DP_PRM_DPV1_STATUS_1] & DP_DPV1_1_WD_BASE_1MS) != 0u) {
        base = DP_WD_BASE_1MS_MS;
    }
    return base * prm[DP_PRM_WD_FACT_1] * prm[DP_PRM_WD_FACT_2];
}

void dpx_pattern(uint8_t *out, size_t len, uint8_t seed)
{
    for (size_t i = 0; i < len; i++) {
        uint8_t v = (uint8_t)(seed + 0x17u * i);
        out[i] = v != 0u ? v : 0x5Au;
    }
}

/* The octets compared for a loopback: the last ones both images have, at most two (the card's
 * process data words follow a parameter channel that does not echo). */
static size_t tail_len(const cf_t *cf)
{
    size_t k = cf->in_len < cf->out_len ? cf->in_len : cf->out_len;
    return k < 2u ? k : 2u;
}

int dpx_dx_until(cf_t *cf, const uint8_t *out, const uint8_t *want, int tries, const char *what)
{
    uint8_t in[DP_IO_LEN_LIMIT];
    size_t k = tail_len(cf);
    for (int i = 0; i < tries; i++) {
        if (!dpx_dx(cf, out, in, what)) return -1;
        if (k > 0u && memcmp(in + cf->in_len - k, want + cf->out_len - k, k) == 0) return i + 1;
    }
    return 0;
}

int dpx_echo_probe(cf_t *cf)
{
    uint8_t a[DP_IO_LEN_LIMIT], b[DP_IO_LEN_LIMIT];
    if (tail_len(cf) == 0u) return 0;
    dpx_pattern(a, cf->out_len, 0x31u);
    dpx_pattern(b, cf->out_len, 0x62u);
    int got = dpx_dx_until(cf, a, a, 4, "loopback probe");
    if (got <= 0) return got;
    got = dpx_dx_until(cf, b, b, 4, "loopback probe");
    return got < 0 ? -1 : got > 0;
}
