/* The master's DP-V1 clients against the real card (with the emulated MOVIDRIVE) on the
 * in-memory bus: class 1 and class 2, data set 47 and I&M0, with the telegrams on the wire
 * checked byte for byte (docs/dpv1.md, protocol.md §A1.6), the SC/poll sequence, the rule of
 * one acyclic telegram between two Data_Exchange, FCB toggling across cyclic, class-1 and
 * class-2 telegrams, and the faults: negative responses, refusal of a third connection, RS,
 * timeouts, a slave that falls silent. */
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "rig/rig.h"

#define BAUD 1500000u
#define MASTER 2u
#define SLAVE 4u

/* ---- the rig: master 2, card 4 with the emulated inverter, every telegram recorded ------- */

typedef struct frame {
    uint8_t b[FDL_FRAME_MAX];
    uint16_t len;
} frame_t;

#define MAX_FRAMES 6000u

/* What the test keeps beside the rig: the recorded telegrams and the fault it injects. */
typedef struct bench {
    membus_port_t *card_port;
    frame_t frames[MAX_FRAMES];
    size_t nframes;
    bool recording;
    bool drop_read_res;  /* the master misses the card's next Read.res from SAP 51 */
    uint64_t dropped_at_ns;
} bench_t;

static rig_t rig; /* large: keep it off the stack */
static bench_t bench;

static void tap(void *ctx, uint64_t t, const uint8_t *f, size_t len, bool local, uint32_t baud)
{
    (void)ctx;
    (void)t;
    (void)local;
    (void)baud;
    if (bench.drop_read_res && len > 10u && f[0] == FDL_SD2 && f[4] == (MASTER | 0x80u) &&
        f[6] == FDL_RSP_DL && f[7] == DPV1_SAP_C1 && f[9] == DPV1_FN_READ) {
        rig.master_port->silenced = true; /* deaf (and mute) until the test lifts it */
        bench.drop_read_res = false;
        bench.dropped_at_ns = rig.bus.now_ns;
    }
    if (!bench.recording || bench.nframes >= MAX_FRAMES || len > FDL_FRAME_MAX) {
        return;
    }
    memcpy(bench.frames[bench.nframes].b, f, len);
    bench.frames[bench.nframes].len = (uint16_t)len;
    bench.nframes++;
}

static const uint8_t cfg_param_3pd[] = {0xF3, 0xF2};

/* cyclic: the master brings slave 4 into Data_Exchange (with DP-V1 parameters if dpv1). */
static void setup(bool cyclic, bool dpv1, uint32_t inverter_delay_us)
{
    memset(&bench, 0, sizeof bench);
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS};
    rig_init(&rig, &rc);
    rig_tap_t rt = {.frame = tap};
    (void)rig_add_tap(&rig, &rt);
    card_options_t co = {.address = SLAVE, .fixed_baud = BAUD, .strict_timing = true,
                         .inverter = CARD_INVERTER_SIM, .inverter_delay_us = inverter_delay_us};
    char err[256] = "no room for the card on the bus"; /* rig_open overwrites it on failure */
    rig_card_t *card = rig_open(&rig, err, sizeof err) == 0
                           ? rig_add_card(&rig, &co, membus_now_us(&rig.bus))
                           : NULL;
    /* The note is empty unless card_station_init failed. */
    CHECK_STR(card != NULL ? card->nvm_note : err, "");
    bench.card_port = &rig.bus.ports[rig.bus.num_ports - 1u]; /* the card's, attached last */
    dp_master_cfg_t mc = {.address = MASTER, .baud = BAUD, .strict_timing = true};
    (void)rig_add_master(&rig, &mc, membus_now_us(&rig.bus));
    if (!cyclic) {
        return;
    }
    dp_master_slave_cfg_t sc = {.address = SLAVE};
    if (dpv1) {
        sc.prm_len = (uint8_t)dp_master_build_prm_dpv1(sc.prm, DFP21B_IDENT, 100,
                                                 dfp21b_user_prm_default,
                                                 sizeof dfp21b_user_prm_default);
    } else {
        sc.prm_len =
            (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 100, dfp21b_user_prm_default,
                                         sizeof dfp21b_user_prm_default);
    }
    memcpy(sc.cfg, cfg_param_3pd, sizeof cfg_param_3pd);
    sc.cfg_len = sizeof cfg_param_3pd;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
    membus_run_for_us(&rig.bus, 20000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
    CHECK_EQ(dp_slave_dpv1_mode(&rig.cards[0].cs.card.dp), dpv1);
}

static bool run_until_call(const dp_master_call_t *c, uint32_t limit_us)
{
    for (uint32_t t = 0; t < limit_us && !dp_master_call_done(c); t += 50u) {
        membus_run_for_us(&rig.bus, 50);
    }
    return dp_master_call_done(c);
}

typedef struct acyc_result {
    bool done;
    bool ok;
    uint8_t pdu[DPV1_MAX_PDU];
    size_t len;
    char error[200];
    uint32_t polls;
} acyc_result_t;

static void acyc_done(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    (void)now;
    acyc_result_t *a = ctx;
    a->done = true;
    a->ok = r->ok;
    a->len = r->len;
    a->polls = r->polls;
    if (r->len > 0u) {
        memcpy(a->pdu, r->pdu, r->len);
    }
    snprintf(a->error, sizeof a->error, "%s", r->ok ? "" : r->error);
}

static bool run_until_result(const acyc_result_t *a, uint32_t limit_us)
{
    for (uint32_t t = 0; t < limit_us && !a->done; t += 50u) {
        membus_run_for_us(&rig.bus, 50);
    }
    return a->done;
}

static dp_master_ds47_req_t ml_request(uint8_t attr, uint16_t index, uint32_t value)
{
    dp_master_ds47_req_t r = {.ref = 1, .id = DS47_ID_MOVILINK, .axis = 0, .n = 1};
    r.p[0] = (dp_master_ds47_param_t){.attribute = attr, .number = index, .value = value};
    return r;
}

/* Runs a DS47 call on port and parses the answer. */
static bool ds47(dp_master_acyc_port_t port, const dp_master_ds47_req_t *req,
                 dp_master_call_t *call, dp_master_ds47_rsp_t *rsp)
{
    memset(call, 0, sizeof *call);
    if (dp_master_ds47_start(call, port, req, NULL, NULL, membus_now_us(&rig.bus)) != 0) {
        return false;
    }
    membus_wake(rig.master_port);
    if (!run_until_call(call, 3000000) || !call->ok) {
        return false;
    }
    char err[128];
    bool ok = dp_master_ds47_parse(req, call->data, call->len, rsp, err, sizeof err);
    if (!ok) {
        fprintf(stderr, "    parse: %s\n", err);
    }
    return ok;
}

/* ---- looking at the wire ------------------------------------------------------------------ */

static bool parse_frame(const frame_t *f, fdl_msg_t *m)
{
    return f->len > 1u && fdl_parse(f->b, f->len, m) == FDL_PARSE_OK;
}

static bool is_request_to(const frame_t *f, uint8_t da, uint8_t sa, fdl_msg_t *m)
{
    return parse_frame(f, m) && (m->fc & FDL_FC_REQUEST) != 0u && m->da == da && m->sa == sa;
}

/* Index of the first request from sa to da at DSAP dsap whose DU starts with fn (or is empty
 * when fn is 0), from index `from`; -1 if none. */
static long find_request(size_t from, uint8_t da, uint8_t sa, uint8_t dsap, int fn)
{
    for (size_t i = from; i < bench.nframes; i++) {
        fdl_msg_t m;
        if (!is_request_to(&bench.frames[i], da, sa, &m) || !m.has_dsap || m.dsap != dsap) {
            continue;
        }
        if ((fn < 0 && m.data_len == 0u) || (fn >= 0 && m.data_len > 0u && m.data[0] == fn)) {
            return (long)i;
        }
    }
    return -1;
}

/* Compares a request telegram with expected bytes in which FC carries FCB = 1 (as the
 * protocol.md §A1.6 examples do): an FCB of 0 on the wire is accepted with FC and FCS
 * adjusted, every other octet must match. */
static void check_request(const frame_t *f, const uint8_t *exp, size_t n, const char *what)
{
    uint8_t e[FDL_FRAME_MAX];
    memcpy(e, exp, n);
    size_t fc = e[0] == FDL_SD2 ? 6u : 3u;
    if (f->len == n && (f->b[fc] ^ e[fc]) == FDL_FC_FCB) {
        e[fc] ^= FDL_FC_FCB;
        e[n - 2u] = (uint8_t)(e[n - 2u] - FDL_FC_FCB);
    }
    if (f->len == n && memcmp(f->b, e, n) == 0) {
        check_passed_++;
        return;
    }
    check_failed_++;
    fprintf(stderr, "[%s] %s differs\n", check_test_name_, what);
    check_hex_("actual  ", f->b, f->len);
    check_hex_("expected", e, n);
}

/* Over the recorded telegrams: between two acyclic class-1 telegrams to slave 4 there is at
 * least one Data_Exchange; FCB toggles with every request from 2 to 4 (FCV set). A retry (the
 * request repeated byte for byte) is exempt, and there are exactly as many as the master
 * counted. Returns the number of class-1 telegrams, retries included. */
static unsigned check_c1_discipline(void)
{
    unsigned c1 = 0;
    unsigned since_dx = 0;
    bool have_fcb = false;
    bool fcb = false;
    bool interleave_ok = true;
    bool fcb_ok = true;
    const frame_t *prev = NULL;
    unsigned repeats = 0;
    for (size_t i = 0; i < bench.nframes; i++) {
        fdl_msg_t m;
        const frame_t *f = &bench.frames[i];
        if (!is_request_to(f, SLAVE, MASTER, &m)) {
            continue;
        }
        bool retry = prev != NULL && prev->len == f->len && memcmp(prev->b, f->b, f->len) == 0;
        prev = f;
        if (retry) {
            repeats++;
            c1 += m.has_dsap && m.dsap == DPV1_SAP_C1;
            continue;
        }
        if ((m.fc & FDL_FC_FCV) != 0u) {
            bool b = (m.fc & FDL_FC_FCB) != 0u;
            if (have_fcb && b == fcb) {
                fcb_ok = false;
            }
            have_fcb = true;
            fcb = b;
        }
        if (!m.has_dsap) {
            since_dx = 0;
        } else if (m.dsap == DPV1_SAP_C1) {
            c1++;
            if (since_dx != 0u) {
                interleave_ok = false;
                fprintf(stderr, "    two acyclic telegrams without Data_Exchange at frame %zu\n", i);
            }
            since_dx++;
        }
    }
    CHECK(interleave_ok);
    CHECK(fcb_ok);
    CHECK_EQ(repeats, rig.master.total_retries); /* identical telegrams are retries only */
    return c1;
}

/* ---- class 1 ------------------------------------------------------------------------------ */

static void test_prm_dpv1_octets(void)
{
    uint8_t prm[DP_MASTER_MAX_PRM];
    size_t n = dp_master_build_prm_dpv1(prm, DFP21B_IDENT, 1000, dfp21b_user_prm_default, 9);
    CHECK_BYTES(prm, n, 0x88, 0x01, 0x64, 0x0B, 0x60, 0x03, 0x00, 0x80, 0x00, 0x00, 0x06, 0x81,
                0x00, 0x00, 0x01, 0x01);
    CHECK(dp_master_prm_is_dpv1(prm, n));
    n = dp_master_build_prm(prm, DFP21B_IDENT, 1000, dfp21b_user_prm_default, 9);
    CHECK(!dp_master_prm_is_dpv1(prm, n));
    n = dp_master_build_prm_dpv1(prm, 0x1234, 0, NULL, 0); /* no user octets: 80 00 00 */
    CHECK_BYTES(prm, n, 0x80, 0x01, 0x01, 0x0B, 0x12, 0x34, 0x00, 0x80, 0x00, 0x00);
}

static void test_c1_ds47_read_8300_on_the_wire(void)
{
    setup(true, true, 0);
    bench.recording = true;
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK(ds47(dp_master_c1_port(&rig.master, 0), &req, &call, &rsp));
    CHECK(!rsp.negative);
    CHECK(rsp.p[0].ok && rsp.p[0].has_value);
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    CHECK_BYTES(call.data, call.len, 0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);

    /* Write.req exactly as protocol.md §A1.6 prints it, answered SC. */
    long w = find_request(0, SLAVE, MASTER, DPV1_SAP_C1, DPV1_FN_WRITE);
    CHECK(w >= 0);
    if (w < 0) return;
    const uint8_t write_req[] = {0x68, 0x13, 0x13, 0x68, 0x84, 0x82, 0x7D, 0x33, 0x33, 0x5F,
                                 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20,
                                 0x6C, 0x00, 0x00, 0x5F, 0x16};
    check_request(&bench.frames[w], write_req, sizeof write_req, "C1 Write DS47");
    CHECK_BYTES(bench.frames[w + 1].b, bench.frames[w + 1].len, 0xE5);
    /* Next telegram to the slave: a Data_Exchange, then the first poll (empty SRD, 51/51). */
    fdl_msg_t m;
    CHECK(is_request_to(&bench.frames[w + 2], SLAVE, MASTER, &m) && !m.has_dsap);
    long p = find_request((size_t)w + 1u, SLAVE, MASTER, DPV1_SAP_C1, -1);
    CHECK_EQ(p, w + 4);
    if (p < 0) return;
    const uint8_t poll[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x7D, 0x33, 0x33, 0xE9, 0x16};
    check_request(&bench.frames[p], poll, sizeof poll, "C1 poll");
    /* The Write.res comes to a poll: DL, SAPs swapped, 5F 00 2F 0A. */
    long rsp_at = -1;
    for (size_t i = (size_t)w; i < bench.nframes; i++) {
        const frame_t *f = &bench.frames[i];
        if (f->len == 15u && f->b[0] == 0x68 && f->b[9] == 0x5F) {
            rsp_at = (long)i;
            break;
        }
    }
    CHECK(rsp_at > w);
    if (rsp_at > 0) {
        CHECK_BYTES(bench.frames[rsp_at].b, bench.frames[rsp_at].len, 0x68, 0x09, 0x09, 0x68, 0x82,
                    0x84, 0x08, 0x33, 0x33, 0x5F, 0x00, 0x2F, 0x0A, 0x0C, 0x16);
    }
    /* Read.req index 47, length 240, as §A1.6 prints it. */
    long r = find_request(0, SLAVE, MASTER, DPV1_SAP_C1, DPV1_FN_READ);
    CHECK(r > rsp_at);
    if (r < 0) return;
    const uint8_t read_req[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x82, 0x7D, 0x33, 0x33, 0x5E,
                                0x00, 0x2F, 0xF0, 0x66, 0x16};
    check_request(&bench.frames[r], read_req, sizeof read_req, "C1 Read DS47");
    /* The last telegram of the call: Read.res with the manual's response octets. */
    bool found = false;
    for (size_t i = (size_t)r; i < bench.nframes; i++) {
        const frame_t *f = &bench.frames[i];
        if (f->len == 25u && f->b[9] == 0x5E) {
            CHECK_BYTES(f->b, f->len, 0x68, 0x13, 0x13, 0x68, 0x82, 0x84, 0x08, 0x33, 0x33, 0x5E,
                        0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72,
                        0x89, fdl_fcs(&f->b[4], 19), 0x16);
            CHECK_EQ(fdl_fcs(&f->b[4], 19), 0xD9);
            found = true;
            break;
        }
    }
    CHECK(found);
    unsigned c1 = check_c1_discipline();
    CHECK_EQ(c1, call.telegrams);
    CHECK(call.telegrams >= 4u); /* Write, >= 1 poll, Read, >= 1 poll */
    CHECK_EQ(call.reads, 1u + call.busy);
    CHECK_EQ(rig.master.timeouts, 0);
}

static void test_c1_manual_examples_and_writes(void)
{
    setup(true, true, 0);
    dp_master_acyc_port_t port = dp_master_c1_port(&rig.master, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    /* MOVILINK write volatile H0 = 3000: the manual's request, answered 01 40 00 01. */
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_WRITE_VOLATILE, 11000, 3000);
    uint8_t built[64];
    CHECK_BYTES(built, dp_master_ds47_build(&req, built, sizeof built), 0x01, 0x40, 0x00, 0x01,
                0x30, 0x00, 0x2A, 0xF8, 0x00, 0x00, 0x43, 0x01, 0x00, 0x00, 0x0B, 0xB8);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x01, 0x40, 0x00, 0x01);
    int32_t v = 0;
    CHECK(movidrive_read_value(&rig.cards[0].cs.md, 11000, &v));
    CHECK_EQ(v, 3000);
    /* PROFIdrive request parameter 8300. */
    req = (dp_master_ds47_req_t){.ref = 1, .id = DS47_ID_REQUEST, .n = 1};
    req.p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8300};
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x01, 0x01, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89);
    /* PROFIdrive change parameter P160 n11 (8489 = 0x2129, axis 0), then read back. */
    req = (dp_master_ds47_req_t){.ref = 0x22, .id = DS47_ID_CHANGE, .n = 1};
    req.p[0] =
        (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8489, .value = 250000};
    CHECK_BYTES(built, dp_master_ds47_build(&req, built, sizeof built), 0x22, 0x02, 0x00, 0x01,
                0x10, 0x00, 0x21, 0x29, 0x00, 0x00, 0x43, 0x01, 0x00, 0x03, 0xD0, 0x90);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x22, 0x02, 0x00, 0x01);
    req = ml_request(DS47_ATTR_ML_READ, 8489, 0);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].value, 250000);
    /* MOVILINK write (non-volatile) of P160 through 0x40 / 0x20. */
    req = ml_request(DS47_ATTR_ML_WRITE, 8489, 123000);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK(movidrive_read_value(&rig.cards[0].cs.md, 8489, &v));
    CHECK_EQ(v, 123000);
    check_c1_discipline();
}

static void test_c1_negative_parameter_results(void)
{
    setup(true, true, 0);
    dp_master_acyc_port_t port = dp_master_c1_port(&rig.master, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    char text[160];
    /* P302 above its maximum: MOVILINK 0x0815 ... */
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_WRITE_VOLATILE, 8517, 99000000u);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK(rsp.negative);
    CHECK_BYTES(call.data, call.len, 0x01, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x15);
    CHECK(!rsp.p[0].ok);
    CHECK_EQ(rsp.p[0].error, 0x0815);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "class 8, additional code 0x15: value too high");
    /* ... and PROFIdrive 0x02 through request id 0x02. */
    req = (dp_master_ds47_req_t){.ref = 7, .id = DS47_ID_CHANGE, .n = 1};
    req.p[0] =
        (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8517, .value = 99000000u};
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x07, 0x82, 0x00, 0x01, 0x44, 0x01, 0x00, 0x02);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "PROFIdrive error 0x02: low or high limit exceeded");
    /* Index that does not exist: 0x0810 / PROFIdrive 0x00; mixed with a good read. */
    req = (dp_master_ds47_req_t){.ref = 9, .id = DS47_ID_MOVILINK, .n = 2};
    req.p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 1};
    req.p[1] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 8300};
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x09, 0xC0, 0x00, 0x02, 0x44, 0x01, 0x08, 0x10, 0x43, 0x01,
                0x31, 0x1C, 0x72, 0x89);
    CHECK(!rsp.p[0].ok && rsp.p[1].ok);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "class 8, additional code 0x10: illegal parameter index");
    /* A failed and a good write: the good one answers 40 00. */
    req = (dp_master_ds47_req_t){.ref = 10, .id = DS47_ID_MOVILINK, .n = 2};
    req.p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_WRITE_VOLATILE, .number = 8517,
                              .value = 99000000u};
    req.p[1] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_WRITE_VOLATILE, .number = 11000,
                              .value = 5};
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x0A, 0xC0, 0x00, 0x02, 0x44, 0x01, 0x08, 0x15, 0x40, 0x00);
    CHECK(!rsp.p[0].ok && rsp.p[1].ok && !rsp.p[1].has_value);
    /* Axis 1: every parameter 0x0019. */
    req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    req.axis = 1;
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].error, 0x0019);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "PROFIdrive error 0x19: axis nonexistent");
    /* DP-V1 level: index 48 -> B0, a header error -> B7. */
    memset(&call, 0, sizeof call);
    const uint8_t junk[4] = {0x01, 0x40, 0x00, 0x01};
    CHECK_EQ(dp_master_call_start(&call, port, 48, junk, sizeof junk, 240, NULL, NULL,
                            membus_now_us(&rig.bus)), 0);
    CHECK(run_until_call(&call, 1000000));
    CHECK(!call.ok && call.dpv1_negative);
    CHECK_EQ(call.neg_fn, 0xDF);
    CHECK_EQ(call.neg_code1, 0xB0);
    CHECK_STR(call.error, "Write.res index 48 negative: Error_Code_1 0xB0 (access: invalid index)");
    memset(&call, 0, sizeof call);
    CHECK_EQ(dp_master_call_start(&call, port, 47, junk, sizeof junk, 240, NULL, NULL,
                            membus_now_us(&rig.bus)), 0);
    CHECK(run_until_call(&call, 1000000));
    CHECK_EQ(call.neg_code1, 0xB7);
    check_c1_discipline();
}

static void test_c1_nineteen_parameters(void)
{
    setup(true, true, 0);
    dp_master_ds47_req_t req = {.ref = 0x55, .id = DS47_ID_MOVILINK, .n = DS47_MAX_PARAMS};
    for (unsigned i = 0; i < DS47_MAX_PARAMS; i++) {
        req.p[i] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 8300};
    }
    req.p[5].number = 8489;
    uint8_t built[DPV1_MAX_DATA];
    CHECK_EQ(dp_master_ds47_build(&req, built, sizeof built), 4 + 6 * 19);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    CHECK(ds47(dp_master_c1_port(&rig.master, 0), &req, &call, &rsp));
    CHECK_EQ(call.len, 4 + 6 * 19);
    unsigned good = 0;
    for (unsigned i = 0; i < DS47_MAX_PARAMS; i++) {
        good += rsp.p[i].ok && rsp.p[i].value == (i == 5 ? 150000u : 0x311C7289u);
    }
    CHECK_EQ(good, 19);
    /* 20 parameters do not build. */
    req.n = 20;
    CHECK_EQ(dp_master_ds47_build(&req, built, sizeof built), 0);
    /* 19 writes: 4 + 19 * 12 = 232 octets. */
    req = (dp_master_ds47_req_t){.ref = 0x56, .id = DS47_ID_MOVILINK, .n = DS47_MAX_PARAMS};
    for (unsigned i = 0; i < DS47_MAX_PARAMS; i++) {
        req.p[i] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_WRITE_VOLATILE,
                                  .number = (uint16_t)(11000 + i), .value = 100u + i};
    }
    CHECK_EQ(dp_master_ds47_build(&req, built, sizeof built), 232);
    CHECK(ds47(dp_master_c1_port(&rig.master, 0), &req, &call, &rsp));
    CHECK_BYTES(call.data, call.len, 0x56, 0x40, 0x00, 0x13);
    int32_t v = 0;
    CHECK(movidrive_read_value(&rig.cards[0].cs.md, 11018, &v));
    CHECK_EQ(v, 118);
}

static void test_c1_slow_inverter_b5_and_exchange_goes_on(void)
{
    setup(true, true, 20000); /* 20 ms per MOVILINK service */
    bench.recording = true;
    uint32_t cycles0 = rig.master.slaves[0].cycles;
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    CHECK(ds47(dp_master_c1_port(&rig.master, 0), &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    CHECK(call.busy >= 1u);             /* Read 47 answered B5 while the inverter worked */
    CHECK_EQ(call.reads, call.busy + 1u);
    /* Data_Exchange went on: one before every acyclic telegram of the call. */
    CHECK(rig.master.slaves[0].cycles - cycles0 + 1u >= call.telegrams);
    /* One B5 telegram as §A1.6 prints it (from slave 4 to master 2). */
    bool b5 = false;
    for (size_t i = 0; i < bench.nframes && !b5; i++) {
        const frame_t *f = &bench.frames[i];
        if (f->len == 15u && f->b[9] == 0xDE) {
            CHECK_BYTES(f->b, f->len, 0x68, 0x09, 0x09, 0x68, 0x82, 0x84, 0x08, 0x33, 0x33, 0xDE,
                        0x80, 0xB5, 0x00, 0x87, 0x16);
            b5 = true;
        }
    }
    CHECK(b5);
    check_c1_discipline();
    /* A bound on the reads: with max_reads 2 the call gives up with a clear text. */
    memset(&call, 0, sizeof call);
    call.max_reads = 2;
    CHECK_EQ(dp_master_ds47_start(&call, dp_master_c1_port(&rig.master, 0), &req, NULL, NULL,
                            membus_now_us(&rig.bus)), 0);
    CHECK(run_until_call(&call, 1000000));
    CHECK(!call.ok);
    CHECK_EQ(call.reads, 2);
    CHECK(strstr(call.error, "still answered B5 (state conflict) after 2 reads") != NULL);
}

static void test_c1_im0(void)
{
    setup(true, true, 0);
    dp_master_call_t call = {0};
    CHECK_EQ(dp_master_im0_start(&call, dp_master_c1_port(&rig.master, 0), NULL, NULL,
                           membus_now_us(&rig.bus)), 0);
    CHECK(run_until_call(&call, 1000000));
    CHECK(call.ok);
    CHECK_EQ(call.len, 68);
    dp_master_im0_t im;
    char err[128] = "";
    CHECK(dp_master_im0_decode(call.data, call.len, &im, err, sizeof err));
    CHECK_EQ(im.manufacturer_id, 0x010A);
    CHECK_STR(im.order_id, "824 240 2           ");
    CHECK_STR(im.serial_number, "DFP-SIM-004     ");
    CHECK_EQ(im.sw_prefix, 'V');
    CHECK_EQ(im.profile_id, 0);
    CHECK_EQ(im.im_version_major, 1);
    CHECK_EQ(im.im_version_minor, 1);
    CHECK_EQ(im.im_supported, 0x001E);
    CHECK(!dp_master_im0_decode(call.data, 20, &im, err, sizeof err));
}

static void test_c1_refusals_and_timeouts(void)
{
    /* Not parameterised for DP-V1: the master does not even queue. */
    setup(true, false, 0);
    const uint8_t read47[4] = {0x5E, 0x00, 0x2F, 0xF0};
    acyc_result_t a = {0};
    CHECK_EQ(dp_master_c1_submit(&rig.master, 0, read47, 4, acyc_done, &a), -1);
    /* The master believes in DP-V1 but the card was parameterised without: RS. */
    rig.master.slaves[0].cfg.prm[DP_PRM_DPV1_STATUS_1] |= DP_DPV1_1_ENABLE;
    CHECK_EQ(dp_master_c1_submit(&rig.master, 0, read47, 4, acyc_done, &a), 0);
    CHECK_EQ(dp_master_c1_submit(&rig.master, 0, read47, 4, acyc_done, &a), -1); /* depth 1 */
    CHECK(dp_master_c1_busy(&rig.master, 0));
    CHECK(run_until_result(&a, 100000));
    CHECK(!a.ok);
    CHECK(strstr(a.error, "RS: SAP 51 not activated") != NULL);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH); /* cyclic exchange unharmed */

    /* C1 response timeout: a 50 us budget runs out while the card still says SC. */
    setup(true, true, 20000);
    rig.master.cfg.c1_timeout_us = 50;
    const uint8_t write47[14] = {0x5F, 0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01,
                                 0x10, 0x00, 0x20, 0x6C, 0x00, 0x00};
    a = (acyc_result_t){0};
    CHECK_EQ(dp_master_c1_submit(&rig.master, 0, write47, sizeof write47, acyc_done, &a), 0);
    membus_run_for_us(&rig.bus, 5000);
    CHECK_EQ(dp_master_c1_submit(&rig.master, 0, read47, 4, acyc_done, &a), 0);
    a = (acyc_result_t){0};
    CHECK(run_until_result(&a, 100000));
    CHECK(!a.ok);
    CHECK(strstr(a.error, "within the response timeout (0 ms") != NULL);

    /* The card falls silent during a call: retries, restart, the call fails. */
    setup(true, true, 0);
    rig.master.cfg.c1_timeout_us = DP_MASTER_C1_TIMEOUT_US_DEFAULT;
    dp_master_call_t call = {0};
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK_EQ(dp_master_ds47_start(&call, dp_master_c1_port(&rig.master, 0), &req, NULL, NULL,
                            membus_now_us(&rig.bus)), 0);
    while (rig.master.slaves[0].c1.state == DP_MASTER_XFER_REQUEST ||
           !rig.master.slaves[0].c1.started) {
        membus_run_for_us(&rig.bus, 10);
    }
    bench.card_port->silenced = true;
    CHECK(run_until_call(&call, 1000000));
    CHECK(!call.ok);
    CHECK(strstr(call.error, "restarted (no answer); the request is lost") != NULL);
    CHECK(rig.master.total_retries >= 1u);
}

static void test_c1_lost_response_is_repeated_by_the_card(void)
{
    /* The master misses the Read.res: it repeats the poll with the same FCB, and the card must
     * repeat the response from its FCB cache (its mailbox is already empty: a fresh poll would
     * get SC and the value would be lost). */
    setup(true, true, 0);
    rig.master.cfg.slot_time_us = 1000; /* the retry comes after the whole answer */
    bench.recording = true;
    bench.drop_read_res = true;
    dp_master_call_t call = {0};
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK_EQ(dp_master_ds47_start(&call, dp_master_c1_port(&rig.master, 0), &req, NULL, NULL,
                            membus_now_us(&rig.bus)), 0);
    for (int i = 0; i < 100000 && !dp_master_call_done(&call); i++) {
        membus_run_for_us(&rig.bus, 10);
        if (rig.master_port->silenced && rig.bus.now_ns - bench.dropped_at_ns > 400000u) {
            rig.master_port->silenced = false;
        }
    }
    CHECK(call.ok);
    CHECK_EQ(rig.master.total_retries, 1);
    dp_master_ds47_rsp_t rsp;
    CHECK(dp_master_ds47_parse(&req, call.data, call.len, &rsp, NULL, 0));
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    /* On the wire: poll, Read.res (missed), the same poll again, the same Read.res again. */
    long first = -1;
    for (size_t i = 0; i + 3u < bench.nframes; i++) {
        const frame_t *f = &bench.frames[i + 1u];
        if (f->len > 10u && f->b[6] == FDL_RSP_DL && f->b[9] == DPV1_FN_READ) {
            first = (long)i;
            break;
        }
    }
    CHECK(first >= 0);
    if (first >= 0) {
        const frame_t *poll1 = &bench.frames[first];
        const frame_t *rsp1 = &bench.frames[first + 1];
        const frame_t *poll2 = &bench.frames[first + 2];
        const frame_t *rsp2 = &bench.frames[first + 3];
        CHECK_EQ(poll1->len, 11);
        CHECK(poll1->len == poll2->len && memcmp(poll1->b, poll2->b, poll1->len) == 0);
        CHECK(rsp1->len == rsp2->len && memcmp(rsp1->b, rsp2->b, rsp1->len) == 0);
    }
    check_c1_discipline();
}

static void test_c1_inverter_timeout_texts(void)
{
    /* The inverter does not answer within the card's 200 ms: MOVILINK 0x0602, and through
     * PROFIdrive the card's manufacturer-range number for it. */
    setup(true, true, 500000);
    dp_master_acyc_port_t port = dp_master_c1_port(&rig.master, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    char text[200];
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].error, 0x0602);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "class 6 code 2: card <-> inverter communication fault");
    CHECK(call.busy > 10u);
    membus_run_for_us(&rig.bus, 600000); /* let the late answer pass */
    req = (dp_master_ds47_req_t){.ref = 3, .id = DS47_ID_REQUEST, .n = 1};
    req.p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8300};
    CHECK(ds47(port, &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].error, 0x0082);
    dp_master_ds47_error_text(rsp.id, rsp.p[0].error, text, sizeof text);
    CHECK_STR(text, "manufacturer specific 0x0082 (MOVILINK 0x0602: class 6 code 2: card <-> "
                    "inverter communication fault)");
}

/* ---- class 2 ------------------------------------------------------------------------------ */

static void c2_setup(dp_master_c2_t *c, uint8_t address, uint8_t ssap)
{
    dp_master_c2_cfg_t cfg = {.slave = SLAVE, .address = address, .ssap = ssap};
    dp_master_c2_init(c, &cfg);
    CHECK_EQ(dp_master_add_c2(&rig.master, c), 0);
}

static bool c2_open(dp_master_c2_t *c, acyc_result_t *a)
{
    memset(a, 0, sizeof *a);
    if (dp_master_c2_open(c, acyc_done, a, membus_now_us(&rig.bus)) != 0) {
        return false;
    }
    membus_wake(rig.master_port);
    return run_until_result(a, 2000000) && a->ok;
}

static void test_c2_open_read_abort_on_the_wire(void)
{
    setup(false, false, 0); /* no class-1 master: the card stays in Wait_Prm */
    bench.recording = true;
    static dp_master_c2_t c;
    c2_setup(&c, 1, 0);
    acyc_result_t a;
    CHECK(c2_open(&c, &a));
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_OPEN);
    CHECK_EQ(c.sap, 0);
    CHECK_BYTES(a.pdu, a.len, 0x57, 0xF0, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                0x00);
    /* Initiate.req (first telegram from 1 to 4: FCV 0, FCB 1), RM answer, polls of SAP 0. */
    CHECK(bench.nframes >= 4u);
    CHECK_BYTES(bench.frames[0].b, bench.frames[0].len, 0x68, 0x19, 0x19, 0x68, 0x84, 0x81, 0x6D,
                0x31, 0x32, 0x57, 0x00, 0x00, 0x00, 0x00, 0xC8, 0x01, 0x00, 0x00, 0x00, 0x00,
                0x00, 0x00, 0x02, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0xF9, 0x16);
    CHECK_BYTES(bench.frames[1].b, bench.frames[1].len, 0x68, 0x09, 0x09, 0x68, 0x81, 0x84, 0x08,
                0x32, 0x31, 0x56, 0x00, 0x00, 0x00, 0xC6, 0x16);
    CHECK_BYTES(bench.frames[2].b, bench.frames[2].len, 0x68, 0x05, 0x05, 0x68, 0x84, 0x81, 0x5D,
                0x00, 0x32, 0x94, 0x16);
    size_t last = bench.nframes - 1u;
    CHECK_BYTES(bench.frames[last].b, bench.frames[last].len, 0x68, 0x11, 0x11, 0x68, 0x81, 0x84,
                0x08, 0x32, 0x00, 0x57, 0xF0, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                0x00, 0x00, fdl_fcs(&bench.frames[last].b[4], 17), 0x16);
    /* A DS47 read on the connection. */
    size_t before = bench.nframes;
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK(ds47(dp_master_c2_port(&c), &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    long w = find_request(before, SLAVE, 1, 0, DPV1_FN_WRITE);
    CHECK(w >= 0);
    if (w >= 0) {
        const uint8_t write_req[] = {0x68, 0x13, 0x13, 0x68, 0x84, 0x81, 0x7D, 0x00, 0x32, 0x5F,
                                     0x00, 0x2F, 0x0A, 0x01, 0x40, 0x00, 0x01, 0x10, 0x00, 0x20,
                                     0x6C, 0x00, 0x00, 0x2A, 0x16};
        check_request(&bench.frames[w], write_req, sizeof write_req, "C2 Write DS47");
        CHECK_BYTES(bench.frames[w + 1].b, bench.frames[w + 1].len, 0xE5);
    }
    /* Abort: 58 00 20 00 to SAP 0, answered SC; the card frees the connection. */
    acyc_result_t ab = {0};
    CHECK_EQ(dp_master_c2_abort(&c, 0, acyc_done, &ab, membus_now_us(&rig.bus)), 0);
    membus_wake(rig.master_port);
    CHECK(run_until_result(&ab, 100000));
    CHECK(ab.ok);
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_CLOSED);
    long abort_at = find_request(before, SLAVE, 1, 0, DPV1_FN_ABORT);
    CHECK(abort_at >= 0);
    if (abort_at >= 0) {
        const uint8_t abort_req[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x81, 0x7D, 0x00, 0x32, 0x58,
                                     0x00, 0x20, 0x00, 0x2C, 0x16};
        check_request(&bench.frames[abort_at], abort_req, sizeof abort_req, "C2 Abort");
        CHECK_BYTES(bench.frames[abort_at + 1].b, bench.frames[abort_at + 1].len, 0xE5);
    }
    CHECK_EQ(rig.cards[0].cs.card.dpv1.c2_aborts, 1);
    CHECK(!rig.cards[0].cs.card.dpv1.c2[0].open);
    CHECK_EQ(dp_slave_state(&rig.cards[0].cs.card.dp), DP_STATE_WAIT_PRM);
    CHECK_EQ(dp_master_c2_submit(&c, (const uint8_t *)"\x5E\x00\x2F\xF0", 4, acyc_done, &ab,
                           membus_now_us(&rig.bus)), -1); /* closed */
    /* The connection can be opened again. */
    CHECK(c2_open(&c, &a));
    CHECK_EQ(c.opens, 2);
}

static void test_c2_im0_and_negative(void)
{
    setup(false, false, 0);
    static dp_master_c2_t c;
    c2_setup(&c, 1, 0);
    acyc_result_t a;
    CHECK(c2_open(&c, &a));
    dp_master_call_t call = {0};
    CHECK_EQ(dp_master_im0_start(&call, dp_master_c2_port(&c), NULL, NULL, membus_now_us(&rig.bus)),
             0);
    membus_wake(rig.master_port);
    CHECK(run_until_call(&call, 1000000));
    dp_master_im0_t im;
    CHECK(call.ok && dp_master_im0_decode(call.data, call.len, &im, NULL, 0));
    CHECK_EQ(im.manufacturer_id, 0x010A);
    /* Write I&M0 is refused: B6. */
    uint8_t rec[68] = {0x08, 0x00, 0xFD, 0xE8};
    memset(&call, 0, sizeof call);
    CHECK_EQ(dp_master_call_start(&call, dp_master_c2_port(&c), 255, rec, sizeof rec, 240, NULL,
                                  NULL, membus_now_us(&rig.bus)),
             0);
    membus_wake(rig.master_port);
    CHECK(run_until_call(&call, 1000000));
    CHECK(call.dpv1_negative);
    CHECK_EQ(call.neg_code1, 0xB6);
    CHECK_EQ(dp_master_c2_state(&c),
             DP_MASTER_C2_OPEN); /* a negative response keeps the connection */
    /* A MOVILINK error through class 2. */
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_WRITE_VOLATILE, 8517, 99000000u);
    dp_master_ds47_rsp_t rsp;
    CHECK(ds47(dp_master_c2_port(&c), &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].error, 0x0815);
}

static void test_c2_third_connection_refused(void)
{
    setup(false, false, 0);
    static dp_master_c2_t c1;
    static dp_master_c2_t c2;
    static dp_master_c2_t c3;
    c2_setup(&c1, 1, 0);
    c2_setup(&c2, 3, 0);
    c2_setup(&c3, 1, 40); /* same master as c1, another SSAP: a third connection */
    acyc_result_t a;
    CHECK(c2_open(&c1, &a));
    CHECK(c2_open(&c2, &a));
    CHECK_EQ(c2.sap, 1);
    bench.recording = true;
    CHECK(!c2_open(&c3, &a));
    CHECK(a.done && !a.ok);
    CHECK_EQ(dp_master_c2_state(&c3), DP_MASTER_C2_CLOSED);
    CHECK_STR(a.error, "connection refused (resource manager SAP 49): Abort from the slave: "
                       "subnet 0, instance MSAC_C2, reason 15 RES resource");
    CHECK_STR(dp_master_c2_error(&c3), a.error);
    CHECK_EQ(rig.cards[0].cs.card.dpv1.c2_refused, 1);
    /* The refusal on the wire: an Abort PDU from SAP 49 to SSAP 40. */
    CHECK_BYTES(bench.frames[1].b, bench.frames[1].len, 0x68, 0x09, 0x09, 0x68, 0x81, 0x84, 0x08,
                0x28, 0x31, 0x58, 0x00, 0x1F, 0x00, 0xDD, 0x16);
    /* Both others still work; the FCB sequence of address 1 is shared by c1 and c3. */
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    CHECK(ds47(dp_master_c2_port(&c1), &req, &call, &rsp));
    CHECK(ds47(dp_master_c2_port(&c2), &req, &call, &rsp));
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    /* After c1 aborts, c3 gets SAP 0. */
    acyc_result_t ab = {0};
    CHECK_EQ(dp_master_c2_abort(&c1, 0, acyc_done, &ab, membus_now_us(&rig.bus)), 0);
    membus_wake(rig.master_port);
    CHECK(run_until_result(&ab, 100000));
    CHECK(c2_open(&c3, &a));
    CHECK_EQ(c3.sap, 0);
    CHECK(ds47(dp_master_c2_port(&c3), &req, &call, &rsp));
    CHECK_EQ(rig.master.timeouts, 0);
}

static void test_c2_idle_keeps_the_connection(void)
{
    setup(false, false, 0);
    static dp_master_c2_t c;
    dp_master_c2_cfg_t cfg = {.slave = SLAVE, .address = 1, .send_timeout = 10}; /* 100 ms */
    dp_master_c2_init(&c, &cfg);
    CHECK_EQ(dp_master_add_c2(&rig.master, &c), 0);
    acyc_result_t a;
    CHECK(c2_open(&c, &a));
    bench.recording = true;
    membus_run_for_us(&rig.bus, 500000); /* 5 send timeouts without a request */
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_OPEN);
    CHECK(c.idles >= 8u && c.idles <= 11u); /* one per 50 ms */
    CHECK_EQ(rig.cards[0].cs.card.dpv1.c2_timeouts, 0);
    long i = find_request(0, SLAVE, 1, 0, DPV1_FN_IDLE);
    CHECK(i >= 0);
    if (i >= 0) {
        const uint8_t idle[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x81, 0x7D, 0x00, 0x32, 0x48,
                                0x00, 0x00, 0x00, 0xFC, 0x16};
        check_request(&bench.frames[i], idle, sizeof idle, "C2 Idle");
        CHECK_BYTES(bench.frames[i + 1].b, bench.frames[i + 1].len, 0x68, 0x09, 0x09, 0x68, 0x81,
                    0x84, 0x08, 0x32, 0x00, 0x48, 0x00, 0x00, 0x00, 0x87, 0x16);
    }
    /* A request right after an Idle still goes through. */
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    dp_master_call_t call;
    dp_master_ds47_rsp_t rsp;
    CHECK(ds47(dp_master_c2_port(&c), &req, &call, &rsp));

    /* Without Idle the card's supervision frees the connection; the next request sees RS. */
    c.cfg.no_idle = true;
    membus_run_for_us(&rig.bus, 300000);
    CHECK_EQ(rig.cards[0].cs.card.dpv1.c2_timeouts, 1);
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_OPEN); /* the master cannot know yet */
    memset(&call, 0, sizeof call);
    CHECK_EQ(dp_master_ds47_start(&call, dp_master_c2_port(&c), &req, NULL, NULL,
                                  membus_now_us(&rig.bus)),
             0);
    membus_wake(rig.master_port);
    CHECK(run_until_call(&call, 1000000));
    CHECK(!call.ok);
    CHECK(strstr(call.error, "RS: SAP 0 not activated") != NULL);
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_CLOSED);
    CHECK(strstr(dp_master_c2_error(&c), "connection closed") != NULL);
}

static void test_c2_and_c1_together_with_cyclic_exchange(void)
{
    setup(true, true, 2000);
    bench.recording = true;
    static dp_master_c2_t c;
    c2_setup(&c, MASTER, 0); /* same address as the class-1 master: one FCB sequence */
    acyc_result_t a;
    CHECK(c2_open(&c, &a));
    dp_master_ds47_req_t r1 = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    dp_master_ds47_req_t r2 = ml_request(DS47_ATTR_ML_READ, 8489, 0);
    r2.ref = 2;
    dp_master_call_t k1 = {0};
    dp_master_call_t k2 = {0};
    uint32_t cycles0 = rig.master.slaves[0].cycles;
    hal_time_us_t t = membus_now_us(&rig.bus);
    CHECK_EQ(dp_master_ds47_start(&k1, dp_master_c1_port(&rig.master, 0), &r1, NULL, NULL, t), 0);
    CHECK_EQ(dp_master_ds47_start(&k2, dp_master_c2_port(&c), &r2, NULL, NULL, t), 0);
    CHECK(run_until_call(&k1, 2000000));
    CHECK(run_until_call(&k2, 2000000));
    dp_master_ds47_rsp_t rsp;
    CHECK(k1.ok && dp_master_ds47_parse(&r1, k1.data, k1.len, &rsp, NULL, 0));
    CHECK_EQ(rsp.p[0].value, 0x311C7289u);
    CHECK(k2.ok && dp_master_ds47_parse(&r2, k2.data, k2.len, &rsp, NULL, 0));
    CHECK_EQ(rsp.p[0].value, 150000);
    CHECK(rig.master.slaves[0].cycles - cycles0 + 1u >= k1.telegrams);
    CHECK_EQ(rig.master.timeouts, 0);
    check_c1_discipline(); /* FCB toggles across DX, C1 and C2 telegrams from address 2 */
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
}

static void test_c2_slave_falls_silent(void)
{
    setup(false, false, 0);
    static dp_master_c2_t c;
    c2_setup(&c, 1, 0);
    acyc_result_t a;
    CHECK(c2_open(&c, &a));
    bench.card_port->silenced = true;
    dp_master_call_t call = {0};
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    CHECK_EQ(dp_master_ds47_start(&call, dp_master_c2_port(&c), &req, NULL, NULL,
                                  membus_now_us(&rig.bus)),
             0);
    membus_wake(rig.master_port);
    CHECK(run_until_call(&call, 1000000));
    CHECK(!call.ok);
    CHECK_STR(call.error, "Write.req index 47: request: no answer from slave 4; connection closed");
    CHECK_EQ(dp_master_c2_state(&c), DP_MASTER_C2_CLOSED);
    CHECK_EQ(rig.master.total_retries, 1);
    /* Opening against a silent slave fails too. */
    CHECK(!c2_open(&c, &a));
    CHECK_STR(a.error, "Initiate (resource manager): no answer from slave 4");
}

/* ---- pure functions ----------------------------------------------------------------------- */

static void test_ds47_parse_and_texts(void)
{
    dp_master_ds47_req_t req = ml_request(DS47_ATTR_ML_READ, 8300, 0);
    dp_master_ds47_rsp_t rsp;
    char err[128];
    const uint8_t good[] = {0x01, 0x40, 0x00, 0x01, 0x43, 0x01, 0x31, 0x1C, 0x72, 0x89};
    CHECK(dp_master_ds47_parse(&req, good, sizeof good, &rsp, err, sizeof err));
    const uint8_t manual_neg[] = {0x01, 0xC0, 0x00, 0x01, 0x44, 0x01, 0x08, 0x11};
    CHECK(dp_master_ds47_parse(&req, manual_neg, sizeof manual_neg, &rsp, err, sizeof err));
    CHECK_EQ(rsp.p[0].error, 0x0811);
    CHECK(!dp_master_ds47_parse(&req, good, 8, &rsp, err, sizeof err)); /* truncated */
    CHECK(strstr(err, "truncated") != NULL);
    const uint8_t wrong_ref[] = {0x02, 0x40, 0x00, 0x01, 0x43, 0x01, 0, 0, 0, 0};
    CHECK(!dp_master_ds47_parse(&req, wrong_ref, sizeof wrong_ref, &rsp, err, sizeof err));
    CHECK_STR(err, "response reference 0x02, request 0x01");
    char text[160];
    dp_master_ds47_error_text(0x40, 0x0505, text, sizeof text);
    CHECK_STR(text, "class 5 code 5: wrong coding of the management or reserved octet");
    dp_master_ds47_error_text(0xC0, 0x0602, text, sizeof text);
    CHECK_STR(text, "class 6 code 2: card <-> inverter communication fault");
    dp_master_ds47_error_text(0x81, 0x0011, text, sizeof text);
    CHECK_STR(text, "PROFIdrive error 0x11: request cannot be executed because of the operating "
                    "state");
    dp_master_ds47_error_text(0x81, 0x0091, text, sizeof text);
    CHECK_STR(text, "manufacturer specific (MOVILINK class 8, additional code 0x11: "
                    "function/parameter not implemented)");
    CHECK_STR(dp_master_v1_error_text(0xB5), "access: state conflict");
    uint8_t ini[32];
    CHECK_EQ(dp_master_c2_build_initiate(ini, 0x0190), 20);
    CHECK_BYTES(ini, 6, 0x57, 0x00, 0x00, 0x00, 0x01, 0x90);
}

int main(void)
{
    RUN_TEST(test_prm_dpv1_octets);
    RUN_TEST(test_ds47_parse_and_texts);
    RUN_TEST(test_c1_ds47_read_8300_on_the_wire);
    RUN_TEST(test_c1_manual_examples_and_writes);
    RUN_TEST(test_c1_negative_parameter_results);
    RUN_TEST(test_c1_nineteen_parameters);
    RUN_TEST(test_c1_slow_inverter_b5_and_exchange_goes_on);
    RUN_TEST(test_c1_im0);
    RUN_TEST(test_c1_refusals_and_timeouts);
    RUN_TEST(test_c1_lost_response_is_repeated_by_the_card);
    RUN_TEST(test_c1_inverter_timeout_texts);
    RUN_TEST(test_c2_open_read_abort_on_the_wire);
    RUN_TEST(test_c2_im0_and_negative);
    RUN_TEST(test_c2_third_connection_refused);
    RUN_TEST(test_c2_idle_keeps_the_connection);
    RUN_TEST(test_c2_and_c1_together_with_cyclic_exchange);
    RUN_TEST(test_c2_slave_falls_silent);
    return check_report();
}
