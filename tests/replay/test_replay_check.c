/* The parts of the replay check a CI run leans on, one by one: --ignore masks (the spec, the
 * octets of an answer it covers, the engine leaving them out and counting them), the kept list
 * of mismatches, the first pass telling a line's capture from a tty's, what replay_infer takes
 * from the capture and what the command line overrides, and the report files' escaping. */
#include <stdlib.h>
#include <string.h>

#include "capture/capture.h"
#include "check.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "replay/infer.h"
#include "replay/replay.h"

#define CARD 4u
#define MASTER 2u
#define BAUD 1500000u

static replay_t rp;
static uint64_t next_index;

static const uint8_t fdl_status_req[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t fdl_status_rsp[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
static const uint8_t sc[] = {0xE5};

static void test_mask_spec(void)
{
    replay_mask_t m;
    memset(&m, 0, sizeof m);
    char err[200];
    CHECK(replay_mask_add(&m, "PI2,dx:4-7", err, sizeof err));
    CHECK(m.any);
    CHECK_EQ(m.pi[0], 0x02); /* PI2 */
    CHECK_EQ(m.du[REPLAY_SVC_DATA_EXCHANGE][0], 0xF0); /* octets 4..7 */
    CHECK(replay_mask_add(&m, "diag:6", err, sizeof err));
    CHECK_EQ(m.du[REPLAY_SVC_SLAVE_DIAG][0], 0x40);
    CHECK_STR(m.text, "PI2,dx:4-7,diag:6");
    CHECK(replay_mask_add(&m, "PI3-PI4,pi9-10,MSAC1 read:1,msac2-data-transport:245", err,
                          sizeof err));
    CHECK_EQ(m.pi[0], 0x0E);
    CHECK_EQ(m.pi[1], 0x03);
    CHECK_EQ(m.du[REPLAY_SVC_MSAC1_READ][0], 0x02);
    CHECK_EQ(m.du[REPLAY_SVC_MSAC2_TRANSPORT][30], 0x20);
    /* A bad item anywhere: nothing of the spec is taken. */
    replay_mask_t before = m;
    CHECK(!replay_mask_add(&m, "PI5,PI0", err, sizeof err));
    CHECK_STR(err, "'PI0': PI1..122 only");
    CHECK(memcmp(&m, &before, sizeof m) == 0);
    CHECK(!replay_mask_add(&m, "dx:9-4", err, sizeof err));
    CHECK_STR(err, "'dx:9-4': the range runs backwards (4 after 9)");
    CHECK(!replay_mask_add(&m, "dx:246", err, sizeof err));
    CHECK_STR(err, "'dx:246': 0..245 only");
    CHECK(!replay_mask_add(&m, "dx:-1", err, sizeof err));
    CHECK(!replay_mask_add(&m, "dx:0x4", err, sizeof err));
    CHECK_STR(err, "'dx:0x4': 0x4 is not a number or a range N-M");
    CHECK(!replay_mask_add(&m, "token:1", err, sizeof err));
    CHECK(strstr(err, "'token:1': unknown service 'token'") == err);
    CHECK(!replay_mask_add(&m, "PI", err, sizeof err));
    CHECK(strstr(err, "'PI': neither PIn nor SERVICE:OCTETS") == err);
    CHECK(!replay_mask_add(&m, "", err, sizeof err));
    CHECK_STR(err, "an empty item (two commas?)");
    CHECK(memcmp(&m, &before, sizeof m) == 0);

    replay_service_t s = REPLAY_SVC_COUNT;
    CHECK(replay_service_parse("Data_Exchange", &s));
    CHECK_EQ(s, REPLAY_SVC_DATA_EXCHANGE);
    CHECK(replay_service_parse("status", &s));
    CHECK_EQ(s, REPLAY_SVC_FDL_STATUS);
    CHECK(replay_service_parse("other fdl function", &s));
    CHECK_EQ(s, REPLAY_SVC_OTHER_FUNCTION);
    CHECK(!replay_service_parse("dxx", &s));
    char key[64];
    CHECK_STR(replay_service_key(REPLAY_SVC_MSAC2_TRANSPORT, key, sizeof key),
              "msac2_data_transport");
    CHECK_STR(replay_service_key(REPLAY_SVC_SLAVE_DIAG, key, sizeof key), "slave_diag");
}

/* A Data_Exchange answer: 8 octets of parameter channel, then PI1..PI3. */
static size_t dx_answer(uint8_t *out, uint16_t pi1, uint16_t pi2, uint16_t pi3)
{
    uint8_t du[14] = {0};
    du[8] = (uint8_t)(pi1 >> 8);
    du[9] = (uint8_t)pi1;
    du[10] = (uint8_t)(pi2 >> 8);
    du[11] = (uint8_t)pi2;
    du[12] = (uint8_t)(pi3 >> 8);
    du[13] = (uint8_t)pi3;
    return fdl_encode(out, MASTER, CARD, 0x08, false, 0, 0, du, sizeof du);
}

static void test_mask_answer(void)
{
    replay_mask_t m;
    memset(&m, 0, sizeof m);
    char err[200];
    CHECK(replay_mask_add(&m, "PI2", err, sizeof err));
    uint8_t f[64];
    size_t n = dx_answer(f, 1, 2, 3);
    CHECK_EQ(n, 23);
    uint8_t bits[CAP_MAX_RECORD / 8u];
    /* PI2 after the channel: data octets 10, 11 = telegram octets 17, 18; and the FCS (21). */
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_DATA_EXCHANGE, 8, f, n, bits, sizeof bits), 3);
    CHECK_EQ(bits[2], 0x26);
    CHECK_EQ(bits[0] | bits[1] | bits[3], 0);
    /* Without a channel PI2 is data octets 2, 3. */
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_RD_INP, 0, f, n, bits, sizeof bits), 3);
    CHECK_EQ(bits[1], 0x06);
    /* No configuration yet, another service, no data unit: nothing. */
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_DATA_EXCHANGE, -1, f, n, bits, sizeof bits), 0);
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_SLAVE_DIAG, 8, f, n, bits, sizeof bits), 0);
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_DATA_EXCHANGE, 8, sc, 1, bits, sizeof bits), 0);
    CHECK_EQ(replay_mask_answer(NULL, REPLAY_SVC_DATA_EXCHANGE, 8, f, n, bits, sizeof bits), 0);
    /* A range past the answer's end masks what there is. */
    CHECK(replay_mask_add(&m, "dx:12-40", err, sizeof err));
    CHECK_EQ(replay_mask_answer(&m, REPLAY_SVC_DATA_EXCHANGE, -1, f, n, bits, sizeof bits), 3);
}

static void test_list(void)
{
    replay_list_t l;
    replay_list_init(&l, 2);
    static replay_listed_t e;
    memset(&e, 0, sizeof e);
    e.expected_present = e.actual_present = true;
    e.request_len = 1;
    e.request[0] = 0xAA;
    e.expected_len = e.actual_len = 4;
    memcpy(e.expected, "\x01\x02\x03\x04", 4);
    memcpy(e.actual, "\x01\x09\x03\x08", 4);
    for (uint64_t i = 1; i <= 3u; i++) {
        e.number = i;
        replay_list_add(&l, &e);
    }
    CHECK_EQ(l.kept, 2);
    CHECK(!l.failed);
    static replay_listed_t got;
    CHECK(replay_list_rewind(&l));
    CHECK(replay_list_next(&l, &got));
    CHECK_EQ(got.number, 1);
    CHECK(replay_list_next(&l, &got));
    CHECK_EQ(got.number, 2);
    CHECK_BYTES(got.actual, got.actual_len, 0x01, 0x09, 0x03, 0x08);
    CHECK_BYTES(got.request, got.request_len, 0xAA);
    CHECK(!replay_list_next(&l, &got));
    uint16_t d[4];
    CHECK_EQ(replay_listed_diffs(&got, d, 4), 2);
    CHECK_EQ(d[0], 1);
    CHECK_EQ(d[1], 3);
    got.mask[0] = 0x02; /* octet 1 masked */
    CHECK_EQ(replay_listed_diffs(&got, d, 4), 1);
    CHECK_EQ(d[0], 3);
    got.actual_present = false;
    CHECK_EQ(replay_listed_diffs(&got, d, 4), 0);
    replay_list_close(&l);
    CHECK(l.spool == NULL);
}

static void feed(uint64_t t_us, const uint8_t *f, size_t len)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.index = ++next_index;
    rec.position = 24u + 100u * (rec.index - 1u);
    rec.has_time = true;
    rec.t_ns = 1700000000000000000ull + t_us * 1000u;
    rec.len = len;
    rec.orig_len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_feed(&rp, &rec);
}

static replay_listed_t handed[4];
static unsigned n_handed;

static void on_mismatch(void *ctx, const replay_listed_t *m)
{
    (void)ctx;
    if (n_handed < 4u) {
        handed[n_handed] = *m;
    }
    n_handed++;
}

/* Parameterised with Param + 3 PD, then one Data_Exchange whose recorded answer is answer. */
static void run_dx(const replay_mask_t *mask, const uint8_t *answer, size_t alen)
{
    replay_options_t o = {.address = CARD, .check = true, .baud = BAUD, .fixed_card_baud = true,
                          .inverter = CARD_INVERTER_NONE, .mask = mask,
                          .on_mismatch = on_mismatch};
    char err[128];
    CHECK_EQ(replay_init(&rp, &o, err, sizeof err), 0);
    next_index = 0;
    n_handed = 0;
    uint8_t f[64];
    uint8_t prm[16] = {0x88, 0x01, 0x0A, 0x0B, 0x60, 0x03, 0x00};
    memcpy(&prm[7], dfp21b_user_prm_default, 9);
    size_t n = fdl_encode(f, CARD, MASTER, 0x5D, true, DP_SAP_SET_PRM, DP_SAP_MASTER, prm, 16);
    feed(0, f, n);
    feed(200, sc, 1);
    uint8_t cfg[2] = {0xF3, 0xF2};
    n = fdl_encode(f, CARD, MASTER, 0x7D, true, DP_SAP_CHK_CFG, DP_SAP_MASTER, cfg, 2);
    feed(400, f, n);
    feed(500, sc, 1);
    uint8_t po[14] = {0};
    po[8] = 0x00;
    po[9] = 0x06;
    po[10] = 0x05;
    po[11] = 0xDC;
    n = fdl_encode(f, CARD, MASTER, 0x5D, false, 0, 0, po, sizeof po);
    feed(1000, f, n);
    feed(1200, answer, alen);
    replay_finish(&rp);
}

/* The engine with a mask: the masked octets (and the FCS) are not compared and are counted; a
 * mismatch is handed over with the octets, the data unit's offset and the mask. */
static void test_engine_mask(void)
{
    uint8_t wrong[64];
    size_t wl = dx_answer(wrong, 0x1111, 0x2222, 0x3333);
    run_dx(NULL, wrong, wl);
    CHECK_EQ(rp.svc[REPLAY_SVC_DATA_EXCHANGE].differ, 1);
    CHECK_EQ(n_handed, 1);
    const replay_listed_t *h = &handed[0];
    CHECK_EQ(h->number, 1);
    CHECK_EQ(h->service, REPLAY_SVC_DATA_EXCHANGE);
    CHECK_EQ(h->record, 5);
    CHECK_EQ(h->expected_record, 6);
    CHECK_EQ(h->data_offset, 7);
    CHECK_EQ(h->masked, 0);
    CHECK(h->expected_present && h->actual_present);
    CHECK_EQ(h->actual_len, 23);
    /* What the card sent, with PI1..PI3 changed: masked, they match. */
    uint8_t recorded[64];
    memcpy(recorded, h->actual, h->actual_len);
    size_t rl = h->actual_len;
    recorded[15] ^= 0x40;
    recorded[17] ^= 0x01;
    recorded[20] ^= 0x80;
    recorded[rl - 2u] = fdl_fcs(&recorded[4], rl - 6u);
    replay_mask_t m;
    memset(&m, 0, sizeof m);
    char err[200];
    CHECK(replay_mask_add(&m, "PI1-3", err, sizeof err));
    run_dx(&m, recorded, rl);
    CHECK_EQ(rp.svc[REPLAY_SVC_DATA_EXCHANGE].matched, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_DATA_EXCHANGE].masked_octets, 7);
    CHECK_EQ(rp.masked_octets, 7);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(n_handed, 0);
    /* PI2 alone masked: PI1 and PI3 still differ; the first difference skips nothing else. */
    memset(&m, 0, sizeof m);
    CHECK(replay_mask_add(&m, "PI2", err, sizeof err));
    run_dx(&m, recorded, rl);
    CHECK_EQ(rp.mismatches, 1);
    CHECK_EQ(handed[0].masked, 3);
    uint16_t d[8];
    CHECK_EQ(replay_listed_diffs(&handed[0], d, 8), 2);
    CHECK_EQ(d[0], 15);
    CHECK_EQ(d[1], 20);
    CHECK(replay_bit(rp.first.mask, 17) && replay_bit(rp.first.mask, 21));
}

static void scan_at(replay_scan_t *s, uint64_t t_us, const uint8_t *f, size_t len)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.index = ++next_index;
    rec.has_time = true;
    rec.t_ns = 1700000000000000000ull + t_us * 1000u;
    rec.len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_scan_feed(s, &rec);
}

/* Ten FDL status polls answered answer_us after the poll began. */
static void scan_polls(replay_scan_t *s, uint64_t answer_us)
{
    replay_scan_init(s);
    next_index = 0;
    for (uint64_t i = 0; i < 10u; i++) {
        scan_at(s, 2000u * i, fdl_status_req, sizeof fdl_status_req);
        scan_at(s, 2000u * i + answer_us, fdl_status_rsp, sizeof fdl_status_rsp);
    }
}

/* A 6-octet poll lasts 44 us at 1.5 Mbit/s; the answer may begin 7.3 us (min TSDR) to 63.8 us
 * (the card's max TSDR) after it ended, a microsecond of slack either way. */
static void test_scan_timing(void)
{
    static replay_scan_t s;
    replay_scan_timing_t w;
    scan_polls(&s, 51);
    CHECK_EQ(replay_scan_timing(&s, CARD, 1500000u, &w), REPLAY_TIMING_LINE);
    CHECK_EQ(w.pairs, 10);
    CHECK_EQ(w.off_line, 0);
    CHECK_EQ(w.min_gap_ns, 51000);
    uint64_t first = 0;
    CHECK(replay_scan_first_answered(&s, CARD, &first));
    CHECK_EQ(first, 1);
    /* At 12 Mbit/s the same answers are 45 us late: still within 63.8 us. */
    CHECK_EQ(replay_scan_timing(&s, CARD, 12000000u, &w), REPLAY_TIMING_LINE);
    /* At 500 kbit/s the poll lasts 132 us: the answers begin before it ended. */
    CHECK_EQ(replay_scan_timing(&s, CARD, 500000u, &w), REPLAY_TIMING_RELAXED);
    CHECK_EQ(w.off_line, 10);
    scan_polls(&s, 108); /* 64 us after the end at 1.5M: within max TSDR and the slack */
    CHECK_EQ(replay_scan_timing(&s, CARD, 1500000u, NULL), REPLAY_TIMING_LINE);
    scan_polls(&s, 110); /* 66 us: late */
    CHECK_EQ(replay_scan_timing(&s, CARD, 1500000u, NULL), REPLAY_TIMING_RELAXED);
    /* A PTY: 0.6 ms whatever the length. */
    scan_polls(&s, 600);
    CHECK_EQ(replay_scan_timing(&s, CARD, 1500000u, &w), REPLAY_TIMING_RELAXED);
    CHECK_EQ(w.max_gap_ns, 600000);
    /* Half late is not a majority; no answers at all is a line. */
    replay_scan_init(&s);
    next_index = 0;
    for (uint64_t i = 0; i < 10u; i++) {
        scan_at(&s, 2000u * i, fdl_status_req, sizeof fdl_status_req);
        scan_at(&s, 2000u * i + (i < 5u ? 51u : 600u), fdl_status_rsp, sizeof fdl_status_rsp);
    }
    CHECK_EQ(replay_scan_timing(&s, CARD, 1500000u, &w), REPLAY_TIMING_LINE);
    CHECK_EQ(w.off_line, 5);
    CHECK_EQ(replay_scan_timing(&s, 5, 1500000u, &w), REPLAY_TIMING_LINE);
    CHECK_EQ(w.pairs, 0);
    /* The first poll unanswered (the card searching its rate): not "on the bus before". */
    replay_scan_init(&s);
    next_index = 0;
    scan_at(&s, 0, fdl_status_req, sizeof fdl_status_req);
    scan_at(&s, 2000, fdl_status_req, sizeof fdl_status_req);
    scan_at(&s, 2051, fdl_status_rsp, sizeof fdl_status_rsp);
    CHECK(!replay_scan_first_answered(&s, CARD, &first));
    CHECK_EQ(first, 1);
}

static void test_infer(void)
{
    static replay_scan_t s;
    replay_inferred_t inf;
    char err[400];
    replay_given_t g = {.file = "f.pcap", .have_address = true, .address = 7, .baud = 19200,
                        .have_timing = true, .timing = REPLAY_TIMING_LINE};
    CHECK_EQ(replay_infer(NULL, NULL, &g, &inf, err, sizeof err), 0);
    CHECK_EQ(inf.address, 7);
    CHECK_STR(inf.address_source, "given with --address");
    CHECK_EQ(inf.baud, 19200);
    CHECK(inf.baud_override && !inf.baud_inferred);
    CHECK(!inf.timing_inferred && inf.timing_given);
    CHECK(!inf.fixed_baud);
    CHECK_EQ(inf.delay_us, REPLAY_INVERTER_DELAY_US_DEFAULT);
    /* A PTY capture: everything from it. */
    scan_polls(&s, 600);
    replay_given_t none = {.file = "f.pcap"};
    CHECK_EQ(replay_infer(&s, NULL, &none, &inf, err, sizeof err), 0);
    CHECK_EQ(inf.address, CARD);
    CHECK(inf.address_inferred);
    CHECK_EQ(inf.timing, REPLAY_TIMING_RELAXED);
    CHECK(inf.timing_inferred);
    CHECK(strstr(inf.timing_source, "a tty/PTY capture: 10 of 10 answers of station 4 begin "
                                    "0.600 to 0.600 ms after their request began") != NULL);
    CHECK_EQ(inf.baud, REPLAY_RELAXED_BAUD);
    CHECK(inf.baud_override && inf.baud_inferred);
    CHECK(inf.fixed_baud && inf.fixed_inferred);
    CHECK_EQ(inf.delay_us, 0);
    CHECK(inf.delay_inferred);
    /* The same with the rate and the inverter's time given: those as given. */
    replay_given_t some = {.file = "f.pcap", .baud = 6000000u, .have_delay = true,
                           .delay_us = 500};
    CHECK_EQ(replay_infer(&s, NULL, &some, &inf, err, sizeof err), 0);
    CHECK_EQ(inf.timing, REPLAY_TIMING_RELAXED);
    CHECK_EQ(inf.baud, 6000000u);
    CHECK_STR(inf.baud_source, "given with --baud");
    CHECK_EQ(inf.delay_us, 500);
    CHECK(inf.fixed_baud);
    /* A line capture whose first poll is answered: the card had its rate. */
    scan_polls(&s, 51);
    CHECK_EQ(replay_infer(&s, NULL, &none, &inf, err, sizeof err), 0);
    CHECK_EQ(inf.timing, REPLAY_TIMING_LINE);
    CHECK_EQ(inf.baud, 1500000u);
    CHECK(!inf.baud_override);
    CHECK(inf.fixed_baud && inf.fixed_inferred);
    CHECK(strstr(inf.fixed_source, "record 1, is answered") != NULL);
    CHECK_EQ(inf.delay_us, REPLAY_INVERTER_DELAY_US_DEFAULT);
    /* Two slaves: no address. */
    static const uint8_t poll5[] = {0x10, 0x05, 0x02, 0x49, 0x50, 0x16};
    static const uint8_t rsp5[] = {0x10, 0x02, 0x05, 0x00, 0x07, 0x16};
    scan_at(&s, 30000, poll5, sizeof poll5);
    scan_at(&s, 30051, rsp5, sizeof rsp5);
    replay_file_status_t st = {.records = 22};
    CHECK_EQ(replay_infer(&s, &st, &none, &inf, err, sizeof err), -1);
    CHECK_STR(err, "2 slaves answer in f.pcap: 4 (10 answers), 5 (1 answers); say which one is "
                   "the card with --address N");
}

/* A file name with characters JSON and XML must escape. */
static void test_report_escaping(void)
{
    replay_options_t o = {.address = CARD, .check = true, .baud = BAUD, .fixed_card_baud = true,
                          .inverter = CARD_INVERTER_NONE};
    char err[128];
    CHECK_EQ(replay_init(&rp, &o, err, sizeof err), 0);
    next_index = 0;
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    replay_report_info_t info = {.file = "a\"b\\c\n<d>&'e\x01.pcap", .format = "pcap",
                                 .position_unit = "byte"};
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    CHECK_EQ(replay_report_json(&rp, &info, out), 0);
    fclose(out);
    CHECK(strstr(text, "\"file\": \"a\\\"b\\\\c\\n<d>&'e\\u0001.pcap\"") != NULL);
    CHECK(strstr(text, "\"verdict\": \"MATCH\", \"exit_status\": 0") != NULL);
    CHECK(strstr(text, "\"inferred\": null") != NULL);
    free(text);
    text = NULL;
    out = open_memstream(&text, &size);
    CHECK_EQ(replay_report_junit(&rp, &info, out), 0);
    fclose(out);
    CHECK(strstr(text, "name=\"dfp-sim replay a&quot;b\\c\n&lt;d&gt;&amp;&apos;e?.pcap\"") != NULL);
    CHECK(strstr(text, "tests=\"2\" failures=\"0\"") != NULL);
    CHECK(strstr(text, "<testcase classname=\"replay.a&quot;b\\c\n&lt;d&gt;&amp;&apos;e?.pcap\" "
                       "name=\"FDL_Status\"/>") != NULL);
    free(text);
}

int main(void)
{
    RUN_TEST(test_mask_spec);
    RUN_TEST(test_mask_answer);
    RUN_TEST(test_list);
    RUN_TEST(test_engine_mask);
    RUN_TEST(test_scan_timing);
    RUN_TEST(test_infer);
    RUN_TEST(test_report_escaping);
    return check_report();
}
