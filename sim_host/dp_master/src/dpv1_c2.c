#include "dp_master/dpv1_c2.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *dp_master_c2_state_name(dp_master_c2_state_t s)
{
    switch (s) {
    case DP_MASTER_C2_CLOSED: return "closed";
    case DP_MASTER_C2_RM: return "Initiate to the resource manager";
    case DP_MASTER_C2_INITIATING: return "waiting for the Initiate.res";
    case DP_MASTER_C2_OPEN: return "open";
    case DP_MASTER_C2_ABORTING: return "aborting";
    }
    return "?";
}

void dp_master_c2_init(dp_master_c2_t *c, const dp_master_c2_cfg_t *cfg)
{
    memset(c, 0, sizeof *c);
    c->cfg = *cfg;
    if (c->cfg.ssap == 0u) c->cfg.ssap = DP_MASTER_C2_SSAP_DEFAULT;
    if (c->cfg.send_timeout == 0u) c->cfg.send_timeout = DP_MASTER_C2_SEND_TIMEOUT_DEFAULT;
    if (c->cfg.response_timeout_us == 0u) {
        c->cfg.response_timeout_us = DP_MASTER_C2_RESPONSE_TIMEOUT_US_DEFAULT;
    }
}

size_t dp_master_c2_build_initiate(uint8_t *out, uint16_t send_timeout)
{
    const uint8_t pdu[DP_MASTER_C2_INITIATE_LEN] = {
        DPV1_FN_INITIATE, 0x00, 0x00, 0x00,
        (uint8_t)(send_timeout >> 8), (uint8_t)send_timeout,
        0x01, 0x00, /* Features_Supported_1: DPMV1_RW (Read/Write); _2: none */
        0x00, 0x00, /* Profile_Features_Supported_1/2 */
        0x00, 0x00, /* Profile_Ident_Number: none (the DFP21B's profile id is 0) */
        0x00, 0x02, /* S_Type 0 (API/SCL only), S_Len 2 */
        0x00, 0x02, /* D_Type, D_Len */
        0x00, 0x00, /* S_Addr: API 0, SCL 0 */
        0x00, 0x00, /* D_Addr: API 0, SCL 0 */
    };
    memcpy(out, pdu, sizeof pdu);
    return sizeof pdu;
}

static void set_error(dp_master_c2_t *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void set_error(dp_master_c2_t *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->error, sizeof c->error, fmt, ap);
    va_end(ap);
}

/* Tells the owner of the current operation how it ended. */
static void report(dp_master_c2_t *c, bool ok, const dp_master_acyc_result_t *base,
                   const char *error, hal_time_us_t t)
{
    dp_master_acyc_done_t done = c->user_done;
    void *ctx = c->user_ctx;
    c->user_done = NULL;
    c->user_ctx = NULL;
    if (done == NULL) {
        return;
    }
    dp_master_acyc_result_t r = *base;
    r.ok = ok;
    r.error = ok ? NULL : error;
    done(ctx, &r, t);
}

static void close_with(dp_master_c2_t *c, const dp_master_acyc_result_t *r, hal_time_us_t t)
{
    c->state = DP_MASTER_C2_CLOSED;
    c->op = DP_MASTER_C2_OP_NONE;
    c->sap = 0;
    bool had_queued = c->queued;
    c->queued = false;
    report(c, false, r, c->error, t);
    if (had_queued && c->queued_done != NULL) {
        dp_master_acyc_result_t q = {.ok = false, .error = c->error, .t_start = t, .t_end = t};
        c->queued_done(c->queued_ctx, &q, t);
    }
}

static void abort_text(char *out, size_t max, const uint8_t *pdu, size_t len)
{
    uint8_t subnet = len > 1u ? pdu[1] : 0u;
    uint8_t ir = len > 2u ? pdu[2] : 0u;
    static const char *const reasons[16] = {
        "0", "SE sequence error", "FE invalid request PDU", "TO connection timeout",
        "RE invalid response PDU", "IV invalid service from the user", "STO Send_Timeout too small",
        "IA invalid additional address information", "OC waiting for FDL_DATA_REPLY.con", "9",
        "10", "11", "12", "13", "14", "RES resource"};
    const char *inst = (ir & 0x30u) == 0x00u ? "FDL" : (ir & 0x30u) == 0x10u ? "MSAC_C2"
                       : (ir & 0x30u) == 0x20u ? "user" : "reserved";
    snprintf(out, max, "Abort from the slave: subnet %u, instance %s, reason %u%s%s", subnet,
             inst, ir & 0x0Fu, (ir & 0x30u) == 0x10u ? " " : "",
             (ir & 0x30u) == 0x10u ? reasons[ir & 0x0Fu] : "");
}

static bool is_abort(const dp_master_acyc_result_t *r)
{
    return r->ok && r->len >= 1u && r->pdu[0] == DPV1_FN_ABORT;
}

static void start_queued(dp_master_c2_t *c, hal_time_us_t now);

static void xfer_done(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now);

/* The resource manager named the connection's SAP: the Initiate goes there next. */
static void rm_answered(dp_master_c2_t *c, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    if (r->len < 2u || r->pdu[0] != DPV1_FN_RM || r->pdu[1] > 48u) {
        set_error(c, "resource manager: unexpected answer (%zu octets, first 0x%02X)", r->len,
                  r->len > 0u ? r->pdu[0] : 0u);
        close_with(c, r, now);
        return;
    }
    c->sap = r->pdu[1];
    c->state = DP_MASTER_C2_INITIATING;
    (void)dp_master_xfer_start_polling(&c->x, c->sap, c->cfg.ssap, c->cfg.response_timeout_us,
                                 xfer_done, c);
}

/* The answer to the resource manager's poll or to the Initiate. */
static void open_done(dp_master_c2_t *c, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    if (!r->ok) {
        set_error(c, "%s: %s", c->state == DP_MASTER_C2_RM ? "Initiate (resource manager)"
                                                     : "Initiate", r->error);
        close_with(c, r, now);
        return;
    }
    if (is_abort(r)) {
        char text[160];
        abort_text(text, sizeof text, r->pdu, r->len);
        set_error(c, "connection refused (%s SAP %u): %s",
                  c->state == DP_MASTER_C2_RM ? "resource manager" : "connection",
                  c->state == DP_MASTER_C2_RM ? DPV1_SAP_RM : c->sap, text);
        close_with(c, r, now);
        return;
    }
    if (c->state == DP_MASTER_C2_RM) {
        rm_answered(c, r, now);
        return;
    }
    if (r->pdu[0] == DPV1_FN_INITIATE && r->len >= 12u) {
        c->state = DP_MASTER_C2_OPEN;
        c->op = DP_MASTER_C2_OP_NONE;
        c->opens++;
        memcpy(c->initiate_res, r->pdu, r->len);
        c->initiate_res_len = (uint8_t)r->len;
        c->error[0] = '\0';
        report(c, true, r, NULL, now);
        start_queued(c, now);
        return;
    }
    if (r->pdu[0] == (DPV1_FN_INITIATE | DPV1_FN_ERROR)) {
        set_error(c, "Initiate refused: %s (Error_Code_1 0x%02X)",
                  dp_master_v1_error_text(r->len > 2u ? r->pdu[2] : 0u),
                  r->len > 2u ? r->pdu[2] : 0u);
    } else {
        set_error(c, "Initiate: unexpected answer (%zu octets, first 0x%02X)", r->len,
                  r->pdu[0]);
    }
    close_with(c, r, now);
}

/* The answer to a request or to the Idle that keeps an open connection alive. */
static void request_done(dp_master_c2_t *c, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    bool idle = c->op == DP_MASTER_C2_OP_IDLE;
    if (!r->ok || is_abort(r)) {
        if (is_abort(r)) {
            char text[160];
            abort_text(text, sizeof text, r->pdu, r->len);
            set_error(c, "connection closed: %s", text);
        } else {
            set_error(c, "%s: %s; connection closed", idle ? "Idle" : "request", r->error);
        }
        close_with(c, r, now);
        return;
    }
    c->op = DP_MASTER_C2_OP_NONE;
    if (idle) {
        if (r->len < 1u || r->pdu[0] != DPV1_FN_IDLE) {
            set_error(c, "Idle answered with 0x%02X (expected 0x48)",
                      r->len > 0u ? r->pdu[0] : 0u);
        }
        c->idles++;
    } else {
        c->requests++;
        report(c, true, r, NULL, now);
    }
    start_queued(c, now);
}

/* Every exchange of x ends here. */
static void xfer_done(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    dp_master_c2_t *c = ctx;
    switch (c->op) {
    case DP_MASTER_C2_OP_NONE:
        return;
    case DP_MASTER_C2_OP_OPEN:
        open_done(c, r, now);
        return;
    case DP_MASTER_C2_OP_REQUEST:
    case DP_MASTER_C2_OP_IDLE:
        request_done(c, r, now);
        return;
    case DP_MASTER_C2_OP_ABORT:
        c->state = DP_MASTER_C2_CLOSED;
        c->op = DP_MASTER_C2_OP_NONE;
        c->sap = 0;
        report(c, r->ok, r, r->error, now);
        return;
    }
}

int dp_master_c2_open(dp_master_c2_t *c, dp_master_acyc_done_t done, void *ctx, hal_time_us_t now)
{
    (void)now;
    if (c->state != DP_MASTER_C2_CLOSED || c->op != DP_MASTER_C2_OP_NONE) {
        return -1;
    }
    uint8_t pdu[DP_MASTER_C2_INITIATE_LEN];
    size_t n = dp_master_c2_build_initiate(pdu, c->cfg.send_timeout);
    if (dp_master_xfer_start(&c->x, DPV1_SAP_RM, c->cfg.ssap, pdu, n, c->cfg.response_timeout_us,
                       xfer_done, c) != 0) {
        return -1;
    }
    c->state = DP_MASTER_C2_RM;
    c->op = DP_MASTER_C2_OP_OPEN;
    c->user_done = done;
    c->user_ctx = ctx;
    c->error[0] = '\0';
    c->initiate_res_len = 0;
    return 0;
}

static int start_request(dp_master_c2_t *c, const uint8_t *pdu, size_t len,
                         dp_master_acyc_done_t done, void *ctx)
{
    if (dp_master_xfer_start(&c->x, c->sap, c->cfg.ssap, pdu, len, c->cfg.response_timeout_us,
                       xfer_done, c) != 0) {
        return -1;
    }
    c->op = DP_MASTER_C2_OP_REQUEST;
    c->user_done = done;
    c->user_ctx = ctx;
    return 0;
}

static void start_queued(dp_master_c2_t *c, hal_time_us_t now)
{
    (void)now;
    if (!c->queued || c->state != DP_MASTER_C2_OPEN || c->op != DP_MASTER_C2_OP_NONE) {
        return;
    }
    c->queued = false;
    if (start_request(c, c->queued_pdu, c->queued_len, c->queued_done, c->queued_ctx) != 0) {
        dp_master_acyc_result_t q = {.ok = false, .error = "request could not be started"};
        c->queued_done(c->queued_ctx, &q, now);
    }
}

int dp_master_c2_submit(dp_master_c2_t *c, const uint8_t *pdu, size_t len,
                        dp_master_acyc_done_t done, void *ctx, hal_time_us_t now)
{
    (void)now;
    if (c->state != DP_MASTER_C2_OPEN || c->queued || len == 0u || len > DPV1_MAX_PDU) {
        return -1;
    }
    if (c->op == DP_MASTER_C2_OP_IDLE) {
        memcpy(c->queued_pdu, pdu, len);
        c->queued_len = (uint16_t)len;
        c->queued_done = done;
        c->queued_ctx = ctx;
        c->queued = true;
        return 0;
    }
    if (c->op != DP_MASTER_C2_OP_NONE) {
        return -1;
    }
    return start_request(c, pdu, len, done, ctx);
}

static void start_abort(dp_master_c2_t *c)
{
    const uint8_t pdu[4] = {DPV1_FN_ABORT, 0x00, c->abort_code, 0x00};
    (void)dp_master_xfer_start(&c->x, c->sap, c->cfg.ssap, pdu, sizeof pdu,
                               c->cfg.response_timeout_us, xfer_done, c);
    c->x.no_response = true;
}

int dp_master_c2_abort(dp_master_c2_t *c, uint8_t instance_reason, dp_master_acyc_done_t done,
                       void *ctx, hal_time_us_t now)
{
    if (c->state == DP_MASTER_C2_CLOSED || c->state == DP_MASTER_C2_ABORTING) {
        return -1;
    }
    bool have_sap = c->state != DP_MASTER_C2_RM;
    /* Whatever runs is given up. */
    if (c->op != DP_MASTER_C2_OP_NONE || c->queued) {
        set_error(c, "aborted by the master");
        dp_master_acyc_result_t r = {.ok = false, .t_start = now, .t_end = now};
        dp_master_c2_op_t op = c->op;
        c->op = DP_MASTER_C2_OP_NONE;
        c->x.state = DP_MASTER_XFER_IDLE;
        c->x.started = false;
        if (op != DP_MASTER_C2_OP_IDLE) {
            report(c, false, &r, c->error, now);
        }
        if (c->queued) {
            c->queued = false;
            c->queued_done(c->queued_ctx, &r, now);
        }
    }
    c->user_done = done;
    c->user_ctx = ctx;
    if (!have_sap) {
        /* The resource manager has not named a SAP yet: nothing to abort on the wire. */
        c->state = DP_MASTER_C2_CLOSED;
        dp_master_acyc_result_t r = {.ok = true, .t_start = now, .t_end = now};
        report(c, true, &r, NULL, now);
        return 0;
    }
    c->abort_code = instance_reason != 0u ? instance_reason : DP_MASTER_C2_ABORT_USER;
    c->op = DP_MASTER_C2_OP_ABORT;
    c->state = DP_MASTER_C2_ABORTING;
    if (c->on_wire) {
        c->abort_pending = true; /* after the answer to the telegram on the wire */
    } else {
        start_abort(c);
    }
    return 0;
}

static int c2_port_submit(void *ctx, unsigned idx, const uint8_t *pdu, size_t len,
                          dp_master_acyc_done_t done, void *done_ctx, hal_time_us_t now)
{
    (void)idx;
    return dp_master_c2_submit(ctx, pdu, len, done, done_ctx, now);
}

dp_master_acyc_port_t dp_master_c2_port(dp_master_c2_t *c)
{
    return (dp_master_acyc_port_t){.submit = c2_port_submit, .ctx = c, .idx = 0};
}

/* ---- driven by the master station ---------------------------------------------------------- */

static hal_time_us_t idle_due(const dp_master_c2_t *c)
{
    /* Half the Send_Timeout (10 ms units) after the last telegram. */
    return c->last_tx + (uint32_t)c->cfg.send_timeout * 5000u;
}

bool dp_master_c2_ready(dp_master_c2_t *c, hal_time_us_t now)
{
    (void)dp_master_xfer_check_timeout(&c->x, now); /* may close the connection */
    if (c->state == DP_MASTER_C2_OPEN && c->op == DP_MASTER_C2_OP_NONE && !c->queued &&
        !c->cfg.no_idle && c->last_tx_valid && hal_time_reached(now, idle_due(c))) {
        const uint8_t pdu[4] = {DPV1_FN_IDLE, 0x00, 0x00, 0x00};
        if (dp_master_xfer_start(&c->x, c->sap, c->cfg.ssap, pdu, sizeof pdu,
                           c->cfg.response_timeout_us, xfer_done, c) == 0) {
            c->op = DP_MASTER_C2_OP_IDLE;
        }
    }
    return dp_master_xfer_busy(&c->x);
}

size_t dp_master_c2_telegram(dp_master_c2_t *c, hal_time_us_t now, uint8_t *dsap,
                             const uint8_t **du)
{
    *dsap = c->x.dsap;
    c->on_wire = true;
    c->last_tx = now;
    c->last_tx_valid = true;
    return dp_master_xfer_telegram(&c->x, now, du);
}

/* An Abort asked for while a telegram was on the wire goes out now; that answer is dropped. */
static bool abort_now(dp_master_c2_t *c)
{
    c->on_wire = false;
    if (!c->abort_pending) {
        return false;
    }
    c->abort_pending = false;
    start_abort(c);
    return true;
}

void dp_master_c2_answer(dp_master_c2_t *c, const fdl_msg_t *msg, bool sc, hal_time_us_t t)
{
    if (abort_now(c)) {
        return;
    }
    dp_master_xfer_answer(&c->x, msg, sc, t);
}

void dp_master_c2_no_answer(dp_master_c2_t *c, hal_time_us_t t)
{
    if (abort_now(c)) {
        return;
    }
    dp_master_xfer_fail(&c->x, t, "no answer from slave %u", c->cfg.slave);
}

hal_time_us_t dp_master_c2_next_deadline(const dp_master_c2_t *c, hal_time_us_t now)
{
    hal_time_us_t next = now + HAL_TIME_NO_DEADLINE_US;
    if (dp_master_xfer_busy(&c->x) && c->x.started) {
        next = c->x.deadline;
    }
    if (c->state == DP_MASTER_C2_OPEN && c->op == DP_MASTER_C2_OP_NONE && !c->cfg.no_idle &&
        c->last_tx_valid) {
        next = hal_time_earlier(next, idle_due(c));
    }
    return next;
}
