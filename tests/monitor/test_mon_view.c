/* The monitor's terminal view (mon_view.h, mon_term.h): the exact lines rendered for a monitor
 * built by hand, the keys moving the selection and scrolling, the panes, tiny and huge screens,
 * the escape-sequence decoder, and the terminal on a real PTY pair (only changed lines are
 * written; the settings come back). "test_mon_view view" runs the renderer's part, "term" the
 * PTY's. */
#include "check.h"
#include "monitor/mon_term.h"
#include "monitor/mon_view.h"

#include <poll.h>
#include <pty.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#define MS(x) ((uint64_t)(x) * 1000000u)
#define S(x) ((uint64_t)(x) * 1000000000u)

static mon_t mon; /* large: not on the stack */
static mon_t mon_big;

/* The rows of the 80-column table for the fixture's two stations. */
static const char heading80[] =
    " ADR ROLE   STATE     MSTR IDENT  DXmean  DXmax TSDRus     REQ   REP  MISS DIAG";
static const char master80[] =
    "   1 master holder       - -           -      -      -     100     0     0    0";
static const char slave80[] =
    "   5 slave  Data_Exch    1 0x6003    2.0    3.0    100     100     0     0    0";

/* A master (1) holding the token and its DP slave (5, ident 0x6003) in data exchange: the
 * figures set by hand, as the core's telegram handling would leave them, so that each column
 * has a known value. */
static void fixture(mon_t *m)
{
    mon_cfg_t cfg = {.baud = 1500000, .timing = true};
    mon_init(m, &cfg);
    m->holder = 1;
    m->line.first_ns = S(1);
    m->line.last_ns = S(60);
    m->line.telegrams = 200;
    mon_station_t *ms = &m->st[1];
    ms->seen = ms->addressed = true;
    ms->role = MON_ROLE_ACTIVE;
    ms->in_ring = true;
    ms->next_station = 1;
    ms->tokens_sent = 50;
    ms->requests_sent = 100;
    ms->first_ns = S(1);
    ms->last_ns = S(60);
    mon_station_t *s = &m->st[5];
    s->seen = s->addressed = true;
    s->role = MON_ROLE_PASSIVE;
    s->dp = true;
    s->dp_state = MON_DP_DATA_EXCH;
    s->master = 1;
    s->ident_known = true;
    s->ident = 0x6003;
    s->first_ns = S(2) + MS(5);
    s->last_ns = S(60);
    s->dx_count = 11;
    s->dx_cycle = (mon_span_t){10, MS(1), MS(3), MS(20)};
    s->tsdr = (mon_span_t){10, 90000, 150000, 1000000};
    s->requests_received = 100;
    s->answers = 100;
    static const uint8_t diag[] = {0x00, 0x0C, 0x00, 0x01, 0x60, 0x03};
    static const uint8_t prm[] = {0x88, 0x01, 0x0B, 0x0B, 0x60, 0x03, 0x00};
    memcpy(s->diag, diag, sizeof diag);
    s->diag_len = sizeof diag;
    memcpy(s->prm, prm, sizeof prm);
    s->prm_len = sizeof prm;
    s->cfg[0] = 0xF3;
    s->cfg[1] = 0xF3;
    s->cfg_len = 2;
}

static void view_init(mon_view_t *v)
{
    memset(v, 0, sizeof *v);
    v->source = "pty /dev/pts/3";
    v->baud = 1500000;
}

/* Line r of a rendered grid without its trailing spaces. */
static char line_text[2048];
static const char *line_of(const char *screen, unsigned cols, unsigned r)
{
    memcpy(line_text, screen + (size_t)r * cols, cols);
    size_t n = cols;
    while (n > 0u && line_text[n - 1u] == ' ') {
        n--;
    }
    line_text[n] = '\0';
    return line_text;
}

static char screen[600u * 320u + 16u];

static void test_header_and_rows(void)
{
    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    mon_view_render(&mon, &v, S(63), screen, 24, 80);
    char want[128];
    snprintf(want, sizeof want, "%-66s%s", "pty /dev/pts/3  1.5 Mbit/s  up 0:01:02",
             "? help  q quit");
    CHECK_STR(line_of(screen, 80, 0), want);
    CHECK_STR(line_of(screen, 80, 1),
              "tel/s -  load -  heard 2  garbled 0  events 0  ring 1  holder 1");
    CHECK_STR(line_of(screen, 80, 2), heading80);
    CHECK_STR(line_of(screen, 80, 3), master80);
    CHECK_STR(line_of(screen, 80, 4), slave80);
    CHECK_STR(line_of(screen, 80, 5), "events, newest first: 0, 0 no longer held (d: details)");
    CHECK_STR(line_of(screen, 80, 6), "no event yet");
    CHECK_STR(line_of(screen, 80, 23), "");
    CHECK_EQ(v.attr[2], MON_ATTR_HEADING);
    CHECK_EQ(v.attr[3], MON_ATTR_SELECTED);
    CHECK_EQ(v.attr[4], MON_ATTR_PLAIN);
    CHECK_EQ(v.attr[5], MON_ATTR_HEADING);

    /* A second later: 1000 telegrams, the line busy half the time. */
    mon.line.telegrams += 1000;
    mon.line.busy_ns += MS(500);
    mon_view_render(&mon, &v, S(64), screen, 24, 80);
    CHECK_STR(line_of(screen, 80, 1),
              "tel/s 1000  load 50.0%  heard 2  garbled 0  events 0  ring 1  holder 1");
    /* A redraw for a key soon after keeps the figures rather than a rate over 10 ms. */
    mon_view_render(&mon, &v, S(64) + MS(10), screen, 24, 80);
    CHECK_STR(line_of(screen, 80, 1),
              "tel/s 1000  load 50.0%  heard 2  garbled 0  events 0  ring 1  holder 1");

    /* Without the line's timing TSDR is "not measurable"; a slave out of data exchange is
     * marked and its row shown as a warning. */
    mon.cfg.timing = false;
    mon.st[5].dp_state = MON_DP_WAIT_PRM;
    mon_view_render(&mon, &v, S(64), screen, 24, 80);
    CHECK_STR(line_of(screen, 80, 4),
              "!  5 slave  Wait_Prm     1 0x6003    2.0    3.0    n/m     100     0     0    0");
    CHECK_EQ(v.attr[4], MON_ATTR_WARNING);
}

/* The core's own figures from telegrams: two masters passing the token show as a ring. */
static void test_from_telegrams(void)
{
    mon_view_t v;
    view_init(&v);
    mon_cfg_t cfg = {.baud = 1500000, .timing = true};
    mon_init(&mon, &cfg);
    uint64_t t = S(1);
    for (unsigned i = 0; i < 20u; i++) {
        const uint8_t token[3] = {0xDC, i % 2u ? 1u : 2u, i % 2u ? 2u : 1u}; /* SD4 DA SA */
        mon_telegram(&mon, token, sizeof token, t, t + 22000u);
        t += MS(1);
    }
    mon_view_render(&mon, &v, t, screen, 24, 80);
    CHECK(strncmp(line_of(screen, 80, 1), "tel/s -  load -  heard 2  garbled 0  events ", 44) ==
          0);
    CHECK(strstr(line_of(screen, 80, 1), "  ring 1,2  holder 1") != NULL);
    CHECK_STR(line_of(screen, 80, 3),
              "   1 master holder       - -           -      -      -       0     0     0    0");
    CHECK_STR(line_of(screen, 80, 4),
              "   2 master in ring      - -           -      -      -       0     0     0    0");
}

static void test_details_pane(void)
{
    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    CHECK_EQ(mon_view_key(&v, '\r'), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(63), screen, 24, 120);
    CHECK_STR(line_of(screen, 120, 5), "station 1: master, holder (e: events)");
    CHECK_STR(line_of(screen, 120, 6), "heard first at 0:00:00.000, last at 0:00:59.000");
    CHECK_STR(line_of(screen, 120, 7),
              "ring: in, next station 1, tokens 50, token repeats 0, rotation min/mean/max "
              "0.0/0.0/0.0 ms, over TTR 0");
    CHECK_EQ(mon_view_key(&v, 'j'), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(63), screen, 24, 120);
    CHECK_EQ(v.selected, 5);
    CHECK_EQ(v.attr[4], MON_ATTR_SELECTED);
    CHECK_EQ(v.attr[3], MON_ATTR_PLAIN);
    CHECK_STR(line_of(screen, 120, 5), "station 5: slave, Data_Exch (e: events)");
    CHECK_STR(line_of(screen, 120, 6), "heard first at 0:00:01.005, last at 0:00:59.000");
    CHECK_STR(line_of(screen, 120, 7), "diag: WD_On | Master_Add 1, ident 0x6003");
    CHECK_STR(line_of(screen, 120, 8), "diag (6): 00 0C 00 01 60 03");
    CHECK_STR(line_of(screen, 120, 9), "DFP21B: 4PD + PARAM");
    CHECK_STR(line_of(screen, 120, 10), "prm (7): 88 01 0B 0B 60 03 00");
    CHECK_STR(line_of(screen, 120, 11), "cfg (2): F3 F3");
    CHECK_STR(line_of(screen, 120, 12), "out (0): -");
    CHECK_STR(line_of(screen, 120, 13), "in (0): -");
    CHECK_STR(line_of(screen, 120, 14),
              "data exchange 11, cycle min/mean/max 1.0/2.0/3.0 ms, diag changes 0, "
              "Stat_Diag 0, watchdog 0 ms");
    CHECK_STR(line_of(screen, 120, 15),
              "TSDR min/mean/max 90/100/150 us (10 answers), below min 0, over max 0, over "
              "slot 0");
    CHECK_STR(line_of(screen, 120, 16),
              "requests sent 0 (repeats 0, unanswered 0), received 100 (repeats 0, missing 0), "
              "answers 100, RS 0, RR 0, UE 0, garbled 0");
    CHECK_EQ(mon_view_key(&v, 'e'), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(63), screen, 24, 120);
    CHECK_STR(line_of(screen, 120, 6), "no event yet");
}

static void add_event(mon_t *m, uint64_t t_ns, mon_level_t level, const char *text)
{
    mon_event_t *ev = &m->events[m->events_total % MON_EVENTS];
    memset(ev, 0, sizeof *ev);
    ev->seq = m->events_total++;
    ev->t_ns = t_ns;
    ev->level = level;
    snprintf(ev->text, sizeof ev->text, "%s", text);
}

static void test_events_pane(void)
{
    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    add_event(&mon, S(1) + MS(1500), MON_LEVEL_INFO, "master 1 entered the ring");
    add_event(&mon, S(3), MON_LEVEL_INFO, "slave 5 entered data exchange with master 1");
    add_event(&mon, S(1) + S(3723) + MS(4), MON_LEVEL_WARN, "slave 5 left data exchange");
    mon_view_render(&mon, &v, S(5000), screen, 24, 80);
    CHECK_STR(line_of(screen, 80, 5), "events, newest first: 3, 0 no longer held (d: details)");
    CHECK_STR(line_of(screen, 80, 6), "1:02:03.004 W slave 5 left data exchange");
    CHECK_STR(line_of(screen, 80, 7),
              "0:00:02.000   slave 5 entered data exchange with master 1");
    CHECK_STR(line_of(screen, 80, 8), "0:00:01.500   master 1 entered the ring");
    CHECK_STR(line_of(screen, 80, 9), "");
    CHECK_EQ(v.attr[6], MON_ATTR_WARNING);
    CHECK_EQ(v.attr[7], MON_ATTR_PLAIN);

    /* 600 events: the ring holds the newest 512; the pane shows the newest that fit. */
    fixture(&mon);
    for (unsigned i = 0; i < 600u; i++) {
        char text[32];
        snprintf(text, sizeof text, "event %u", i);
        add_event(&mon, S(2) + MS(i), i % 2u ? MON_LEVEL_ERROR : MON_LEVEL_INFO, text);
    }
    mon_view_render(&mon, &v, S(5000), screen, 24, 80);
    CHECK_STR(line_of(screen, 80, 1),
              "tel/s -  load -  heard 2  garbled 0  events 600  ring 1  holder 1");
    CHECK_STR(line_of(screen, 80, 5),
              "events, newest first: 600, 88 no longer held (d: details)");
    CHECK_STR(line_of(screen, 80, 6), "0:00:01.599 E event 599");
    CHECK_STR(line_of(screen, 80, 23), "0:00:01.582   event 582");
}

/* 30 slaves at 10..39 on a 10-row screen: 7 rows of the table show. */
static void test_selection_scrolls(void)
{
    mon_view_t v;
    view_init(&v);
    mon_cfg_t cfg = {.baud = 1500000, .timing = true};
    mon_init(&mon, &cfg);
    for (unsigned a = 10; a < 40u; a++) {
        mon.st[a].seen = true;
        mon.st[a].role = MON_ROLE_PASSIVE;
        mon.st[a].requests_received = a;
    }
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.page, 7);
    CHECK_EQ(v.selected, 10);
    CHECK_STR(line_of(screen, 80, 3),
              "  10 slave  -            - -           -      -      -      10     0     0    0");
    CHECK_EQ(v.attr[3], MON_ATTR_SELECTED);
    CHECK_EQ(mon_view_key(&v, MON_KEY_END), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.selected, 39);
    CHECK_EQ(v.top, 23);
    CHECK(strncmp(line_of(screen, 80, 3), "  33 slave", 10) == 0);
    CHECK(strncmp(line_of(screen, 80, 9), "  39 slave", 10) == 0);
    CHECK_EQ(v.attr[9], MON_ATTR_SELECTED);
    CHECK_EQ(v.attr[3], MON_ATTR_PLAIN);
    mon_view_key(&v, MON_KEY_PGUP);
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.selected, 32);
    CHECK_EQ(v.top, 22);
    CHECK_EQ(v.attr[3], MON_ATTR_SELECTED);
    mon_view_key(&v, MON_KEY_HOME);
    mon_view_key(&v, MON_KEY_UP);
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.selected, 10);
    CHECK_EQ(v.top, 0);
    mon_view_key(&v, 'j');
    mon_view_key(&v, 'j');
    mon_view_key(&v, MON_KEY_DOWN);
    mon_view_key(&v, 'k');
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.selected, 12);
    CHECK_EQ(v.attr[5], MON_ATTR_SELECTED);
    /* A station heard for the first time above it keeps the same station selected. */
    mon.st[3].seen = true;
    mon.st[3].role = MON_ROLE_PASSIVE;
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK_EQ(v.selected, 12);
    CHECK_EQ(v.attr[6], MON_ATTR_SELECTED);
    /* The help line takes the last row; Esc closes it; a lone Esc never quits. */
    CHECK_EQ(mon_view_key(&v, '?'), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(2), screen, 10, 80);
    CHECK(strncmp(line_of(screen, 80, 9), "keys: up/down j/k PgUp/PgDn Home/End select", 43) ==
          0);
    CHECK_EQ(v.attr[9], MON_ATTR_HEADING);
    CHECK_EQ(v.page, 6);
    CHECK_EQ(mon_view_key(&v, MON_KEY_ESC), MON_VIEW_CHANGED);
    CHECK_EQ(mon_view_key(&v, MON_KEY_ESC), MON_VIEW_IGNORED);
    CHECK_EQ(mon_view_key(&v, 'x'), MON_VIEW_IGNORED);
    CHECK_EQ(mon_view_key(&v, 'q'), MON_VIEW_QUIT);
    /* the terminal sends no signals while the view is up: Ctrl-C and Ctrl-\ are keys */
    CHECK_EQ(mon_view_key(&v, 0x03), MON_VIEW_QUIT);
    CHECK_EQ(mon_view_key(&v, 0x1c), MON_VIEW_QUIT);
    CHECK_EQ(mon_view_key(&v, 0x1a), MON_VIEW_IGNORED);
}

static void test_pause_freezes(void)
{
    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    mon_view_render(&mon, &v, S(10), screen, 24, 80);
    CHECK_EQ(mon_view_key(&v, 'p'), MON_VIEW_CHANGED);
    mon_view_render(&mon, &v, S(11), screen, 24, 80);
    mon.line.telegrams += 5000;
    mon_view_render(&mon, &v, S(20), screen, 24, 80);
    CHECK(strncmp(line_of(screen, 80, 0), "pty /dev/pts/3  1.5 Mbit/s  up 0:00:10  PAUSED", 46) ==
          0);
    CHECK(strncmp(line_of(screen, 80, 1), "tel/s -  load -", 15) == 0);
    mon_view_key(&v, 'p');
    mon_view_render(&mon, &v, S(21), screen, 24, 80);
    CHECK(strncmp(line_of(screen, 80, 0), "pty /dev/pts/3  1.5 Mbit/s  up 0:00:20  ", 40) == 0);
    CHECK(strncmp(line_of(screen, 80, 1), "tel/s 454  load 0.0%", 20) == 0);
}

/* Sizes from 1x1 to 40x130: each fills exactly rows * cols characters. */
static void size_sweep(const mon_t *m, mon_view_t *v)
{
    unsigned bad = 0;
    for (unsigned rows = 1; rows <= 40u; rows += 3u) {
        for (unsigned cols = 1; cols <= 130u; cols += 7u) {
            memset(screen, '#', sizeof screen);
            mon_view_render(m, v, S(5), screen, rows, cols);
            bad += screen[rows * cols] != '#' || memchr(screen, '#', rows * cols) != NULL;
        }
    }
    CHECK_EQ(bad, 0);
}

/* Nothing heard yet, and a view whose selection is garbage: both panes say so. */
static void test_empty_monitor(void)
{
    mon_view_t v;
    view_init(&v);
    v.source = NULL;
    v.baud = 0;
    mon_cfg_t cfg = {0};
    mon_init(&mon, &cfg);
    v.selected_known = true;
    v.selected = 200;
    mon_view_key(&v, 'd');
    mon_view_render(&mon, &v, S(5), screen, 24, 80);
    char want[128];
    snprintf(want, sizeof want, "%-66s%s", "monitor  rate unknown  up 0:00:00", "? help  q quit");
    CHECK_STR(line_of(screen, 80, 0), want);
    CHECK_STR(line_of(screen, 80, 1),
              "tel/s -  load -  heard 0  garbled 0  events 0  ring -  holder -");
    CHECK_STR(line_of(screen, 80, 3), "    no station heard yet");
    CHECK_STR(line_of(screen, 80, 4), "details (e: events)");
    CHECK_STR(line_of(screen, 80, 5), "no station selected");
    size_sweep(&mon, &v);
}

static void test_tiny_screen(void)
{
    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    memset(screen, '#', sizeof screen);
    mon_view_render(&mon, &v, S(63), screen, 5, 20);
    CHECK_STR(line_of(screen, 20, 0), "pty /dev/pts/3  1.5");
    CHECK_STR(line_of(screen, 20, 1), " ADR ROLE   STATE");
    CHECK_STR(line_of(screen, 20, 2), "   1 master holder");
    CHECK_STR(line_of(screen, 20, 3), "   5 slave  Data_Exc");
    CHECK_STR(line_of(screen, 20, 4), "");
    CHECK_EQ(screen[100], '#'); /* nothing past rows * cols */
    mon_view_key(&v, 'd');
    mon_view_key(&v, '?');
    mon_view_render(&mon, &v, S(63), screen, 5, 20);
    CHECK_STR(line_of(screen, 20, 4), "keys: up/down j/k Pg");
    CHECK_EQ(screen[100], '#');
    memset(screen, '#', sizeof screen);
    mon_view_render(&mon, &v, S(63), screen, 1, 1);
    CHECK_EQ(screen[0], 'p');
    CHECK_EQ(screen[1], '#');
    memset(screen, '#', sizeof screen);
    mon_view_render(&mon, &v, S(63), screen, 2, 3);
    CHECK_STR(line_of(screen, 3, 1), "key");
    CHECK_EQ(screen[6], '#');
}

static void all_stations(mon_t *m)
{
    fixture(m);
    for (unsigned a = 0; a < MON_STATIONS; a++) {
        m->st[a].seen = true;
        m->st[a].role = a < 3u ? MON_ROLE_ACTIVE : MON_ROLE_PASSIVE;
        m->st[a].in_ring = a < 3u;
    }
}

static void test_128_stations(void)
{
    mon_view_t v;
    view_init(&v);
    all_stations(&mon_big);
    memset(screen, '#', sizeof screen);
    mon_view_render(&mon_big, &v, S(63), screen, 200, 300);
    /* 127 stations (127 is broadcast, never a row), the pane below them. */
    CHECK(strncmp(line_of(screen, 300, 3), "   0 master in ring", 19) == 0);
    CHECK(strncmp(line_of(screen, 300, 4), "   1 master holder", 18) == 0);
    CHECK(strncmp(line_of(screen, 300, 129), " 126 slave", 10) == 0);
    CHECK_STR(line_of(screen, 300, 130),
              "events, newest first: 0, 0 no longer held (d: details)");
    CHECK_STR(line_of(screen, 300, 1),
              "tel/s -  load -  heard 128  garbled 0  events 0  ring 0,1,2  holder 1");
    CHECK_EQ(screen[200u * 300u], '#');
    /* On 24 lines the table scrolls to the last station. */
    mon_view_key(&v, MON_KEY_END);
    mon_view_render(&mon_big, &v, S(63), screen, 24, 80);
    CHECK_EQ(v.selected, 126);
    CHECK(strncmp(line_of(screen, 80, 16), " 126 slave", 10) == 0);
    CHECK_EQ(v.attr[16], MON_ATTR_SELECTED);
    CHECK_STR(line_of(screen, 80, 17), "events, newest first: 0, 0 no longer held (d: details)");
    /* Taller than any terminal: lines past MON_VIEW_MAX_ROWS stay blank. */
    mon_view_render(&mon_big, &v, S(63), screen, 600, 10);
    CHECK_STR(line_of(screen, 10, 599), "");
    CHECK_STR(line_of(screen, 10, 0), "pty /dev/p");
    mon_view_key(&v, 'd');
    size_sweep(&mon_big, &v);
    mon_view_key(&v, 'e');
    size_sweep(&mon_big, &v);
}

static void test_keys_decoder(void)
{
    mon_keys_t k;
    memset(&k, 0, sizeof k);
    /* An arrow key split across reads. */
    mon_keys_feed(&k, (const uint8_t *)"\x1b", 1, MS(100));
    CHECK_EQ(mon_keys_next(&k, MS(101)), -1);
    mon_keys_feed(&k, (const uint8_t *)"[", 1, MS(102));
    CHECK_EQ(mon_keys_next(&k, MS(103)), -1);
    mon_keys_feed(&k, (const uint8_t *)"Aj", 2, MS(104));
    CHECK_EQ(mon_keys_next(&k, MS(104)), MON_KEY_UP);
    CHECK_EQ(mon_keys_next(&k, MS(104)), 'j');
    CHECK_EQ(mon_keys_next(&k, MS(104)), -1);
    /* A lone Esc, once nothing follows it. */
    mon_keys_feed(&k, (const uint8_t *)"\x1b", 1, MS(200));
    CHECK_EQ(mon_keys_next(&k, MS(249)), -1);
    CHECK_EQ(mon_keys_next(&k, MS(250)), MON_KEY_ESC);
    CHECK_EQ(mon_keys_next(&k, MS(250)), -1);
    /* The forms terminals send, an unknown one dropped whole, Esc then a key. */
    static const char seq1[] = "\x1bOB\x1b[1;5A\x1b[H\x1b[F\x1b[4~\x1b[5~";
    static const char seq2[] = "\x1b[6~\x1b[15~x\x1bq\x1b[1~";
    mon_keys_feed(&k, (const uint8_t *)seq1, sizeof seq1 - 1u, MS(300));
    static const int want1[] = {MON_KEY_DOWN, MON_KEY_UP,  MON_KEY_HOME,
                                MON_KEY_END,  MON_KEY_END, MON_KEY_PGUP};
    for (unsigned i = 0; i < sizeof want1 / sizeof want1[0]; i++) {
        CHECK_EQ(mon_keys_next(&k, MS(300)), want1[i]);
    }
    mon_keys_feed(&k, (const uint8_t *)seq2, sizeof seq2 - 1u, MS(300));
    static const int want2[] = {MON_KEY_PGDN, 'x', MON_KEY_ESC, 'q', MON_KEY_HOME, -1};
    for (unsigned i = 0; i < sizeof want2 / sizeof want2[0]; i++) {
        CHECK_EQ(mon_keys_next(&k, MS(300)), want2[i]);
    }
    /* A flood is cut at the buffer, never overrun. */
    uint8_t flood[100];
    memset(flood, 'j', sizeof flood);
    mon_keys_feed(&k, flood, sizeof flood, MS(400));
    unsigned n = 0;
    while (mon_keys_next(&k, MS(400)) == 'j') {
        n++;
    }
    CHECK_EQ(n, sizeof k.buf);
}

/* What the terminal wrote, read from the PTY's master side until it is quiet. */
static size_t drain(int fd, char *buf, size_t cap)
{
    size_t n = 0;
    struct pollfd p = {fd, POLLIN, 0};
    while (n < cap - 1u && poll(&p, 1, 200) == 1) {
        ssize_t r = read(fd, buf + n, cap - 1u - n);
        if (r <= 0) {
            break;
        }
        n += (size_t)r;
    }
    buf[n] = '\0';
    return n;
}

static int key_within(mon_term_t *t, unsigned ms)
{
    for (unsigned i = 0; i < ms; i++) {
        int key = mon_term_poll_key(t);
        if (key >= 0) {
            return key;
        }
        usleep(1000);
    }
    return -1;
}

static void test_term_pty(void)
{
    int mfd;
    int sfd;
    struct winsize ws = {.ws_row = 8, .ws_col = 80};
    if (openpty(&mfd, &sfd, NULL, NULL, &ws) != 0) {
        CHECK(!"openpty");
        return;
    }
    struct termios before;
    tcgetattr(sfd, &before);
    static mon_term_t t;
    char err[128] = "";
    CHECK_EQ(mon_term_open(&t, sfd, sfd, err, sizeof err), 0);
    static char out[65536];
    CHECK_EQ(drain(mfd, out, sizeof out), 22);
    CHECK_STR(out, "\x1b[?1049h\x1b[?25l\x1b[0m\x1b[2J");
    struct termios raw;
    tcgetattr(sfd, &raw);
    CHECK_EQ(raw.c_lflag & (ICANON | ECHO), 0);
    /* no signals from the keyboard: SIGQUIT or SIGTSTP would leave the terminal raw */
    CHECK_EQ(raw.c_lflag & ISIG, 0);

    mon_view_t v;
    view_init(&v);
    fixture(&mon);
    mon_term_draw(&t, &mon, &v, S(63));
    size_t n = drain(mfd, out, sizeof out);
    CHECK(strncmp(out, "\x1b[0m\x1b[2J\x1b[1;1Hpty /dev/pts/3", 28) == 0);
    CHECK(strstr(out, "\x1b[4;1H\x1b[0;7m   1 master holder") != NULL);
    CHECK(strstr(out, "\x1b[8;1H") != NULL);
    CHECK_EQ(n, t.bytes_written);

    /* One count changes: only its line is written, whole, where it is. */
    mon.st[5].requests_received++;
    mon_term_draw(&t, &mon, &v, S(63));
    n = drain(mfd, out, sizeof out);
    static const char want[] = "\x1b[5;1H"
                               "   5 slave  Data_Exch    1 0x6003    2.0    3.0    100     101"
                               "     0     0    0 ";
    CHECK_STR(out, want);
    CHECK_EQ(n, sizeof want - 1u);
    /* Nothing changed: nothing written. */
    uint64_t written = t.bytes_written;
    mon_term_draw(&t, &mon, &v, S(63));
    CHECK_EQ(drain(mfd, out, sizeof out), 0);
    CHECK_EQ(t.bytes_written, written);
    /* Paused: the figures stay as they were, whatever the monitor counts meanwhile. */
    mon_view_key(&v, 'p');
    mon_term_draw(&t, &mon, &v, S(63));
    drain(mfd, out, sizeof out);
    CHECK(strstr(out, "PAUSED") != NULL);
    mon.st[5].requests_received += 10;
    mon_term_draw(&t, &mon, &v, S(70));
    CHECK_EQ(drain(mfd, out, sizeof out), 0);
    mon_view_key(&v, 'p');
    mon_term_draw(&t, &mon, &v, S(70));
    drain(mfd, out, sizeof out);
    CHECK(strstr(out, "\x1b[5;1H   5 slave  Data_Exch    1 0x6003    2.0    3.0    100"
                      "     111") != NULL);
    /* A resize is seen at the next draw: all of it again. */
    struct winsize bigger = {.ws_row = 12, .ws_col = 90};
    ioctl(mfd, TIOCSWINSZ, &bigger);
    mon_term_draw(&t, &mon, &v, S(70));
    drain(mfd, out, sizeof out);
    CHECK(strncmp(out, "\x1b[0m\x1b[2J\x1b[1;1H", 14) == 0);
    CHECK(strstr(out, "\x1b[12;1H") != NULL);
    CHECK_EQ(t.rows, 12);
    CHECK_EQ(t.cols, 90);

    /* Keys: an arrow's sequence from the terminal, then a letter. */
    CHECK_EQ(write(mfd, "\x1b[B", 3), 3);
    CHECK_EQ(key_within(&t, 1000), MON_KEY_DOWN);
    CHECK_EQ(write(mfd, "q", 1), 1);
    CHECK_EQ(key_within(&t, 1000), 'q');

    mon_term_close(&t);
    CHECK_STR((drain(mfd, out, sizeof out), out), "\x1b[0m\x1b[?25h\x1b[?1049l");
    struct termios after;
    tcgetattr(sfd, &after);
    CHECK_EQ(after.c_lflag, before.c_lflag);
    CHECK_EQ(after.c_iflag, before.c_iflag);
    CHECK_EQ(after.c_cc[VMIN], before.c_cc[VMIN]);
    CHECK_EQ(after.c_cc[VTIME], before.c_cc[VTIME]);
    mon_term_restore(&t); /* twice: nothing more */
    CHECK_EQ(drain(mfd, out, sizeof out), 0);
    close(sfd);
    close(mfd);

    int p[2];
    CHECK_EQ(pipe(p), 0);
    CHECK_EQ(mon_term_open(&t, p[0], p[1], err, sizeof err), -1);
    CHECK_STR(err, "the terminal view needs a terminal on stdin and stdout");
    mon_term_close(&t);
    close(p[0]);
    close(p[1]);
}

int main(int argc, char **argv)
{
    bool view = argc < 2 || strcmp(argv[1], "view") == 0;
    bool term = argc < 2 || strcmp(argv[1], "term") == 0;
    if (view) {
        RUN_TEST(test_header_and_rows);
        RUN_TEST(test_from_telegrams);
        RUN_TEST(test_details_pane);
        RUN_TEST(test_events_pane);
        RUN_TEST(test_selection_scrolls);
        RUN_TEST(test_pause_freezes);
        RUN_TEST(test_tiny_screen);
        RUN_TEST(test_empty_monitor);
        RUN_TEST(test_128_stations);
        RUN_TEST(test_keys_decoder);
    }
    if (term) {
        RUN_TEST(test_term_pty);
    }
    return check_report();
}
