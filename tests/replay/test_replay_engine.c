/* The replay engine fed record by record, the way a reader hands them over: which records go
 * onto the bus, what counts as the card's recorded answer, how each request is judged (exact
 * octets, counts per service), what the first mismatch keeps, and the edge cases of
 * docs/replay.md: the card answering an unanswered request and the other way round, a capture
 * starting in data exchange, SAP extensions, SDN, FCB repeats, tokens and a second master,
 * damaged records, records without times, a capture that ends after a request, the address
 * scan and timing conflicts; times going back (clock steps, records out of order), long idle
 * gaps (shortened without changing what the card does), rates outside the ten, a stop request
 * in a gap. */
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

/* Bus times at which the capture's records went onto the bus (on_telegram), in order. */
#define MAX_SEEN 64u
static uint64_t seen_ns[MAX_SEEN];
static unsigned seen;

static void on_telegram(void *ctx, const replay_telegram_t *t)
{
    (void)ctx;
    if (t->source == REPLAY_FROM_CAPTURE && seen < MAX_SEEN) {
        seen_ns[seen++] = t->t_ns;
    }
}

static void start_with(const replay_options_t *o)
{
    char err[128];
    CHECK_EQ(replay_init(&rp, o, err, sizeof err), 0);
    next_index = 0;
    seen = 0;
}

static void start(bool check, bool fixed_baud)
{
    replay_options_t o = {.address = CARD, .check = check, .baud = BAUD,
                          .fixed_card_baud = fixed_baud, .inverter = CARD_INVERTER_NONE,
                          .on_telegram = on_telegram};
    start_with(&o);
}

/* One record at t_us (has_time false when t_us is UINT64_MAX), as a reader makes it, with the
 * rate the record carries (0: none). */
static void feed_at_rate(uint64_t t_us, const uint8_t *f, size_t len, uint32_t baud)
{
    static cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.index = ++next_index;
    rec.position = 24u + 100u * (rec.index - 1u);
    rec.has_time = t_us != UINT64_MAX;
    rec.t_ns = rec.has_time ? 1700000000000000000ull + t_us * 1000u : 0u;
    rec.baud = baud;
    rec.len = len;
    rec.orig_len = len;
    memcpy(rec.data, f, len);
    (void)cap_check_telegram(rec.data, rec.len, rec.problem, sizeof rec.problem);
    replay_feed(&rp, &rec);
}

static void feed(uint64_t t_us, const uint8_t *f, size_t len)
{
    feed_at_rate(t_us, f, len, 0);
}

/* The report as text (free it). */
static char *report_text(int *status)
{
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    replay_report_info_t info = {.file = "t.pcap", .format = "pcap", .position_unit = "byte",
                                 .baud_source = "given"};
    *status = replay_report(&rp, &info, out);
    fclose(out);
    return text;
}

static size_t enc(uint8_t *out, uint8_t da, uint8_t sa, uint8_t fc, bool saps, uint8_t dsap,
                  uint8_t ssap, const uint8_t *du, size_t n)
{
    return fdl_encode(out, da, sa, fc, saps, dsap, ssap, du, n);
}

/* Frames used throughout (protocol.md §A1.6 and what the card answers). */
static const uint8_t fdl_status_req[] = {0x10, 0x04, 0x02, 0x49, 0x4F, 0x16};
static const uint8_t fdl_status_rsp[] = {0x10, 0x02, 0x04, 0x00, 0x06, 0x16};
static const uint8_t rs_rsp[] = {0x10, 0x02, 0x04, 0x03, 0x09, 0x16};
static const uint8_t sc[] = {0xE5};
/* Slave_Diag, first request (FCV=0 FCB=1), and the card's Wait_Prm answer (SD2, 8 DU octets). */
static const uint8_t diag_req_first[] = {0x68, 0x05, 0x05, 0x68, 0x84, 0x82, 0x6D, 0x3C, 0x3E,
                                         0xED, 0x16};
static const uint8_t diag_wait_prm[] = {0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84, 0x08, 0x3E, 0x3C,
                                        0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16};

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
    CHECK_EQ(dp_slave_state(&rp.cs->card.dp), DP_STATE_DATA_EXCH);
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
    /* The context: the telegrams before the request, oldest first, the card's answers too. */
    CHECK_EQ(rp.first.n_before, 4);
    CHECK_EQ(rp.first.before[0].record, 1);
    CHECK_EQ(rp.first.before[1].source, REPLAY_FROM_CARD);
    CHECK_EQ(rp.first.before[2].record, 3);
    CHECK_EQ(rp.first.before[3].source, REPLAY_FROM_CARD);
    CHECK(rp.first.actual_present);
    CHECK_BYTES(rp.first.actual.data, rp.first.actual.len, 0x68, 0x0B, 0x0B, 0x68, 0x82, 0x84,
                0x08, 0x3E, 0x3C, 0x02, 0x05, 0x00, 0xFF, 0x60, 0x03, 0xF1, 0x16);
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
    CHECK_EQ(rp.rig.bus.collisions, 0); /* nothing overlapped on the bus */
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
    CHECK_EQ(replay_scan_rate(&s, NULL), 0); /* no times: nothing to go by */
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
    replay_scan_rate_t why;
    CHECK_EQ(replay_scan_rate(&s, &why), 12000000u);
    CHECK_EQ(why.decided.record, 2);
    CHECK_EQ(why.decided.bits, 77);
    CHECK(!why.outlier);
    replay_scan_init(&s);
    scan_timed(&s, 100, fdl_status_req, sizeof fdl_status_req);
    scan_timed(&s, 151, fdl_status_rsp, sizeof fdl_status_rsp);
    scan_timed(&s, 400, fdl_status_req, sizeof fdl_status_req);
    CHECK_EQ(replay_scan_rate(&s, NULL), 1500000u);
    /* Telegrams that overlap at any rate: 12M, the highest there is. */
    replay_scan_init(&s);
    scan_timed(&s, 100, fdl_status_req, sizeof fdl_status_req);
    scan_timed(&s, 100, fdl_status_rsp, sizeof fdl_status_rsp);
    CHECK_EQ(replay_scan_rate(&s, NULL), 12000000u);
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

/* A record stamped a day earlier than the one before (a text capture over midnight) and one
 * 1 us earlier (a pcap): no unsigned difference across the step (which made a gap of 584
 * years), the record goes right after the one before (no spacing known yet) and is the anchor
 * for the rest. */
static void test_time_going_back(void)
{
    start(false, true);
    feed(86399999000ull, fdl_status_req, sizeof fdl_status_req); /* 23:59:59.999 */
    feed(1000, fdl_status_req, sizeof fdl_status_req);           /* 00:00:00.001 */
    feed(3000, fdl_status_req, sizeof fdl_status_req);
    replay_finish(&rp);
    CHECK_EQ(rp.backwards, 1);
    CHECK_EQ(rp.clock_steps, 1);
    CHECK_EQ(rp.out_of_order, 0);
    CHECK_EQ(rp.max_back_ns, 86399998000000ull);
    CHECK_EQ(rp.first_back_record, 2);
    CHECK_EQ(rp.first_back_position, 124);
    CHECK_EQ(rp.deferred, 0);
    CHECK_EQ(seen, 3);
    /* Request 1 takes 6 x 7333 ns; the card's answer (fixed rate) follows, then TSYN. */
    uint64_t answer_end = 44000u + 11u * 1000u * 1000u / 1500u + 6u * 7333u;
    CHECK(seen_ns[1] >= answer_end && seen_ns[1] < answer_end + 30000u);
    CHECK_EQ(seen_ns[2], seen_ns[1] + 2000000u); /* its recorded spacing from the anchor */
    CHECK(rp.rig.bus.now_ns < 10000000u);
    int status;
    char *text = report_text(&status);
    CHECK_EQ(status, 0);
    CHECK(strstr(text, "timing    1 records stamped earlier than the record before (first: "
                       "record 2 (byte 124); at most 86399.998000 s back): 1 clock steps, "
                       "re-anchored") != NULL);
    free(text);

    start(false, true);
    feed(100, fdl_status_req, sizeof fdl_status_req);
    feed(99, fdl_status_req, sizeof fdl_status_req);
    replay_finish(&rp);
    CHECK_EQ(rp.clock_steps, 1);
    CHECK_EQ(seen, 2);
    CHECK(seen_ns[1] < 1000000u);
}

/* A clock step back in a cyclic capture (records 2 ms apart, then 150 ms back): the record after
 * the step goes on at the cycle the records before had, the rest keep their spacing from it.
 * Without re-anchoring every later record was "late" and packed behind the one before. */
static void test_clock_step_keeps_the_pace(void)
{
    start(true, true);
    for (unsigned i = 0; i < 6u; i++) {
        uint64_t t = 2000u * i - (i >= 3u ? 150000u : 0u) + 150000u;
        feed(t, fdl_status_req, sizeof fdl_status_req);
        feed(t + 51u, fdl_status_rsp, sizeof fdl_status_rsp);
    }
    replay_finish(&rp);
    CHECK_EQ(rp.backwards, 1);
    CHECK_EQ(rp.clock_steps, 1);
    CHECK_EQ(rp.first_back_record, 7);
    CHECK_EQ(rp.deferred, 0);
    CHECK_EQ(seen, 6);
    for (unsigned i = 1; i < 6u; i++) {
        CHECK_EQ(seen_ns[i] - seen_ns[i - 1u], 2000000u);
    }
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 6);
    /* Telemetry's clock goes on steadily across the step. */
    CHECK_EQ(replay_capture_ns(&rp, seen_ns[3]), 1700000000000000000ull + 156000000ull);
}

/* A record out of order by less than the spacing before it (10 us back, records 2 ms apart):
 * right after the one before; the anchor stays, so the next records keep their recorded times. */
static void test_record_out_of_order(void)
{
    start(false, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(2000, fdl_status_req, sizeof fdl_status_req);
    feed(4000, fdl_status_req, sizeof fdl_status_req);
    feed(3990, fdl_status_req, sizeof fdl_status_req);
    feed(6000, fdl_status_req, sizeof fdl_status_req);
    replay_finish(&rp);
    CHECK_EQ(rp.backwards, 1);
    CHECK_EQ(rp.out_of_order, 1);
    CHECK_EQ(rp.clock_steps, 0);
    CHECK_EQ(seen, 5);
    CHECK(seen_ns[3] > seen_ns[2] && seen_ns[3] < seen_ns[2] + 200000u);
    CHECK_EQ(seen_ns[4], 6000000u);
    CHECK_EQ(rp.deferred, 0);
}

/* A card searching its rate since power-up (the first request is at 1.5 Mbit/s, it listens at
 * 12 first): it listens at 1.5 Mbit/s from 60 to 80 ms into each search cycle. A request 30 days
 * later in that window is answered, one in the 500 kbit/s window (80..100 ms) is not: the gap
 * is shortened by whole cycles and the card is where a full simulation would have it (checked
 * against the unshortened replay, which took 4.7 s for this gap). */
static void test_long_gap_shortened_exactly(void)
{
    const uint64_t cycle_us = replay_search_cycle_ns() / 1000u;
    CHECK_EQ(cycle_us, 1189754u); /* 5 x 20 ms + the dwells at 187.5k .. 9.6k */
    const uint64_t k = 2178589u;  /* 30 days of cycles */
    const uint64_t offsets[2] = {70000u, 90000u};
    for (unsigned i = 0; i < 2u; i++) {
        start(true, false);
        uint64_t t2 = k * cycle_us + offsets[i];
        feed(0, fdl_status_req, sizeof fdl_status_req);
        feed(t2, fdl_status_req, sizeof fdl_status_req);
        feed(t2 + 51u, fdl_status_rsp, sizeof fdl_status_rsp);
        replay_finish(&rp);
        CHECK_EQ(rp.gaps_cut, 1);
        CHECK_EQ(rp.gaps_turning, 0);
        CHECK_EQ(rp.first_cut_record, 2);
        CHECK_EQ(seen, 2);
        CHECK_EQ(seen_ns[1] + rp.cut_ns, t2 * 1000u);
        CHECK_EQ(rp.cut_ns % (cycle_us * 1000u), 0);
        /* Kept: the settling time and less than a cycle more. */
        CHECK(seen_ns[1] >= REPLAY_GAP_SETTLE_NS);
        CHECK(seen_ns[1] < REPLAY_GAP_SETTLE_NS + cycle_us * 1000u + 2000000000u);
        const replay_counts_t *c = &rp.svc[REPLAY_SVC_FDL_STATUS];
        CHECK_EQ(c->requests, 2);
        CHECK_EQ(c->card_silent, i == 0u ? 1u : 2u);
        CHECK_EQ(rp.card_tx, i == 0u ? 1u : 0u);
        /* The capture's clock is still known after the cut (LCM telemetry uses it). */
        CHECK_EQ(replay_capture_ns(&rp, seen_ns[1]), 1700000000000000000ull + t2 * 1000u);
    }
    int status;
    char *text = report_text(&status);
    CHECK(strstr(text, "timing    1 idle gaps shortened, by ") != NULL);
    CHECK(strstr(text, "whole baud-search cycles of 1.189754 s were left out") != NULL);
    free(text);
    /* A gap of centuries (a pcap's epoch 0 before 2024) ends as quickly. */
    start(false, false);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(UINT64_MAX / 1000u - 1700000000000000000ull / 1000u, fdl_status_req,
         sizeof fdl_status_req);
    replay_finish(&rp);
    CHECK_EQ(rp.gaps_cut, 1);
    CHECK(rp.rig.bus.now_ns < REPLAY_GAP_SETTLE_NS + 10000000000ull);
}

/* With a fixed rate the idle card has nothing periodic: the whole gap beyond the settling
 * time goes, in whole microseconds. */
static void test_long_gap_fixed_rate(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(51, fdl_status_rsp, sizeof fdl_status_rsp);
    feed(3600000000ull, fdl_status_req, sizeof fdl_status_req); /* an hour later */
    feed(3600000051ull, fdl_status_rsp, sizeof fdl_status_rsp);
    replay_finish(&rp);
    CHECK_EQ(rp.gaps_cut, 1);
    CHECK_EQ(rp.mismatches, 0);
    CHECK_EQ(rp.svc[REPLAY_SVC_FDL_STATUS].matched, 2);
    CHECK(seen_ns[1] >= REPLAY_GAP_SETTLE_NS && seen_ns[1] < REPLAY_GAP_SETTLE_NS + 1000000u);
}

/* A gap shorter than the settling time is simulated as recorded. */
static void test_gap_below_settling_kept(void)
{
    start(true, true);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(1000000000ull, fdl_status_req, sizeof fdl_status_req); /* 1000 s */
    replay_finish(&rp);
    CHECK_EQ(rp.gaps_cut, 0);
    CHECK_EQ(seen_ns[1], 1000000000000ull);
}

static volatile int stop_flag;

/* Stands for SIGINT arriving while the bus runs through a gap: the card's baud search steps are
 * the only events there. */
static void stop_after_10_s(void *ctx, uint64_t t_ns, const dp_event_t *ev)
{
    (void)ctx;
    (void)ev;
    if (t_ns >= 10000000000ull) {
        stop_flag = 1;
    }
}

/* A stop request while the bus runs through a long gap ends the run within a slice (the bus ran
 * the whole gap before looking at it): the record after the gap is not put on the bus and the
 * request before it is not judged. */
static void test_stop_in_a_gap(void)
{
    stop_flag = 0;
    replay_options_t o = {.address = CARD, .check = true, .baud = BAUD,
                          .inverter = CARD_INVERTER_NONE, .stop = &stop_flag,
                          .on_telegram = on_telegram, .on_card_event = stop_after_10_s};
    start_with(&o);
    feed(0, fdl_status_req, sizeof fdl_status_req);
    feed(2000, fdl_status_req, sizeof fdl_status_req);
    feed(1000000000ull, fdl_status_req, sizeof fdl_status_req); /* 1000 s later: not reached */
    replay_finish(&rp);
    CHECK(rp.interrupted);
    CHECK_EQ(seen, 2);
    CHECK_EQ(rp.records, 2);
    CHECK(rp.rig.bus.now_ns >= 10000000000ull);
    CHECK(rp.rig.bus.now_ns <= 10000000000ull + REPLAY_SLICE_NS + 1000000000ull);
    CHECK_EQ(replay_total_requests(&rp), 1); /* the second request's window never closed */
}

/* A record's rate: the ten PROFIBUS rates only (anything else goes at the options' rate and is
 * counted), and baud_override puts every record at the options' rate. */
static void test_record_rates(void)
{
    start(false, true);
    feed_at_rate(0, fdl_status_req, sizeof fdl_status_req, 1000000u); /* not a PROFIBUS rate */
    feed_at_rate(1000, fdl_status_req, sizeof fdl_status_req, 0xFFFFFFFFu);
    replay_finish(&rp);
    CHECK_EQ(rp.odd_rate_records, 2);
    CHECK_EQ(rp.first_odd_rate, 1000000u);
    CHECK_EQ(rp.min_baud_seen, 0);
    CHECK_EQ(rp.last_end_ns, seen_ns[1] + 6u * (uint64_t)hal_uart_char_ns(BAUD));
    CHECK_EQ(rp.card_tx, 2); /* at the card's fixed 1.5 Mbit/s */
    int status;
    char *text = report_text(&status);
    CHECK(strstr(text, "note      2 records carry a rate that is not a PROFIBUS rate (first: "
                       "1000000 bit/s): they went onto the bus at 1.5 Mbit/s") != NULL);
    free(text);

    cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.baud = 12000000u;
    CHECK_EQ(replay_bus_baud(&rp, &rec), 12000000u);
    rec.baud = 1000000u;
    CHECK_EQ(replay_bus_baud(&rp, &rec), BAUD);
    replay_options_t o = {.address = CARD, .baud = BAUD, .baud_override = true,
                          .fixed_card_baud = true, .inverter = CARD_INVERTER_NONE,
                          .on_telegram = on_telegram};
    start_with(&o);
    rec.baud = 12000000u;
    CHECK_EQ(replay_bus_baud(&rp, &rec), BAUD);
    feed_at_rate(0, fdl_status_req, sizeof fdl_status_req, 12000000u);
    replay_finish(&rp);
    CHECK_EQ(rp.rate_overridden, 1);
    CHECK_EQ(rp.card_tx, 1); /* it went at 1.5 Mbit/s, the card's rate */
    text = report_text(&status);
    CHECK(strstr(text, "bus       1.5 Mbit/s (given; it overrides the capture's own rate, "
                       "12 Mbit/s, for every record)") != NULL);
    free(text);

    o.baud = 1000000u; /* the engine refuses a rate it has no character time for */
    char err[128];
    CHECK_EQ(replay_init(&rp, &o, err, sizeof err), -1);
    CHECK_STR(err, "1000000 bit/s is not a PROFIBUS rate");
}

/* The first pass: a pair of records whose time goes back bounds nothing (it was taken as a gap
 * of 1 us, which needs 12 Mbit/s); with enough answers, one pair alone needing a rate four
 * times higher than any other is left out; with few, it decides. */
static void test_scan_rate_robust(void)
{
    replay_scan_t s;
    replay_scan_rate_t why;
    replay_scan_init(&s);
    next_index = 0;
    for (unsigned i = 0; i < 3u; i++) {
        scan_timed(&s, 2000u * i, fdl_status_req, sizeof fdl_status_req);
        scan_timed(&s, 2000u * i + 51u, fdl_status_rsp, sizeof fdl_status_rsp);
    }
    scan_timed(&s, 3000, fdl_status_req, sizeof fdl_status_req); /* 1051 us back */
    scan_timed(&s, 3051, fdl_status_rsp, sizeof fdl_status_rsp);
    CHECK_EQ(replay_scan_rate(&s, &why), 1500000u);
    CHECK_EQ(s.backward_pairs, 1);
    CHECK_EQ(s.timed_answers, 4);
    CHECK(!why.outlier);

    /* Ten request/answer pairs at 1.5 Mbit/s pace, and one answer 3 us after its request. */
    replay_scan_init(&s);
    next_index = 0;
    for (unsigned i = 0; i < 10u; i++) {
        scan_timed(&s, 2000u * i, fdl_status_req, sizeof fdl_status_req);
        scan_timed(&s, 2000u * i + (i == 6u ? 3u : 51u), fdl_status_rsp, sizeof fdl_status_rsp);
    }
    CHECK_EQ(replay_scan_rate(&s, &why), 1500000u);
    CHECK(why.outlier);
    CHECK_EQ(why.ignored.record, 14);
    CHECK_EQ(why.ignored.prev_record, 13);
    CHECK_EQ(why.ignored.gap_ns, 3000);
    CHECK_EQ(why.decided.bits, 77);
    CHECK_EQ(why.decided.gap_ns, 51000);

    /* The same with only four pairs: too few to call one an outlier. */
    replay_scan_init(&s);
    next_index = 0;
    for (unsigned i = 0; i < 4u; i++) {
        scan_timed(&s, 2000u * i, fdl_status_req, sizeof fdl_status_req);
        scan_timed(&s, 2000u * i + (i == 2u ? 3u : 51u), fdl_status_rsp, sizeof fdl_status_rsp);
    }
    CHECK_EQ(replay_scan_rate(&s, &why), 12000000u);
    CHECK(!why.outlier);
    CHECK_EQ(why.decided.record, 6);

    /* A rate outside the ten in a record is no recorded rate. */
    replay_scan_init(&s);
    cap_record_t rec;
    memset(&rec, 0, sizeof rec);
    rec.baud = 1000000u;
    rec.len = sizeof fdl_status_req;
    memcpy(rec.data, fdl_status_req, rec.len);
    replay_scan_feed(&s, &rec);
    CHECK_EQ(s.recorded_baud, 0);
    rec.baud = 500000u;
    replay_scan_feed(&s, &rec);
    CHECK_EQ(s.recorded_baud, 500000u);
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
    RUN_TEST(test_time_going_back);
    RUN_TEST(test_clock_step_keeps_the_pace);
    RUN_TEST(test_record_out_of_order);
    RUN_TEST(test_long_gap_shortened_exactly);
    RUN_TEST(test_long_gap_fixed_rate);
    RUN_TEST(test_gap_below_settling_kept);
    RUN_TEST(test_stop_in_a_gap);
    RUN_TEST(test_record_rates);
    RUN_TEST(test_scan_rate_robust);
    return check_report();
}
