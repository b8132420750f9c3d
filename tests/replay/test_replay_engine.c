/* The replay engine fed record by record, the way a reader hands them over: which records go
 * onto the bus, what counts as the card's recorded answer, how each request is judged (exact
 * octets, counts per service), what the first mismatch keeps, and the edge cases of
 * docs/replay.md: the card answering an unanswered request and the other way round, a capture
 * starting in data exchange, SAP extensions, SDN, FCB repeats, tokens and a second master,
 * damaged records, records without times, a capture that ends after a request, the address
 * scan and timing conflicts. */
#include <stdlib.h>
#include <string.h>

#include "capture/capture.h"
#include "check.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "replay/replay.h"

#define CARD 4u
#define MASTER 2u
#define BAUD 1500000u

static replay_t rp;
static uint64_t next_index;

static void start(bool check, bool fixed_baud)
{
    replay_options_t o = {.address = CARD, .check = check, .baud = BAUD,
                          .fixed_card_baud = fixed_baud, .inverter = CARD_INVERTER_NONE};
    char err[128];
    CHECK_EQ(replay_init(&rp, &o, err, sizeof err), 0);
    next_index = 0;
}

/* One record at t_us (has_time false when t_us is UINT64_MAX), as a reader makes it. */
static void feed(uint64_t t_us, const uint8_t *f, size_t len)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.index = ++next_index;
    rec.position = 24u + 100u * (rec.index - 1u);
    rec.has_time = t_us != UINT64_MAX;
    rec.t_ns = rec.has_time ? 1700000000000000000ull + t_us * 1000u : 0u;
    rec.len = len;
    rec.orig_len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_feed(&rp, &rec);
}

static size_t enc(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *du, size_t n)
{
    return fdl_encode(out, da, sa, fc, saps, dsap, ssap, du, n);
}

/* Frames used throughout (profibus-dp.md §1.6 and what the card answers). */
static const uint8_t fdl_status_req[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t fdl_status_rsp[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
static const uint8_t rs_rsp[] = {0x10, 0x02, 0x04, 0x03, 0x09, 0x16};
static const uint8_t sc[] = {0xE5};
/* Slave_Diag, first request (FCV=0 FCB=1), and the card's Wait_Prm answer (SD3). */
static const uint8_t diag_req_first[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                         0xED, 0x16};
static const uint8_t diag_wait_prm[] = {0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00,
                                        0xFF, 0x60, 0x03, 0xF1, 0x16};

static void test_startup_matches(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    feed(200, diag_req_first, sizeof diag_req_first);
    feed(280, diag_wait_prm, sizeof diag_wait_prm);
    replay_finish(&rp);
    CHECK_EQ(rp.records, 4);
    CHECK_EQ(rp.injected, 2);       /* the two requests */
    CHECK_EQ(rp.own_answers, 2);    /* the recorded answers stay off the bus */
    CHECK_EQ(rp.card_tx, 2);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].requests, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_SLAVE_DIAG].requests, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_SLAVE_DIAG].matched, 1);
    CHECK_EQ(rp.mismatches, 0);
    CHECK(!rp.first.valid);
    replay_report_info_t info = {.file = "t", .format = "pcap", .position_unit = "byte"};
    FILE *null = fopen("/dev/null", "w");
    CHECK_EQ(replay_report(&rp, &info, null), 0);
    fclose(null);
}

/* The capture shows no answer (the next record is another request); the card answers. */
static void test_card_answers_unanswered_request(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(5000, fdl_status_req, sizeof fdl_status_req);
    feed(5051, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    const replay_counts_t *c = &rp.svc[REPLAY_SVC_FDL_STATUS];
    CHECK_EQ(c->requests, 2);
    CHECK_EQ(c->matched, 1);
    CHECK_EQ(c->differ, 1);
    CHECK_EQ(c->capture_silent, 1);
    CHECK_EQ(c->card_silent, 0);
    CHECK_EQ(rp.mismatches, 1);
    const replay_mismatch_t *m = &rp.first;
    CHECK(m->valid);
    CHECK_EQ(m->request.record, 1);
    CHECK_EQ(m->request.position, 24);
    CHECK(!m->expected_present);
    CHECK(m->actual_present);
    CHECK_BYTES(m->actual.data, m->actual.len, 0x10, 0x02, 0x04, 0x00, 0x06, 0x16);
    CHECK_EQ(m->service, REPLAY_SVC_FDL_STATUS);
    replay_report_info_t info = {.file = "t", .format = "pcap", .position_unit = "byte"};
    FILE *null = fopen("/dev/null", "w");
    CHECK_EQ(replay_report(&rp, &info, null), 1);
    fclose(null);
}

/* The capture shows an answer, the card is still looking for the rate (it powers up at the
 * first record and starts its search at 12 Mbit/s). */
static void test_card_silent_during_baud_search(void)
{
    start(true, false);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    const replay_counts_t *c = &rp.svc[REPLAY_SVC_FDL_STATUS];
    CHECK_EQ(c->requests, 1);
    CHECK_EQ(c->differ, 1);
    CHECK_EQ(c->card_silent, 1);
    CHECK_EQ(c->capture_silent, 0);
    CHECK(rp.first.expected_present);
    CHECK(!rp.first.actual_present);
    CHECK_EQ(rp.first.baud_state, DP_BAUD_SEARCH);
    CHECK_EQ(rp.first.card_baud, 12000000u);
    CHECK_EQ(rp.first.expected.record, 2);
    CHECK_EQ(rp.first.expected.position, 124);
}

static size_t dx_request(uint8_t *out, bool fcb, uint8_t value)
{
    uint8_t o[6] = {0x00, 0x06, 0x05, 0xDC, 0x00, value};
    return enc(out, CARD, MASTER, (uint8_t)(0x5D | (fcb ? 0x20 : 0x00)), false, 0, 0, o, 6);
}

/* A capture that starts in data exchange: the card is in Wait_Prm and answers RS. */
static void test_capture_starting_in_data_exchange(void)
{
    start(true, true);
    uint8_t req[64];
    uint8_t rsp[64];
    uint8_t in[6] = {0x02, 0x07, 0x05, 0xDC, 0x01, 0x54};
    size_t rl = enc(rsp, MASTER, CARD, 0x08, false, 0, 0, in, 6);
    for (unsigned i = 0; i < 3u; i++) {
        size_t n = dx_request(req, (i & 1u) != 0u, (uint8_t)i);
        feed(2000u * i, req, n);
        feed(2000u * i + 120u, rsp, rl);
    }
    replay_finish(&rp);
    const replay_counts_t *c = &rp.svc[REPLAY_SVC_DATA_EXCHANGE];
    CHECK_EQ(c->requests, 3);
    CHECK_EQ(c->differ, 3);
    const replay_mismatch_t *m = &rp.first;
    CHECK(m->valid);
    CHECK_EQ(m->card_state, DP_STATE_WAIT_PRM);
    CHECK(!m->set_prm_seen);
    CHECK_BYTES(m->actual.data, m->actual.len, 0x10, 0x02, 0x04, 0x03, 0x09, 0x16);
    /* The report says why. */
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    replay_report_info_t info = {.file = "mid.pcap", .format = "pcap", .position_unit = "byte"};
    CHECK_EQ(replay_report(&rp, &info, out), 1);
    fclose(out);
    CHECK(strstr(text, "first mismatch: record 1 (byte 24)") != NULL);
    CHECK(strstr(text, "perhaps in the middle of data exchange") != NULL);
    CHECK(strstr(text, "RS (service not activated)") != NULL);
    CHECK(strstr(text, "result: DIFFERENT: 3 of 3 replies differ") != NULL);
    free(text);
    (void)rs_rsp;
}

/* Set_Prm and Chk_Cfg as SD2 with SAP extension octets, then Data_Exchange; Global_Control as
 * SDN to the card's own address (checked: no answer expected) and to 127 (not checked). */
static void test_sap_extension_and_sdn(void)
{
    start(true, true);
    uint8_t f[64];
    size_t n;
    feed(0, diag_req_first, sizeof diag_req_first);
    feed(80, diag_wait_prm, sizeof diag_wait_prm);
    /* Set_Prm: Lock, WD_On 1 x 10 x 10 ms, ident 0x6003, DFP21B user prm. */
    uint8_t prm[16] = {0x88, 0x01, 0x0A, 0x0B, 0x60, 0x03, 0x00};
    memcpy(&prm[7], dfp21b_user_prm_default, 9);
    n = enc(f, CARD, MASTER, 0x5D, true, DP_SAP_SET_PRM, DP_SAP_MASTER, prm, 16);
    feed(400, f, n);
    feed(600, sc, 1);
    uint8_t cfg[2] = {0xF3, 0xF2};
    n = enc(f, CARD, MASTER, 0x7D, true, DP_SAP_CHK_CFG, DP_SAP_MASTER, cfg, 2);
    feed(800, f, n);
    feed(900, sc, 1);
    /* Global_Control Operate to the card itself, then to everybody. */
    uint8_t gc[2] = {0x00, 0x00};
    n = enc(f, CARD, MASTER, 0x46, true, DP_SAP_GLOBAL_CONTROL, DP_SAP_MASTER, gc, 2);
    feed(1200, f, n);
    n = enc(f, 127, MASTER, 0x46, true, DP_SAP_GLOBAL_CONTROL, DP_SAP_MASTER, gc, 2);
    feed(1400, f, n);
    replay_finish(&rp);
    CHECK_EQ(rp.svc[REPLAY_SVC_SET_PRM].requests, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_SET_PRM].matched, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_CHK_CFG].requests, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_CHK_CFG].matched, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_GLOBAL_CONTROL].requests, 1); /* the one to address 4 */
    CHECK_EQ(rp.svc[REPLAY_SVC_GLOBAL_CONTROL].matched, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_GLOBAL_CONTROL].capture_silent, 1);
    CHECK_EQ(rp.svc[REPLAY_SVC_GLOBAL_CONTROL].card_silent, 1);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(dp_slave_state(&rp.card.card.dp), DP_STATE_DATA_EXCH);
}

/* FCB: a request the capture shows unanswered, then the master's repeat (same FCB) with an
 * answer. The card answered the first (a mismatch: not a repeat), the repeat gets the cached
 * reply (a match). Then a repeat that the capture leaves unanswered: its mismatch is marked as
 * a repeat. */
static void test_fcb_repeat(void)
{
    start(true, true);
    uint8_t f[32];
    feed(0, diag_req_first, sizeof diag_req_first);
    feed(80, diag_wait_prm, sizeof diag_wait_prm);
    size_t n = enc(f, CARD, MASTER, 0x5D, true, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, NULL, 0);
    feed(1000, f, n);          /* FCV=1 FCB=0: unanswered in the capture */
    feed(3000, f, n);          /* the retry */
    feed(3080, diag_wait_prm, sizeof diag_wait_prm);
    replay_finish(&rp);
    CHECK_EQ(rp.svc[REPLAY_SVC_SLAVE_DIAG].requests, 3);
    CHECK_EQ(rp.svc[REPLAY_SVC_SLAVE_DIAG].matched, 2);
    CHECK_EQ(rp.svc[REPLAY_SVC_SLAVE_DIAG].differ, 1);
    CHECK_EQ(rp.first.request.record, 3);
    CHECK(!rp.first.fcb_repeat);

    start(true, true);
    feed(0, diag_req_first, sizeof diag_req_first);
    feed(80, diag_wait_prm, sizeof diag_wait_prm);
    feed(1000, f, n);
    feed(1080, diag_wait_prm, sizeof diag_wait_prm);
    feed(3000, f, n); /* repeated, and the capture shows nothing */
    feed(5000, fdl_status_req, sizeof fdl_status_req);
    feed(5051, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.mismatches, 1);
    CHECK_EQ(rp.first.request.record, 5);
    CHECK(rp.first.fcb_repeat);
    CHECK(rp.first.actual_present);
    CHECK_BYTES(rp.first.actual.data, rp.first.actual.len, 0xA2, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16);
}

/* Tokens, a second master, another slave: all go onto the bus; requests of master 3 to the card
 * are checked like master 2's; the other slave's answers are not the card's. */
static void test_tokens_and_two_masters(void)
{
    start(true, true);
    static const uint8_t token_2_3[] = {0xDC, 0x03, 0x02};
    static const uint8_t token_3_2[] = {0xDC, 0x02, 0x03};
    uint8_t f[32];
    feed(0, token_2_3, 3);
    size_t n = enc(f, CARD, 3, 0x49, false, 0, 0, NULL, 0); /* FDL status from master 3 */
    feed(100, f, n);
    uint8_t rsp3[8];
    size_t rn = enc(rsp3, 3, CARD, 0x00, false, 0, 0, NULL, 0);
    feed(151, rsp3, rn);
    n = enc(f, 5, 3, 0x49, false, 0, 0, NULL, 0); /* to another slave, which answers */
    feed(400, f, n);
    uint8_t rsp5[8];
    rn = enc(rsp5, 3, 5, 0x00, false, 0, 0, NULL, 0);
    feed(451, rsp5, rn);
    feed(600, token_3_2, 3);
    feed(700, fdl_status_req, sizeof fdl_status_req);
    feed(751, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.injected, 6);    /* tokens, both requests of master 3, slave 5's answer, req */
    CHECK_EQ(rp.own_answers, 2);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].requests, 2);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 2);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(rp.unsolicited, 0);
}

/* A request record with a bad FCS goes onto the bus as recorded; the card ignores it. */
static void test_damaged_request(void)
{
    start(true, true);
    uint8_t bad[sizeof fdl_status_req];
    memcpy(bad, fdl_status_req, sizeof bad);
    bad[4] ^= 0x01; /* FCS */
    feed(0, bad, sizeof bad);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    feed(1000, fdl_status_req, sizeof fdl_status_req);
    feed(1051, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.damaged_count, 1);
    CHECK_EQ(rp.damaged[0].record, 1);
    CHECK_EQ(rp.damaged[0].position, 24);
    CHECK(rp.damaged[0].problem[0] != '\0');
    CHECK_EQ(rp.mismatches, 1);
    CHECK(rp.first.request_problem[0] != '\0');
    CHECK(!rp.first.actual_present);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 1);
}

/* An unreadable text line (no octets, a problem) between a request and its answer is listed
 * as damaged and changes nothing else. */
static void test_unreadable_line_between(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    static cap_record_t bad;
    memset(&bad, 0, sizeof bad);
    bad.index = ++next_index;
    bad.position = 7;
    snprintf(bad.problem, sizeof bad.problem, "not hex: 'zz'");
    replay_feed(&rp, &bad);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 1);
    CHECK_EQ(rp.damaged_count, 1);
    CHECK_EQ(rp.damaged[0].record, 2);
    CHECK_EQ(rp.damaged[0].position, 7);
    CHECK_STR(rp.damaged[0].problem, "not hex: 'zz'");
    CHECK_EQ(rp.injected, 1);
}

/* Text captures without times: synthetic times keep the card's answers apart. */
static void test_untimed_records(void)
{
    start(true, true);
    feed(UINT64_MAX, fdl_status_req, sizeof fdl_status_req);
    feed(UINT64_MAX, fdl_status_rsp, sizeof fdl_status_rsp);
    feed(UINT64_MAX, diag_req_first, sizeof diag_req_first);
    feed(UINT64_MAX, diag_wait_prm, sizeof diag_wait_prm);
    feed(UINT64_MAX, fdl_status_req, sizeof fdl_status_req);
    feed(UINT64_MAX, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.untimed, 3);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(replay_total_requests(&rp), 3);
    CHECK_EQ(rp.deferred, 0);
    /* The second request starts after the card's 14-octet answer plus 66 bit times. */
    uint64_t answer_ns = 14u * (uint64_t)hal_uart_char_ns(BAUD);
    CHECK(rp.last_inject_ns > 2u * answer_ns);
}

/* The file ends right after a request: its answer is not in the capture, so it is not judged. */
static void test_capture_ending_after_a_request(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    feed(1000, fdl_status_req, sizeof fdl_status_req);
    replay_finish(&rp);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(replay_total_requests(&rp), 1);
    CHECK(rp.tail_unchecked);
    CHECK_EQ(rp.tail_record, 3);
}

/* Telegrams recorded at 12 Mbit/s spacing replayed at 1.5 Mbit/s overlap: they are moved and
 * the report's timing line counts them. */
static void test_rate_that_does_not_fit(void)
{
    start(false, true);
    for (unsigned i = 0; i < 10u; i++) {
        feed(10u * i, fdl_status_req, sizeof fdl_status_req); /* 10 us apart; 44 us long */
    }
    replay_finish(&rp);
    CHECK_EQ(rp.deferred, 9);
    CHECK_EQ(rp.deferred_beyond_resolution, 9);
    CHECK_EQ(rp.first_conflict_record, 2);
    CHECK_EQ(rp.bus.collisions, 0); /* nothing overlapped on the bus */
}

/* Without --check nothing is judged, the records are still replayed. */
static void test_without_check(void)
{
    start(false, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(replay_total_requests(&rp), 0);
    CHECK_EQ(rp.card_tx, 1);
    CHECK_EQ(rp.own_answers, 1);
}

static void scan_feed(replay_scan_t *s, const uint8_t *f, size_t len)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_scan_feed(s, &rec);
}

static void test_scan(void)
{
    replay_scan_t s;
    replay_scan_init(&s);
    uint8_t f[32];
    size_t n;
    scan_feed(&s, fdl_status_req, sizeof fdl_status_req);
    scan_feed(&s, fdl_status_rsp, sizeof fdl_status_rsp); /* 4 answers */
    n = enc(f, 7, MASTER, 0x5D, true, DP_SAP_SET_PRM, DP_SAP_MASTER, (const uint8_t[]){0x88, 1, 1,
            11, 0x60, 0x03, 0}, 7);
    scan_feed(&s, f, n);
    scan_feed(&s, sc, 1);                                 /* 7 answers with SC */
    n = enc(f, 3, MASTER, 0x49, false, 0, 0, NULL, 0);
    scan_feed(&s, f, n);
    n = enc(f, MASTER, 3, 0x20, false, 0, 0, NULL, 0);  /* a master's FDL status reply */
    scan_feed(&s, f, n);
    scan_feed(&s, (const uint8_t[]){0xDC, 0x03, 0x02}, 3);
    uint8_t found[8];
    unsigned k = replay_scan_result(&s, found, 8);
    CHECK_EQ(k, 2);
    CHECK_EQ(found[0], 4);
    CHECK_EQ(found[1], 7);
    CHECK_EQ(s.answers[4], 1);
    CHECK_EQ(s.answers[7], 1);
    CHECK(s.master[2]);
    CHECK(s.master[3]);
    CHECK_EQ(replay_scan_rate(&s), 0); /* no times: nothing to go by */
}

static void scan_timed(replay_scan_t *s, uint64_t t_us, const uint8_t *f, size_t len)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.index = ++next_index;
    rec.has_time = true;
    rec.t_ns = t_us * 1000u;
    rec.len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_scan_feed(s, &rec);
}

/* The lowest rate the recorded timing allows: an answer 6 us after a 6-octet request needs
 * (66 + 11) bits in 7 us (one added for rounding): 11 Mbit/s, so 12M; 52 us: 1.5M. */
static void test_scan_rate(void)
{
    replay_scan_t s;
    replay_scan_init(&s);
    next_index = 0;
    scan_timed(&s, 100, fdl_status_req, sizeof fdl_status_req);
    scan_timed(&s, 106, fdl_status_rsp, sizeof fdl_status_rsp);
    CHECK_EQ(replay_scan_rate(&s), 12000000u);
    CHECK_EQ(s.need_record, 2);
    CHECK_EQ(s.need_bits, 77);
    replay_scan_init(&s);
    scan_timed(&s, 100, fdl_status_req, sizeof fdl_status_req);
    scan_timed(&s, 151, fdl_status_rsp, sizeof fdl_status_rsp);
    scan_timed(&s, 400, fdl_status_req, sizeof fdl_status_req);
    CHECK_EQ(replay_scan_rate(&s), 1500000u);
    /* Telegrams that overlap at any rate: 12M, the highest there is. */
    replay_scan_init(&s);
    scan_timed(&s, 100, fdl_status_req, sizeof fdl_status_req);
    scan_timed(&s, 100, fdl_status_rsp, sizeof fdl_status_rsp);
    CHECK_EQ(replay_scan_rate(&s), 12000000u);
}

static void test_describe(void)
{
    char t[256];
    replay_describe(diag_wait_prm, sizeof diag_wait_prm, NULL, t, sizeof t);
    CHECK_STR(t, "Slave_Diag reply 4 -> 2 (DL): Station_Not_Ready Prm_Req | no master, "
                 "ident 0x6003");
    replay_describe(fdl_status_req, sizeof fdl_status_req, NULL, t, sizeof t);
    CHECK_STR(t, "FDL_Status 2 -> 4 (FDL status request)");
    replay_describe(rs_rsp, sizeof rs_rsp, NULL, t, sizeof t);
    CHECK_STR(t, "reply 4 -> 2: RS (service not activated)");
    static const uint8_t read_neg[] = {0x68, 0x09, 0x09, 0x68, 0x82, 0x84, 0x08, 0x33, 0x33,
                                       0xDE, 0x80, 0xB5, 0x00, 0x87, 0x16};
    replay_describe(read_neg, sizeof read_neg, NULL, t, sizeof t);
    CHECK_STR(t, "MSAC1 reply 4 -> 2 (DL, SAPs 51/51): Read negative: decode 0x80, code 0xB5 "
                 "(access: state conflict), 0x00");
    static const uint8_t ds47_read[] = {0x68, 0x09, 0x09, 0x68, 0x84, 0x82, 0x5D, 0x33, 0x33,
                                        0x5E, 0x00, 0x2F, 0xF0, 0x46, 0x16};
    replay_describe(ds47_read, sizeof ds47_read, NULL, t, sizeof t);
    CHECK_STR(t, "MSAC1 read 2 -> 4 (SRD high FCV=1 FCB=0, SAPs 51/51): Read.req slot 0 index 47 "
                 "length 240");
    replay_frame_t m;
    replay_frame_parse(ds47_read, sizeof ds47_read, &m);
    CHECK_EQ(replay_service_of(&m), REPLAY_SVC_MSAC1_READ);
    replay_describe((const uint8_t[]){0xDC, 0x03, 0x02}, 3, NULL, t, sizeof t);
    CHECK_STR(t, "token 2 -> 3");
    replay_dx_layout_t lay = {.known = true, .param_channel = true};
    static const uint8_t dx_rsp[] = {0x68, 0x11, 0x11, 0x68, 0x02, 0x04, 0x08, 0x71, 0x00, 0x20,
                                     0x7E, 0x00, 0x04, 0x85, 0xA8, 0x04, 0x07, 0x05, 0xDC, 0x01,
                                     0x54, 0x8F, 0x16};
    replay_describe(dx_rsp, sizeof dx_rsp, &lay, t, sizeof t);
    CHECK_STR(t, "reply 4 -> 2 DL: param channel [71 00 20 7E 00 04 85 A8] handshake 1, read "
                 "index 8318 data 0x000485A8; PI 0407 05DC 0154");
    /* A cut record still yields what its header has. */
    replay_frame_parse(dx_rsp, 7, &m);
    CHECK_EQ(m.kind, REPLAY_KIND_RESPONSE);
    CHECK(m.has_header);
    CHECK_EQ(m.sa, 4);
    replay_frame_parse(dx_rsp, 3, &m);
    CHECK_EQ(m.kind, REPLAY_KIND_GARBAGE);
}

int main(void)
{
    RUN_TEST(test_startup_matches);
    RUN_TEST(test_card_answers_unanswered_request);
    RUN_TEST(test_card_silent_during_baud_search);
    RUN_TEST(test_capture_starting_in_data_exchange);
    RUN_TEST(test_sap_extension_and_sdn);
    RUN_TEST(test_fcb_repeat);
    RUN_TEST(test_tokens_and_two_masters);
    RUN_TEST(test_damaged_request);
    RUN_TEST(test_unreadable_line_between);
    RUN_TEST(test_untimed_records);
    RUN_TEST(test_capture_ending_after_a_request);
    RUN_TEST(test_rate_that_does_not_fit);
    RUN_TEST(test_without_check);
    RUN_TEST(test_scan);
    RUN_TEST(test_scan_rate);
    RUN_TEST(test_describe);
    return check_report();
}
