/* The monitor on a running rig, for the control API: rig_doc (the published document: nothing
 * before the first publication, the newest one whole to readers copying while the loop
 * publishes, a publication skipped while every other buffer is read, a document too large
 * refused), mon_rig on the in-memory bus with the demo's line (card 4, master 2: its events in
 * the rig_ctl ring as kind "bus", its document every MON_RIG_PUBLISH_NS), and the route GET
 * /api/v1/bus: 404 without a monitor, 503 before its first document, then the document as
 * published. */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "check.h"
#include "http/http_server.h"
#include "monitor/mon_rig.h"
#include "rig/rig.h"
#include "rig/rig_ctl.h"
#include "rig/rig_doc.h"

static rig_doc_t doc;  /* 2 MB each: never on a stack */
static rig_t rig;
static rig_ctl_t ctl;
static mon_rig_t live;

/* ---- rig_doc ----------------------------------------------------------------------------- */

static void test_nothing_before_the_first_publication(void)
{
    rig_doc_init(&doc);
    size_t len = 99;
    CHECK(rig_doc_copy(&doc, &len) == NULL);
    CHECK_EQ(len, 0);
    CHECK(rig_doc_publish(&doc, "{\"a\":1}", 7));
    char *c = rig_doc_copy(&doc, &len);
    CHECK_STR(c, "{\"a\":1}");
    CHECK_EQ(len, 7);
    free(c);
}

static void test_skipped_while_every_other_buffer_is_read(void)
{
    rig_doc_init(&doc);
    CHECK(rig_doc_publish(&doc, "first", 5));
    unsigned cur = atomic_load(&doc.current);
    for (unsigned i = 0; i < RIG_DOC_BUFS; i++) { /* three clients copying the others */
        if (i != cur) {
            atomic_fetch_add(&doc.use[i], 1u);
        }
    }
    CHECK(!rig_doc_publish(&doc, "second", 6));
    CHECK_EQ(doc.skipped, 1);
    size_t len;
    char *c = rig_doc_copy(&doc, &len);
    CHECK_STR(c, "first");
    free(c);
    for (unsigned i = 0; i < RIG_DOC_BUFS; i++) {
        if (i != cur) {
            atomic_fetch_sub(&doc.use[i], 1u);
        }
    }
    CHECK(rig_doc_publish(&doc, "second", 6));
    c = rig_doc_copy(&doc, &len);
    CHECK_STR(c, "second");
    free(c);
}

static void test_too_large_and_abandoned_keep_the_last(void)
{
    rig_doc_init(&doc);
    CHECK(rig_doc_publish(&doc, "kept", 4));
    static char big[RIG_DOC_CAP + 1u];
    memset(big, 'x', sizeof big);
    CHECK(!rig_doc_publish(&doc, big, sizeof big));
    CHECK(rig_doc_publish(&doc, big, RIG_DOC_CAP)); /* exactly the capacity fits */
    CHECK(rig_doc_publish(&doc, "kept", 4));
    char *b = rig_doc_begin(&doc);
    CHECK(b != NULL);
    if (b != NULL) {
        memcpy(b, "cut", 3);
        rig_doc_abandon(&doc);
    }
    CHECK_EQ(doc.too_large, 1);
    size_t len;
    char *c = rig_doc_copy(&doc, &len);
    CHECK_STR(c, "kept");
    free(c);
}

/* Document k: its number in 8 digits, then a filler letter of k up to a length of k. */
static size_t doc_len(unsigned k)
{
    return 8u + (k * 7919u) % 20000u;
}

static atomic_bool writer_done;
static atomic_uint torn;
static atomic_uint copies;

static void *doc_reader(void *arg)
{
    (void)arg;
    while (!atomic_load(&writer_done)) {
        size_t len;
        char *c = rig_doc_copy(&doc, &len);
        if (c == NULL) {
            continue;
        }
        unsigned k = (unsigned)strtoul((char[9]){c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7],
                                                 0},
                                       NULL, 10);
        bool whole = len == doc_len(k);
        for (size_t i = 8; whole && i < len; i++) {
            whole = c[i] == (char)('a' + k % 26u);
        }
        if (!whole) {
            atomic_fetch_add(&torn, 1u);
        }
        atomic_fetch_add(&copies, 1u);
        free(c);
    }
    return NULL;
}

static void test_readers_copy_whole_documents(void)
{
    rig_doc_init(&doc);
    static char text[RIG_DOC_CAP];
    atomic_store(&writer_done, false);
    atomic_store(&torn, 0u);
    atomic_store(&copies, 0u);
    pthread_t r[3];
    for (unsigned i = 0; i < 3u; i++) {
        CHECK_EQ(pthread_create(&r[i], NULL, doc_reader, NULL), 0);
    }
    unsigned published = 0;
    /* At least 20000 documents, and on until the readers have copied some (a loaded machine
     * may start them late); bounded, so a reader that never copies fails the check below. */
    unsigned k = 0;
    for (; k < 2000000u && (k < 20000u || atomic_load(&copies) < 300u); k++) {
        size_t n = doc_len(k);
        (void)snprintf(text, 9, "%08u", k);
        memset(text + 8, 'a' + (int)(k % 26u), n - 8u);
        published += rig_doc_publish(&doc, text, n) ? 1u : 0u;
    }
    atomic_store(&writer_done, true);
    for (unsigned i = 0; i < 3u; i++) {
        pthread_join(r[i], NULL);
    }
    CHECK_EQ(atomic_load(&torn), 0u);
    CHECK(atomic_load(&copies) >= 300u);
    CHECK_EQ(published + doc.skipped, k);
}

/* ---- mon_rig on the demo's line ----------------------------------------------------------- */

static void line_setup(void)
{
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .baud = 1500000u};
    rig_init(&rig, &rc);
    char err[128];
    CHECK_EQ(rig_open(&rig, err, sizeof err), 0);
    CHECK_EQ(rig_ctl_init(&ctl, &rig, "demo", false), 0);
}

static bool bus_event(const char *source, const char *needle)
{
    static rig_ctl_event_t ev[RIG_CTL_EVENTS];
    uint64_t lost;
    size_t n = rig_ctl_events(&ctl, 0, ev, RIG_CTL_EVENTS, &lost);
    for (size_t i = 0; i < n; i++) {
        if (strcmp(ev[i].kind, "bus") == 0 && strcmp(ev[i].source, source) == 0 &&
            strstr(ev[i].text, needle) != NULL) {
            return true;
        }
    }
    return false;
}

static void test_mon_rig_logs_and_publishes(void)
{
    line_setup();
    mon_cfg_t cfg = {.baud = 1500000u, .timing = true};
    mon_rig_init(&live, &ctl, &cfg, "in-memory bus", rig_elapsed_ns(&rig));
    CHECK(ctl.bus == &live.doc);
    rig_tap_t tap = mon_rig_tap(&live);
    CHECK_EQ(rig_add_tap(&rig, &tap), 0);
    card_options_t co = {.address = 4, .strict_timing = true, .inverter = CARD_INVERTER_SIM};
    CHECK(rig_add_card(&rig, &co, membus_now_us(&rig.bus)) != NULL);
    dp_master_cfg_t mc = {.address = 2, .baud = 1500000u, .strict_timing = true,
                          .cycle_us = 2000, .token_ring = true};
    dp_master_t *m = rig_add_master(&rig, &mc, membus_now_us(&rig.bus));
    dp_master_slave_cfg_t sc = {.address = 4, .cfg_len = 2, .cfg = {0xF3, 0xF2}};
    static const uint8_t user[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x00};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, 0x6003, 100, user, sizeof user);
    CHECK(dp_master_add_slave(m, &sc) >= 0);
    size_t len;
    CHECK(rig_doc_copy(&live.doc, &len) == NULL); /* nothing until the first service */
    /* The start-up (the card's DFP21B user parameters: 9 octets), in 1 ms turns of the loop (at
     * most 3 s) */
    for (unsigned i = 0; i < 3000u && live.mon.st[4].dp_state != MON_DP_DATA_EXCH; i++) {
        membus_run_for_us(&rig.bus, 1000u);
        mon_rig_service(&live, rig_elapsed_ns(&rig));
    }
    /* On to the first publication, the bus running meanwhile: the monitor's clock must not
     * run ahead of the line (a slave whose master seems silent past its watchdog leaves). */
    for (uint64_t t0 = rig_elapsed_ns(&rig); rig_elapsed_ns(&rig) - t0 <= MON_RIG_PUBLISH_NS;) {
        membus_run_for_us(&rig.bus, 1000u);
        mon_rig_service(&live, rig_elapsed_ns(&rig));
    }
    CHECK_EQ(live.mon.st[4].dp_state, MON_DP_DATA_EXCH);
    CHECK(bus_event("station 4", "data exchange"));
    CHECK(bus_event("station 2", "station 2"));
    char *c = rig_doc_copy(&live.doc, &len);
    CHECK(c != NULL && len > 0u && c[0] == '{');
    CHECK(c != NULL && strstr(c, "0x6003") != NULL);
    free(c);
    /* One document per MON_RIG_PUBLISH_NS: none more before it is over, one once it is. */
    unsigned cur = atomic_load(&live.doc.current);
    uint64_t t = live.last_publish_ns;
    mon_rig_service(&live, t + MON_RIG_PUBLISH_NS - 1u);
    CHECK_EQ(atomic_load(&live.doc.current), cur);
    mon_rig_service(&live, t + MON_RIG_PUBLISH_NS);
    CHECK(atomic_load(&live.doc.current) != cur);
    rig_ctl_destroy(&ctl);
    rig_close(&rig);
}

/* A station sending an illegal telegram (SA 127) a hundred times in a second: the log takes
 * MON_RIG_EVENTS_PER_S of them and one line for the rest; the monitor counts all. */
static void test_an_event_flood_is_bounded_in_the_log(void)
{
    line_setup();
    mon_cfg_t cfg = {.baud = 1500000u, .timing = true};
    uint64_t t = rig_elapsed_ns(&rig) + 5000000000ull;
    mon_rig_init(&live, &ctl, &cfg, "in-memory bus", t);
    rig_tap_t tap = mon_rig_tap(&live);
    static const uint8_t sa127[] = {0x10, 0x02, 0x7F, 0x49, 0xCA, 0x16};
    uint64_t before = rig_ctl_next_seq(&ctl);
    for (unsigned i = 0; i < 100u; i++) {
        tap.frame(tap.ctx, t + i * 1000000ull, sa127, sizeof sa127, false, 1500000u);
    }
    CHECK_EQ(live.mon.line.illegal, 100);
    CHECK_EQ(rig_ctl_next_seq(&ctl) - before, MON_RIG_EVENTS_PER_S);
    mon_rig_service(&live, t + 999000000ull); /* the second is not over */
    CHECK_EQ(rig_ctl_next_seq(&ctl) - before, MON_RIG_EVENTS_PER_S);
    mon_rig_service(&live, t + 1000000000ull);
    CHECK_EQ(rig_ctl_next_seq(&ctl) - before, MON_RIG_EVENTS_PER_S + 1u);
    CHECK(bus_event("sim", "80 more bus events in one second not logged (over 20); GET "
                           "/api/v1/bus has the monitor's counts"));
    tap.frame(tap.ctx, t + 1100000000ull, sa127, sizeof sa127, false, 1500000u);
    CHECK_EQ(rig_ctl_next_seq(&ctl) - before, MON_RIG_EVENTS_PER_S + 2u); /* a new second */
    rig_ctl_destroy(&ctl);
    rig_close(&rig);
}

/* ---- the route ---------------------------------------------------------------------------- */

/* "STATUS BODY" of GET /api/v1/bus (HTTP/1.0: the server closes after the answer). */
static void get_bus(uint16_t port, char *out, size_t n)
{
    static char raw[1u << 20];
    out[0] = '\0';
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons(port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        snprintf(out, n, "no connection");
        if (fd >= 0) {
            close(fd);
        }
        return;
    }
    const char req[] = "GET /api/v1/bus HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
    CHECK_EQ(write(fd, req, sizeof req - 1u), (long long)(sizeof req - 1u));
    size_t got = 0;
    ssize_t k;
    while (got + 1u < sizeof raw && (k = read(fd, raw + got, sizeof raw - 1u - got)) > 0) {
        got += (size_t)k;
    }
    raw[got] = '\0';
    close(fd);
    const char *body = strstr(raw, "\r\n\r\n");
    snprintf(out, n, "%.3s %s", raw + 9, body != NULL ? body + 4 : "");
}

static void test_route(void)
{
    line_setup();
    http_config_t hc = {.listen = "127.0.0.1:0", .no_auth = true};
    char err[200];
    http_server_t *srv = http_server_start(&ctl, &hc, err, sizeof err);
    CHECK(srv != NULL);
    if (srv == NULL) {
        fprintf(stderr, "%s\n", err);
        return;
    }
    static char got[1u << 20];
    get_bus(http_server_port(srv), got, sizeof got);
    CHECK_STR(got, "404 {\"error\":\"this process has no bus monitor\"}");
    http_server_stop(srv);
    /* with a document that nobody has published yet, then published */
    rig_doc_init(&doc);
    ctl.bus = &doc;
    srv = http_server_start(&ctl, &hc, err, sizeof err);
    CHECK(srv != NULL);
    if (srv != NULL) {
        get_bus(http_server_port(srv), got, sizeof got);
        CHECK_STR(got, "503 {\"error\":\"the bus monitor has published nothing yet; try "
                       "again\"}");
        CHECK(rig_doc_publish(&doc, "{\"stations\":[]}", 15));
        get_bus(http_server_port(srv), got, sizeof got);
        CHECK_STR(got, "200 {\"stations\":[]}");
        http_server_stop(srv);
    }
    rig_ctl_destroy(&ctl);
    rig_close(&rig);
}

int main(void)
{
    RUN_TEST(test_nothing_before_the_first_publication);
    RUN_TEST(test_skipped_while_every_other_buffer_is_read);
    RUN_TEST(test_too_large_and_abandoned_keep_the_last);
    RUN_TEST(test_readers_copy_whole_documents);
    RUN_TEST(test_mon_rig_logs_and_publishes);
    RUN_TEST(test_an_event_flood_is_bounded_in_the_log);
    RUN_TEST(test_route);
    return check_report();
}
