/* The replay report (format in docs/replay.md). */
#include <string.h>

#include "replay/infer.h"
#include "replay/param_text.h"
#include "replay/replay.h"
#include "report_out.h"

void replay_where(const replay_report_info_t *info, uint64_t record, uint64_t position,
                  char *out, size_t max)
{
    snprintf(out, max, "record %llu (%s %llu)", (unsigned long long)record,
             info->position_unit != NULL ? info->position_unit : "position",
             (unsigned long long)position);
}

static void print_kept(FILE *out, const replay_report_info_t *info, const replay_kept_t *k,
                       const replay_dx_layout_t *lay, replay_param_ctx_t *pc, const char *indent)
{
    char hex[3u * CAP_MAX_RECORD + 8u];
    char text[512];
    char at[96];
    replay_hex(k->data, k->len, hex, sizeof hex);
    replay_describe(k->data, k->len, lay, text, sizeof text);
    if (k->source == REPLAY_FROM_CARD) {
        snprintf(at, sizeof at, "card");
    } else {
        replay_where(info, k->record, k->position, at, sizeof at);
    }
    fprintf(out, "%s%12.6f s  %-26s %s\n%s%16s %s\n", indent, (double)k->t_ns / 1e9, at, hex,
            indent, "", text);
    if (replay_param_text(k->data, k->len, lay, pc, text, sizeof text) > 0u) {
        fprintf(out, "%s%16s %s\n", indent, "", text);
    }
}

static void print_octets(FILE *out, const char *label, const replay_kept_t *k,
                         const replay_dx_layout_t *lay, replay_param_ctx_t *pc)
{
    char hex[3u * CAP_MAX_RECORD + 8u];
    char text[512];
    replay_hex(k->data, k->len, hex, sizeof hex);
    replay_describe(k->data, k->len, lay, text, sizeof text);
    fprintf(out, "  %-9s %s\n  %-9s %s\n", label, hex, "", text);
    if (replay_param_text(k->data, k->len, lay, pc, text, sizeof text) > 0u) {
        fprintf(out, "  %-9s %s\n", "", text);
    }
}

static bool needs_data_exch(replay_service_t s)
{
    switch (s) {
    case REPLAY_SVC_DATA_EXCHANGE:
    case REPLAY_SVC_MSAC1_READ:
    case REPLAY_SVC_MSAC1_WRITE:
    case REPLAY_SVC_MSAC1_POLL:
    case REPLAY_SVC_MSAC1_ALARM_ACK:
    case REPLAY_SVC_MSAC1_OTHER:
    case REPLAY_SVC_RD_OUTP:
        return true;
    default:
        return false;
    }
}

/* Does a recorded answer belong to the request: addressed to its sender, from its SAP? */
static bool answer_fits(const replay_kept_t *req, const replay_kept_t *ans)
{
    replay_frame_t q;
    replay_frame_t a;
    replay_frame_parse(req->data, req->len, &q);
    replay_frame_parse(ans->data, ans->len, &a);
    if (a.kind == REPLAY_KIND_SC) {
        return true;
    }
    if (a.kind != REPLAY_KIND_RESPONSE || !a.has_header || !q.has_header || a.da != q.sa) {
        return false;
    }
    if (q.has_dsap != a.has_ssap) {
        return false;
    }
    return !q.has_dsap || a.ssap == q.dsap;
}

/* The reasons a reader needs to make sense of the first difference. */
static void explain(FILE *out, const replay_t *r, const replay_mismatch_t *m)
{
    const char *lead = "  why       ";
    const char *more = "            ";
    const char *p = lead;
#define WHY(...)                                                                              \
    do {                                                                                      \
        fputs(p, out);                                                                        \
        fprintf(out, __VA_ARGS__);                                                            \
        fputc('\n', out);                                                                     \
        p = more;                                                                             \
    } while (0)
    if (m->request_problem[0] != '\0') {
        WHY("the request record is damaged (%s); it went onto the bus as recorded, and the "
            "card hears it so", m->request_problem);
    }
    if (m->expected_problem[0] != '\0') {
        WHY("the recorded answer is damaged (%s): the card's answer cannot equal it",
            m->expected_problem);
    }
    /* Answers that do not depend on a parameterisation (class 2 needs none). */
    bool state_free = m->service == REPLAY_SVC_FDL_STATUS || m->service == REPLAY_SVC_SET_PRM ||
                      (m->service >= REPLAY_SVC_MSAC2_INITIATE &&
                       m->service <= REPLAY_SVC_MSAC2_OTHER);
    if (m->expected_present && !answer_fits(&m->request, &m->expected)) {
        WHY("the recorded answer does not fit this request (other addresses or SAPs): a stray "
            "telegram in the capture, e.g. a late answer to an earlier request");
    }
    if (m->baud_state == DP_BAUD_SEARCH) {
        char b[32];
        WHY("the card had not found the bus rate when the request ended (listening at %s): it "
            "heard the request garbled. The card powers up at the first record and searches "
            "from 12 Mbit/s down; if the real card was on the bus earlier, replay with "
            "--fixed-baud", replay_baud_text(m->card_baud, b, sizeof b));
    } else if (m->card_state != DP_STATE_DATA_EXCH && !m->set_prm_seen && !state_free) {
        WHY("the card is in %s and the capture has no Set_Prm to it before this request: the "
            "capture starts after the real card was parameterised (by this or an earlier "
            "master), perhaps in the middle of data exchange. The emulated card powers up at "
            "the first record, so its answers differ until a master parameterises it in the "
            "capture (Set_Prm, Chk_Cfg); Data_Exchange gets RS until then",
            dp_state_name(m->card_state));
    } else if (needs_data_exch(m->service) && m->card_state != DP_STATE_DATA_EXCH) {
        WHY("the card is in %s: its parameterisation in the capture did not complete or it "
            "left data exchange (watchdog, refused Set_Prm/Chk_Cfg)",
            dp_state_name(m->card_state));
    }
    if (m->fcb_repeat) {
        WHY("a repeated request (FCV=1, the same FCB as this master's previous request): the "
            "card answers it from its reply cache without executing it again");
    }
    if (!m->expected_present && m->actual_present) {
        WHY("the capture shows no answer to this request, the card answered");
    } else if (m->expected_present && !m->actual_present) {
        WHY("the card did not answer");
    } else if (m->expected_present && m->actual_present) {
        size_t n = m->expected.len < m->actual.len ? m->expected.len : m->actual.len;
        size_t i = 0;
        while (i < n && (m->expected.data[i] == m->actual.data[i] || replay_bit(m->mask, i))) {
            i++;
        }
        if (i < n) {
            WHY("first difference at octet %zu: expected %02X, the card sent %02X", i,
                m->expected.data[i], m->actual.data[i]);
        } else {
            WHY("the card's answer has %zu octets, the recorded one %zu", m->actual.len,
                m->expected.len);
        }
    }
    (void)r;
#undef WHY
}

static const char *or_given(const char *text)
{
    return text != NULL ? text : "given";
}

/* The bus line: which rate, and where it came from. */
static void print_bus(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char b[32];
    char b2[32];
    char b3[32];
    if (r->opt.baud_override && r->min_baud_seen != 0u && r->rate_overridden == 0u) {
        fprintf(out, "  bus       %s (%s, the rate the capture records too)\n",
                replay_baud_text(r->opt.baud, b, sizeof b), or_given(info->baud_source));
    } else if (r->opt.baud_override && r->min_baud_seen != 0u) {
        fprintf(out, "  bus       %s (%s; it overrides the capture's own rate, %s%s%s, for "
                     "every record)\n",
                replay_baud_text(r->opt.baud, b, sizeof b), or_given(info->baud_source),
                replay_baud_text(r->min_baud_seen, b2, sizeof b2),
                r->max_baud_seen != r->min_baud_seen ? " .. " : "",
                r->max_baud_seen != r->min_baud_seen ? replay_baud_text(r->max_baud_seen, b3, sizeof b3)
                                                     : "");
    } else if (r->min_baud_seen != 0u && r->min_baud_seen == r->max_baud_seen) {
        fprintf(out, "  bus       %s (recorded in the capture)\n",
                replay_baud_text(r->min_baud_seen, b, sizeof b));
    } else if (r->min_baud_seen != 0u) {
        fprintf(out, "  bus       %s .. %s (recorded per telegram)\n",
                replay_baud_text(r->min_baud_seen, b, sizeof b), replay_baud_text(r->max_baud_seen, b2,
                                                                     sizeof b2));
    } else {
        fprintf(out, "  bus       %s (%s)\n", replay_baud_text(r->opt.baud, b, sizeof b),
                or_given(info->baud_source));
    }
}

/* The card line: address, how it starts, the inverter; each with why when it was inferred. */
static void print_card(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    const replay_inferred_t *inf = info->inferred;
    fprintf(out, "  card      DFP21B at address %u (%s), ", r->opt.address,
            or_given(info->address_source));
    if (!r->opt.fixed_card_baud) {
        fputs("automatic baud search from the first record", out);
    } else if (inf != NULL && inf->fixed_source[0] != '\0') {
        fprintf(out, "fixed at the bus rate (%s)", inf->fixed_source);
    } else {
        fputs("fixed at the bus rate", out);
    }
    if (r->opt.inverter != CARD_INVERTER_SIM) {
        fputs("; inverter: none (PI echoes PO)\n", out);
    } else if (r->opt.inverter_delay_us != REPLAY_INVERTER_DELAY_US_DEFAULT && inf != NULL) {
        fprintf(out, "; inverter: emulated MOVIDRIVE, %u us per parameter service (%s)\n",
                r->opt.inverter_delay_us, inf->delay_source);
    } else {
        fputs("; inverter: emulated MOVIDRIVE\n", out);
    }
}

/* How the capture's times were taken, when it is not a line's or the command line said. */
static void print_timing_mode(FILE *out, const replay_report_info_t *info)
{
    const replay_inferred_t *inf = info->inferred;
    if (inf == NULL || (inf->timing == REPLAY_TIMING_LINE && !inf->timing_given)) {
        return;
    }
    fprintf(out, "  timing    %s (%s%s)\n", inf->timing == REPLAY_TIMING_RELAXED ? "relaxed" : "line",
            inf->timing_inferred ? "inferred: " : "", inf->timing_source);
}

/* What was replayed against what: the file, the card, the bus, the records, the card's end. */
static void print_header(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char b[32];
    fprintf(out, "replay of %s (%s): %llu records, %.6f s of bus time\n",
            info->file != NULL ? info->file : "(records)",
            info->format != NULL ? info->format : "?", (unsigned long long)r->records,
            (double)r->last_record_ns / 1e9);
    print_card(out, r, info);
    print_bus(out, r, info);
    print_timing_mode(out, info);
    if (info->source_note != NULL && info->source_note[0] != '\0') {
        fprintf(out, "  source    %s\n", info->source_note);
    }
    fprintf(out, "  records   %llu put on the bus, %llu the card's recorded answers (the card "
                 "makes its own), %llu damaged\n",
            (unsigned long long)r->injected, (unsigned long long)r->own_answers,
            (unsigned long long)r->damaged_count);
    if (r->untimed > 0u) {
        fprintf(out, "  time      %llu records without a time: synthetic times (end of the "
                     "previous telegram + %u bit times before an answer, %u before a request "
                     "or token)\n",
                (unsigned long long)r->untimed, REPLAY_SYNTH_GAP_ANSWER_BITS,
                REPLAY_SYNTH_GAP_REQUEST_BITS);
    }
    fprintf(out, "  card sent %llu telegrams; state at the end: %s, %s %s\n",
            (unsigned long long)r->card_tx, dp_state_name(dp_slave_state(&r->cs->card.dp)),
            dp_baud_state_name(dp_slave_baud_state(&r->cs->card.dp)),
            replay_baud_text(dp_slave_baud(&r->cs->card.dp), b, sizeof b));
}

/* Records the replay treated specially: odd rates, stray answers, an unanswered last request. */
static void print_notes(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    if (r->odd_rate_records > 0u) {
        char b[32];
        fprintf(out, "  note      %llu records carry a rate that is not a PROFIBUS rate (first: "
                     "%u bit/s): they went onto the bus at %s\n",
                (unsigned long long)r->odd_rate_records, r->first_odd_rate,
                replay_baud_text(r->opt.baud, b, sizeof b));
    }
    if (r->stray_answers > 0u) {
        fprintf(out, "  note      %llu answers from station %u in the capture follow no request "
                     "to it (not compared)\n",
                (unsigned long long)r->stray_answers, r->opt.address);
    }
    if (r->tail_unchecked) {
        char at[96];
        replay_where(info, r->tail_record, r->tail_position, at, sizeof at);
        fprintf(out, "  note      the capture ends with a request to the card (%s, %s): its "
                     "answer is not in the file, so it is not compared\n", at,
                replay_service_name(r->tail_service));
    }
}

static void print_backwards(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char at[96];
    replay_where(info, r->first_back_record, r->first_back_position, at, sizeof at);
    fprintf(out, "  timing    %llu records stamped earlier than the record before (first: %s; "
                 "at most %.6f s back)", (unsigned long long)r->backwards, at,
            (double)r->max_back_ns / 1e9);
    if (r->clock_steps > 0u) {
        fprintf(out, ": %llu clock steps, re-anchored (the record went onto the bus at the "
                     "spacing of the records before it, the records after it keep their "
                     "recorded spacing from it)", (unsigned long long)r->clock_steps);
    }
    if (r->out_of_order > 0u) {
        fprintf(out, "%s %llu out of order by less than that spacing (the record went onto "
                     "the bus right after the one before, the records after it at their "
                     "recorded times)", r->clock_steps > 0u ? ";" : ":",
                (unsigned long long)r->out_of_order);
    }
    fputc('\n', out);
}

/* Where the replay's timing departed from the capture's: moved telegrams, times going back,
 * shortened and whole long gaps. */
static void print_timing(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char at[96];
    if (r->deferred_beyond_resolution > 0u) {
        char b[32];
        replay_where(info, r->first_conflict_record, r->first_conflict_position, at, sizeof at);
        fprintf(out, "  timing    %llu telegrams would have overlapped the one before at %s "
                     "and went onto the bus later (at most %.1f us; first: %s): does the rate "
                     "fit the capture? (--baud)\n",
                (unsigned long long)r->deferred_beyond_resolution,
                replay_baud_text(r->opt.baud, b, sizeof b), (double)r->max_defer_ns / 1e3, at);
    }
    if (r->backwards > 0u) {
        print_backwards(out, r, info);
    }
    if (r->gaps_cut > 0u) {
        replay_where(info, r->first_cut_record, r->first_cut_position, at, sizeof at);
        fprintf(out, "  timing    %llu idle gaps shortened, by %.6f s of bus time in all (first: "
                     "before %s): after at least %.1f s of each the card had settled (rate "
                     "lost or fixed, no watchdog, drive at rest) and whole baud-search cycles "
                     "of %.6f s were left out; bus times after a shortened gap are that much "
                     "earlier than the capture's\n",
                (unsigned long long)r->gaps_cut, (double)r->cut_ns / 1e9, at,
                (double)REPLAY_GAP_SETTLE_NS / 1e9, (double)replay_search_cycle_ns() / 1e9);
    }
    if (r->gaps_turning > 0u) {
        fprintf(out, "  timing    %llu idle gaps longer than %.1f s simulated whole: the "
                     "emulated drive was still turning (its position changes with time)\n",
                (unsigned long long)r->gaps_turning, (double)REPLAY_GAP_SETTLE_NS / 1e9);
    }
}

/* Without --check: the file's problems and "replayed". */
static int print_unchecked_result(FILE *out, const replay_t *r, const replay_report_info_t *info,
                                  bool file_ok)
{
    if (info->file_error != NULL) {
        fprintf(out, "file error: %s\n", info->file_error);
    }
    if (info->interrupted) {
        fprintf(out, "interrupted after %llu records\n", (unsigned long long)r->records);
    }
    if (r->damaged_count > 0u) {
        fprintf(out, "damaged records: %llu\n", (unsigned long long)r->damaged_count);
        for (uint64_t i = 0; i < r->damaged_count && i < REPLAY_DAMAGED_LISTED; i++) {
            char at[96];
            replay_where(info, r->damaged[i].record, r->damaged[i].position, at, sizeof at);
            fprintf(out, "  %s: %s\n", at, r->damaged[i].problem);
        }
    }
    fprintf(out, "result: %s\n", file_ok ? "replayed" : "replay incomplete");
    return file_ok ? 0 : 1;
}

/* The first request whose answer differed: the octets, the card's state, why, what came before. */
static void print_first_mismatch(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char b[32];
    char at[96];
    const replay_mismatch_t *m = &r->first;
    replay_param_ctx_t pc = {0};
    replay_param_ctx_t expected_pc;
    replay_where(info, m->request.record, m->request.position, at, sizeof at);
    fprintf(out, "\nfirst mismatch: %s, t = %.6f s, %s\n", at, (double)m->request.t_ns / 1e9,
            replay_service_name(m->service));
    print_octets(out, "request", &m->request, &m->layout, &pc);
    expected_pc = pc; /* both answers belong to the one request */
    if (m->expected_present) {
        replay_where(info, m->expected.record, m->expected.position, at, sizeof at);
        fprintf(out, "  expected  %s:\n", at);
        print_octets(out, "", &m->expected, &m->layout, &expected_pc);
    } else {
        fprintf(out, "  expected  no answer (the next record is not from station %u)\n",
                r->opt.address);
    }
    if (m->actual_present) {
        fprintf(out, "  actual    the card's answer:\n");
        print_octets(out, "", &m->actual, &m->layout, &pc);
    } else {
        fprintf(out, "  actual    no answer from the card\n");
    }
    fprintf(out, "  card      %s when the request began; %s %s when it ended\n",
            dp_state_name(m->card_state),
            m->baud_state == DP_BAUD_SEARCH ? "searching the rate, listening at" : "rate",
            replay_baud_text(m->card_baud, b, sizeof b));
    explain(out, r, m);
    if (m->n_before > 0u) {
        fprintf(out, "  before it:\n");
        replay_param_ctx_t before_pc = {0};
        for (unsigned i = 0; i < m->n_before; i++) {
            print_kept(out, info, &m->before[i], &m->layout, &before_pc, "    ");
        }
    }
}

static void print_counts(FILE *out, const char *name, const replay_counts_t *c)
{
    fprintf(out, "%-22s %10llu %10llu %10llu %12llu %12llu\n", name,
            (unsigned long long)c->requests, (unsigned long long)c->matched,
            (unsigned long long)c->differ, (unsigned long long)c->capture_silent,
            (unsigned long long)c->card_silent);
}

/* Requests, matches and differences per service, and their total. */
static void print_service_table(FILE *out, const replay_t *r)
{
    fprintf(out, "\n%-22s %10s %10s %10s %12s %12s\n", "service", "requests", "match", "differ",
            "capture:", "card:");
    fprintf(out, "%-22s %10s %10s %10s %12s %12s\n", "", "", "", "", "no answer", "no answer");
    replay_counts_t sum = {0};
    for (unsigned i = 0; i < REPLAY_SVC_COUNT; i++) {
        const replay_counts_t *c = &r->svc[i];
        if (c->requests == 0u) {
            continue;
        }
        print_counts(out, replay_service_name((replay_service_t)i), c);
        sum.requests += c->requests;
        sum.matched += c->matched;
        sum.differ += c->differ;
        sum.capture_silent += c->capture_silent;
        sum.card_silent += c->card_silent;
    }
    print_counts(out, "total", &sum);
}

/* Mismatches, damaged records and the file's problems, below the table. */
static void print_check_details(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    char at[96];
    fprintf(out, "mismatches: %llu\n", (unsigned long long)r->mismatches);
    replay_print_list(out, r, info);
    if (r->unsolicited > 0u) {
        fprintf(out, "card telegrams outside any request's window: %llu\n",
                (unsigned long long)r->unsolicited);
    }
    fprintf(out, "damaged records: %llu\n", (unsigned long long)r->damaged_count);
    for (uint64_t i = 0; i < r->damaged_count && i < REPLAY_DAMAGED_LISTED; i++) {
        replay_where(info, r->damaged[i].record, r->damaged[i].position, at, sizeof at);
        fprintf(out, "  %s: %s\n", at, r->damaged[i].problem);
    }
    if (r->damaged_count > REPLAY_DAMAGED_LISTED) {
        fprintf(out, "  ... and %llu more\n",
                (unsigned long long)(r->damaged_count - REPLAY_DAMAGED_LISTED));
    }
    if (info->file_error != NULL) {
        fprintf(out, "file error: %s\n", info->file_error);
    }
    if (info->interrupted) {
        fprintf(out, "interrupted after %llu records\n", (unsigned long long)r->records);
    }
}

const char *replay_verdict(const replay_t *r, const replay_report_info_t *info, int *status)
{
    bool file_ok = info->file_error == NULL && !info->interrupted;
    const char *v = "MATCH";
    int st = 1;
    if (!r->opt.check) {
        v = file_ok ? "replayed" : "replay incomplete";
        st = file_ok ? 0 : 1;
    } else if (replay_total_requests(r) == 0u) {
        v = "NOTHING CHECKED";
    } else if (r->mismatches > 0u) {
        v = "DIFFERENT";
    } else if (!file_ok) {
        v = "INCOMPLETE";
    } else {
        st = 0;
    }
    if (status != NULL) {
        *status = st;
    }
    return v;
}

/* The verdict of --check; returns the exit status. */
static int print_verdict(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    int status = 0;
    const char *v = replay_verdict(r, info, &status);
    uint64_t total = replay_total_requests(r);
    bool file_ok = info->file_error == NULL && !info->interrupted;
    if (total == 0u) {
        fprintf(out, "result: %s: no request to station %u in the capture\n", v,
                r->opt.address);
    } else if (r->mismatches > 0u) {
        fprintf(out, "result: %s: %llu of %llu replies differ%s\n", v,
                (unsigned long long)r->mismatches, (unsigned long long)total,
                file_ok ? "" : " (and the file was not read to its end)");
    } else if (!file_ok) {
        fprintf(out, "result: %s: the %llu replies checked match, but the file was not read "
                     "to its end\n", v, (unsigned long long)total);
    } else {
        fprintf(out, "result: %s: all %llu replies match\n", v, (unsigned long long)total);
    }
    return status;
}

int replay_report(const replay_t *r, const replay_report_info_t *info, FILE *out)
{
    print_header(out, r, info);
    print_notes(out, r, info);
    print_timing(out, r, info);
    bool file_ok = info->file_error == NULL && !info->interrupted;
    if (!r->opt.check) {
        return print_unchecked_result(out, r, info, file_ok);
    }
    if (r->first.valid) {
        print_first_mismatch(out, r, info);
    }
    print_service_table(out, r);
    print_check_details(out, r, info);
    return print_verdict(out, r, info);
}
