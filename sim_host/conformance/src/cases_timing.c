/* The "Timing" group: the station delay of the answers against min TSDR and the GSD's MaxTsdr,
 * and the baud search over the rates the GSD claims (docs/protocol.md §A2). A medium that cannot
 * time answers (a PTY, an LCM segment) or change its rate makes these NOT APPLICABLE. The
 * watchdog's times are the DP state machine group's (dp.watchdog.expiry). */
#include <stdio.h>
#include <string.h>

#include "conformance/cf_cases_v1t.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_wire.h"

/* The min TSDR timing.tsdr.min sets (bit times): far above the default 11 and any MaxTsdr of
 * the slow rates, so an answer that ignores it shows. */
#define RAISED_MIN_TSDR 100u
/* How long the slave may take to find a new rate: its baud control time on the old rate, then
 * a search over every rate (protocol.md §A2.3 leaves both times to the implementation). */
#define BAUD_FOLLOW_BOUND_MS 10000u

static uint32_t bits_us(uint32_t bits, uint32_t baud)
{
    return (uint32_t)(((uint64_t)bits * 1000000u + baud - 1u) / baud);
}

static bool timing_claimed(cf_t *cf)
{
    if (!cf->link.timing || cf->link.baud == 0u) {
        return cf_na(cf, "%s does not time answers to the bit", cf->link.name);
    }
    return true;
}

typedef struct tsdr_span {
    uint32_t lo, hi;        /* the bounds the answers must keep (bit times) */
    int32_t seen_lo, seen_hi;
    unsigned answers;
} tsdr_span_t;

/* One answer's station delay against the span. */
static bool judge_tsdr(cf_t *cf, const cf_reply_t *r, const char *what, tsdr_span_t *s)
{
    char txt[64];
    if (r->len == 0u || r->garbled) {
        return cf_fail(cf, "%s: expected an answer, got %s", what,
                       cf_reply_text(r, txt, sizeof txt));
    }
    if (!cf_check(cf, r->tsdr_bits != CF_TSDR_UNKNOWN, "%s: the medium times answers but "
                  "gave no TSDR", what) ||
        !cf_check(cf, r->tsdr_bits >= (int32_t)s->lo && r->tsdr_bits <= (int32_t)s->hi,
                  "%s: expected TSDR %u..%u bit times, got %d", what, s->lo, s->hi,
                  (int)r->tsdr_bits)) {
        return false;
    }
    if (s->answers == 0u || r->tsdr_bits < s->seen_lo) {
        s->seen_lo = r->tsdr_bits;
    }
    if (s->answers == 0u || r->tsdr_bits > s->seen_hi) {
        s->seen_hi = r->tsdr_bits;
    }
    s->answers++;
    return true;
}

/* Answers of several kinds in Data_Exch: Slave_Diag, Get_Cfg, Data_Exchange, FDL status. */
static bool answers_within(cf_t *cf, tsdr_span_t *s)
{
    uint8_t out[244] = { 0 };
    size_t out_len = cf->out_len < sizeof out ? cf->out_len : sizeof out;
    cf_reply_t r;
    for (int i = 0; i < 3; i++) {
        if (!cf_data_exchange(cf, out, out_len, &r) ||
            !judge_tsdr(cf, &r, "Data_Exchange", s)) {
            return false;
        }
    }
    return cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r) && judge_tsdr(cf, &r, "Slave_Diag", s) &&
           cf_dp(cf, DP_SAP_GET_CFG, NULL, 0, &r) && judge_tsdr(cf, &r, "Get_Cfg", s) &&
           cf_request(cf, cf->opt.master, FDL_REQ_FDL_STATUS, -1, -1, NULL, 0, &r) &&
           judge_tsdr(cf, &r, "Request FDL Status", s);
}

static void case_tsdr_min(cf_t *cf)
{
    if (!timing_claimed(cf)) {
        return;
    }
    uint32_t baud = cf->link.baud, slot = cf->link.slot_us;
    uint8_t saved = cf->prm[DP_PRM_MIN_TSDR];
    tsdr_span_t s = { RAISED_MIN_TSDR, 1023u, 0, 0, 0 }; /* 1023: TSDR's largest value */
    /* The tester's slot time grows with the delay it asks for (TSL > max TSDR + 15). */
    uint32_t need = bits_us(RAISED_MIN_TSDR + 1023u + 15u, baud);
    cf->link.slot_us = slot > need ? slot : need;
    cf->prm[DP_PRM_MIN_TSDR] = RAISED_MIN_TSDR;
    bool up = cf_start_up(cf);
    cf->prm[DP_PRM_MIN_TSDR] = saved;
    if (up && answers_within(cf, &s)) {
        cf_info(cf, "min TSDR %u: %u answers with TSDR %d..%d bit times", RAISED_MIN_TSDR,
                s.answers, (int)s.seen_lo, (int)s.seen_hi);
    }
    /* Back to the start-up's min TSDR (Set_Prm with lock) for the cases after this one. */
    if (!cf->link_failed) {
        (void)cf_start_up(cf);
    }
    cf->link.slot_us = slot;
}

static void case_tsdr_max(cf_t *cf)
{
    if (!timing_claimed(cf)) {
        return;
    }
    uint32_t baud = cf->link.baud;
    uint32_t max = gsd_max_tsdr_bits(cf->gsd, baud);
    if (max == 0u) {
        return (void)cf_na(cf, "the GSD gives no MaxTsdr at %u bit/s (the rate is not claimed)",
                           baud);
    }
    if (cf->prm[DP_PRM_MIN_TSDR] != FDL_MIN_TSDR_DEFAULT_BITS) {
        return (void)cf_fail(cf, "the start-up Set_Prm sets min TSDR %u, not 11",
                             cf->prm[DP_PRM_MIN_TSDR]);
    }
    /* The lower bound is timing.tsdr.min's: here only the latest answer counts. */
    tsdr_span_t s = { 0, max, 0, 0, 0 };
    if (cf_start_up(cf) && answers_within(cf, &s)) {
        cf_info(cf, "MaxTsdr %u at %u bit/s: %u answers with TSDR %d..%d bit times", max, baud,
                s.answers, (int)s.seen_lo, (int)s.seen_hi);
    }
}

/* The default slot time TSL at a rate (protocol.md §A2.1), widened to MaxTsdr + 15 where the
 * GSD asks for more. */
static uint32_t slot_bits(const cf_t *cf, uint32_t baud)
{
    uint32_t tsl = baud <= 187500u ? 100u : baud <= 500000u ? 200u : baud <= 1500000u ? 300u
                 : baud <= 3000000u ? 400u : baud <= 6000000u ? 600u : 1000u;
    uint32_t max = gsd_max_tsdr_bits(cf->gsd, baud) + 15u;
    return max > tsl ? max : tsl;
}

/* The tester goes to baud (its slot time with it); the slave must answer Slave_Diag there
 * within the bound. */
static bool follow(cf_t *cf, uint32_t baud, uint64_t *took_ms)
{
    uint64_t t0 = cf->link.ops->now_ns(cf->link.ctx);
    uint64_t t = t0;
    cf_reply_t r;
    cf_answer_t a;
    if (cf->link.ops->set_baud(cf->link.ctx, baud) != 0) {
        return cf_fail(cf, "the link could not switch to %u bit/s", baud);
    }
    cf->link.baud = baud;
    cf->link.slot_us = bits_us(slot_bits(cf, baud), baud);
    /* Between tries at least TSYN of the new rate: the slave only takes a request after it. */
    uint32_t gap_ms = bits_us(FDL_TSYN_BITS, baud) / 1000u + 1u;
    while (t - t0 < (uint64_t)BAUD_FOLLOW_BOUND_MS * 1000000u) {
        /* FCV=0 each time: requests the slave missed leave no FCB to match. */
        cf_fcb_restart(cf, cf->opt.master);
        if (!cf_dp(cf, DP_SAP_SLAVE_DIAG, NULL, 0, &r)) {
            return false;
        }
        if (cf_answer(&r, &a) && a.du_len >= DP_DIAG_STD_LEN) {
            *took_ms = (t - t0) / 1000000u;
            return true;
        }
        if (!cf_pause_ms(cf, gap_ms)) {
            return false;
        }
        t = cf->link.ops->now_ns(cf->link.ctx);
    }
    return cf_fail(cf, "the tester went to %u bit/s: expected Slave_Diag answered there within "
                   "%u ms (baud control, then the search), got no answer", baud,
                   BAUD_FOLLOW_BOUND_MS);
}

static void case_baud_search(cf_t *cf)
{
    if (!cf->link.has_baud || cf->link.baud == 0u) {
        return (void)cf_na(cf, "%s cannot change its rate", cf->link.name);
    }
    uint32_t home = cf->link.baud, home_slot = cf->link.slot_us;
    uint64_t took = 0;
    for (size_t i = GSD_RATE_COUNT; i-- > 0u;) {
        uint32_t baud = gsd_rate_baud(i);
        if (baud == home || !gsd_supports_baud(cf->gsd, baud)) {
            continue;
        }
        if (!follow(cf, baud, &took)) {
            break;
        }
        cf_info(cf, "%s %u ms", gsd_rate_name(i), (unsigned)took);
    }
    /* Home again, whatever happened: the cases after this one run at the run's rate. */
    if (!cf->link_failed) {
        bool failed = cf_decided(cf);
        if (follow(cf, home, &took) && !failed) {
            cf_info(cf, "back to %u bit/s in %u ms", home, (unsigned)took);
        }
    }
    cf->link.baud = home;
    cf->link.slot_us = home_slot;
}

static void case_rates_unclaimed(cf_t *cf)
{
    char list[96] = "";
    size_t at = 0, n = 0;
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) {
        if (!gsd_supports_baud(cf->gsd, gsd_rate_baud(i))) {
            at += (size_t)snprintf(&list[at], sizeof list - at, "%s%s", n++ ? ", " : "",
                                   gsd_rate_name(i));
        }
    }
    if (n > 0u) {
        cf_na(cf, "rates the GSD does not claim are not tested: %s", list);
    } else {
        cf_info(cf, "the GSD claims all ten rates");
    }
}

#define STD_TIMING "IEC 61158-4-3 bus timing: TSDR, min TSDR (protocol.md §A2.1, §A3.2)"

const cf_case_t cf_cases_timing[] = {
    { "timing.tsdr.min", "Timing", STD_TIMING,
      "with min TSDR raised to 100 bit times by Set_Prm, every answer waits at least that",
      case_tsdr_min },
    { "timing.tsdr.max", "Timing", STD_TIMING " and GSD MaxTsdr_<rate> (protocol.md §A2.2)",
      "with min TSDR 11, no answer later than the GSD's MaxTsdr at the rate",
      case_tsdr_max },
    { "timing.baud_search", "Timing",
      "IEC 61158-4-3 / PI 2.032 every baud rate; automatic rate detection (protocol.md §A2.3)",
      "the slave follows the tester to every rate the GSD claims and answers there",
      case_baud_search },
    { "timing.rates_unclaimed", "Timing", "GSD <rate>_supp (PI GSD specification 2.122)",
      "rates the GSD does not claim are listed, not tested", case_rates_unclaimed },
};
const size_t cf_cases_timing_count = sizeof cf_cases_timing / sizeof cf_cases_timing[0];
