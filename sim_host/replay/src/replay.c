#include "replay/replay.h"

#include <string.h>
#include <time.h>

#include "dp_slave/fdl_wire.h"
#include "sim_hal/host_clock.h"

#include "judge.h"


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

/* A problem text kept with a pending telegram; nearly always empty, and kept twice per cycle
 * (snprintf's formatting was a few per cent of a replay). */
static void keep_text(char *dst, size_t size, const char *src)
{
    size_t n = strnlen(src, size - 1u);
    memcpy(dst, src, n);
    dst[n] = '\0';
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

static void card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    replay_t *r = ctx;
    (void)card;
    if (r->opt.on_card_event != NULL) {
        r->opt.on_card_event(r->opt.ctx, r->rig.bus.now_ns, ev);
    }
}

static void param_service(void *ctx, unsigned card, uint8_t channel,
                          const uint8_t req[ML_TELEGRAM_LEN], const uint8_t rsp[ML_TELEGRAM_LEN])
{
    replay_t *r = ctx;
    (void)card;
    if (r->opt.param_observer != NULL) {
        r->opt.param_observer(r->opt.param_observer_ctx, channel, req, rsp);
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
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .baud = r->opt.baud};
    rig_init(&r->rig, &rc);
    rig_tap_t tap = {.ctx = r, .frame = bus_tap, .card_event = card_event,
                     .param = param_service};
    (void)rig_add_tap(&r->rig, &tap);
    if (rig_open(&r->rig, err, errlen) != 0) {
        return -1;
    }
    card_options_t co = {.address = opt->address,
                         .fixed_baud = opt->fixed_card_baud ? r->opt.baud : 0u,
                         .strict_timing = true,
                         .inverter = opt->inverter,
                         .inverter_delay_us = opt->inverter_delay_us};
    rig_card_t *card = rig_add_card(&r->rig, &co, 0);
    if (card == NULL) {
        (void)snprintf(err, errlen, "the card could not be put on the bus");
        return -1;
    }
    r->cs = &card->cs;
    /* The injector is only a UART: it transmits when replay_feed says, and hears nothing. */
    sim_station_t inj = {0};
    r->inj_port = rig_attach_station(&r->rig, &inj, &r->inj_uart);
    r->inj_baud = r->opt.baud;
    (void)r->inj_uart.ops->set_baud(r->inj_uart.ctx, r->inj_baud);
    if (card->nvm_note[0] != '\0') {
        (void)snprintf(err, errlen, "%s", card->nvm_note);
        return -1;
    }
    return 0;
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

static void give_service_turn(const replay_t *r)
{
    if (r->opt.service != NULL) {
        r->opt.service(r->opt.service_ctx);
    }
}

/* Sleeps until the monotonic clock reads due_ns. False when a stop request ended the wait (a
 * signal interrupts the sleep: EINTR). */
static bool sleep_until(const replay_t *r, uint64_t due_ns)
{
    struct timespec ts = {.tv_sec = (time_t)(due_ns / 1000000000u),
                          .tv_nsec = (long)(due_ns % 1000000000u)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) != 0) {
        if (stop_requested(r)) {
            return false;
        }
    }
    return true;
}

/* --speed real: sleeps until the wall clock reaches bus time t, giving the service hook its
 * turns meanwhile. False when a stop request ended the wait. */
static bool wait_wall(const replay_t *r, uint64_t t)
{
    uint64_t due = r->wall_start_ns + t;
    uint64_t now = host_clock_mono_ns();
    while (due > now) {
        uint64_t step = due;
        if (r->opt.service != NULL && due - now > REPLAY_SERVICE_NS) {
            step = now + REPLAY_SERVICE_NS;
        }
        if (!sleep_until(r, step)) {
            return false;
        }
        give_service_turn(r);
        now = host_clock_mono_ns();
    }
    return true;
}

/* Runs the bus to bus time t in slices of REPLAY_SLICE_NS, looking at the stop request between
 * them (the card wakes many times a second during a baud search, so one long run could take
 * minutes); with --speed real the wall clock first catches up with each slice. Returns false,
 * and sets interrupted, when a stop request ended it short of t. */
static bool run_to(replay_t *r, uint64_t t)
{
    while (r->rig.bus.now_ns < t) {
        if (stop_requested(r)) {
            r->interrupted = true;
            return false;
        }
        uint64_t next = t - r->rig.bus.now_ns > REPLAY_SLICE_NS ? r->rig.bus.now_ns + REPLAY_SLICE_NS : t;
        if (r->opt.speed == REPLAY_SPEED_REAL && !wait_wall(r, next)) {
            continue; /* stopped while waiting: the loop's test ends it */
        }
        membus_run_until_ns(&r->rig.bus, next);
        give_service_turn(r);
    }
    return true;
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
    const dp_slave_t *dp = &r->cs->card.dp;
    if (dp_slave_baud_state(dp) == DP_BAUD_CONTROL) {
        return false;
    }
    if (dp->wd_on && dp_slave_state(dp) != DP_STATE_WAIT_PRM) {
        return false;
    }
    if (r->cs->inverter == CARD_INVERTER_SIM &&
        (r->cs->md.speed_actual_mrpm != 0 || r->cs->md.speed_setpoint_mrpm != 0)) {
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
    if (!run_to(r, r->rig.bus.now_ns + settle_ns(r))) {
        return want;
    }
    while (!card_at_rest(r)) {
        if (want - r->rig.bus.now_ns <= REPLAY_SLICE_NS) {
            r->gaps_turning++;
            return want;
        }
        if (!run_to(r, r->rig.bus.now_ns + REPLAY_SLICE_NS)) {
            return want;
        }
    }
    uint64_t period = dp_slave_baud_state(&r->cs->card.dp) == DP_BAUD_SEARCH
                          ? replay_search_cycle_ns()
                          : 1000u; /* fixed rate: keep whole microseconds, the card's clock */
    uint64_t cut = (want - r->rig.bus.now_ns) / period * period;
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

/* A record without a time (text captures): right after the telegram before it, with the gap a
 * station would leave. */
static uint64_t untimed_slot(replay_t *r, bool starts_cycle, uint32_t baud, uint64_t busy)
{
    r->untimed++;
    uint32_t gap = starts_cycle ? REPLAY_SYNTH_GAP_REQUEST_BITS : REPLAY_SYNTH_GAP_ANSWER_BITS;
    uint64_t t = busy + (r->injected > 0u ? bits_ns(baud, gap) : 0u);
    return t > r->rig.bus.now_ns ? t : r->rig.bus.now_ns;
}

/* The idle the line needs before this kind of telegram: TSYN before a request or token, min TSDR
 * before an answer. */
static uint64_t idle_before(const replay_frame_t *m, bool starts_cycle, uint32_t baud)
{
    if (starts_cycle) {
        return bits_ns(baud, FDL_TSYN_BITS);
    }
    if (m->kind == REPLAY_KIND_RESPONSE || m->kind == REPLAY_KIND_SC) {
        return bits_ns(baud, FDL_MIN_TSDR_DEFAULT_BITS);
    }
    return 0u;
}

/* The record's time goes back: a difference across it means nothing (and must never be taken
 * unsigned). By less than the spacing of the records before, the record is out of order (merged
 * or buffered recorders): it goes on right after the one before and the records after it keep
 * their recorded times. By more, the clock stepped: the record goes on at the spacing the
 * records before had (on a cyclic bus the best guess the step leaves; right after the one before
 * when there is none) and becomes the anchor, so the records after it keep their spacing from
 * it. Returns true, with the bus time in *t, for a record out of order. */
static bool time_went_back(replay_t *r, const cap_record_t *rec, uint64_t earliest, uint64_t *t)
{
    uint64_t back = r->last_time_ns - rec->t_ns;
    if (r->backwards == 0u) {
        r->first_back_record = rec->index;
        r->first_back_position = rec->position;
    }
    r->backwards++;
    if (back > r->max_back_ns) {
        r->max_back_ns = back;
    }
    uint64_t soonest = earliest > r->rig.bus.now_ns ? earliest : r->rig.bus.now_ns;
    if (back < r->last_spacing_ns) {
        r->out_of_order++;
        *t = soonest;
        return true;
    }
    r->clock_steps++;
    uint64_t paced = r->last_inject_ns + r->last_spacing_ns;
    anchor_at(r, rec->t_ns, paced > soonest ? paced : soonest);
    return false;
}

/* A recorded time that would overlap the telegram before it goes on at the line's earliest;
 * counted, and reported as a conflict beyond the capture's time resolution. */
static uint64_t defer_to_line(replay_t *r, const cap_record_t *rec, uint64_t want,
                              uint64_t earliest)
{
    if (want >= earliest) {
        return want;
    }
    uint64_t d = earliest - want;
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
    return earliest;
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
        return r->rig.bus.now_ns;
    }
    const membus_t *bus = &r->rig.bus;
    uint64_t busy = bus->line_busy_until_ns > r->last_end_ns ? bus->line_busy_until_ns
                                                             : r->last_end_ns;
    if (!rec->has_time) {
        return untimed_slot(r, starts_cycle, baud, busy);
    }
    if ((rec->t_ns % 1000u) != 0u) {
        r->time_resolution_us = false;
    }
    uint64_t earliest = r->injected > 0u || busy > 0u
                            ? busy + idle_before(m, starts_cycle, baud)
                            : 0u;
    if (!r->have_anchor) {
        /* The first timed record: earlier untimed ones (if any) keep their synthetic times. */
        uint64_t start = r->injected > 0u ? busy + bits_ns(baud, REPLAY_SYNTH_GAP_REQUEST_BITS)
                                          : 0u;
        anchor_at(r, rec->t_ns, start);
    } else if (r->have_last_time && rec->t_ns < r->last_time_ns) {
        uint64_t t = 0;
        if (time_went_back(r, rec, earliest, &t)) {
            return t;
        }
    } else if (r->have_last_time) {
        r->last_spacing_ns = rec->t_ns - r->last_time_ns;
    }
    r->have_last_time = true;
    r->last_time_ns = rec->t_ns;
    uint64_t want = bus_time_of(r, rec->t_ns);
    if (want > bus->now_ns && want - bus->now_ns > settle_ns(r)) {
        want = shorten_gap(r, rec, want);
        if (r->interrupted) {
            return bus->now_ns;
        }
    }
    uint64_t t = defer_to_line(r, rec, want, earliest);
    return t > bus->now_ns ? t : bus->now_ns;
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

/* The card's recorded answer: not injected (the card produces its own); it is what the pending
 * request's answer is compared with. */
static void own_answer_recorded(replay_t *r, const cap_record_t *rec)
{
    r->own_answers++;
    if (!r->prev_request_to_card) {
        r->stray_answers++;
    } else if (r->pending && !r->pend_expected) {
        r->pend_expected = true;
        keep(&r->pend_expected_rec, REPLAY_FROM_CAPTURE, 0, rec->index, rec->position, rec->data,
             rec->len);
        keep_text(r->pend_expected_problem, sizeof r->pend_expected_problem, rec->problem);
    }
    r->prev_request_to_card = false;
}

/* A request to the card opens the window in which its answer is collected (with check on), and
 * its FCB is remembered per master. */
static void request_to_card(replay_t *r, const cap_record_t *rec, const replay_frame_t *m,
                            uint64_t t)
{
    if (r->opt.check && rec->len > 0u) {
        r->pending = true;
        r->pend_service = replay_service_of(m);
        keep(&r->pend_request, REPLAY_FROM_CAPTURE, t, rec->index, rec->position, rec->data,
             rec->len);
        keep_text(r->pend_request_problem, sizeof r->pend_request_problem, rec->problem);
        r->pend_expected = false;
        r->pend_actual = false;
        r->pend_card_state = dp_slave_state(&r->cs->card.dp);
        uint8_t prev = r->last_fc[m->sa];
        r->pend_fcb_repeat = (m->fc & FDL_FC_FCV) != 0u && prev != 0xFFu &&
                             (prev & FDL_FC_FCB) == (m->fc & FDL_FC_FCB) &&
                             (m->fc & FDL_FC_CODE_MASK) != FDL_REQ_FDL_STATUS;
    }
    r->last_fc[m->sa] = m->fc;
    if (replay_service_of(m) == REPLAY_SVC_SET_PRM) {
        r->set_prm_seen = true;
    }
}

/* Puts the record on the bus now, at baud. */
static void inject(replay_t *r, const cap_record_t *rec, const replay_frame_t *m, uint64_t t,
                   uint32_t baud)
{
    replay_judge(r);
    if (baud != r->inj_baud) {
        r->inj_baud = baud;
        (void)r->inj_uart.ops->set_baud(r->inj_uart.ctx, baud);
    }
    bool to_card = m->kind == REPLAY_KIND_REQUEST && m->has_header && m->da == r->opt.address &&
                   m->da != FDL_ADDR_BROADCAST;
    if (to_card) {
        request_to_card(r, rec, m, t);
    }
    r->prev_request_to_card = to_card && replay_expects_answer(m);
    if (rec->len > 0u) {
        r->injecting = true;
        r->inj_rec = rec;
        (void)r->inj_uart.ops->transmit(r->inj_uart.ctx, rec->data, rec->len,
                                        membus_now_us(&r->rig.bus));
        r->injecting = false;
        r->inj_rec = NULL;
        r->injected++;
    }
    r->last_inject_ns = r->rig.bus.now_ns;
    r->last_end_ns = r->rig.bus.now_ns + (uint64_t)hal_uart_char_ns(baud) * rec->len;
    r->last_record_ns = r->rig.bus.now_ns;
}

static void count_record(replay_t *r, const cap_record_t *rec)
{
    r->records++;
    r->last_index = rec->index;
    r->octets += rec->len;
    if (rec->problem[0] != '\0' || rec->len < rec->orig_len) {
        note_damage(r, rec);
    }
    note_rate(r, rec);
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
    if (rec->len == 0u) {
        /* A line a text importer could not read: nothing went on the wire. It is listed as
         * damaged and leaves the order of the telegrams around it alone. */
        count_record(r, rec);
        return;
    }
    replay_frame_t m;
    replay_frame_parse(rec->data, rec->len, &m);
    replay_feed_frame(r, rec, &m);
}

void replay_feed_frame(replay_t *r, const cap_record_t *rec, const replay_frame_t *m)
{
    if (!r->started) {
        r->started = true;
        r->wall_start_ns = host_clock_mono_ns();
    }
    if (r->interrupted) {
        return;
    }
    if (is_card_answer(r, m)) {
        count_record(r, rec);
        own_answer_recorded(r, rec);
        return;
    }
    uint32_t baud = replay_bus_baud(r, rec);
    uint64_t t = schedule(r, rec, m, baud);
    if (r->interrupted || !run_to(r, t)) {
        return; /* stopped in the gap before it: the record was not replayed */
    }
    count_record(r, rec);
    inject(r, rec, m, t, baud);
}

void replay_finish(replay_t *r)
{
    if (r->finished) {
        return;
    }
    r->finished = true;
    if (run_to(r, r->last_end_ns)) {
        /* The card has handed its answer to the UART by now; let it go out. */
        uint64_t end = r->rig.bus.line_busy_until_ns > r->rig.bus.now_ns ? r->rig.bus.line_busy_until_ns
                                                                : r->rig.bus.now_ns;
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
    replay_judge(r);
}
