/* The first pass over a capture (docs/replay.md): which station is the card, and the lowest
 * PROFIBUS rate its recorded timing allows. */
#include <string.h>

#include "dp_slave/fdl_wire.h"
#include "replay/replay.h"

/* ---- first pass: who answers --------------------------------------------------------------- */

void replay_scan_init(replay_scan_t *s)
{
    memset(s, 0, sizeof *s);
}

static void scan_keep_pair(replay_scan_t *s, const replay_scan_pair_t *p)
{
    if (p->need_baud > s->need.need_baud) {
        s->need2 = s->need;
        s->need = *p;
    } else if (p->need_baud > s->need2.need_baud) {
        s->need2 = *p;
    }
}

/* A request to station addr followed by its answer, gap_ns from start to start: at which rates
 * a line could have carried it. On a line the answer begins no earlier than min TSDR after the
 * request's end and (from the DFP21B) no later than its max TSDR; a microsecond of slack either
 * way for rounded timestamps. */
static void line_bounds(replay_scan_t *s, size_t req_len)
{
    s->bounds_len = req_len;
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        uint64_t baud = hal_uart_bauds[i];
        uint64_t req_ns = 11u * (uint64_t)req_len * 1000000000ull / baud;
        uint64_t min_tsdr_ns = FDL_MIN_TSDR_DEFAULT_BITS * 1000000000ull / baud;
        uint64_t max_tsdr_ns = REPLAY_CARD_MAX_TSDR_MIN_BITS * 1000000000ull / baud;
        if (max_tsdr_ns < REPLAY_CARD_MAX_TSDR_NS) {
            max_tsdr_ns = REPLAY_CARD_MAX_TSDR_NS;
        }
        s->early_below[i] = req_ns + min_tsdr_ns;
        s->late_above[i] = req_ns + max_tsdr_ns + 1000u;
    }
}

static void station_pair(replay_scan_t *s, uint8_t addr, uint64_t gap_ns, size_t req_len)
{
    replay_scan_station_t *st = &s->station[addr & 0x7Fu];
    if (st->pairs == 0u || gap_ns < st->min_gap_ns) {
        st->min_gap_ns = gap_ns;
    }
    if (gap_ns > st->max_gap_ns) {
        st->max_gap_ns = gap_ns;
    }
    st->pairs++;
    if (s->bounds_len != req_len) {
        line_bounds(s, req_len); /* requests mostly have the length of the one before */
    }
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        bool early = gap_ns + 1000u < s->early_below[i];
        bool late = gap_ns > s->late_above[i];
        if (early || late) {
            st->off_line[i]++;
        }
    }
}

/* The recorded timing bounds the rate from below: a telegram cannot begin before the one before
 * it ended, nor an answer before min TSDR (11 bit times) after its request. Timestamps may be
 * rounded to microseconds: one is added to every gap. A pair whose time goes back (a clock
 * step, a record out of order) bounds nothing: it is counted and left out. */
static void scan_timing(replay_scan_t *s, const cap_record_t *rec, bool answers_prev,
                        uint8_t answerer)
{
    if (rec->baud != 0u && replay_is_profibus_baud(rec->baud)) {
        s->recorded_baud = rec->baud;
    }
    if (!rec->has_time || rec->problem[0] != '\0') {
        /* Damaged records may be a recorder's artefacts: their timing proves nothing. */
        s->have_prev_time = false;
        return;
    }
    if (s->have_prev_time && rec->t_ns < s->prev_t_ns) {
        s->backward_pairs++;
    } else if (s->have_prev_time) {
        uint64_t bits = 11u * (uint64_t)s->prev_len + (answers_prev ? 11u : 0u);
        uint64_t gap_ns = rec->t_ns - s->prev_t_ns;
        replay_scan_pair_t p = {.need_baud = bits * 1000000000ull / (gap_ns + 1000u),
                                .record = rec->index,
                                .prev_record = s->prev_index,
                                .gap_ns = gap_ns,
                                .bits = (uint32_t)bits};
        scan_keep_pair(s, &p);
        s->timed_pairs++;
        if (answers_prev) {
            s->timed_answers++;
            station_pair(s, answerer, gap_ns, s->prev_len);
        }
    }
    s->have_prev_time = true;
    s->prev_t_ns = rec->t_ns;
    s->prev_len = rec->len;
    s->prev_index = rec->index;
}

/* The lowest PROFIBUS rate of at least need bit/s (12 Mbit/s when even that is too slow), as an
 * index into hal_uart_bauds[] (highest rate first, the order of the baud search). */
static unsigned rate_index(uint64_t need)
{
    unsigned i = HAL_UART_NUM_BAUDS - 1u;
    while (i > 0u && hal_uart_bauds[i] < need) {
        i--;
    }
    return i;
}

uint32_t replay_scan_rate(const replay_scan_t *s, replay_scan_rate_t *why)
{
    replay_scan_rate_t w;
    memset(&w, 0, sizeof w);
    if (s->timed_answers > 0u) {
        unsigned i = rate_index(s->need.need_baud);
        w.decided = s->need;
        /* On a line every request/answer pair needs close to the rate in use, and the rates are
         * at least a factor of 2 apart: a single pair needing two rates more than any other (a
         * factor of 4 or more) is a timestamp gone wrong, not the line. */
        unsigned i2 = rate_index(s->need2.need_baud);
        if (s->timed_answers >= REPLAY_SCAN_OUTLIER_MIN_ANSWERS && i + 2u <= i2) {
            w.outlier = true;
            w.ignored = s->need;
            w.decided = s->need2;
            i = i2;
        }
        w.baud = hal_uart_bauds[i];
    }
    if (why != NULL) {
        *why = w;
    }
    return w.baud;
}

void replay_scan_feed(replay_scan_t *s, const cap_record_t *rec)
{
    if (rec->len == 0u) {
        s->records++;
        return; /* an unreadable text line: nothing was on the wire */
    }
    replay_frame_t m;
    replay_frame_parse(rec->data, rec->len, &m);
    replay_scan_feed_frame(s, rec, &m);
}

void replay_scan_feed_frame(replay_scan_t *s, const cap_record_t *rec, const replay_frame_t *m)
{
    s->records++;
    bool was_request = s->prev_request;
    uint8_t da = s->prev_da;
    s->prev_request = false;
    bool answered = was_request && (m->kind == REPLAY_KIND_SC ||
                                    (m->kind == REPLAY_KIND_RESPONSE && m->has_header &&
                                     m->sa == da));
    if (was_request && s->station[da].first == 1u) {
        s->station[da].first = answered ? 2u : 3u;
    }
    bool answers_prev = answered && rec->problem[0] == '\0';
    scan_timing(s, rec, answers_prev, da);
    if (rec->problem[0] != '\0') {
        return; /* a damaged record says nothing reliable about who is who */
    }
    switch (m->kind) {
    case REPLAY_KIND_REQUEST:
        s->master[m->sa] = true;
        s->prev_request = m->da != FDL_ADDR_BROADCAST && replay_expects_answer(m);
        s->prev_da = m->da;
        if (s->prev_request && s->station[m->da].first == 0u) {
            s->station[m->da].first = 1u;
            s->station[m->da].first_record = rec->index;
        }
        return;
    case REPLAY_KIND_TOKEN:
        if (m->has_header) {
            s->master[m->sa] = true;
            s->master[m->da] = true;
        }
        return;
    case REPLAY_KIND_RESPONSE:
        /* Masters answer FDL status requests with their station type; slaves with 00. */
        if ((m->fc & FDL_FC_STATION_MASK) == 0u) {
            s->answers[m->sa]++;
        }
        return;
    case REPLAY_KIND_SC:
        if (was_request) {
            s->answers[da]++;
        }
        return;
    case REPLAY_KIND_GARBAGE:
        return;
    }
}

unsigned replay_scan_result(const replay_scan_t *s, uint8_t *out, unsigned max)
{
    unsigned n = 0;
    for (unsigned a = 0; a <= 125u; a++) {
        if (s->answers[a] > 0u && !s->master[a]) {
            if (n < max) {
                out[n] = (uint8_t)a;
            }
            n++;
        }
    }
    return n;
}

replay_timing_t replay_scan_timing(const replay_scan_t *s, uint8_t address, uint32_t baud,
                                   replay_scan_timing_t *why)
{
    replay_scan_timing_t w;
    memset(&w, 0, sizeof w);
    w.baud = baud;
    const replay_scan_station_t *st = &s->station[address & 0x7Fu];
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        if (hal_uart_bauds[i] == baud) {
            w.pairs = st->pairs;
            w.off_line = st->off_line[i];
            w.min_gap_ns = st->min_gap_ns;
            w.max_gap_ns = st->max_gap_ns;
        }
    }
    /* A majority, so that a few late answers (a slow recorder's hiccup) do not decide. */
    w.mode = w.pairs > 0u && 2u * w.off_line > w.pairs ? REPLAY_TIMING_RELAXED : REPLAY_TIMING_LINE;
    if (why != NULL) {
        *why = w;
    }
    return w.mode;
}

bool replay_scan_first_answered(const replay_scan_t *s, uint8_t address, uint64_t *record)
{
    const replay_scan_station_t *st = &s->station[address & 0x7Fu];
    if (record != NULL) {
        *record = st->first_record;
    }
    return st->first == 2u;
}
