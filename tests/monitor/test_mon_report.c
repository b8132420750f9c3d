/* The monitor's reports (mon_report.h) on a mon_t filled by hand as the core fills it: the JSON
 * document parsed with cJSON (keys, nulls, spans, escaping, the events' window), the JUnit
 * verdicts with their counts and failure texts, mon_report_ok, and the terminal summary. */
#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "monitor/mon_report.h"

#define MS 1000000ull
#define US 1000ull
#define S 1000000000ull

static char text[1u << 19];
static mon_t mon;

static const char *render(int which, const mon_report_info_t *info, const mon_report_opts_t *o)
{
    mon_buf_t b = {text, sizeof text, 0, 0};
    mon_sink_t sink = mon_buf_sink(&b);
    text[0] = '\0';
    if (which == 0) {
        mon_report_json(&mon, info, &sink);
    } else if (which == 1) {
        mon_report_junit(&mon, info, o, &sink);
    } else {
        mon_report_text(&mon, info, &sink);
    }
    CHECK_EQ(b.overflow, 0);
    return text;
}

static void span(mon_span_t *s, uint64_t n, uint64_t min, uint64_t max, uint64_t sum)
{
    *s = (mon_span_t){.n = n, .min_ns = min, .max_ns = max, .sum_ns = sum};
}

static void add_event(mon_event_type_t type, mon_level_t level, unsigned st, unsigned other,
                      uint64_t t_ns, const char *txt)
{
    mon_event_t *e = &mon.events[mon.events_total % MON_EVENTS];
    *e = (mon_event_t){.seq = mon.events_total, .t_ns = t_ns, .type = type, .level = level,
                       .station = (uint8_t)st, .other = (uint8_t)other, .value = 7};
    snprintf(e->text, sizeof e->text, "%s", txt);
    mon.events_total++;
}

static void set(uint8_t *dst, uint8_t *len, const uint8_t *src, size_t n)
{
    memcpy(dst, src, n);
    *len = (uint8_t)n;
}

/* Master 2 alone in its ring; the DFP21B 5 in data exchange (Param + 3 PD, the octets of
 * param_channel.pcap); slave 6 waiting for parameters; slave 7 addressed, never heard. */
static void build(bool timing, uint32_t ttr_bits)
{
    mon_cfg_t cfg = {.baud = 1500000u, .timing = timing, .tsl_bits = 300u, .ttr_bits = ttr_bits};
    mon_init(&mon, &cfg);
    mon.line = (mon_line_t){.telegrams = 1000, .octets = 9000, .tokens = 100, .requests = 450,
                            .answers = 440, .short_acks = 3, .unanswered = 10, .garbled = 1,
                            .busy_ns = 3 * S};
    mon.holder = 2;
    mon_station_t *m = &mon.st[2];
    *m = (mon_station_t){.seen = true, .role = MON_ROLE_ACTIVE, .first_ns = 2 * S,
                         .last_ns = 13 * S, .in_ring = true, .next_station = 2,
                         .fdl_status_known = true, .fdl_status = 0x30, .tokens_sent = 100,
                         .requests_sent = 450, .repeats_sent = 2, .unanswered_sent = 10,
                         .rotations_over_ttr = 4, .master = MON_NO_MASTER};
    span(&m->rotation, 99, 1 * MS, 5 * MS, 198 * MS);

    mon_station_t *s = &mon.st[5];
    *s = (mon_station_t){.seen = true, .addressed = true, .role = MON_ROLE_PASSIVE,
                         .first_ns = S + S / 2, .last_ns = 13 * S, .requests_received = 400,
                         .answers = 399, .missing = 1, .repeats_received = 2, .dp = true,
                         .dp_state = MON_DP_DATA_EXCH, .master = 2, .ident_known = true,
                         .ident = 0x6003, .dx_count = 390, .min_tsdr_bits = 11,
                         .watchdog_ms = 100, .diag_changes = 3, .stat_diag = 1};
    span(&s->tsdr, 399, 10 * US, 20 * US, 399 * 15 * US);
    span(&s->dx_cycle, 389, 1 * MS, 3 * MS, 389 * 2 * MS);
    static const uint8_t prm[] = {0x88, 0x01, 0x0A, 0x0B, 0x60, 0x03, 0x00, 0x00,
                                  0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};
    static const uint8_t cfg_du[] = {0xF3, 0xF2};
    static const uint8_t diag[] = {0x00, 0x0C, 0x00, 0x02, 0x60, 0x03};
    static const uint8_t out[] = {0x71, 0x00, 0x20, 0x6C, 0x00, 0x00, 0x00, 0x00,
                                  0x00, 0x06, 0x05, 0xDC, 0x00, 0x00};
    static const uint8_t in[] = {0x71, 0x00, 0x20, 0x6C, 0x31, 0x1C, 0x72, 0x89,
                                 0x02, 0x02, 0x00, 0x00, 0x00, 0x00};
    set(s->prm, &s->prm_len, prm, sizeof prm);
    set(s->cfg, &s->cfg_len, cfg_du, sizeof cfg_du);
    set(s->diag, &s->diag_len, diag, sizeof diag);
    set(s->outputs, &s->out_len, out, sizeof out);
    set(s->inputs, &s->in_len, in, sizeof in);

    mon_station_t *w = &mon.st[6];
    *w = (mon_station_t){.seen = true, .addressed = true, .role = MON_ROLE_PASSIVE,
                         .first_ns = 3 * S, .last_ns = 12 * S, .requests_received = 40,
                         .answers = 40, .dp = true, .dp_state = MON_DP_WAIT_PRM,
                         .master = MON_NO_MASTER, .ident_known = true, .ident = 0x80E0};
    static const uint8_t diag6[] = {0x02, 0x05, 0x00, 0xFF, 0x80, 0xE0};
    set(w->diag, &w->diag_len, diag6, sizeof diag6);

    mon_station_t *g = &mon.st[7];
    *g = (mon_station_t){.addressed = true, .requests_received = 9, .missing = 9, .dp = true,
                         .master = MON_NO_MASTER};

    add_event(MON_EV_NEW_STATION, MON_LEVEL_INFO, 2, 0, 2 * S, "new station 2 (active)");
    add_event(MON_EV_DX_ENTER, MON_LEVEL_INFO, 5, 2, 2 * S + 500 * MS,
              "slave 5 entered data exchange with master 2");
    add_event(MON_EV_DX_LEAVE, MON_LEVEL_WARN, 6, 2, 12 * S,
              "slave 6 left data exchange: \"Prm_Req\" <diag> & \\ \t");
}

static const mon_report_info_t info = {.source = "/tmp/line/\"port3\"", .t_start_ns = S,
                                       .t_now_ns = 13 * S + S / 2, .last_events = 2};

static cJSON *station(cJSON *doc, int addr)
{
    cJSON *it;
    cJSON_ArrayForEach(it, cJSON_GetObjectItem(doc, "stations"))
    {
        if (cJSON_GetObjectItem(it, "address")->valueint == addr) {
            return it;
        }
    }
    return NULL;
}

static const char *str(cJSON *o, const char *k)
{
    cJSON *v = cJSON_GetObjectItem(o, k);
    return cJSON_IsString(v) ? v->valuestring : "(not a string)";
}

static double num(cJSON *o, const char *k)
{
    cJSON *v = cJSON_GetObjectItem(o, k);
    return cJSON_IsNumber(v) ? v->valuedouble : -1.0;
}

static bool is_null(cJSON *o, const char *k)
{
    return cJSON_IsNull(cJSON_GetObjectItem(o, k));
}

#define CHECK_NUM(actual, expected) CHECK_EQ((long long)((actual)*1000.0 + 0.5), \
                                             (long long)((expected)*1000.0 + 0.5))

static void test_json_monitor_line_ring(void)
{
    build(true, 0u);
    cJSON *doc = cJSON_Parse(render(0, &info, NULL));
    CHECK(doc != NULL);
    if (doc == NULL) {
        return;
    }
    cJSON *mo = cJSON_GetObjectItem(doc, "monitor");
    CHECK_NUM(num(mo, "t_s"), 12.5);
    CHECK_NUM(num(mo, "baud"), 1500000);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(mo, "timing")));
    CHECK_STR(str(mo, "source"), "/tmp/line/\"port3\"");
    CHECK_NUM(num(mo, "tsl_bits"), 300);
    CHECK_NUM(num(mo, "ttr_bits"), 0);
    cJSON *li = cJSON_GetObjectItem(doc, "line");
    CHECK_NUM(num(li, "telegrams"), 1000);
    CHECK_NUM(num(li, "short_acks"), 3);
    CHECK_NUM(num(li, "unanswered"), 10);
    CHECK_NUM(num(li, "load_pct"), 24.0); /* 3 s busy in 12.5 s */
    cJSON *ring = cJSON_GetObjectItem(doc, "ring");
    cJSON *members = cJSON_GetObjectItem(ring, "members");
    CHECK_EQ(cJSON_GetArraySize(members), 1);
    CHECK_EQ(cJSON_GetArrayItem(members, 0)->valueint, 2);
    CHECK_NUM(num(ring, "holder"), 2);
    /* every station seen or addressed, in address order */
    cJSON *sts = cJSON_GetObjectItem(doc, "stations");
    CHECK_EQ(cJSON_GetArraySize(sts), 4);
    CHECK_EQ(cJSON_GetObjectItem(cJSON_GetArrayItem(sts, 3), "address")->valueint, 7);
    cJSON_Delete(doc);
    mon.holder = 255u;
    doc = cJSON_Parse(render(0, &info, NULL));
    CHECK(is_null(cJSON_GetObjectItem(doc, "ring"), "holder"));
    cJSON_Delete(doc);
}

static void test_json_master(void)
{
    build(true, 0u);
    cJSON *doc = cJSON_Parse(render(0, &info, NULL));
    cJSON *m = station(doc, 2);
    CHECK(m != NULL);
    if (m == NULL) {
        cJSON_Delete(doc);
        return;
    }
    CHECK_STR(str(m, "role"), "active");
    CHECK_STR(str(m, "fdl_status"), "in ring");
    CHECK_NUM(num(m, "first_s"), 1.0);
    CHECK_NUM(num(m, "last_s"), 12.0);
    CHECK_NUM(num(m, "next_station"), 2);
    CHECK_NUM(num(m, "tokens_sent"), 100);
    cJSON *rot = cJSON_GetObjectItem(m, "rotation_ms");
    CHECK_NUM(num(rot, "n"), 99);
    CHECK_NUM(num(rot, "min"), 1.0);
    CHECK_NUM(num(rot, "mean"), 2.0);
    CHECK_NUM(num(rot, "max"), 5.0);
    CHECK_NUM(num(m, "requests_sent"), 450);
    CHECK_NUM(num(m, "unanswered_sent"), 10);
    CHECK(is_null(m, "tsdr_us")); /* never answered */
    CHECK(is_null(m, "dp"));
    cJSON_Delete(doc);
}

static void test_json_dfp21b(void)
{
    build(true, 0u);
    cJSON *doc = cJSON_Parse(render(0, &info, NULL));
    cJSON *s = station(doc, 5);
    cJSON *dp = cJSON_GetObjectItem(s, "dp");
    CHECK(dp != NULL);
    if (dp == NULL) {
        cJSON_Delete(doc);
        return;
    }
    CHECK_STR(str(s, "role"), "passive");
    CHECK(is_null(s, "fdl_status"));
    CHECK(is_null(s, "next_station"));
    CHECK_NUM(num(s, "missing"), 1);
    CHECK_NUM(num(s, "repeats_received"), 2);
    cJSON *tsdr = cJSON_GetObjectItem(s, "tsdr_us");
    CHECK_NUM(num(tsdr, "min"), 10.0);
    CHECK_NUM(num(tsdr, "mean"), 15.0);
    CHECK_NUM(num(tsdr, "max"), 20.0);
    CHECK_STR(str(dp, "state"), "Data_Exch");
    CHECK_NUM(num(dp, "master"), 2);
    CHECK_STR(str(dp, "ident"), "0x6003");
    CHECK_STR(str(dp, "prm"), "88010A0B6003000000000681000001" "01");
    CHECK_STR(str(dp, "cfg"), "F3F2");
    CHECK_STR(str(dp, "diag"), "000C00026003");
    CHECK_STR(str(dp, "diag_text"), "WD_On | Master_Add 2, ident 0x6003");
    CHECK_STR(str(dp, "outputs"), "7100206C000000000006" "05DC0000");
    CHECK_NUM(num(dp, "dx_count"), 390);
    CHECK_NUM(num(cJSON_GetObjectItem(dp, "dx_cycle_ms"), "mean"), 2.0);
    /* the running sum: a client's mean between two documents, exact however long the run */
    CHECK_NUM(num(cJSON_GetObjectItem(dp, "dx_cycle_ms"), "sum"), 778.0);
    CHECK_NUM(num(tsdr, "sum"), 15.0 * 399);
    CHECK_NUM(num(dp, "min_tsdr_bits"), 11);
    CHECK_NUM(num(dp, "watchdog_ms"), 100);
    cJSON *d = cJSON_GetObjectItem(dp, "dfp21b");
    CHECK_STR(str(d, "pd_config"), "3PD + PARAM");
    CHECK_NUM(num(d, "pd_words"), 3);
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(d, "param_channel")));
    CHECK_STR(str(d, "control_word"), "0x0006");
    CHECK_STR(str(d, "control_text"), "enable, no rapid stop, no stop");
    CHECK_STR(str(d, "status_word"), "0x0202");
    CHECK_STR(str(d, "param_request"), "read P076 firmware basic unit (8300)");
    CHECK_STR(str(d, "param_answer"), "read P076 firmware basic unit (8300) = 823947913");
    cJSON_Delete(doc);
}

static void test_json_other_slaves(void)
{
    build(false, 0u);
    cJSON *doc = cJSON_Parse(render(0, &info, NULL));
    cJSON *w = station(doc, 6);
    cJSON *dp = cJSON_GetObjectItem(w, "dp");
    CHECK_STR(str(dp, "state"), "Wait_Prm");
    CHECK(is_null(dp, "master"));
    CHECK_STR(str(dp, "ident"), "0x80E0");
    CHECK_STR(str(dp, "prm"), "");
    CHECK_STR(str(dp, "diag_text"), "Station_Not_Ready Prm_Req | no master, ident 0x80E0");
    CHECK(is_null(dp, "dx_cycle_ms"));
    CHECK(is_null(dp, "dfp21b"));
    /* timing false: no TSDR figure even where answers were timed */
    CHECK(is_null(station(doc, 5), "tsdr_us"));
    CHECK(cJSON_IsFalse(cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "monitor"), "timing")));
    cJSON *g = station(doc, 7);
    CHECK(cJSON_IsFalse(cJSON_GetObjectItem(g, "seen")));
    CHECK(cJSON_IsTrue(cJSON_GetObjectItem(g, "addressed")));
    CHECK_STR(str(g, "role"), "unknown");
    CHECK(is_null(g, "first_s"));
    CHECK(is_null(g, "last_s"));
    dp = cJSON_GetObjectItem(g, "dp");
    CHECK_STR(str(dp, "state"), "-");
    CHECK(is_null(dp, "ident"));
    CHECK(is_null(dp, "diag_text"));
    cJSON_Delete(doc);
}

static void test_json_events(void)
{
    build(true, 0u);
    cJSON *doc = cJSON_Parse(render(0, &info, NULL));
    cJSON *ev = cJSON_GetObjectItem(doc, "events");
    CHECK_NUM(num(ev, "total"), 3);
    CHECK_NUM(num(ev, "dropped"), 0);
    cJSON *last = cJSON_GetObjectItem(ev, "last");
    CHECK_EQ(cJSON_GetArraySize(last), 2); /* info.last_events */
    cJSON *e = cJSON_GetArrayItem(last, 1);
    CHECK_NUM(num(e, "seq"), 2);
    CHECK_NUM(num(e, "t_s"), 11.0);
    CHECK_STR(str(e, "level"), "warn");
    CHECK_STR(str(e, "type"), "dx_leave");
    CHECK_NUM(num(e, "station"), 6);
    CHECK_NUM(num(e, "other"), 2);
    CHECK_NUM(num(e, "value"), 7);
    CHECK_STR(str(e, "text"), "slave 6 left data exchange: \"Prm_Req\" <diag> & \\ \t");
    CHECK_NUM(num(cJSON_GetArrayItem(last, 0), "seq"), 1);
    cJSON_Delete(doc);
    /* past the ring's size: the newest are held, the rest counted as dropped */
    while (mon.events_total < MON_EVENTS + 88u) {
        add_event(MON_EV_STAT_DIAG, MON_LEVEL_INFO, 5, 0, 13 * S, "stat diag");
    }
    doc = cJSON_Parse(render(0, &info, NULL));
    ev = cJSON_GetObjectItem(doc, "events");
    CHECK_NUM(num(ev, "total"), MON_EVENTS + 88u);
    CHECK_NUM(num(ev, "dropped"), 88);
    last = cJSON_GetObjectItem(ev, "last");
    CHECK_NUM(num(cJSON_GetArrayItem(last, 1), "seq"), MON_EVENTS + 87u);
    cJSON_Delete(doc);
    /* more asked for than held: the held ones only */
    mon_report_info_t all = info;
    all.last_events = 100000u;
    doc = cJSON_Parse(render(0, &all, NULL));
    last = cJSON_GetObjectItem(cJSON_GetObjectItem(doc, "events"), "last");
    CHECK_EQ(cJSON_GetArraySize(last), (int)MON_EVENTS);
    CHECK_NUM(num(cJSON_GetArrayItem(last, 0), "seq"), 88);
    cJSON_Delete(doc);
}

static unsigned count(const char *hay, const char *needle)
{
    unsigned n = 0;
    for (const char *p = strstr(hay, needle); p != NULL; p = strstr(p + 1, needle)) {
        n++;
    }
    return n;
}

static void test_junit_verdicts(void)
{
    build(true, 0u);
    static const uint8_t expect[] = {5, 9};
    mon_report_opts_t o = {.max_repeats = 1, .max_missing = 0, .expect = expect, .n_expect = 2};
    const char *x = render(1, &info, &o);
    /* 2: rotation (skipped, no TTR); 5, 6, 7 and the expected 9: four cases each */
    CHECK(strstr(x, "<testsuite name=\"dfp-sim monitor\" tests=\"17\" failures=\"6\" "
                    "errors=\"0\" skipped=\"4\" time=\"12.500\">") != NULL);
    CHECK_EQ(count(x, "<testcase "), 17u);
    CHECK_EQ(count(x, "<failure "), 6u);
    CHECK(strstr(x, "<property name=\"source\" value=\"/tmp/line/&quot;port3&quot;\"/>") !=
          NULL);
    CHECK(strstr(x, "name=\"2 token rotation\">\n    <skipped message=\"no TTR given: "
                    "rotations not judged\"/>") != NULL);
    CHECK(strstr(x, "name=\"5 data exchange\"/>") != NULL);
    CHECK(strstr(x, "name=\"5 retries\">\n    <failure message=\"2 repeats received, at most 1 "
                    "allowed\">2 repeats received, at most 1 allowed</failure>") != NULL);
    CHECK(strstr(x, "name=\"5 missing answers\">\n    <failure message=\"1 requests "
                    "unanswered, at most 0 allowed\">") != NULL);
    CHECK(strstr(x, "name=\"5 station delay\"/>") != NULL);
    CHECK(strstr(x, "<failure message=\"slave 6 in Wait_Prm at the end, not Data_Exch\">") !=
          NULL);
    CHECK(strstr(x, "name=\"6 station delay\">\n    <skipped message=\"no answer timed\"/>") !=
          NULL);
    CHECK(strstr(x, "<failure message=\"slave 7 never heard\">") != NULL);
    CHECK(strstr(x, "<failure message=\"9 requests unanswered, at most 0 allowed\">") != NULL);
    CHECK(strstr(x, "<failure message=\"slave 9 never heard\">") != NULL);
    CHECK(strstr(x, "name=\"9 retries\"/>") != NULL);
    CHECK(!mon_report_ok(&mon, &o));
}

static void test_junit_tsdr_and_rotation(void)
{
    build(true, 5000u);
    mon.st[5].tsdr_over_max = 3;
    mon.st[5].max_tsdr_bits = 150;
    mon_report_opts_t o = {.max_repeats = 5, .max_missing = 10};
    const char *x = render(1, &info, &o);
    CHECK(strstr(x, "<failure message=\"4 of 99 rotations over TTR 5000 bit times (longest "
                    "5.000 ms)\">") != NULL);
    CHECK(strstr(x, "<failure message=\"3 answers later than max TSDR 150 bit times, 0 sooner "
                    "than min TSDR 11 bit times (TSDR 10.0..20.0 us)\">") != NULL);
    mon.st[5].tsdr_over_max = 0;
    mon.st[2].rotations_over_ttr = 0;
    mon.st[6].dp_state = MON_DP_DATA_EXCH;
    mon.st[7].dp = false; /* no DP slave, not expected: no case */
    CHECK(mon_report_ok(&mon, &o));
    x = render(1, &info, &o);
    CHECK(strstr(x, "tests=\"9\" failures=\"0\" errors=\"0\" skipped=\"1\"") != NULL);
    CHECK(strstr(x, "name=\"2 token rotation\"/>") != NULL);
    /* without line timing nothing is judged late or early */
    build(false, 0u);
    mon.st[5].tsdr_over_max = 3;
    x = render(1, &info, &o);
    CHECK(strstr(x, "name=\"5 station delay\">\n    <skipped message=\"not measurable: the "
                    "telegram times are not the line&apos;s\"/>") != NULL);
    /* a station expected that is heard but gets no DP service */
    static const uint8_t expect[] = {2};
    o.expect = expect;
    o.n_expect = 1;
    x = render(1, &info, &o);
    CHECK(strstr(x, "<failure message=\"station 2: no DP service to it seen\">") != NULL);
}

static void test_junit_xml_escaping(void)
{
    build(true, 0u);
    mon_report_info_t in = info;
    in.source = "a&b<c>'d'";
    const char *x = render(1, &in, NULL);
    CHECK(strstr(x, "value=\"a&amp;b&lt;c&gt;&apos;d&apos;\"") != NULL);
    CHECK(strstr(x, "a&b") == NULL);
}

static void test_text_summary(void)
{
    build(true, 0u);
    const char *t = render(2, &info, NULL);
    static const char head[] = "monitor /tmp/line/\"port3\": 12.500 s, 1000 telegrams, 100 "
                               "tokens, 1 garbled, 0 illegal, 10 unanswered, 0 lost tokens\n";
    CHECK(strncmp(t, head, sizeof head - 1u) == 0);
    CHECK(strstr(t, "\naddr role    ring DP state  master ident  requests   answers missing "
                    "repeats  TSDR us    DX ms\n") != NULL);
    CHECK(strstr(t, "\n   2 active  ring -              -     -         0         0       0 "
                    "      0        -        -\n") != NULL);
    CHECK(strstr(t, "\n   5 passive -    Data_Exch      2  6003       400       399       1 "
                    "      2     15.0    2.000\n") != NULL);
    CHECK(strstr(t, "\n   7 unknown -    -              -     -         9         0       9 "
                    "      0        -        -\n") != NULL);
    CHECK(strstr(t, "\nevents: 3 (0 no longer held)\n      1.500000 info  slave 5 entered "
                    "data exchange with master 2\n     11.000000 warn  slave 6 left") != NULL);
    CHECK_EQ(count(t, "\n"), 9u);
}

/* A source named in bytes that are no UTF-8 (a Latin-1 file name): JSON and XML must be UTF-8,
 * so such a byte becomes U+FFFD (JSON) or '?' (XML); real UTF-8 goes through as it is. */
static void test_not_utf8(void)
{
    build(true, 0u);
    mon_report_info_t latin1 = info;
    latin1.source = "caf\xe9 \xc3\xa9 \xe2\x82 x";
    const char *j = render(0, &latin1, NULL);
    CHECK(strstr(j, "\"source\":\"caf\\ufffd \xc3\xa9 \\ufffd\\ufffd x\"") != NULL);
    cJSON *doc = cJSON_Parse(j);
    CHECK(doc != NULL);
    cJSON_Delete(doc);
    const char *x = render(1, &latin1, NULL);
    CHECK(strstr(x, "value=\"caf? \xc3\xa9 ?? x\"") != NULL);
}

int main(void)
{
    RUN_TEST(test_json_monitor_line_ring);
    RUN_TEST(test_json_master);
    RUN_TEST(test_json_dfp21b);
    RUN_TEST(test_json_other_slaves);
    RUN_TEST(test_json_events);
    RUN_TEST(test_junit_verdicts);
    RUN_TEST(test_junit_tsdr_and_rotation);
    RUN_TEST(test_junit_xml_escaping);
    RUN_TEST(test_text_summary);
    RUN_TEST(test_not_utf8);
    return check_report();
}
