/* The check as a JSON object (dfp-sim replay --report json FILE, docs/replay.md "Report
 * files"). Written by hand: a handful of fields, strings escaped by replay_json_string. */
#include <string.h>

#include "replay/infer.h"
#include "replay/replay.h"
#include "report_out.h"

static void json_bool(FILE *out, bool b)
{
    fputs(b ? "true" : "false", out);
}

/* "name": {"<value_key>": value, "inferred": b, "source": "..."} without the value. */
static void json_source(FILE *out, bool inferred, const char *source, bool last)
{
    fputs(", \"inferred\": ", out);
    json_bool(out, inferred);
    fputs(", \"source\": ", out);
    replay_json_string(out, source);
    fputs(last ? "}\n" : "},\n", out);
}

/* What the first pass inferred, with the reasons the text report gives. */
static void json_inferred(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    const struct replay_inferred *inf = info->inferred;
    if (inf == NULL) {
        fputs("  \"inferred\": null,\n", out);
        return;
    }
    fprintf(out, "  \"inferred\": {\n    \"address\": {\"value\": %u", inf->address);
    json_source(out, inf->address_inferred, inf->address_source, false);
    fprintf(out, "    \"rate\": {\"baud\": %u", r->opt.baud);
    json_source(out, inf->baud_inferred, inf->baud_source, false);
    fputs("    \"timing\": {\"mode\": ", out);
    replay_json_string(out, inf->timing == REPLAY_TIMING_RELAXED ? "relaxed" : "line");
    json_source(out, inf->timing_inferred, inf->timing_source, false);
    fputs("    \"fixed_baud\": {\"value\": ", out);
    json_bool(out, inf->fixed_baud);
    json_source(out, inf->fixed_inferred, inf->fixed_source, false);
    fprintf(out, "    \"inverter_delay\": {\"us\": %u", inf->delay_us);
    json_source(out, inf->delay_inferred, inf->delay_source, true);
    fputs("  },\n", out);
}

static void json_counts(FILE *out, const replay_counts_t *c)
{
    fprintf(out, "\"requests\": %llu, \"matched\": %llu, \"differ\": %llu, \"missing\": %llu, "
                 "\"extra\": %llu, \"capture_no_answer\": %llu, \"card_no_answer\": %llu, "
                 "\"masked_octets\": %llu",
            (unsigned long long)c->requests, (unsigned long long)c->matched,
            (unsigned long long)c->differ, (unsigned long long)c->missing,
            (unsigned long long)c->extra, (unsigned long long)c->capture_silent,
            (unsigned long long)c->card_silent, (unsigned long long)c->masked_octets);
}

/* Counts per service kind with requests, then their total. */
static void json_services(FILE *out, const replay_t *r)
{
    replay_counts_t sum;
    memset(&sum, 0, sizeof sum);
    char key[64];
    fputs("  \"services\": [", out);
    bool first = true;
    for (unsigned i = 0; i < REPLAY_SVC_COUNT; i++) {
        const replay_counts_t *c = &r->svc[i];
        if (c->requests == 0u) {
            continue;
        }
        fputs(first ? "\n    {\"service\": " : ",\n    {\"service\": ", out);
        first = false;
        replay_json_string(out, replay_service_name((replay_service_t)i));
        fputs(", \"key\": ", out);
        replay_json_string(out, replay_service_key((replay_service_t)i, key, sizeof key));
        fputs(", ", out);
        json_counts(out, c);
        fputc('}', out);
        sum.requests += c->requests;
        sum.matched += c->matched;
        sum.differ += c->differ;
        sum.missing += c->missing;
        sum.extra += c->extra;
        sum.capture_silent += c->capture_silent;
        sum.card_silent += c->card_silent;
        sum.masked_octets += c->masked_octets;
    }
    fputs(first ? "],\n  \"total\": {" : "\n  ],\n  \"total\": {", out);
    json_counts(out, &sum);
    fputs("},\n", out);
}

static void json_mismatch(FILE *out, const replay_report_info_t *info, const replay_listed_t *m)
{
    static uint16_t diffs[CAP_MAX_RECORD];
    char text[256];
    fprintf(out, "      {\"number\": %llu, \"record\": %llu, \"position\": %llu, "
                 "\"position_unit\": ",
            (unsigned long long)m->number, (unsigned long long)m->record,
            (unsigned long long)m->position);
    replay_json_string(out, info->position_unit != NULL ? info->position_unit : "position");
    fprintf(out, ", \"time_s\": %.6f, \"service\": ", (double)m->t_ns / 1e9);
    replay_json_string(out, replay_service_name(m->service));
    fputs(", \"key\": ", out);
    replay_json_string(out, replay_service_key(m->service, text, sizeof text));
    replay_listed_what(m, text, sizeof text);
    fputs(",\n       \"what\": ", out);
    replay_json_string(out, text);
    fputs(",\n       \"request\": ", out);
    replay_json_hex(out, true, m->request, m->request_len);
    fputs(",\n       \"expected\": ", out);
    replay_json_hex(out, m->expected_present, m->expected, m->expected_len);
    if (m->expected_present) {
        fprintf(out, ", \"expected_record\": %llu", (unsigned long long)m->expected_record);
    } else {
        fputs(", \"expected_record\": null", out);
    }
    fputs(",\n       \"actual\": ", out);
    replay_json_hex(out, m->actual_present, m->actual, m->actual_len);
    size_t n = replay_listed_diffs(m, diffs, CAP_MAX_RECORD);
    fputs(",\n       \"differing_octets\": [", out);
    for (size_t i = 0; i < n; i++) {
        fprintf(out, "%s%u", i > 0u ? ", " : "", diffs[i]);
    }
    fprintf(out, "], \"data_offset\": %u, \"masked_octets\": %u}", m->data_offset, m->masked);
}

static void json_mismatches(FILE *out, const replay_t *r, const replay_report_info_t *info)
{
    replay_list_t *l = info->list;
    uint64_t kept = l != NULL && !l->failed ? l->kept : 0u;
    fprintf(out, "  \"mismatches\": {\"count\": %llu, \"listed\": %llu, \"not_listed\": %llu, "
                 "\"list_error\": ",
            (unsigned long long)r->mismatches, (unsigned long long)kept,
            (unsigned long long)(r->mismatches - kept));
    replay_json_string(out, l != NULL && l->failed ? l->error : NULL);
    fputs(", \"items\": [", out);
    replay_listed_t m;
    bool first = true;
    if (l != NULL && replay_list_rewind(l)) {
        while (replay_list_next(l, &m)) {
            fputs(first ? "\n" : ",\n", out);
            first = false;
            json_mismatch(out, info, &m);
        }
    }
    fputs(first ? "]},\n" : "\n  ]},\n", out);
}

int replay_report_json(const replay_t *r, const replay_report_info_t *info, FILE *out)
{
    int status = 0;
    const char *verdict = replay_verdict(r, info, &status);
    fputs("{\n  \"file\": ", out);
    replay_json_string(out, info->file);
    fputs(", \"format\": ", out);
    replay_json_string(out, info->format);
    fputs(",\n  \"verdict\": ", out);
    replay_json_string(out, verdict);
    fprintf(out, ", \"exit_status\": %d, \"checked\": ", status);
    json_bool(out, r->opt.check);
    fprintf(out, ",\n  \"records\": %llu, \"bus_time_s\": %.6f,\n",
            (unsigned long long)r->records, (double)r->last_record_ns / 1e9);
    fprintf(out, "  \"card\": {\"address\": %u, \"baud\": %u, \"fixed_baud\": ", r->opt.address,
            r->opt.baud);
    json_bool(out, r->opt.fixed_card_baud);
    fputs(", \"inverter\": ", out);
    replay_json_string(out, r->opt.inverter == CARD_INVERTER_SIM ? "sim" : "none");
    fprintf(out, ", \"inverter_delay_us\": %u},\n", r->opt.inverter_delay_us);
    json_inferred(out, r, info);
    json_services(out, r);
    fputs("  \"ignore\": ", out);
    replay_json_string(out, r->opt.mask != NULL && r->opt.mask->any ? r->opt.mask->text : NULL);
    fprintf(out, ", \"masked_octets\": %llu,\n", (unsigned long long)r->masked_octets);
    json_mismatches(out, r, info);
    fprintf(out, "  \"damaged_records\": %llu, \"file_error\": ",
            (unsigned long long)r->damaged_count);
    replay_json_string(out, info->file_error);
    fputs(", \"interrupted\": ", out);
    json_bool(out, info->interrupted);
    fputs("\n}\n", out);
    return ferror(out) ? -1 : 0;
}
