/* Target ds47: data set 47 (ds47_write / ds47_poll / ds47_read / ds47_reset) over the MOVILINK
 * service client and a fake inverter link the input drives (answers, errors, mismatched and
 * garbage answers, silence until the 200 ms timeout, late answers after a reset).
 *
 * Input: a 32-bit start time, then operations (op octet, low 3 bits):
 *   0  raw request: u8 length, octets (what a master wrote after the DP-V1 header)
 *   1  structured request built with the master's codec (dp_master_ds47_build): ref, id (0x01,
 *      0x02, 0x40 or raw), axis (mostly 0), n, and per parameter attribute, elements, number,
 *      subindex, value (mostly valid)
 *   2  the link answers the oldest request it holds (bits 3..4 mode, bit 5 keep it)
 *   3  time passes (u16 µs << bits 3..5), then ml_client_poll and ds47_poll
 *   4  ds47_read with room for u8 octets
 *   5  ds47_reset (the connection closed)
 *
 * Properties:
 *  - ds47_write answers 0, B5 exactly while a request runs, or B7;
 *  - every MOVILINK service goes out on the connection's channel, belongs to the request that
 *    is running (none after a reset or completion), and for a request built from known fields
 *    the services are exactly the expected ones: one per parameter that is not refused before,
 *    in order, with its index, service and value, none twice, none missing at completion;
 *  - ds47_read answers B5 exactly while nothing is ready, B7 when the room is too small, and a
 *    response that fits; for a structured request the master's parser (dp_master_ds47_parse)
 *    accepts the response and a read answered by the inverter carries the inverter's value. */
#include "dp_master/dpv1_ds47.h"
#include "dpv1/ds47.h"
#include "fuzz_link.h"
#include "movilink/movilink_client.h"

#define CH 2u

typedef struct expect {
    bool known; /* built from fields: the services are predictable */
    dp_master_ds47_req_t req;
    uint8_t n_svc;
    uint8_t svc_param[DS47_MAX_PARAMS]; /* parameter index of each expected service */
    uint8_t issued;
    uint32_t tags[DS47_MAX_PARAMS];
    bool answered[DS47_MAX_PARAMS];
    uint32_t value[DS47_MAX_PARAMS];
} expect_t;

typedef struct rig {
    ml_client_t ml;
    fake_link_t link;
    ds47_t d;
    hal_time_us_t now;
    bool running; /* a request is ours to expect services for */
    uint32_t last_tag; /* the last service sent: the one the client waits for */
    expect_t e;
} rig_t;

static rig_t r;

static void on_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN], uint32_t tag)
{
    (void)ctx;
    r.last_tag = tag;
    PROPERTY(channel == CH, "a data set 47 service on channel %u", channel);
    PROPERTY(r.running, "a MOVILINK service with no request running (after a reset or the end)");
    PROPERTY(r.d.state == DS47_BUSY, "a service while data set 47 is not busy");
    TRACE("  link <- ch%u tag %u: %02X %02X %u %08X\n", channel, tag, req[0], req[1], ml_index(req),
          ml_data(req));
    if (!r.e.known) {
        return;
    }
    PROPERTY(r.e.issued < r.e.n_svc, "service %u for a request that needs %u (duplicate)",
             r.e.issued + 1u, r.e.n_svc);
    const dp_master_ds47_param_t *p = &r.e.req.p[r.e.svc_param[r.e.issued]];
    uint8_t want_svc = r.e.req.id == DS47_ID_MOVILINK ? (uint8_t)(p->attribute >> 4)
                       : r.e.req.id == DS47_ID_CHANGE ? ML_SVC_WRITE
                                                      : ML_SVC_READ;
    PROPERTY(ml_index(req) == p->number && (req[0] & ML_MGMT_SERVICE_MASK) == want_svc,
             "service %u: index %u service %u, expected index %u service %u", r.e.issued + 1u,
             ml_index(req), req[0] & ML_MGMT_SERVICE_MASK, p->number, want_svc);
    bool wr = want_svc == ML_SVC_WRITE || want_svc == ML_SVC_WRITE_VOLATILE;
    PROPERTY(ml_data(req) == (wr ? p->value : 0u), "service %u carries %08X", r.e.issued + 1u,
             ml_data(req));
    r.e.tags[r.e.issued++] = tag;
}

static void deliver(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    /* Which service of the running request does this answer complete? Record the value the
     * inverter reported for a read (the first matching answer wins, as in the client). */
    /* Only a request still in flight takes an answer; a quarantined channel (its request timed
     * out) drops it. */
    if (r.link.delivering && r.ml.ch[channel].busy &&
        ml_index(rsp) == ml_index(r.ml.ch[channel].req) &&
        (rsp[0] & ML_MGMT_SERVICE_MASK) == (r.ml.ch[channel].req[0] & ML_MGMT_SERVICE_MASK)) {
        /* The client takes this answer for its pending request (the last one sent). */
        if (fz_known("ml_late_answer")) {
            PROPERTY(r.link.delivering_tag == r.last_tag, "channel %u: the service sent as tag %u "
                     "completed by the late answer to tag %u (same service and index)", channel,
                     r.last_tag, r.link.delivering_tag);
        }
        if (r.running && r.e.known && r.link.delivering_tag == r.last_tag) {
            for (uint8_t k = 0; k < r.e.issued; k++) {
                if (r.e.tags[k] == r.last_tag) {
                    r.e.answered[k] = (rsp[0] & ML_MGMT_ERROR) == 0u;
                    r.e.value[k] = ml_data(rsp);
                }
            }
        }
    }
    TRACE("  link -> ch%u answer to tag %u: %02X %02X %u %08X\n", channel, r.link.delivering_tag,
          rsp[0], rsp[1], ml_index(rsp), ml_data(rsp));
    ml_client_response(&r.ml, channel, rsp);
}

static uint8_t pick_attr(fz_t *f, uint8_t id)
{
    uint8_t a = fz_u8(f);
    if ((a & 0x80u) != 0u) {
        return fz_u8(f); /* anything */
    }
    if (id == DS47_ID_MOVILINK) {
        return (uint8_t)(0x10u * (1u + a % 3u));
    }
    return DS47_ATTR_VALUE;
}

static size_t structured(fz_t *f, uint8_t *out, size_t max)
{
    dp_master_ds47_req_t *q = &r.e.req;
    memset(q, 0, sizeof *q);
    q->ref = fz_u8(f);
    uint8_t idsel = fz_u8(f);
    static const uint8_t ids[4] = {DS47_ID_REQUEST, DS47_ID_CHANGE, DS47_ID_MOVILINK, 0};
    q->id = (idsel & 3u) == 3u ? fz_u8(f) : ids[idsel & 3u];
    q->axis = (idsel & 0x80u) != 0u ? fz_u8(f) : 0u;
    q->n = (uint8_t)(1u + fz_u8(f) % DS47_MAX_PARAMS);
    for (unsigned i = 0; i < q->n; i++) {
        dp_master_ds47_param_t *p = &q->p[i];
        p->attribute = pick_attr(f, q->id);
        uint8_t shape = fz_u8(f);
        p->elements = (shape & 0x80u) != 0u ? fz_u8(f) : (uint8_t)(shape & 1u);
        p->number = (uint16_t)(8300u + fz_u16(f) % 4000u);
        p->subindex = (shape & 0x40u) != 0u ? fz_u16(f) : 0u;
        p->value = fz_u32(f);
    }
    return dp_master_ds47_build(q, out, max);
}

/* Which parameters need a MOVILINK service (docs/dpv1.md), computed from the fields. */
static void expect_services(void)
{
    const dp_master_ds47_req_t *q = &r.e.req;
    r.e.n_svc = 0;
    if (q->axis != 0u) {
        return;
    }
    for (uint8_t i = 0; i < q->n; i++) {
        const dp_master_ds47_param_t *p = &q->p[i];
        bool ok;
        if (q->id == DS47_ID_MOVILINK) {
            uint8_t svc = (uint8_t)(p->attribute >> 4);
            ok = svc == ML_SVC_READ || svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE;
        } else {
            ok = p->attribute == DS47_ATTR_VALUE;
        }
        ok = ok && p->subindex == 0u && p->elements <= 1u;
        if (ok) {
            r.e.svc_param[r.e.n_svc++] = i;
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size, 0};
    memset(&r, 0, sizeof r);
    r.now = fz_u32(&f);
    r.link.on_request = on_request;
    r.link.deliver = deliver;
    ml_client_init(&r.ml, fl_link(&r.link), 0);
    ds47_init(&r.d, &r.ml, CH);

    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        TRACE("op %u (%02X) t=%u state %d\n", op & 7u, op, r.now, (int)r.d.state);
        switch (op & 7u) {
        case 0:
        case 1: {
            uint8_t req[DPV1_MAX_DATA];
            size_t len;
            expect_t saved = r.e;
            bool was_running = r.running;
            bool known = (op & 7u) == 1u;
            if (known) {
                len = structured(&f, req, sizeof req);
                if (len == 0u) {
                    r.e = saved;
                    break;
                }
            } else {
                len = fz_u8(&f) % (DPV1_MAX_DATA + 1u);
                fz_bytes(&f, req, len);
            }
            bool busy = r.d.state == DS47_BUSY;
            /* Expect the new request's services (ds47_write starts the first one at once). */
            dp_master_ds47_req_t q = r.e.req;
            memset(&r.e, 0, sizeof r.e);
            r.e.known = known;
            r.e.req = q;
            if (known) {
                expect_services();
            }
            r.running = true;
            if (fz_trace_on()) fz_hex("ds47_write", req, len);
            uint8_t rc = ds47_write(&r.d, req, len, r.now);
            TRACE("  -> %02X, state %d\n", rc, (int)r.d.state);
            PROPERTY(rc == 0u || rc == DPV1_ERR_STATE_CONFLICT || rc == DPV1_ERR_INVALID_RANGE,
                     "ds47_write answered %02X", rc);
            PROPERTY((rc == DPV1_ERR_STATE_CONFLICT) == busy, "ds47_write %02X while busy %d",
                     rc, busy);
            if (known && !busy) {
                PROPERTY(r.e.req.ref != 0u || rc == DPV1_ERR_INVALID_RANGE,
                         "request reference 0 answered %02X", rc);
                PROPERTY(rc == 0u || r.e.req.id != DS47_ID_REQUEST || r.e.req.ref == 0u,
                         "a well-formed PROFIdrive request refused with %02X", rc);
            }
            if (rc != 0u) {
                r.e = saved;
                r.running = was_running;
            } else if (r.d.state == DS47_DONE) {
                r.running = false;
            }
            break;
        }
        case 2:
            (void)fl_answer(&r.link, &f, CH, (uint8_t)((op >> 3) & 3u), (op & 0x20u) != 0u);
            break;
        case 3: {
            r.now += (uint32_t)fz_u16(&f) << ((op >> 3) & 7u);
            (void)ml_client_poll(&r.ml, r.now);
            ds47_poll(&r.d, r.now);
            break;
        }
        case 4: {
            size_t max = fz_u8(&f);
            uint8_t out[256];
            size_t len = 0;
            ds47_state_t st = r.d.state;
            uint8_t need = r.d.rsp_len;
            uint8_t rc = ds47_read(&r.d, out, max, &len);
            if (st != DS47_DONE) {
                PROPERTY(rc == DPV1_ERR_STATE_CONFLICT, "read while not done: %02X", rc);
                break;
            }
            if (max < need) {
                PROPERTY(rc == DPV1_ERR_INVALID_RANGE, "read into %zu octets of %u: %02X", max,
                         need, rc);
                break;
            }
            PROPERTY(rc == 0u && len == need && len <= max, "read: %02X, %zu octets", rc, len);
            PROPERTY(len >= 4u, "a response of %zu octets", len);
            if (fz_trace_on()) fz_hex("ds47_read", out, len);
            if (r.e.known) {
                PROPERTY(r.e.issued == r.e.n_svc, "completed after %u of %u services (lost)",
                         r.e.issued, r.e.n_svc);
                dp_master_ds47_rsp_t rsp;
                char err[160] = "";
                bool ok = dp_master_ds47_parse(&r.e.req, out, len, &rsp, err, sizeof err);
                if (!ok) fz_hex("response", out, len);
                PROPERTY(ok, "the master cannot parse the response: %s", err);
                for (uint8_t k = 0; k < r.e.n_svc; k++) {
                    uint8_t i = r.e.svc_param[k];
                    bool reads = !dp_master_ds47_param_writes(&r.e.req, i);
                    if (r.e.answered[k] && reads) {
                        PROPERTY(rsp.p[i].ok && rsp.p[i].has_value && rsp.p[i].value == r.e.value[k],
                                 "parameter %u: the inverter read %08X, the response says %d/%08X",
                                 i, r.e.value[k], rsp.p[i].ok, rsp.p[i].value);
                    }
                }
            }
            r.running = false;
            break;
        }
        case 5:
            ds47_reset(&r.d);
            r.running = false;
            break;
        default:
            break;
        }
        if (r.d.state == DS47_DONE && r.running && r.e.known) {
            PROPERTY(r.e.issued == r.e.n_svc, "done after %u of %u services (lost)", r.e.issued,
                     r.e.n_svc);
        }
        if (r.d.state == DS47_DONE) {
            r.running = false;
        }
    }
    return 0;
}
