/* What the replay takes from the capture (replay/infer.h). */
#include "replay/infer.h"

#include <string.h>

static const char *rate_text(uint32_t baud, char *buf, size_t max)
{
    if (baud >= 1000000u) {
        snprintf(buf, max, "%g Mbit/s", (double)baud / 1e6);
    } else {
        snprintf(buf, max, "%g kbit/s", (double)baud / 1e3);
    }
    return buf;
}

/* The card's address from the first pass: the one slave that answers. */
static int address_from_scan(const replay_scan_t *scan, const replay_file_status_t *st,
                             const replay_given_t *g, replay_inferred_t *o, char *err,
                             size_t errlen)
{
    uint8_t found[REPLAY_SCAN_MAX];
    unsigned n = scan != NULL ? replay_scan_result(scan, found, REPLAY_SCAN_MAX) : 0u;
    if (n == 0u) {
        snprintf(err, errlen, "no slave answers in %s (%llu records%s%s): nothing tells which "
                              "station is the card; give --address N", g->file,
                 (unsigned long long)(st != NULL ? st->records : 0u),
                 st != NULL && st->read_error ? "; " : "",
                 st != NULL && st->read_error ? st->error : "");
        return -1;
    }
    if (n > 1u) {
        char list[1024];
        size_t k = 0;
        for (unsigned i = 0; i < n && k + 40u < sizeof list; i++) {
            k += (size_t)snprintf(list + k, sizeof list - k, "%s%u (%llu answers)",
                                  i > 0u ? ", " : "", found[i],
                                  (unsigned long long)scan->answers[found[i]]);
        }
        snprintf(err, errlen, "%u slaves answer in %s: %s; say which one is the card with "
                              "--address N", n, g->file, list);
        return -1;
    }
    o->address = found[0];
    o->address_inferred = true;
    snprintf(o->address_source, sizeof o->address_source,
             "from the capture: the only slave that answers, %llu answers",
             (unsigned long long)scan->answers[o->address]);
    return 0;
}

/* Appends to the baud source text; *used stays within its size. */
static void baud_source_add(replay_inferred_t *o, size_t *used, int k)
{
    *used += k > 0 && (size_t)k < sizeof o->baud_source - *used ? (size_t)k : 0u;
}

/* The rate the recorded timing needs, with why. */
static void baud_from_timing(const replay_scan_t *scan, replay_inferred_t *o)
{
    replay_scan_rate_t why;
    uint32_t inferred = replay_scan_rate(scan, &why);
    if (inferred == 0u) {
        snprintf(o->baud_source, sizeof o->baud_source,
                 "the capture records no rate and no timed request with its answer: the "
                 "default, the rate of dfp-sim demo and record; --baud to change");
        return;
    }
    o->baud = inferred;
    size_t used = 0;
    baud_source_add(o, &used, snprintf(o->baud_source, sizeof o->baud_source,
                    "the capture records no rate; the lowest rate its timing allows: record "
                    "%llu begins %.1f us after record %llu, which needs %u bit times in that gap",
                    (unsigned long long)why.decided.record, (double)why.decided.gap_ns / 1e3,
                    (unsigned long long)why.decided.prev_record, why.decided.bits));
    if (why.outlier) {
        baud_source_add(o, &used, snprintf(o->baud_source + used, sizeof o->baud_source - used,
                        "; left out: record %llu, %.1f us after record %llu, alone needs a rate "
                        "four times higher (a bad timestamp?)",
                        (unsigned long long)why.ignored.record,
                        (double)why.ignored.gap_ns / 1e3,
                        (unsigned long long)why.ignored.prev_record));
    }
    if (scan->backward_pairs > 0u) {
        baud_source_add(o, &used, snprintf(o->baud_source + used, sizeof o->baud_source - used,
                        "; %llu records earlier than the one before left out",
                        (unsigned long long)scan->backward_pairs));
    }
    snprintf(o->baud_source + used, sizeof o->baud_source - used, "; --baud to override");
}

static void infer_rate(const replay_scan_t *scan, const replay_given_t *g, replay_inferred_t *o)
{
    if (g->baud != 0u) {
        o->baud = g->baud;
        o->baud_override = true;
        snprintf(o->baud_source, sizeof o->baud_source, "given with --baud");
        return;
    }
    o->baud_inferred = true;
    if (scan != NULL && scan->recorded_baud != 0u) {
        o->baud = scan->recorded_baud; /* also the rate a --fixed-baud card starts at */
        snprintf(o->baud_source, sizeof o->baud_source, "recorded in the capture");
    } else if (scan != NULL) {
        baud_from_timing(scan, o);
    }
}

/* Line or tty: the card's answers judged at the rate the replay would use. */
static void infer_timing(const replay_scan_t *scan, const replay_given_t *g,
                         replay_inferred_t *o)
{
    if (g->have_timing) {
        o->timing = g->timing;
        o->timing_given = true;
        snprintf(o->timing_source, sizeof o->timing_source, "given with --timing");
        return;
    }
    if (scan == NULL) {
        snprintf(o->timing_source, sizeof o->timing_source,
                 "not inferred: the file can be read only once; --timing relaxed for a tty "
                 "capture");
        return;
    }
    o->timing_inferred = true;
    replay_scan_timing_t w;
    uint32_t judged = o->baud != 0u ? o->baud : REPLAY_DEFAULT_BAUD;
    o->timing = replay_scan_timing(scan, o->address, judged, &w);
    char b[32];
    const char *which = g->baud != 0u ? "given with --baud"
                        : scan->recorded_baud != 0u ? "the rate the capture records"
                                                    : "the lowest rate the timing allows";
    if (w.pairs == 0u) {
        snprintf(o->timing_source, sizeof o->timing_source,
                 "no timed request to station %u with its answer: taken as a line's",
                 o->address);
    } else if (o->timing == REPLAY_TIMING_LINE) {
        snprintf(o->timing_source, sizeof o->timing_source,
                 "%llu of %llu answers of station %u begin within the card's min..max TSDR "
                 "after their request at %s (%s)", (unsigned long long)(w.pairs - w.off_line),
                 (unsigned long long)w.pairs, o->address, rate_text(judged, b, sizeof b), which);
    } else {
        snprintf(o->timing_source, sizeof o->timing_source,
                 "a tty/PTY capture: %llu of %llu answers of station %u begin %.3f to %.3f ms "
                 "after their request began, too late for a line at %s (%s) or before the "
                 "request could have ended; --timing line to replay it as a line's",
                 (unsigned long long)w.off_line, (unsigned long long)w.pairs, o->address,
                 (double)w.min_gap_ns / 1e6, (double)w.max_gap_ns / 1e6,
                 rate_text(judged, b, sizeof b), which);
    }
}

/* What a relaxed capture changes: the fastest rate (every recorded spacing fits), a card that
 * is not searching its rate (on a tty it had one), the inverter of dfp-sim slave (at once). */
static void infer_card(const replay_scan_t *scan, const replay_given_t *g, replay_inferred_t *o)
{
    bool relaxed = o->timing == REPLAY_TIMING_RELAXED;
    if (relaxed && g->baud == 0u) {
        o->baud = REPLAY_RELAXED_BAUD;
        o->baud_override = true;
        snprintf(o->baud_source, sizeof o->baud_source,
                 "relaxed timing: every record at its recorded time on the fastest rate, where "
                 "any recorded spacing fits");
    }
    uint64_t first = 0;
    if (g->fixed_baud) {
        o->fixed_baud = true;
        snprintf(o->fixed_source, sizeof o->fixed_source, "given with --fixed-baud");
    } else if (relaxed) {
        o->fixed_baud = o->fixed_inferred = true;
        snprintf(o->fixed_source, sizeof o->fixed_source,
                 "relaxed timing: the card on the tty had its rate");
    } else if (scan != NULL && replay_scan_first_answered(scan, o->address, &first)) {
        o->fixed_baud = o->fixed_inferred = true;
        snprintf(o->fixed_source, sizeof o->fixed_source,
                 "inferred: the capture's first request to it, record %llu, is answered: the "
                 "card had its rate before the capture began", (unsigned long long)first);
    }
    if (g->have_delay) {
        o->delay_us = g->delay_us;
        snprintf(o->delay_source, sizeof o->delay_source, "given with --inverter-delay");
    } else if (relaxed) {
        o->delay_us = 0u;
        o->delay_inferred = true;
        snprintf(o->delay_source, sizeof o->delay_source,
                 "relaxed timing: as in dfp-sim slave");
    } else {
        o->delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT;
        snprintf(o->delay_source, sizeof o->delay_source, "the default, as dfp-sim demo and "
                                                          "record");
    }
}

int replay_infer(const replay_scan_t *scan, const replay_file_status_t *st,
                 const replay_given_t *g, replay_inferred_t *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (g->have_address) {
        out->address = g->address;
        snprintf(out->address_source, sizeof out->address_source, "given with --address");
    } else if (address_from_scan(scan, st, g, out, err, errlen) != 0) {
        return -1;
    }
    infer_rate(scan, g, out);
    infer_timing(scan, g, out);
    infer_card(scan, g, out);
    return 0;
}
