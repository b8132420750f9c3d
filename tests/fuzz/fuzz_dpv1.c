/* Target dpv1: the card's DP-V1 side as the FDL layer drives it (dpv1_sap_request on the receive
 * path, dpv1_poll from the main loop, dpv1_dp_state from the DP state), with data set 47 and I&M
 * behind it, the MOVILINK client and a fake inverter link, and an NVM that may fail writes.
 *
 * Input: a 32-bit start time, then operations (op octet, low 3 bits):
 *   0  a raw SAP request: master, DSAP, SSAP, u8 length, octets (DSAP/SSAP from op bits 3..5:
 *      0 C1 51/51, 1 RM 49, 2 SAP 0, 3 SAP 1, else raw octets)
 *   1  a structured request on a connection (bits 3..4: C1, C2 #0, C2 #1, the RM with an
 *      Initiate): Read/Write of index 47 (data set 47 built with the master's codec) or 255
 *      (I&M call), Initiate with a Send_Timeout, Idle, Abort, or a poll (no data)
 *   2  the DP state: Data_Exch or not, DP-V1 mode, locking master
 *   3  time passes (u16 µs << bits 3..5), then dpv1_poll and ml_client_poll
 *   4  the link answers the oldest request on a channel (bits 3..4 mode, bit 5 keep it)
 *   5  the NVM fails (or works again)
 *
 * Properties:
 *  - only SAPs 51, 49, 0 and 1 are served; MSAC1 only while open (Data_Exch + DP-V1) for the
 *    locking master with SSAP 51; a connection SAP only for the master and SSAP that initiated
 *    it and only within its Send_Timeout of the last telegram; the RM answers 56 SAP 00 00 or
 *    Abort 58 00 1x 00; an answer never exceeds 244 octets;
 *  - a response is handed out once, on a poll, and answers the request in the mailbox: same
 *    function (bit 7 for a negative one, 4 octets, decode 0x80), Read.res echoes slot/index and
 *    length <= the asked length, Write.res echoes the 4-octet header, Initiate.res only on a
 *    connection that an Initiate opened; responses <= requests per connection;
 *  - every MOVILINK service runs on the channel of an open connection (1 for C1, 2/3 for C2). */
#include "dp_master/dpv1_ds47.h"
#include "dp_master/dpv1_xfer.h"
#include "dp_slave/fdl_frame.h"
#include "dpv1/dpv1.h"
#include "dpv1/dpv1_wire.h"
#include "fuzz_link.h"

typedef struct conn_model {
    bool bound;       /* C2: the RM bound it (our view) */
    uint8_t master;
    uint8_t ssap;
    uint32_t timeout_us;
    hal_time_us_t last;
    uint8_t req[DPV1_MAX_PDU];
    uint8_t req_len;
    bool have_req; /* a request is in the mailbox or being served */
    uint32_t requests;
    uint32_t responses;
} conn_model_t;

typedef struct fake_nvm {
    uint8_t mem[512];
    bool fail;
} fake_nvm_t;

typedef struct rig {
    ml_client_t ml;
    fake_link_t link;
    fake_nvm_t nvm;
    dpv1_t d;
    hal_time_us_t now;
    conn_model_t c1, c2[2];
    bool c1_open;
    uint8_t c1_master;
} rig_t;

static rig_t r;

static size_t nvm_size(void *ctx) { (void)ctx; return sizeof r.nvm.mem; }
static int nvm_read(void *ctx, size_t off, uint8_t *d, size_t len)
{
    fake_nvm_t *n = ctx;
    if (off + len > sizeof n->mem) return -1;
    memcpy(d, &n->mem[off], len);
    return 0;
}
static int nvm_write(void *ctx, size_t off, const uint8_t *d, size_t len)
{
    fake_nvm_t *n = ctx;
    if (n->fail || off + len > sizeof n->mem) return -1;
    memcpy(&n->mem[off], d, len);
    return 0;
}
static const hal_nvm_ops_t nvm_ops = {.size = nvm_size, .read = nvm_read, .write = nvm_write};

static void on_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN], uint32_t tag)
{
    (void)ctx;
    (void)req;
    (void)tag;
    PROPERTY(channel >= 1u && channel <= 3u, "a DP-V1 service on channel %u", channel);
}

static void deliver(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)ctx;
    ml_client_response(&r.ml, channel, rsp);
}

/* The response handed out for the request in the model's mailbox. */
static void check_response(conn_model_t *m, const uint8_t *rsp, size_t len, bool class2)
{
    PROPERTY(m->have_req, "a response with no request in the mailbox");
    PROPERTY(len >= 4u, "a response of %zu octets", len);
    const uint8_t *q = m->req;
    m->responses++;
    m->have_req = false;
    PROPERTY(m->responses <= m->requests, "%u responses for %u requests", m->responses,
             m->requests);
    if ((rsp[0] & DPV1_FN_ERROR) != 0u) {
        PROPERTY(len == 4u && rsp[1] == DPV1_ERROR_DECODE && (rsp[0] & 0x7Fu) == (q[0] & 0x7Fu),
                 "negative response %02X %02X to function %02X (%zu octets)", rsp[0], rsp[1],
                 q[0], len);
        return;
    }
    switch (q[0]) {
    case DPV1_FN_READ:
        PROPERTY(m->req_len >= 4u && memcmp(rsp, q, 3) == 0 && rsp[3] == len - 4u &&
                     rsp[3] <= q[3] && rsp[3] > 0u,
                 "Read.res does not answer the Read.req");
        break;
    case DPV1_FN_WRITE:
        PROPERTY(len == 4u && memcmp(rsp, q, 4) == 0, "Write.res does not echo the header");
        break;
    case DPV1_FN_INITIATE:
        PROPERTY(class2 && len == 12u && rsp[0] == DPV1_FN_INITIATE,
                 "Initiate.res on class %d, %zu octets", class2 ? 2 : 1, len);
        break;
    default:
        PROPERTY(false, "a positive response %02X to function %02X", rsp[0], q[0]);
    }
}

/* One SRD to a DP-V1 SAP, with everything the FDL layer would check on the answer. */
static void sap(uint8_t master, uint8_t dsap, uint8_t ssap, const uint8_t *data, size_t len)
{
    /* The room dp_slave gives for a short reply: the DU after FDL_TX_HEADROOM octets. */
    uint8_t given[FDL_TX_HEADROOM + DP_SAP_REPLY_SHORT + 16];
    memset(given, 0xA5, sizeof given);
    dp_sap_reply_t out = {.buf = given};
    bool c1_ok = r.c1_open && r.c1_master == master && ssap == DPV1_SAP_C1;
    int c2i = dsap < 2u ? (int)dsap : -1;
    conn_model_t *m2 = c2i >= 0 ? &r.c2[c2i] : NULL;
    bool c2_ok = m2 != NULL && m2->bound && m2->master == master && m2->ssap == ssap &&
                 hal_time_diff(r.now, m2->last) <= (int32_t)m2->timeout_us;
    if (fz_trace_on()) {
        TRACE("SRD m%u %u->%u t=%u ", master, ssap, dsap, r.now);
        fz_hex("req", data, len);
    }
    dp_sap_answer_t a = dpv1_sap_request(&r.d, master, dsap, ssap, data, len, &out, r.now);
    const uint8_t *reply = &out.buf[FDL_TX_HEADROOM];
    size_t rlen = a == DP_SAP_ANSWER_DATA ? out.len : 0u;
    TRACE("  answer %d, %zu octets\n", (int)a, rlen);
    PROPERTY(a == DP_SAP_NOT_SERVED || a == DP_SAP_ANSWER_SC || a == DP_SAP_ANSWER_DATA,
             "answer %d", (int)a);
    if (a == DP_SAP_ANSWER_DATA) {
        PROPERTY(rlen >= 1u && rlen <= DP_SAP_REPLY_MAX, "reply of %zu octets", rlen);
        PROPERTY(out.buf != given || rlen <= DP_SAP_REPLY_SHORT,
                 "%zu octets written into the %u-octet room for a short reply", rlen,
                 (unsigned)DP_SAP_REPLY_SHORT);
        PROPERTY(given[FDL_TX_HEADROOM + DP_SAP_REPLY_SHORT] == 0xA5u,
                 "wrote past the room for a short reply");
        PROPERTY(!out.sum_known || out.sum == fdl_fcs(reply, rlen),
                 "octet sum %02X given, the response's is %02X", out.sum, fdl_fcs(reply, rlen));
        PROPERTY(out.buf == given || out.guard != NULL, "a response in the device's buffer "
                 "without a guard");
    }
    if (dsap == DPV1_SAP_C1) {
        PROPERTY(c1_ok || a == DP_SAP_NOT_SERVED, "MSAC1 served while closed or for master %u",
                 master);
        if (!c1_ok) return;
        if (len > 0u) {
            PROPERTY(a == DP_SAP_ANSWER_SC, "a C1 request answered %d", (int)a);
            r.c1.requests++;
            r.c1.have_req = true;
            r.c1.req_len = (uint8_t)(len > DPV1_MAX_PDU ? DPV1_MAX_PDU : len);
            memcpy(r.c1.req, data, r.c1.req_len);
        } else if (a == DP_SAP_ANSWER_DATA) {
            check_response(&r.c1, reply, rlen, false);
        }
        return;
    }
    if (dsap == DPV1_SAP_RM) {
        PROPERTY(a == DP_SAP_ANSWER_DATA && rlen == 4u, "the RM answered %d (%zu octets)", (int)a,
                 rlen);
        if (reply[0] == DPV1_FN_RM) {
            PROPERTY(len >= DPV1_INITIATE_MIN && data[0] == DPV1_FN_INITIATE && reply[1] < 2u &&
                         reply[2] == 0u && reply[3] == 0u,
                     "RM answer %02X %02X %02X %02X", reply[0], reply[1], reply[2], reply[3]);
            /* the connection is bound; the same master+SSAP lost its previous one */
            for (int i = 0; i < 2; i++) {
                if (r.c2[i].bound && r.c2[i].master == master && r.c2[i].ssap == ssap) {
                    r.c2[i].bound = false;
                }
            }
            conn_model_t *m = &r.c2[reply[1]];
            PROPERTY(!m->bound || hal_time_diff(r.now, m->last) > (int32_t)m->timeout_us,
                     "the RM gave away connection %u while it is in use", reply[1]);
            *m = (conn_model_t){.bound = true, .master = master, .ssap = ssap, .last = r.now,
                                .have_req = true, .requests = 1};
            uint32_t to = (uint32_t)((data[4] << 8) | data[5]);
            m->timeout_us = (to == 0u ? 1u : to) * 10000u;
            m->req_len = (uint8_t)(len > DPV1_MAX_PDU ? DPV1_MAX_PDU : len);
            memcpy(m->req, data, m->req_len);
        } else {
            PROPERTY(reply[0] == DPV1_FN_ABORT && reply[1] == 0u && (reply[2] & 0xF0u) == 0x10u &&
                         reply[3] == 0u,
                     "RM answer %02X %02X %02X %02X", reply[0], reply[1], reply[2], reply[3]);
        }
        return;
    }
    if (m2 != NULL) {
        PROPERTY(c2_ok || a == DP_SAP_NOT_SERVED, "connection SAP %u served for master %u SSAP %u "
                 "(bound %d to %u/%u, silent %d us of %u)", dsap, master, ssap, m2->bound,
                 m2->master, m2->ssap, hal_time_diff(r.now, m2->last), m2->timeout_us);
        if (!c2_ok) {
            if (m2->bound && m2->master == master && m2->ssap == ssap) {
                m2->bound = false; /* silent too long: closed */
            }
            return;
        }
        PROPERTY(a != DP_SAP_NOT_SERVED, "an open connection refused its master");
        m2->last = r.now;
        if (len > 0u && data[0] == DPV1_FN_ABORT) {
            PROPERTY(a == DP_SAP_ANSWER_SC, "Abort answered %d", (int)a);
            m2->bound = false;
        } else if (len > 0u && data[0] == DPV1_FN_IDLE) {
            PROPERTY(a == DP_SAP_ANSWER_DATA && rlen == (len < 4u ? len : 4u) &&
                         memcmp(reply, data, rlen) == 0,
                     "Idle not echoed");
        } else if (len > 0u) {
            PROPERTY(a == DP_SAP_ANSWER_SC, "a C2 request answered %d", (int)a);
            m2->requests++;
            m2->have_req = true;
            m2->req_len = (uint8_t)(len > DPV1_MAX_PDU ? DPV1_MAX_PDU : len);
            memcpy(m2->req, data, m2->req_len);
        } else if (a == DP_SAP_ANSWER_DATA) {
            check_response(m2, reply, rlen, true);
        }
        return;
    }
    PROPERTY(a == DP_SAP_NOT_SERVED, "SAP %u served", dsap);
}

static size_t build_pdu(fz_t *f, uint8_t kind, uint8_t *pdu)
{
    switch (kind % 7u) {
    case 0: { /* Write 47 */
        dp_master_ds47_req_t q = {.ref = fz_u8(f),
                                  .id = (uint8_t[]){1, 2, 0x40, 0x40}[fz_u8(f) & 3u],
                                  .axis = 0,
                                  .n = (uint8_t)(1u + fz_u8(f) % 3u)};
        for (unsigned i = 0; i < q.n; i++) {
            q.p[i] =
                (dp_master_ds47_param_t){.attribute = q.id == 0x40
                                                          ? (uint8_t)(0x10u * (1u + fz_u8(f) % 3u))
                                                          : 0x10u,
                                         .number = (uint16_t)(8300u + fz_u8(f)),
                                         .value = fz_u32(f)};
        }
        size_t n = dp_master_ds47_build(&q, &pdu[4], DPV1_MAX_DATA);
        pdu[0] = DPV1_FN_WRITE; pdu[1] = fz_u8(f); pdu[2] = 47; pdu[3] = (uint8_t)n;
        return 4u + n;
    }
    case 1: /* Read 47 / 255 */
        pdu[0] = DPV1_FN_READ; pdu[1] = fz_u8(f); pdu[2] = fz_bool(f) ? 47u : 255u;
        pdu[3] = fz_u8(f);
        return 4;
    case 2: { /* I&M call */
        uint8_t fi = fz_u8(f);
        size_t n = (fi & 0x80u) != 0u ? 4u + 64u : 4u;
        pdu[0] = DPV1_FN_WRITE; pdu[1] = 0; pdu[2] = 255; pdu[3] = (uint8_t)n;
        pdu[4] = 0x08; pdu[5] = 0; pdu[6] = 0xFD; pdu[7] = (uint8_t)(0xE8u + fi % 6u);
        fz_bytes(f, &pdu[8], n - 4u);
        return 4u + n;
    }
    case 3: /* Idle */
        pdu[0] = DPV1_FN_IDLE; pdu[1] = pdu[2] = pdu[3] = 0;
        return 4;
    case 4: /* Abort */
        pdu[0] = DPV1_FN_ABORT; pdu[1] = 0; pdu[2] = 0x20u | (fz_u8(f) & 0x0Fu); pdu[3] = 0;
        return 4;
    case 5: { /* Initiate, as our class-2 client sends it */
        uint16_t to = fz_u16(f);
        const uint8_t ini[20] = {DPV1_FN_INITIATE, 0, 0, 0, (uint8_t)(to >> 8), (uint8_t)to, 1, 0,
                                 fz_u8(f), fz_u8(f), 0, 0, 0, 2, 0, 2, 0, 0, 0, 0};
        memcpy(pdu, ini, sizeof ini);
        return sizeof ini;
    }
    default:
        return 0; /* a poll */
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
    dpv1_cfg_t cfg = {.ml = &r.ml, .ch_c1 = 1, .ch_c2 = {2, 3},
                      .identity = {.manufacturer_id = 0x010A, .order_id = "824 240 2",
                                   .serial = "FUZZ", .software_revision = {'V', 1, 2, 3}},
                      .nvm = {.ops = &nvm_ops, .ctx = &r.nvm}};
    dpv1_init(&r.d, &cfg);

    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        switch (op & 7u) {
        case 0: {
            uint8_t master = (uint8_t)(fz_u8(&f) & 0x7Fu);
            uint8_t dsap;
            uint8_t ssap;
            switch ((op >> 3) & 7u) {
            case 0: dsap = ssap = DPV1_SAP_C1; break;
            case 1: dsap = DPV1_SAP_RM; ssap = (uint8_t)(fz_u8(&f) & 0x3Fu); break;
            case 2: dsap = 0; ssap = (uint8_t)(fz_u8(&f) & 0x3Fu); break;
            case 3: dsap = 1; ssap = (uint8_t)(fz_u8(&f) & 0x3Fu); break;
            default: dsap = (uint8_t)(fz_u8(&f) & 0x3Fu); ssap = (uint8_t)(fz_u8(&f) & 0x3Fu); break;
            }
            uint8_t pdu[246];
            size_t len = fz_u8(&f) % 245u;
            fz_bytes(&f, pdu, len);
            sap(master, dsap, ssap, pdu, len);
            break;
        }
        case 1: {
            uint8_t pdu[DPV1_MAX_PDU + 8];
            uint8_t kind = fz_u8(&f);
            uint8_t which = (uint8_t)((op >> 3) & 3u);
            if (which == 3u) {
                size_t n = build_pdu(&f, 5, pdu);
                sap((uint8_t)(1u + (op >> 5)), DPV1_SAP_RM, (uint8_t)(50u + ((op >> 5) & 1u)), pdu, n);
                break;
            }
            size_t n = build_pdu(&f, kind, pdu);
            if (which == 0u) {
                sap(r.c1_open ? r.c1_master : 2u, DPV1_SAP_C1, DPV1_SAP_C1, pdu, n);
            } else {
                conn_model_t *m = &r.c2[which - 1u];
                sap(m->bound ? m->master : 1u, (uint8_t)(which - 1u), m->bound ? m->ssap : 50u, pdu, n);
            }
            break;
        }
        case 2: {
            bool dx = (op & 0x08u) != 0u;
            bool v1 = (op & 0x10u) != 0u;
            uint8_t master = (op & 0x20u) != 0u ? (uint8_t)(fz_u8(&f) & 0x7Fu) : 2u;
            dpv1_dp_state(&r.d, dx, v1, master);
            bool open = dx && v1;
            if (open && (!r.c1_open || r.c1_master != master)) {
                r.c1 = (conn_model_t){0};
            } else if (!open) {
                r.c1 = (conn_model_t){0};
            }
            r.c1_open = open;
            r.c1_master = master;
            break;
        }
        case 3: {
            r.now += (uint32_t)fz_u16(&f) << ((op >> 3) & 7u);
            (void)ml_client_poll(&r.ml, r.now);
            hal_time_us_t next = dpv1_poll(&r.d, r.now);
            PROPERTY(hal_time_diff(next, r.now) > 0, "dpv1_poll deadline not in the future");
            for (int i = 0; i < 2; i++) {
                conn_model_t *m = &r.c2[i];
                if (m->bound && hal_time_diff(r.now, m->last) >= (int32_t)m->timeout_us) {
                    m->bound = false; /* supervision closed it */
                }
            }
            break;
        }
        case 4:
            (void)fl_answer(&r.link, &f, (uint8_t)(1u + fz_u8(&f) % 3u), (uint8_t)((op >> 3) & 3u),
                            (op & 0x20u) != 0u);
            break;
        case 5:
            r.nvm.fail = fz_bool(&f);
            break;
        default:
            break;
        }
        /* the card's view of the connections agrees with the model */
        PROPERTY(r.d.c1.open == r.c1_open, "MSAC1 open %d, expected %d", r.d.c1.open, r.c1_open);
        for (int i = 0; i < 2; i++) {
            if (!r.c2[i].bound) {
                PROPERTY(!r.d.c2[i].open || hal_time_diff(r.now, r.d.c2[i].last_rx) > (int32_t)r.d.c2[i].send_timeout_us ||
                         r.d.c2[i].master != r.c2[i].master || r.d.c2[i].ssap != r.c2[i].ssap,
                         "connection %d open but closed in the model", i);
            }
        }
    }
    return 0;
}
