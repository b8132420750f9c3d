#include "dp_master/dpv1_xfer.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "dp_slave/fdl_wire.h"

static int begin(dp_master_xfer_t *x, uint8_t dsap, uint8_t ssap, uint32_t timeout_us,
                 dp_master_acyc_done_t done, void *ctx)
{
    if (x->state != DP_MASTER_XFER_IDLE) {
        return -1;
    }
    x->dsap = dsap;
    x->ssap = ssap;
    x->timeout_us = timeout_us;
    x->started = false;
    x->no_response = false;
    x->polls = 0;
    x->telegrams = 0;
    x->done = done;
    x->ctx = ctx;
    x->error[0] = '\0';
    return 0;
}

int dp_master_xfer_start(dp_master_xfer_t *x, uint8_t dsap, uint8_t ssap, const uint8_t *pdu,
                         size_t len, uint32_t timeout_us, dp_master_acyc_done_t done, void *ctx)
{
    if (len == 0u || len > DPV1_MAX_PDU || begin(x, dsap, ssap, timeout_us, done, ctx) != 0) {
        return -1;
    }
    memcpy(x->pdu, pdu, len);
    x->len = (uint16_t)len;
    x->state = DP_MASTER_XFER_REQUEST;
    return 0;
}

int dp_master_xfer_start_polling(dp_master_xfer_t *x, uint8_t dsap, uint8_t ssap,
                                 uint32_t timeout_us, dp_master_acyc_done_t done, void *ctx)
{
    if (begin(x, dsap, ssap, timeout_us, done, ctx) != 0) {
        return -1;
    }
    x->len = 0;
    x->state = DP_MASTER_XFER_POLL;
    return 0;
}

size_t dp_master_xfer_telegram(dp_master_xfer_t *x, hal_time_us_t now, const uint8_t **du)
{
    if (!x->started) {
        x->started = true;
        x->t_start = now;
        x->deadline = now + x->timeout_us;
    }
    x->telegrams++;
    if (x->state == DP_MASTER_XFER_REQUEST) {
        *du = x->pdu;
        return x->len;
    }
    x->polls++;
    *du = NULL;
    return 0;
}

static void finish(dp_master_xfer_t *x, bool ok, const uint8_t *pdu, size_t len, hal_time_us_t t)
{
    /* Copy what the callback needs: it may start the next exchange in this struct. */
    uint8_t rsp[DPV1_MAX_PDU];
    char err[sizeof x->error];
    size_t n = len > sizeof rsp ? sizeof rsp : len;
    /* cppcheck 2.10 only sees the len == 0 callers (a response PDU comes with len > 0). */
    // cppcheck-suppress knownConditionTrueFalse
    if (n > 0u) {
        memcpy(rsp, pdu, n);
    }
    memcpy(err, x->error, sizeof err);
    dp_master_acyc_result_t r = {.ok = ok, .pdu = rsp, .len = n, .error = ok ? NULL : err,
                           .polls = x->polls, .telegrams = x->telegrams,
                           .t_start = x->t_start, .t_end = t};
    dp_master_acyc_done_t done = x->done;
    void *ctx = x->ctx;
    x->state = DP_MASTER_XFER_IDLE;
    x->started = false;
    if (ok) {
        x->completed++;
    } else {
        x->failed++;
    }
    if (done != NULL) {
        done(ctx, &r, t);
    }
}

void dp_master_xfer_fail(dp_master_xfer_t *x, hal_time_us_t now, const char *fmt, ...)
{
    if (x->state == DP_MASTER_XFER_IDLE) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(x->error, sizeof x->error, fmt, ap);
    va_end(ap);
    finish(x, false, NULL, 0, now);
}

static bool timed_out(const dp_master_xfer_t *x, hal_time_us_t now)
{
    return x->started && hal_time_reached(now, x->deadline);
}

static void fail_timeout(dp_master_xfer_t *x, hal_time_us_t now)
{
    dp_master_xfer_fail(x, now, "no %s within the response timeout (%u ms; %u polls answered SC)",
                  x->state == DP_MASTER_XFER_REQUEST ? "acknowledgement of the request"
                                               : "response",
                  (unsigned)(x->timeout_us / 1000u), (unsigned)x->polls);
}

void dp_master_xfer_answer(dp_master_xfer_t *x, const fdl_msg_t *msg, bool sc, hal_time_us_t t)
{
    if (x->state == DP_MASTER_XFER_IDLE) {
        return;
    }
    uint8_t code = sc ? 0xFFu : (uint8_t)(msg->fc & FDL_FC_CODE_MASK);
    if (x->no_response) {
        finish(x, true, NULL, 0, t);
        return;
    }
    bool data = !sc && (code == FDL_RSP_DL || code == FDL_RSP_DH || code == FDL_RSP_RDL ||
                        code == FDL_RSP_RDH) && msg->data_len > 0u;
    if (data) {
        if (!msg->has_dsap || !msg->has_ssap || msg->dsap != x->ssap || msg->ssap != x->dsap) {
            dp_master_xfer_fail(x, t, "answer with the wrong SAPs (%u/%u, expected %u/%u)",
                          msg->has_dsap ? msg->dsap : 0u, msg->has_ssap ? msg->ssap : 0u,
                          x->ssap, x->dsap);
            return;
        }
        finish(x, true, msg->data, msg->data_len, t);
        return;
    }
    if (sc || code == FDL_RSP_NR || code == FDL_RSP_OK || code == FDL_RSP_DL ||
        code == FDL_RSP_DH) {
        /* Taken, or not ready yet: poll next time (unless the time is up). */
        x->state = DP_MASTER_XFER_POLL;
        if (timed_out(x, t)) {
            fail_timeout(x, t);
        }
        return;
    }
    switch (code) {
    case FDL_RSP_RS:
        dp_master_xfer_fail(x, t, "RS: SAP %u not activated for us (MSAC1 closed, connection not "
                            "bound, or another master)", x->dsap);
        return;
    case FDL_RSP_RR:
        dp_master_xfer_fail(x, t, "RR: the slave has no resource for SAP %u", x->dsap);
        return;
    case FDL_RSP_UE:
        dp_master_xfer_fail(x, t, "UE: user error at SAP %u", x->dsap);
        return;
    default:
        dp_master_xfer_fail(x, t, "unexpected answer FC 0x%02X", msg->fc);
        return;
    }
}

hal_time_us_t dp_master_xfer_check_timeout(dp_master_xfer_t *x, hal_time_us_t now)
{
    if (x->state == DP_MASTER_XFER_IDLE || !x->started) {
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    if (timed_out(x, now)) {
        fail_timeout(x, now);
        return now + HAL_TIME_NO_DEADLINE_US;
    }
    return x->deadline;
}

const char *dp_master_v1_error_text(uint8_t code1)
{
    switch (code1) {
    case 0xA0: return "application: read error";
    case 0xA1: return "application: write error";
    case 0xA2: return "application: module failure";
    case 0xA8: return "application: version conflict";
    case 0xA9: return "application: feature not supported";
    case 0xB0: return "access: invalid index";
    case 0xB1: return "access: write length error";
    case 0xB2: return "access: invalid slot";
    case 0xB3: return "access: type conflict";
    case 0xB4: return "access: invalid area";
    case 0xB5: return "access: state conflict";
    case 0xB6: return "access: access denied";
    case 0xB7: return "access: invalid range";
    case 0xB8: return "access: invalid parameter";
    case 0xB9: return "access: invalid type";
    case 0xC0: return "resource: read constraint conflict";
    case 0xC1: return "resource: write constraint conflict";
    case 0xC2: return "resource: busy";
    case 0xC3: return "resource: unavailable";
    default: break;
    }
    switch (code1 >> 4) {
    case 0xA: return "application: user specific";
    case 0xB: return "access: user specific";
    case 0xC: return "resource: user specific";
    case 0xD: case 0xE: case 0xF: return "user specific";
    default: return "unknown error class";
    }
}

bool dp_master_v1_is_negative(const uint8_t *pdu, size_t len, uint8_t *code1)
{
    if (len < 1u || (pdu[0] & DPV1_FN_ERROR) == 0u) {
        return false;
    }
    if (code1 != NULL) {
        *code1 = len >= 3u ? pdu[2] : 0u;
    }
    return true;
}
