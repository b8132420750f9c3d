#include "replay/replay.h"

#include <string.h>
#include <time.h>

#include "dp_slave/fdl_wire.h"
#include "sim_hal/host_clock.h"

/* The ring keeps a few more than REPLAY_CONTEXT telegrams: when a request's window closes, the
 * request and the card's answer are the newest entries, and the context lies before them. */
#define RING_SIZE (sizeof(((replay_t *)0)->ring) / sizeof(((replay_t *)0)->ring[0]))

static uint64_t bits_ns(uint32_t baud, uint32_t bits)
{
    return ((uint64_t)bits * 1000000000ull + baud - 1u) / baud;
}

static void keep(replay_kept_t *k, replay_source_t src, uint64_t t, uint64_t record,
                 uint64_t position, const uint8_t *data, size_t len)
{
    k->source = src;
    k->t_ns = t;
    k->record = record;
    k->position = position;
    k->len = len < sizeof k->data ? len : sizeof k->data;
    memcpy(k->data, data, k->len);
}

static void ring_push(replay_t *r, replay_source_t src, uint64_t t, uint64_t record,
                      uint64_t position, const uint8_t *data, size_t len)
{
    if (!r->opt.check) {
        return; /* the context is only for the check report */
    }
    keep(&r->ring[r->ring_next], src, t, record, position, data, len);
    r->ring_next = (unsigned)((r->ring_next + 1u) % RING_SIZE);
    if (r->ring_len < RING_SIZE) {
        r->ring_len++;
    }
}

/* Every telegram any station puts on the replay bus. */
static void bus_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len,
                    bool local, uint32_t baud)
{
    (void)local;
    replay_t *r = ctx;
    replay_telegram_t t = {.t_ns = t_start_ns, .baud = baud, .data = frame, .len = len,
                           .problem = ""};
    if (r->injecting) {
        t.source = REPLAY_FROM_CAPTURE;
        t.record = r->inj_rec->index;
        t.position = r->inj_rec->position;
        t.problem = r->inj_rec->problem;
    } else {
        t.source = REPLAY_FROM_CARD;
        r->card_tx++;
        if (r->pending && !r->pend_actual) {
            r->pend_actual = true;
            keep(&r->pend_actual_rec, REPLAY_FROM_CARD, t_start_ns, 0, 0, frame, len);
        } else {
            r->unsolicited++;
        }
    }
    ring_push(r, t.source, t.t_ns, t.record, t.position, frame, len);
    if (r->opt.on_telegram != NULL) {
        r->opt.on_telegram(r->opt.ctx, &t);
    }
}

static void card_event(void *ctx, const dp_event_t *ev)
{
    replay_t *r = ctx;
    if (r->opt.on_card_event != NULL) {
        r->opt.on_card_event(r->opt.ctx, r->bus.now_ns, ev);
    }
}

bool replay_is_profibus_baud(uint32_t baud)
{
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        if (hal_uart_bauds[i] == baud) {
            return true;
        }
    }
    return false;
}

uint64_t replay_search_cycle_ns(void)
{
    uint64_t ns = 0;
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        ns += (uint64_t)dp_baud_search_dwell_us(hal_uart_bauds[i]) * 1000u;
    }
    return ns;
}

int replay_init(replay_t *r, const replay_options_t *opt, char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    r->opt = *opt;
    if (r->opt.baud == 0u) {
        r->opt.baud = REPLAY_DEFAULT_BAUD;
    }
    if (!replay_is_profibus_baud(r->opt.baud)) {
        /* Character times are only defined for the PROFIBUS rates (hal_uart_char_ns). */
        snprintf(err, errlen, "%u bit/s is not a PROFIBUS rate", r->opt.baud);
        return -1;
    }
    memset(r->last_fc, 0xFF, sizeof r->last_fc);
    r->time_resolution_us = true;
    membus_init(&r->bus);
    membus_set_tap(&r->bus, bus_tap, r);
    hal_uart_t card_uart;
    sim_station_t cs = card_station(&r->card);
    r->card_port = membus_attach(&r->bus, &cs, &card_uart);
    /* The injector is only a UART: it transmits when replay_feed says, and hears nothing. */
    sim_station_t inj = {0};
    r->inj_port = membus_attach(&r->bus, &inj, &r->inj_uart);
    r->inj_baud = r->opt.baud;
    (void)r->inj_uart.ops->set_baud(r->inj_uart.ctx, r->inj_baud);
    card_options_t co = {.address = opt->address,
                         .fixed_baud = opt->fixed_card_baud ? r->opt.baud : 0u,
                         .strict_timing = true,
                         .inverter = opt->inverter,
                         .inverter_delay_us = opt->inverter_delay_us,
                         .event = card_event,
                         .ctx = r,
                         .param_observer = opt->param_observer,
                         .param_observer_ctx = opt->param_observer_ctx};
    return card_station_init(&r->card, &co, card_uart, 0, err, errlen);
}

uint32_t replay_bus_baud(const replay_t *r, const cap_record_t *rec)
{
    /* A rate outside the ten is a reader's or recorder's error: it must not reach the UART
     * model (hal_uart_char_ns), whatever the file says. */
    if (!r->opt.baud_override && replay_is_profibus_baud(rec->baud)) {
        return rec->baud;
    }
    return r->opt.baud;
}

uint64_t replay_capture_ns(const replay_t *r, uint64_t bus_ns)
{
    if (!r->have_anchor) {
        return bus_ns;
    }
    /* Unsigned arithmetic wraps: right also when the first record came after untimed ones. */
    return r->origin_ns + bus_ns + r->cut_ns;
}

static bool stop_requested(const replay_t *r)
{
    return r->opt.stop != NULL && *r->opt.stop != 0;
}

/* --speed real: sleeps until the wall clock reaches bus time t. False when a stop request ended
 * the wait (a signal interrupts the sleep: EINTR). */
static bool wait_wall(const replay_t *r, uint64_t t)
{
    uint64_t due = r->wall_start_ns + t;
    if (due <= host_clock_mono_ns()) {
        return true;
    }
    struct timespec ts = {.tv_sec = (time_t)(due / 1000000000u),
                          .tv_nsec = (long)(due % 1000000000u)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
        if (stop_requested(r)) {
            return false;
        }
    }
    return true;
}

/* Runs the bus to bus time t in slices of REPLAY_SLICE_NS, looking at the stop request between
 * them (the card wakes many times a second during a baud search, so one long run could take
 * minutes); with --speed real the wall clock first catches up with each slice. Returns false,
 * and sets interrupted, when a stop request ended it short of t. */
static bool run_to(replay_t *r, uint64_t t)
{
    while (r->bus.now_ns < t) {
        if (stop_requested(r)) {
            r->interrupted = true;
            return false;
        }
        uint64_t next = t - r->bus.now_ns > REPLAY_SLICE_NS ? r->bus.now_ns + REPLAY_SLICE_NS : t;
        if (r->opt.speed == REPLAY_SPEED_REAL && !wait_wall(r, next)) {
            continue; /* stopped while waiting: the loop's test ends it */
        }
        membus_run_until_ns(&r->bus, next);
    }
    return true;
}

static void close_window(replay_t *r)
{
    if (!r->pending) {
        return;
    }
    r->pending = false;
    replay_counts_t *c = &r->svc[r->pend_service];
    c->requests++;
    if (!r->pend_expected) c->capture_silent++;
    if (!r->pend_actual) c->card_silent++;
    bool same = r->pend_expected == r->pend_actual &&
                (!r->pend_expected ||
                 (r->pend_expected_rec.len == r->pend_actual_rec.len &&
                  memcmp(r->pend_expected_rec.data, r->pend_actual_rec.data,
                         r->pend_actual_rec.len) == 0));
    if (same) {
        c->matched++;
        return;
    }
    c->differ++;
    r->mismatches++;
    if (r->first.valid) {
        return;
    }
    replay_mismatch_t *m = &r->first;
    m->valid = true;
    m->service = r->pend_service;
    m->request = r->pend_request;
    snprintf(m->request_problem, sizeof m->request_problem, "%s", r->pend_request_problem);
    m->expected_present = r->pend_expected;
    m->expected = r->pend_expected_rec;
    snprintf(m->expected_problem, sizeof m->expected_problem, "%s", r->pend_expected_problem);
    m->actual_present = r->pend_actual;
    m->actual = r->pend_actual_rec;
    m->fcb_repeat = r->pend_fcb_repeat;
    m->card_state = r->pend_card_state;
    /* The rate as the request ended: still searching means the card did not take it. */
    m->baud_state = dp_slave_baud_state(&r->card.card.dp);
    m->card_baud = dp_slave_baud(&r->card.card.dp);
    m->set_prm_seen = r->set_prm_seen;
    const dfp21b_t *card = &r->card.card;
    m->layout.known = card->pd.valid;
    m->layout.param_channel = card->pd.param_channel;
    /* The newest ring entries are the request and (if any) the card's answer. */
    unsigned skip = 1u + (r->pend_actual ? 1u : 0u);
    unsigned n = 0;
    if (r->ring_len > skip) {
        n = r->ring_len - skip;
    }
    if (n > REPLAY_CONTEXT) {
        n = REPLAY_CONTEXT;
    }
    for (unsigned i = 0; i < n; i++) {
        unsigned back = skip + n - i; /* 1 = newest */
        unsigned idx = (unsigned)((r->ring_next + RING_SIZE - back) % RING_SIZE);
        m->before[i] = r->ring[idx];
    }
    m->n_before = n;
}

static void note_damage(replay_t *r, const cap_record_t *rec)
{
    if (r->damaged_count < REPLAY_DAMAGED_LISTED) {
        replay_damaged_t *d = &r->damaged[r->damaged_count];
        d->record = rec->index;
        d->position = rec->position;
        snprintf(d->problem, sizeof d->problem, "%s", rec->problem);
    }
    r->damaged_count++;
}

static void anchor_at(replay_t *r, uint64_t capture_ns, uint64_t bus_ns)
{
    if (!r->have_anchor) {
        r->origin_ns = capture_ns - bus_ns;
    }
    r->have_anchor = true;
    r->anchor_capture_ns = capture_ns;
    r->anchor_bus_ns = bus_ns;
}

/* The bus time of a recorded time at or after the anchor (saturating: a gap of centuries must
 * not wrap around to an early time). */
static uint64_t bus_time_of(const replay_t *r, uint64_t capture_ns)
{
    uint64_t d = capture_ns - r->anchor_capture_ns;
    return d > UINT64_MAX - r->anchor_bus_ns ? UINT64_MAX : r->anchor_bus_ns + d;
}

/* How much of an idle gap is simulated before it may be shortened: every one-shot timer the
 * card has runs out by then. From the last telegram: the DP watchdog after at most
 * 255 x 255 x 10 ms = 650.25 s, the baud control after at most twice that (dp_slave never lets
 * the rate go before the watchdog could expire; 1 s without a watchdog), a class-2 connection
 * after at most 65535 x 10 ms = 655.35 s, a MOVILINK service after the inverter's delay or the
 * card's timeout (ML_RESPONSE_TIMEOUT_US). */
static uint64_t settle_ns(const replay_t *r)
{
    uint64_t ns = REPLAY_GAP_SETTLE_NS;
    uint64_t service = ((uint64_t)r->opt.inverter_delay_us + ML_RESPONSE_TIMEOUT_US) * 1000u;
    return service > ns ? service : ns;
}

/* Nothing in the card changes any more with time but its baud search: the rate is lost (or
 * fixed), no watchdog is armed, and the emulated drive stands still (while it turns, the
 * position it reports grows). */
static bool card_at_rest(const replay_t *r)
{
    const dp_slave_t *dp = &r->card.card.dp;
    if (dp_slave_baud_state(dp) == DP_BAUD_CONTROL) {
        return false;
    }
    if (dp->wd_on && dp_slave_state(dp) != DP_STATE_WAIT_PRM) {
        return false;
    }
    if (r->card.inverter == CARD_INVERTER_SIM &&
        (r->card.md.speed_actual_mrpm != 0 || r->card.md.speed_setpoint_mrpm != 0)) {
        return false;
    }
    return true;
}

/* An idle gap longer than settle_ns before the record due at bus time want: it is simulated up
 * to settle_ns, and further until the card is at rest; then whole baud-search cycles are left
 * out (any amount with a fixed rate). The search repeats exactly (dp_slave: each rate's dwell
 * from the moment the last one ended), so the card listens at the same rate with the same time
 * left when the record comes as it would after the whole gap: nothing the record or the card's
 * answer shows can differ. The inverter status the card polls meanwhile (diagnosis alarms) is
 * a read on its own channel and stays the same while the drive is at rest. Returns the bus time
 * for the record; the record becomes the anchor when the gap was shortened. */
static uint64_t shorten_gap(replay_t *r, const cap_record_t *rec, uint64_t want)
{
    if (!run_to(r, r->bus.now_ns + settle_ns(r))) {
        return want;
    }
    while (!card_at_rest(r)) {
        if (want - r->bus.now_ns <= REPLAY_SLICE_NS) {
            r->gaps_turning++;
            return want;
        }
        if (!run_to(r, r->bus.now_ns + REPLAY_SLICE_NS)) {
            return want;
        }
    }
    uint64_t period = dp_slave_baud_state(&r->card.card.dp) == DP_BAUD_SEARCH
                          ? replay_search_cycle_ns()
                          : 1000u; /* fixed rate: keep whole microseconds, the card's clock */
    uint64_t cut = (want - r->bus.now_ns) / period * period;
    if (cut == 0u) {
        return want;
    }
    if (r->gaps_cut == 0u) {
        r->first_cut_record = rec->index;
        r->first_cut_position = rec->position;
    }
    r->gaps_cut++;
    r->cut_ns += cut;
    anchor_at(r, rec->t_ns, want - cut);
    return want - cut;
}

/* When the record goes onto the bus (bus time). Never while the line is busy: a recorded time
 * that would overlap the telegram before it (a rate that does not fit, or timestamps rounded to
 * microseconds at 12 Mbit/s) is moved to the end of that telegram plus the idle the next one
 * needs, and counted. A time earlier than the last timed record's re-anchors: the record goes
 * on as early as the line allows and the records after it keep their recorded spacing from it.
 * Sets interrupted (and returns early) when a stop request came first. */
static uint64_t schedule(replay_t *r, const cap_record_t *rec, const replay_frame_t *m,
                         uint32_t baud)
{
    bool starts_cycle = m->kind == REPLAY_KIND_REQUEST || m->kind == REPLAY_KIND_TOKEN;
    /* Let the card answer the previous telegram first: its reply then occupies the line. */
    if (!run_to(r, r->last_end_ns)) {
        return r->bus.now_ns;
    }
    uint64_t busy = r->bus.line_busy_until_ns > r->last_end_ns ? r->bus.line_busy_until_ns
                                                               : r->last_end_ns;
    if (!rec->has_time) {
        r->untimed++;
        uint32_t gap = starts_cycle ? REPLAY_SYNTH_GAP_REQUEST_BITS : REPLAY_SYNTH_GAP_ANSWER_BITS;
        uint64_t t = busy + (r->injected > 0u ? bits_ns(baud, gap) : 0u);
        return t > r->bus.now_ns ? t : r->bus.now_ns;
    }
    if ((rec->t_ns % 1000u) != 0u) {
        r->time_resolution_us = false;
    }
    uint64_t idle = starts_cycle ? bits_ns(baud, FDL_TSYN_BITS)
                    : (m->kind == REPLAY_KIND_RESPONSE || m->kind == REPLAY_KIND_SC)
                        ? bits_ns(baud, FDL_MIN_TSDR_DEFAULT_BITS)
                        : 0u;
    uint64_t earliest = r->injected > 0u || busy > 0u ? busy + idle : 0u;
    if (!r->have_anchor) {
        /* The first timed record: earlier untimed ones (if any) keep their synthetic times. */
        uint64_t start = r->injected > 0u ? busy + bits_ns(baud, REPLAY_SYNTH_GAP_REQUEST_BITS)
                                          : 0u;
        anchor_at(r, rec->t_ns, start);
    } else if (r->have_last_time && rec->t_ns < r->last_time_ns) {
        /* The time goes back: a difference across it means nothing (and must never be taken
         * unsigned). By less than the spacing of the records before, the record is out of
         * order (merged or buffered recorders): it goes on right after the one before and the
         * records after it keep their recorded times. By more, the clock stepped: the record
         * goes on at the spacing the records before had (on a cyclic bus the best guess the
         * step leaves; right after the one before when there is none) and becomes the anchor,
         * so the records after it keep their spacing from it. */
        uint64_t back = r->last_time_ns - rec->t_ns;
        if (r->backwards == 0u) {
            r->first_back_record = rec->index;
            r->first_back_position = rec->position;
        }
        r->backwards++;
        if (back > r->max_back_ns) {
            r->max_back_ns = back;
        }
        uint64_t soonest = earliest > r->bus.now_ns ? earliest : r->bus.now_ns;
        if (back < r->last_spacing_ns) {
            r->out_of_order++;
            return soonest;
        }
        r->clock_steps++;
        uint64_t paced = r->last_inject_ns + r->last_spacing_ns;
        anchor_at(r, rec->t_ns, paced > soonest ? paced : soonest);
    } else if (r->have_last_time) {
        r->last_spacing_ns = rec->t_ns - r->last_time_ns;
    }
    r->have_last_time = true;
    r->last_time_ns = rec->t_ns;
    uint64_t want = bus_time_of(r, rec->t_ns);
    if (want > r->bus.now_ns && want - r->bus.now_ns > settle_ns(r)) {
        want = shorten_gap(r, rec, want);
        if (r->interrupted) {
            return r->bus.now_ns;
        }
    }
    uint64_t t = want;
    if (t < earliest) {
        uint64_t d = earliest - t;
        r->deferred++;
        if (d > r->max_defer_ns) {
            r->max_defer_ns = d;
        }
        /* Stations time their telegrams in whole microseconds, and a capture may round its
         * timestamps to them: within that, a moved telegram is no conflict. */
        uint64_t tolerance = 1000u + (r->time_resolution_us ? 1000u : 0u);
        if (d > tolerance) {
            if (r->deferred_beyond_resolution == 0u) {
                r->first_conflict_record = rec->index;
                r->first_conflict_position = rec->position;
            }
            r->deferred_beyond_resolution++;
        }
        t = earliest;
    }
    return t > r->bus.now_ns ? t : r->bus.now_ns;
}

static bool is_card_answer(const replay_t *r, const replay_frame_t *m)
{
    if (m->kind == REPLAY_KIND_RESPONSE && m->has_header && m->sa == r->opt.address) {
        return true;
    }
    return m->kind == REPLAY_KIND_SC && r->prev_request_to_card;
}

static void note_rate(replay_t *r, const cap_record_t *rec)
{
    if (rec->baud == 0u) {
        return;
    }
    if (!replay_is_profibus_baud(rec->baud)) {
        if (r->odd_rate_records == 0u) {
            r->first_odd_rate = rec->baud;
        }
        r->odd_rate_records++;
        return;
    }
    if (r->min_baud_seen == 0u || rec->baud < r->min_baud_seen) r->min_baud_seen = rec->baud;
    if (rec->baud > r->max_baud_seen) r->max_baud_seen = rec->baud;
    if (r->opt.baud_override && rec->baud != r->opt.baud) {
        r->rate_overridden++;
    }
}

void replay_feed(replay_t *r, const cap_record_t *rec)
{
    if (!r->started) {
        r->started = true;
        r->wall_start_ns = host_clock_mono_ns();
    }
    if (r->interrupted) {
        return; /* the bus has stopped: nothing more goes on it */
    }
    replay_frame_t m;
    bool on_wire = rec->len > 0u;
    bool own_answer = false;
    uint32_t baud = r->opt.baud;
    uint64_t t = 0;
    if (on_wire) {
        replay_frame_parse(rec->data, rec->len, &m);
        own_answer = is_card_answer(r, &m);
        if (!own_answer) {
            baud = replay_bus_baud(r, rec);
            t = schedule(r, rec, &m, baud);
            if (r->interrupted || !run_to(r, t)) {
                return; /* stopped in the gap before it: the record was not replayed */
            }
        }
    }
    r->records++;
    r->last_index = rec->index;
    r->octets += rec->len;
    if (rec->problem[0] != '\0' || rec->len < rec->orig_len) {
        note_damage(r, rec);
    }
    note_rate(r, rec);
    if (!on_wire) {
        /* A line a text importer could not read: nothing went on the wire. It is listed as
         * damaged and leaves the order of the telegrams around it alone. */
        return;
    }
    if (own_answer) {
        /* The card produces its own answers; the recorded one is what to expect. */
        r->own_answers++;
        if (!r->prev_request_to_card) {
            r->stray_answers++;
        } else if (r->pending && !r->pend_expected) {
            r->pend_expected = true;
            keep(&r->pend_expected_rec, REPLAY_FROM_CAPTURE, 0, rec->index, rec->position,
                 rec->data, rec->len);
            snprintf(r->pend_expected_problem, sizeof r->pend_expected_problem, "%s",
                     rec->problem);
        }
        r->prev_request_to_card = false;
        return;
    }
    close_window(r);
    if (baud != r->inj_baud) {
        r->inj_baud = baud;
        (void)r->inj_uart.ops->set_baud(r->inj_uart.ctx, baud);
    }
    bool to_card = m.kind == REPLAY_KIND_REQUEST && m.has_header && m.da == r->opt.address &&
                   m.da != FDL_ADDR_BROADCAST;
    if (to_card && r->opt.check && rec->len > 0u) {
        r->pending = true;
        r->pend_service = replay_service_of(&m);
        keep(&r->pend_request, REPLAY_FROM_CAPTURE, t, rec->index, rec->position, rec->data,
             rec->len);
        snprintf(r->pend_request_problem, sizeof r->pend_request_problem, "%s", rec->problem);
        r->pend_expected = false;
        r->pend_actual = false;
        r->pend_card_state = dp_slave_state(&r->card.card.dp);
        uint8_t prev = r->last_fc[m.sa];
        r->pend_fcb_repeat = (m.fc & FDL_FC_FCV) != 0u && prev != 0xFFu &&
                             (prev & FDL_FC_FCB) == (m.fc & FDL_FC_FCB) &&
                             (m.fc & FDL_FC_CODE_MASK) != FDL_REQ_FDL_STATUS;
    }
    if (to_card) {
        r->last_fc[m.sa] = m.fc;
        if (replay_service_of(&m) == REPLAY_SVC_SET_PRM) {
            r->set_prm_seen = true;
        }
    }
    r->prev_request_to_card = to_card && replay_expects_answer(&m);
    if (rec->len > 0u) {
        r->injecting = true;
        r->inj_rec = rec;
        (void)r->inj_uart.ops->transmit(r->inj_uart.ctx, rec->data, rec->len,
                                        membus_now_us(&r->bus));
        r->injecting = false;
        r->inj_rec = NULL;
        r->injected++;
    }
    r->last_inject_ns = r->bus.now_ns;
    r->last_end_ns = r->bus.now_ns + (uint64_t)hal_uart_char_ns(baud) * rec->len;
    r->last_record_ns = r->bus.now_ns;
}

void replay_finish(replay_t *r)
{
    if (r->finished) {
        return;
    }
    r->finished = true;
    if (run_to(r, r->last_end_ns)) {
        /* The card has handed its answer to the UART by now; let it go out. */
        uint64_t end = r->bus.line_busy_until_ns > r->bus.now_ns ? r->bus.line_busy_until_ns
                                                                : r->bus.now_ns;
        (void)run_to(r, end + 1000u);
    }
    if (r->interrupted) {
        /* Stopped before the last request's answer was due: it is not judged. */
        r->pending = false;
        return;
    }
    if (r->pending && !r->pend_expected && r->pend_request.record == r->last_index) {
        r->pending = false;
        r->tail_unchecked = true;
        r->tail_service = r->pend_service;
        r->tail_record = r->pend_request.record;
        r->tail_position = r->pend_request.position;
    }
    close_window(r);
}

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

/* The recorded timing bounds the rate from below: a telegram cannot begin before the one before
 * it ended, nor an answer before min TSDR (11 bit times) after its request. Timestamps may be
 * rounded to microseconds: one is added to every gap. A pair whose time goes back (a clock
 * step, a record out of order) bounds nothing: it is counted and left out. */
static void scan_timing(replay_scan_t *s, const cap_record_t *rec, bool answers_prev)
{
    if (replay_is_profibus_baud(rec->baud)) {
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
    s->records++;
    if (rec->len == 0u) {
        return; /* an unreadable text line: nothing was on the wire */
    }
    replay_frame_t m;
    replay_frame_parse(rec->data, rec->len, &m);
    bool was_request = s->prev_request;
    uint8_t da = s->prev_da;
    s->prev_request = false;
    bool answers_prev = was_request && rec->problem[0] == '\0' &&
                        (m.kind == REPLAY_KIND_SC ||
                         (m.kind == REPLAY_KIND_RESPONSE && m.has_header && m.sa == da));
    scan_timing(s, rec, answers_prev);
    if (rec->problem[0] != '\0') {
        return; /* a damaged record says nothing reliable about who is who */
    }
    switch (m.kind) {
    case REPLAY_KIND_REQUEST:
        s->master[m.sa] = true;
        s->prev_request = m.da != FDL_ADDR_BROADCAST && replay_expects_answer(&m);
        s->prev_da = m.da;
        return;
    case REPLAY_KIND_TOKEN:
        if (m.has_header) {
            s->master[m.sa] = true;
            s->master[m.da] = true;
        }
        return;
    case REPLAY_KIND_RESPONSE:
        /* Masters answer FDL status requests with their station type; slaves with 00. */
        if ((m.fc & FDL_FC_STATION_MASK) == 0u) {
            s->answers[m.sa]++;
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
