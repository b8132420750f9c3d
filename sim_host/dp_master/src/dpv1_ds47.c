#include "dp_master/dpv1_ds47.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "dp_master/param_channel.h"

/* ---- DS47 request / response ---------------------------------------------------------------- */

bool dp_master_ds47_param_writes(const dp_master_ds47_req_t *r, unsigned i)
{
    if (r->id == DS47_ID_CHANGE) {
        return true;
    }
    if (r->id == DS47_ID_MOVILINK) {
        uint8_t svc = (uint8_t)(r->p[i].attribute & 0xF0u);
        return svc == DS47_ATTR_ML_WRITE || svc == DS47_ATTR_ML_WRITE_VOLATILE;
    }
    return false;
}

size_t dp_master_ds47_build(const dp_master_ds47_req_t *r, uint8_t *out, size_t max)
{
    if (r->n == 0u || r->n > DS47_MAX_PARAMS) {
        return 0;
    }
    size_t need = 4u + 6u * r->n;
    for (unsigned i = 0; i < r->n; i++) {
        need += dp_master_ds47_param_writes(r, i) ? 6u : 0u;
    }
    if (need > max) {
        return 0;
    }
    size_t n = 0;
    out[n++] = r->ref;
    out[n++] = r->id;
    out[n++] = r->axis;
    out[n++] = r->n;
    for (unsigned i = 0; i < r->n; i++) {
        const dp_master_ds47_param_t *p = &r->p[i];
        out[n++] = p->attribute;
        out[n++] = p->elements;
        out[n++] = (uint8_t)(p->number >> 8);
        out[n++] = (uint8_t)p->number;
        out[n++] = (uint8_t)(p->subindex >> 8);
        out[n++] = (uint8_t)p->subindex;
    }
    for (unsigned i = 0; i < r->n; i++) {
        if (!dp_master_ds47_param_writes(r, i)) {
            continue;
        }
        uint32_t v = r->p[i].value;
        out[n++] = DS47_FORMAT_DWORD;
        out[n++] = 1u;
        out[n++] = (uint8_t)(v >> 24);
        out[n++] = (uint8_t)(v >> 16);
        out[n++] = (uint8_t)(v >> 8);
        out[n++] = (uint8_t)v;
    }
    return n;
}

static void errf(char *err, size_t errlen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void errf(char *err, size_t errlen, const char *fmt, ...)
{
    if (err == NULL || errlen == 0u) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* Octets of one value of a format (PROFIdrive data types; 0 = unknown). */
static size_t format_size(uint8_t f)
{
    switch (f) {
    case 0x01: case 0x02: case 0x05: case 0x41: return 1;
    case 0x03: case 0x06: case 0x42: return 2;
    case 0x04: case 0x07: case 0x08: case 0x43: return 4;
    default: return 0;
    }
}

/* One value block at d[*pos]: format, count, values (padded to words). */
static bool parse_block(const uint8_t *d, size_t len, size_t *pos, dp_master_ds47_result_t *res,
                        unsigned i, char *err, size_t errlen)
{
    if (*pos + 2u > len) {
        errf(err, errlen, "parameter %u: block missing (%zu octets in all)", i + 1u, len);
        return false;
    }
    uint8_t fmt = d[*pos];
    uint8_t count = d[*pos + 1u];
    *pos += 2u;
    res->format = fmt;
    if (fmt == DS47_FORMAT_ZERO) {
        res->ok = true;
        return true;
    }
    if (fmt == DS47_FORMAT_ERROR) {
        if (count < 1u || *pos + 2u * (size_t)count > len) {
            errf(err, errlen, "parameter %u: error block with %u values truncated", i + 1u,
                 count);
            return false;
        }
        res->ok = false;
        res->error = (uint16_t)((d[*pos] << 8) | d[*pos + 1u]);
        *pos += 2u * (size_t)count;
        return true;
    }
    size_t sz = format_size(fmt);
    if (sz == 0u) {
        errf(err, errlen, "parameter %u: unknown format 0x%02X", i + 1u, fmt);
        return false;
    }
    size_t bytes = sz * count;
    size_t padded = bytes + (bytes & 1u);
    if (count < 1u || *pos + bytes > len) {
        errf(err, errlen, "parameter %u: %u values of format 0x%02X truncated", i + 1u, count,
             fmt);
        return false;
    }
    uint32_t v = 0;
    for (size_t k = 0; k < sz; k++) {
        v = (v << 8) | d[*pos + k];
    }
    res->ok = true;
    res->has_value = true;
    res->value = v;
    *pos += padded <= len - *pos ? padded : bytes;
    return true;
}

bool dp_master_ds47_parse(const dp_master_ds47_req_t *req, const uint8_t *d, size_t len,
                          dp_master_ds47_rsp_t *rsp, char *err, size_t errlen)
{
    memset(rsp, 0, sizeof *rsp);
    if (len < 4u) {
        errf(err, errlen, "DS47 response of %zu octets (at least 4)", len);
        return false;
    }
    rsp->ref = d[0];
    rsp->id = d[1];
    rsp->axis = d[2];
    rsp->n = d[3];
    rsp->negative = (d[1] & DS47_ID_ERROR) != 0u;
    if (rsp->ref != req->ref) {
        errf(err, errlen, "response reference 0x%02X, request 0x%02X", rsp->ref, req->ref);
        return false;
    }
    if ((uint8_t)(rsp->id & (uint8_t)~DS47_ID_ERROR) != req->id) {
        errf(err, errlen, "response id 0x%02X to request id 0x%02X", rsp->id, req->id);
        return false;
    }
    if (rsp->axis != req->axis || rsp->n != req->n || rsp->n > DS47_MAX_PARAMS) {
        errf(err, errlen, "response axis %u / %u parameters, request axis %u / %u", rsp->axis,
             rsp->n, req->axis, req->n);
        return false;
    }
    size_t pos = 4;
    for (unsigned i = 0; i < rsp->n; i++) {
        dp_master_ds47_result_t *res = &rsp->p[i];
        if (!rsp->negative && dp_master_ds47_param_writes(req, i)) {
            res->ok = true; /* a successful write has no block */
            continue;
        }
        if (!parse_block(d, len, &pos, res, i, err, errlen)) {
            return false;
        }
        if (!rsp->negative && !res->ok) {
            errf(err, errlen, "parameter %u: error block in a positive response", i + 1u);
            return false;
        }
    }
    if (pos != len) {
        errf(err, errlen, "%zu octets after the last block", len - pos);
        return false;
    }
    return true;
}

size_t dp_master_ml_error_value_text(uint16_t value, char *out, size_t max)
{
    uint8_t cls = (uint8_t)(value >> 8);
    uint8_t low = (uint8_t)value;
    if (value == 0x0502u) {
        int n = snprintf(out, max, "class 5 code 2: connection timeout (inverter in reset or "
                                   "system fault)");
        return n < 0 ? 0u : (size_t)n;
    }
    uint8_t tg[ML_TELEGRAM_LEN] = {0};
    tg[4] = cls;
    if (cls == ML_CLASS_OTHER) {
        tg[7] = low; /* class 8: code 0, the additional code carries the reason */
    } else {
        tg[5] = low;
    }
    return ml_error_text(tg, out, max);
}

static const char *profidrive_text(uint16_t e)
{
    switch (e) {
    case 0x00: return "impermissible parameter number";
    case 0x01: return "parameter value cannot be changed";
    case 0x02: return "low or high limit exceeded";
    case 0x03: return "faulty subindex";
    case 0x04: return "no array";
    case 0x05: return "incorrect data type";
    case 0x06: return "setting not permitted (may only be reset)";
    case 0x07: return "description element cannot be changed";
    case 0x09: return "no description data available";
    case 0x0B: return "no operation priority";
    case 0x0F: return "no text array available";
    case 0x11: return "request cannot be executed because of the operating state";
    case 0x14: return "value impermissible";
    case 0x15: return "response too long";
    case 0x16: return "parameter address impermissible";
    case 0x17: return "illegal format";
    case 0x18: return "number of values inconsistent";
    case 0x19: return "axis nonexistent";
    default: return NULL;
    }
}

size_t dp_master_ds47_error_text(uint8_t id, uint16_t error, char *out, size_t max)
{
    int n;
    const char *pd = profidrive_text(error);
    if ((id & 0x7Fu) == DS47_ID_MOVILINK && error >= 0x0100u) {
        return dp_master_ml_error_value_text(error, out, max);
    }
    if (pd != NULL) {
        n = snprintf(out, max, "PROFIdrive error 0x%02X: %s", error, pd);
    } else if (error >= 0x0080u && error < 0x0090u) {
        /* Class-8 additional codes start at 0x10; below that the card puts the code of a
         * class-5/6 MOVILINK error (0x0505, 0x0602, 0x0608) after 0x80. */
        uint16_t v = (uint16_t)(((error & 0x0Fu) == 0x05u ? 0x0500u : 0x0600u) | (error & 0x0Fu));
        char ml[96];
        ml[0] = '\0';
        dp_master_ml_error_value_text(v, ml, sizeof ml);
        n = snprintf(out, max, "manufacturer specific 0x%04X (MOVILINK 0x%04X: %s)", error, v, ml);
    } else if (error >= 0x0080u && error <= 0x00FFu) {
        char ml[96];
        dp_master_ml_error_value_text((uint16_t)(0x0800u | (error - 0x80u)), ml, sizeof ml);
        n = snprintf(out, max, "manufacturer specific (MOVILINK %s)", ml);
    } else if (error >= 0x0065u && error <= 0x00FFu) {
        n = snprintf(out, max, "manufacturer specific error 0x%02X", error);
    } else {
        n = snprintf(out, max, "unknown error value 0x%04X", error);
    }
    return n < 0 ? 0u : (size_t)n;
}

/* ---- I&M0 ----------------------------------------------------------------------------------- */

static uint16_t be16(const uint8_t *p) { return (uint16_t)((p[0] << 8) | p[1]); }

bool dp_master_im0_decode(const uint8_t *d, size_t len, dp_master_im0_t *o, char *err,
                          size_t errlen)
{
    memset(o, 0, sizeof *o);
    if (len < 4u || d[0] != IM_FN_CALL || be16(&d[2]) != IM_INDEX_0) {
        errf(err, errlen, "I&M answer does not start 08 00 FD E8 (%zu octets)", len);
        return false;
    }
    if (len != 4u + IM_RECORD_LEN) {
        errf(err, errlen, "I&M0 record of %zu octets (64 expected)", len - 4u);
        return false;
    }
    const uint8_t *r = d + 4;
    memcpy(o->header, r, 10);
    o->manufacturer_id = be16(&r[10]);
    memcpy(o->order_id, &r[12], 20);
    memcpy(o->serial_number, &r[32], 16);
    o->hardware_revision = be16(&r[48]);
    o->sw_prefix = (char)r[50];
    o->sw_major = r[51];
    o->sw_minor = r[52];
    o->sw_bugfix = r[53];
    o->rev_counter = be16(&r[54]);
    o->profile_id = be16(&r[56]);
    o->profile_specific_type = be16(&r[58]);
    o->im_version_major = r[60];
    o->im_version_minor = r[61];
    o->im_supported = be16(&r[62]);
    return true;
}

/* ---- the record call ------------------------------------------------------------------------ */

static void call_finish(dp_master_call_t *c, bool ok, hal_time_us_t now)
{
    c->ok = ok;
    c->state = DP_MASTER_CALL_DONE;
    c->t_end = now;
    if (c->done != NULL) {
        c->done(c->ctx, c, now);
    }
}

static void call_fail(dp_master_call_t *c, hal_time_us_t now, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void call_fail(dp_master_call_t *c, hal_time_us_t now, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->error, sizeof c->error, fmt, ap);
    va_end(ap);
    call_finish(c, false, now);
}

static void call_answer(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now);

static int submit_read(dp_master_call_t *c, hal_time_us_t now)
{
    const uint8_t pdu[4] = {DPV1_FN_READ, c->slot, c->index, c->read_len};
    c->reads++;
    return dp_master_acyc_submit(&c->port, pdu, sizeof pdu, call_answer, c, now);
}

static void call_answer(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    dp_master_call_t *c = ctx;
    const char *what = c->state == DP_MASTER_CALL_WRITE ? "Write" : "Read";
    c->telegrams += r->telegrams;
    c->polls += r->polls;
    if (!r->ok) {
        call_fail(c, now, "%s.req index %u: %s", what, c->index, r->error);
        return;
    }
    uint8_t code1 = 0;
    if (dp_master_v1_is_negative(r->pdu, r->len, &code1)) {
        if (c->state == DP_MASTER_CALL_READ && code1 == DPV1_ERR_STATE_CONFLICT) {
            c->busy++;
            if (c->reads >= c->max_reads || hal_time_reached(now, c->deadline)) {
                call_fail(c, now, "no answer to the request: Read.req index %u still answered "
                          "B5 (state conflict) after %u reads, %u ms", c->index,
                          (unsigned)c->reads, (unsigned)((now - c->t_start) / 1000u));
                return;
            }
            if (submit_read(c, now) != 0) {
                call_fail(c, now, "Read.req index %u could not be queued", c->index);
            }
            return;
        }
        c->dpv1_negative = true;
        c->neg_fn = r->pdu[0];
        c->neg_code1 = code1;
        call_fail(c, now, "%s.res index %u negative: Error_Code_1 0x%02X (%s)", what, c->index,
                  code1, dp_master_v1_error_text(code1));
        return;
    }
    if (c->state == DP_MASTER_CALL_WRITE) {
        if (r->len < 4u || r->pdu[0] != DPV1_FN_WRITE || r->pdu[2] != c->index) {
            call_fail(c, now, "Write.req index %u: unexpected answer (%zu octets, first 0x%02X)",
                      c->index, r->len, r->len > 0u ? r->pdu[0] : 0u);
            return;
        }
        c->state = DP_MASTER_CALL_READ;
        if (submit_read(c, now) != 0) {
            call_fail(c, now, "Read.req index %u could not be queued", c->index);
        }
        return;
    }
    if (r->len < 4u || r->pdu[0] != DPV1_FN_READ || r->pdu[2] != c->index ||
        r->pdu[3] != r->len - 4u) {
        call_fail(c, now, "Read.req index %u: unexpected answer (%zu octets, first 0x%02X, "
                  "length octet %u)", c->index, r->len, r->len > 0u ? r->pdu[0] : 0u,
                  r->len > 3u ? r->pdu[3] : 0u);
        return;
    }
    c->len = (uint8_t)(r->len - 4u);
    memcpy(c->data, r->pdu + 4, c->len);
    call_finish(c, true, now);
}

int dp_master_call_start(dp_master_call_t *c, dp_master_acyc_port_t port, uint8_t index,
                         const uint8_t *data, size_t len, uint8_t read_len,
                         dp_master_call_done_t done, void *ctx, hal_time_us_t now)
{
    if (c->state == DP_MASTER_CALL_WRITE || c->state == DP_MASTER_CALL_READ ||
        len > DPV1_MAX_DATA || len == 0u) {
        return -1;
    }
    uint32_t max_reads = c->max_reads != 0u ? c->max_reads : 10000u;
    uint32_t timeout_us = c->timeout_us != 0u ? c->timeout_us : 5000000u;
    uint8_t slot = c->slot;
    memset(c, 0, sizeof *c);
    c->slot = slot;
    c->port = port;
    c->index = index;
    c->read_len = read_len;
    c->max_reads = max_reads;
    c->timeout_us = timeout_us;
    c->t_start = now;
    c->deadline = now + timeout_us;
    c->done = done;
    c->ctx = ctx;
    memcpy(c->wdata, data, len);
    c->wlen = (uint8_t)len;
    uint8_t pdu[DPV1_MAX_PDU];
    pdu[0] = DPV1_FN_WRITE;
    pdu[1] = c->slot;
    pdu[2] = index;
    pdu[3] = (uint8_t)len;
    memcpy(&pdu[4], data, len);
    c->state = DP_MASTER_CALL_WRITE;
    if (dp_master_acyc_submit(&port, pdu, 4u + len, call_answer, c, now) != 0) {
        c->state = DP_MASTER_CALL_IDLE;
        return -1;
    }
    return 0;
}

int dp_master_ds47_start(dp_master_call_t *c, dp_master_acyc_port_t port,
                         const dp_master_ds47_req_t *req, dp_master_call_done_t done, void *ctx,
                         hal_time_us_t now)
{
    uint8_t buf[DPV1_MAX_DATA];
    size_t n = dp_master_ds47_build(req, buf, sizeof buf);
    if (n == 0u) {
        return -1;
    }
    return dp_master_call_start(c, port, DPV1_INDEX_DS47, buf, n, DPV1_MAX_DATA, done, ctx, now);
}

int dp_master_im0_start(dp_master_call_t *c, dp_master_acyc_port_t port, dp_master_call_done_t done,
                        void *ctx, hal_time_us_t now)
{
    const uint8_t sel[4] = {IM_FN_CALL, 0x00, (uint8_t)(IM_INDEX_0 >> 8), (uint8_t)IM_INDEX_0};
    return dp_master_call_start(c, port, DPV1_INDEX_IM, sel, sizeof sel, DPV1_MAX_DATA, done, ctx,
                                now);
}
