/* Two receivers fed one character stream, to hold the MCU collector (fdl_collect.h, then
 * fdl_rx_telegram) against the per-character assembler fdl_rx_char. Shared by
 * tests/unit/test_fdl_collect.c and tests/fuzz/fuzz_fdl_collect.c.
 *
 * The reference is fdl_rx_char, polled as a main loop polls it: fdl_rx_poll at the deadline it
 * returns, so a silence of FDL_RX_FORGET_US or more reads as "unknown". The collector runs as
 * a UART interrupt would run it: fdl_collect_char for an error-free character, fdl_collect_slow
 * with the flags otherwise, and after each FDL_COLLECT_TELEGRAM the next of three buffers;
 * what it hands on goes through a second fdl_rx_t with fdl_rx_telegram (FDL_COLLECT_ERROR as
 * .error). The buffer of the last telegram handed on must not change before the next one.
 *
 * Per character each side yields events: the errors it counted (fdl_rx's error_count; a pause
 * first) and then a telegram, with octets, length, end time and idle before it. twin_char()
 * compares the events and the two receivers' states and names the outcome: the same, one of
 * the two differences fdl_collect.h documents (their documented outcome checked), one of the
 * differences found beyond them (named so a test can show each), or a mismatch.
 *
 * Bad FCS/ED followed without a pause (documented): fdl_rx waits for a pause, the collector
 * does not. From there the two may disagree until their states agree again (a "window"); in
 * strict timing every event of fdl_rx in it must also come from the collector, and every
 * telegram only the collector reports must have too little idle before it for TSYN, so the
 * core refuses it as a request (fdl_station.c tsyn_violated). */
#ifndef TESTS_UNIT_FDL_COLLECT_TWIN_H
#define TESTS_UNIT_FDL_COLLECT_TWIN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "dp_slave/fdl_collect.h"
#include "dp_slave/fdl_gap.h"
#include "dp_slave/fdl_rx.h"
#include "dp_slave/fdl_wire.h"
#include "hal/hal_time.h"

#define TWIN_BUFS 3u
#define TWIN_EVENTS 3u

typedef struct twin_event {
    fdl_rx_error_t error; /* FDL_RX_OK: a telegram, described by the fields below */
    uint16_t len;
    hal_time_us_t end_t;
    uint32_t idle_before_ns;
    uint8_t octets[FDL_FRAME_MAX];
} twin_event_t;

typedef struct twin_side {
    unsigned n;
    twin_event_t ev[TWIN_EVENTS];
} twin_side_t;

typedef enum twin_verdict {
    TWIN_SAME = 0,
    /* documented: the character after a bad FCS/ED, without a pause, is taken by the collector
     * and ignored by fdl_rx (and what follows, until both agree again) */
    TWIN_DOC_AFTER_CHECK,
    /* documented: a pause and an error flag on one character: fdl_rx counts GAP and CHAR, the
     * collector reports CHAR */
    TWIN_DOC_PAUSE_CHAR,
    /* beyond the documentation: a pause and a character that cannot start a telegram: fdl_rx
     * counts GAP and SD, the collector reports SD */
    TWIN_GAP_SD,
    /* beyond: a silence of 2^31 µs or more: fdl_rx, polled, reads it as unknown (long); the
     * collector has no poll and sees the wrapped difference */
    TWIN_LONG_SILENCE,
    /* beyond: relaxed timing, after an error, a timestamp earlier than the previous one: fdl_rx
     * takes it as a resync pause (unsigned cast of a negative difference), the collector not */
    TWIN_RELAXED_BACK,
    TWIN_MISMATCH,
    TWIN_VERDICTS
} twin_verdict_t;

static const char *const twin_verdict_names[TWIN_VERDICTS] __attribute__((unused)) = {
    "same", "doc: after bad FCS/ED", "doc: pause + char error", "pause + bad SD",
    "silence >= 2^31 us", "relaxed, time backwards", "MISMATCH",
};

typedef struct twin {
    fdl_rx_t ref;  /* fdl_rx_char */
    fdl_collect_t col;
    fdl_rx_t core; /* fdl_rx_telegram, fed by col */
    uint8_t *bufs[TWIN_BUFS]; /* FDL_FRAME_MAX octets each, the caller's */
    unsigned filling;         /* the buffer col collects into */
    int held;                 /* the buffer of the last telegram handed on, -1 none */
    uint16_t held_len;
    uint8_t held_copy[FDL_FRAME_MAX];
    bool strict;
    hal_time_us_t t0;
    int64_t last_us; /* true time of the previous character (the µs clock is t0 + it) */
    bool have_last;
    twin_verdict_t window; /* TWIN_SAME, or the difference whose window is open */
    twin_side_t ref_ev;    /* events of the last character */
    twin_side_t col_ev;
    const char *why; /* what did not match, for the report */
    unsigned long count[TWIN_VERDICTS];
    unsigned long frames;  /* telegrams both reported identically */
    unsigned long windows; /* windows opened */
} twin_t;

static inline void twin_init(twin_t *tw, uint8_t *const bufs[TWIN_BUFS], uint32_t baud,
                             bool strict, hal_time_us_t t0)
{
    memset(tw, 0, sizeof *tw);
    for (unsigned k = 0; k < TWIN_BUFS; k++) {
        tw->bufs[k] = bufs[k];
    }
    tw->held = -1;
    tw->strict = strict;
    tw->t0 = t0;
    fdl_rx_init(&tw->ref, baud, strict);
    fdl_collect_init(&tw->col, tw->bufs[0], baud, strict);
    fdl_rx_init(&tw->core, baud, strict);
}

static inline hal_time_us_t twin_clock(const twin_t *tw, int64_t true_us)
{
    return (hal_time_us_t)(tw->t0 + (uint64_t)true_us);
}

/* Both receivers between telegrams and equally synchronised, or holding the same part of one
 * (whose end sets "synced" alike on both): from here they behave alike. */
static inline bool twin_states_equal(const twin_t *tw)
{
    bool ref_busy = tw->ref.collecting;
    bool col_busy = tw->col.len != 0u;
    if (ref_busy != col_busy) {
        return false;
    }
    if (!ref_busy) {
        return tw->ref.synced == tw->col.synced;
    }
    return tw->ref.len == tw->col.len && memcmp(tw->ref.buf, tw->col.buf, tw->ref.len) == 0 &&
           tw->ref.idle_before_pending_ns == tw->col.idle_before_ns;
}

static inline void twin_set_baud(twin_t *tw, uint32_t baud)
{
    fdl_rx_set_baud(&tw->ref, baud);
    fdl_collect_set_baud(&tw->col, baud);
    fdl_rx_set_baud(&tw->core, baud);
    if (tw->window != TWIN_SAME && twin_states_equal(tw)) {
        tw->window = TWIN_SAME;
    }
}

static inline void twin_add_error(twin_t *tw, twin_side_t *s, fdl_rx_error_t e)
{
    if (s->n == TWIN_EVENTS) {
        tw->why = "more events on one character than possible";
        return;
    }
    s->ev[s->n++] = (twin_event_t){.error = e};
}

static inline void twin_add_frame(twin_t *tw, twin_side_t *s, const fdl_rx_t *rx)
{
    if (s->n == TWIN_EVENTS || rx->frame_len == 0u || rx->frame_len > FDL_FRAME_MAX) {
        tw->why = "a telegram event that cannot be";
        return;
    }
    twin_event_t *e = &s->ev[s->n++];
    *e = (twin_event_t){.error = FDL_RX_OK, .len = rx->frame_len, .end_t = rx->frame_end_t,
                        .idle_before_ns = rx->idle_before_ns};
    memcpy(e->octets, rx->frame, rx->frame_len);
}

static inline void twin_ref_char(twin_t *tw, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    uint32_t before[FDL_RX_ERR_COUNT];
    memcpy(before, tw->ref.error_count, sizeof before);
    fdl_rx_result_t r = fdl_rx_char(&tw->ref, byte, flags, t);
    twin_side_t *s = &tw->ref_ev;
    s->n = 0;
    if (tw->ref.error_count[FDL_RX_ERR_GAP] != before[FDL_RX_ERR_GAP]) {
        twin_add_error(tw, s, FDL_RX_ERR_GAP);
    }
    for (unsigned e = 1; e < FDL_RX_ERR_COUNT; e++) {
        for (uint32_t k = before[e]; e != FDL_RX_ERR_GAP && k != tw->ref.error_count[e]; k++) {
            twin_add_error(tw, s, (fdl_rx_error_t)e);
        }
    }
    if (r == FDL_RX_FRAME) {
        twin_add_frame(tw, s, &tw->ref);
    } else if (r == FDL_RX_ERROR && (s->n == 0u || s->ev[s->n - 1u].error != tw->ref.last_error)) {
        tw->why = "fdl_rx_char reported an error it did not count last";
    }
}

static inline void twin_col_telegram(twin_t *tw, twin_side_t *s)
{
    const fdl_rx_telegram_t *tg = &tw->col.telegram;
    if (tg->buf != tw->bufs[tw->filling]) {
        tw->why = "the telegram is not in the buffer the collector was given";
        return;
    }
    if (tw->held >= 0 && memcmp(tw->bufs[tw->held], tw->held_copy, tw->held_len) != 0) {
        tw->why = "the buffer of the telegram handed on before changed";
    }
    fdl_rx_result_t r = fdl_rx_telegram(&tw->core, tg);
    if (r == FDL_RX_FRAME) {
        if (tw->core.frame != tg->buf) {
            tw->why = "fdl_rx_telegram's frame is not the telegram's buffer";
        }
        twin_add_frame(tw, s, &tw->core);
    } else {
        twin_add_error(tw, s, tw->core.last_error);
    }
    tw->held = (int)tw->filling;
    tw->held_len = tg->len <= FDL_FRAME_MAX ? tg->len : 0u;
    memcpy(tw->held_copy, tg->buf, tw->held_len);
    tw->filling = (tw->filling + 1u) % TWIN_BUFS;
    fdl_collect_give_buffer(&tw->col, tw->bufs[tw->filling]);
}

static inline void twin_col_char(twin_t *tw, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    unsigned out = flags != 0u ? fdl_collect_slow(&tw->col, byte, flags, t)
                               : fdl_collect_char(&tw->col, byte, t);
    twin_side_t *s = &tw->col_ev;
    s->n = 0;
    if ((out & ~(FDL_COLLECT_TELEGRAM | FDL_COLLECT_ERROR)) != 0u) {
        tw->why = "unknown bits in the collector's result";
    }
    if ((out & FDL_COLLECT_ERROR) != 0u) {
        fdl_rx_telegram_t tg = {.buf = NULL, .len = 0, .error = tw->col.error,
                                .end_t = tw->col.error_t, .idle_before_ns = UINT32_MAX};
        if (tw->col.error == FDL_RX_OK || tw->col.error >= FDL_RX_ERR_COUNT) {
            tw->why = "FDL_COLLECT_ERROR without an error";
        } else if (fdl_rx_telegram(&tw->core, &tg) != FDL_RX_ERROR ||
                   tw->core.last_error != tw->col.error) {
            tw->why = "fdl_rx_telegram did not pass the collector's error on";
        }
        twin_add_error(tw, s, tw->col.error);
    }
    if ((out & FDL_COLLECT_TELEGRAM) != 0u) {
        twin_col_telegram(tw, s);
    }
}

static inline bool twin_event_equal(const twin_event_t *a, const twin_event_t *b)
{
    if (a->error != b->error) {
        return false;
    }
    return a->error != FDL_RX_OK ||
           (a->len == b->len && a->end_t == b->end_t && a->idle_before_ns == b->idle_before_ns &&
            memcmp(a->octets, b->octets, a->len) == 0);
}

static inline bool twin_side_has(const twin_side_t *s, const twin_event_t *e)
{
    for (unsigned k = 0; k < s->n; k++) {
        if (twin_event_equal(&s->ev[k], e)) {
            return true;
        }
    }
    return false;
}

static inline bool twin_sides_equal(const twin_side_t *a, const twin_side_t *b)
{
    if (a->n != b->n) {
        return false;
    }
    for (unsigned k = 0; k < a->n; k++) {
        if (!twin_event_equal(&a->ev[k], &b->ev[k])) {
            return false;
        }
    }
    return true;
}

/* The side's errors are exactly e1 (, e2) and nothing else. */
static inline bool twin_side_is(const twin_side_t *s, fdl_rx_error_t e1, fdl_rx_error_t e2)
{
    unsigned n = e2 == FDL_RX_OK ? 1u : 2u;
    return s->n == n && s->ev[0].error == e1 && (n == 1u || s->ev[1].error == e2);
}

/* fdl_station.c's TSYN rule: a request needs 33 bit times of idle before it. */
static inline bool twin_tsyn_violated(const twin_t *tw, uint32_t idle_before_ns)
{
    return idle_before_ns != UINT32_MAX &&
           (uint64_t)idle_before_ns + FDL_RX_GAP_TOLERANCE_NS <
               (uint64_t)FDL_TSYN_BITS * tw->ref.char_ns / FDL_CHAR_BITS;
}

/* Inside the window after a bad FCS/ED, strict timing: what fdl_rx reports the collector
 * reports too, and a telegram only the collector reports fails TSYN. */
static inline bool twin_after_check_ok(twin_t *tw)
{
    if (!tw->strict) {
        return true; /* relaxed timing: the core judges no TSYN, nothing to hold it to */
    }
    for (unsigned k = 0; k < tw->ref_ev.n; k++) {
        if (!twin_side_has(&tw->col_ev, &tw->ref_ev.ev[k])) {
            tw->why = "after a bad FCS/ED: fdl_rx reported what the collector did not";
            return false;
        }
    }
    for (unsigned k = 0; k < tw->col_ev.n; k++) {
        const twin_event_t *e = &tw->col_ev.ev[k];
        if (e->error == FDL_RX_OK && !twin_side_has(&tw->ref_ev, e) &&
            !twin_tsyn_violated(tw, e->idle_before_ns)) {
            tw->why = "after a bad FCS/ED: the collector's telegram had TSYN idle before it";
            return false;
        }
    }
    return true;
}

static inline bool twin_ends_in_check_error(const twin_side_t *s)
{
    return s->n > 0u &&
           (s->ev[s->n - 1u].error == FDL_RX_ERR_FCS || s->ev[s->n - 1u].error == FDL_RX_ERR_ED);
}

typedef struct twin_pre {
    uint8_t flags;
    bool long_silence; /* fdl_rx forgot the previous character, the collector cannot */
    bool relaxed_back; /* relaxed, time backwards, both between telegrams after an error */
} twin_pre_t;

static inline twin_verdict_t twin_judge(twin_t *tw, const twin_pre_t *pre)
{
    bool same_ev = twin_sides_equal(&tw->ref_ev, &tw->col_ev);
    bool same_state = twin_states_equal(tw);
    /* the one-character differences, alike inside a window */
    bool pause_char = pre->flags != 0u &&
                      twin_side_is(&tw->ref_ev, FDL_RX_ERR_GAP, FDL_RX_ERR_CHAR) &&
                      twin_side_is(&tw->col_ev, FDL_RX_ERR_CHAR, FDL_RX_OK);
    bool gap_sd = twin_side_is(&tw->ref_ev, FDL_RX_ERR_GAP, FDL_RX_ERR_SD) &&
                  twin_side_is(&tw->col_ev, FDL_RX_ERR_SD, FDL_RX_OK);
    twin_verdict_t v;
    if (tw->why != NULL) {
        v = TWIN_MISMATCH;
    } else if (!same_ev && pause_char && (same_state || tw->window != TWIN_SAME)) {
        v = TWIN_DOC_PAUSE_CHAR;
    } else if (!same_ev && gap_sd && (same_state || tw->window != TWIN_SAME)) {
        v = TWIN_GAP_SD;
    } else if (tw->window != TWIN_SAME) {
        v = same_ev ? TWIN_SAME : tw->window;
        if (!same_ev && tw->window == TWIN_DOC_AFTER_CHECK && !twin_after_check_ok(tw)) {
            v = TWIN_MISMATCH;
        }
    } else if (same_ev && same_state) {
        v = TWIN_SAME;
    } else if (same_ev && twin_ends_in_check_error(&tw->ref_ev) && tw->ref.len == 0u &&
               tw->col.len == 0u && !tw->ref.synced && tw->col.synced) {
        v = TWIN_SAME; /* equal so far; the difference shows with the next character */
        tw->window = TWIN_DOC_AFTER_CHECK;
        tw->windows++;
    } else if (pre->long_silence || pre->relaxed_back) {
        v = pre->long_silence ? TWIN_LONG_SILENCE : TWIN_RELAXED_BACK;
        if (!same_state) {
            tw->window = v;
            tw->windows++;
        }
    } else {
        v = TWIN_MISMATCH;
        tw->why = same_ev ? "the receivers' states differ" : "the events differ";
    }
    if (tw->window != TWIN_SAME && same_state) {
        tw->window = TWIN_SAME;
    }
    tw->count[v]++;
    if (same_ev) {
        for (unsigned k = 0; k < tw->ref_ev.n; k++) {
            tw->frames += tw->ref_ev.ev[k].error == FDL_RX_OK ? 1u : 0u;
        }
    }
    return v;
}

/* One character at true_us microseconds from the start (the µs clock reads t0 + true_us; it may
 * go backwards, as clock jitter does). */
static inline twin_verdict_t twin_char(twin_t *tw, uint8_t byte, uint8_t flags, int64_t true_us)
{
    hal_time_us_t t = twin_clock(tw, true_us);
    twin_pre_t pre = {.flags = flags};
    if (tw->have_last) {
        int32_t col_dt = hal_time_diff(t, tw->col.last_t);
        bool ref_forgets = true_us - tw->last_us >= (int64_t)FDL_RX_FORGET_US;
        pre.long_silence = ref_forgets && (col_dt < 0 || (uint32_t)col_dt < FDL_RX_FORGET_US);
        pre.relaxed_back = !tw->strict && col_dt < 0 && !tw->ref.collecting && !tw->ref.synced &&
                           tw->col.len == 0u && !tw->col.synced;
        if (ref_forgets) {
            /* the main loop polls at the deadline fdl_rx_poll gave */
            (void)fdl_rx_poll(&tw->ref, twin_clock(tw, tw->last_us + (int64_t)FDL_RX_FORGET_US));
            if (tw->ref.have_last) {
                tw->why = "fdl_rx_poll at its deadline did not forget";
            }
        }
    }
    tw->have_last = true;
    tw->last_us = true_us;
    twin_ref_char(tw, byte, flags, t);
    twin_col_char(tw, byte, flags, t);
    return twin_judge(tw, &pre);
}

/* After the last character: the telegram handed on last is still intact. */
static inline bool twin_finish(twin_t *tw)
{
    if (tw->held >= 0 && memcmp(tw->bufs[tw->held], tw->held_copy, tw->held_len) != 0) {
        tw->why = "the buffer of the last telegram handed on changed";
        return false;
    }
    return tw->why == NULL;
}

#endif
