/* ProSoft AN-X-PBCAPT analyser lines (capture/text_import.h), e.g.
 *   "46: a 3.040,029 g 0,027 g.................. |........SD2 120<0 SRDH 8a 8a"
 * The analyser prints a decoded frame: reference, times and graphs, detailed status, delimiter
 * name, "DA<SA", SAPs, frame control mnemonic, data, maybe "ED" and "[FCS]". The frame is rebuilt
 * where the line has what a frame needs; docs/captures.md says what is lost (FCB/FCV). */
#include "text_formats.h"

#include <stdio.h>
#include <string.h>

#include "dp_slave/fdl_wire.h"

#define STATUS_COLUMNS 8u
/* FC bits 5-4: FCB/FCV of a request, station type of a reply (protocol.md §A1.4). The
 * analyser shows neither. */
#define FC_HIDDEN_BITS (FDL_FC_FCB | FDL_FC_FCV)

/* Frame control mnemonics of the AN-X-PBCAPT manual (page 27 of the AN-X-PB manual) with FCB and
 * FCV 0 (the analyser prints neither by default). SDAL..SDNH follow the manual's naming and its
 * equation example "SDNL"; the page listing them was not available (docs/captures.md). MDLY,
 * MKEP and MTM2 are the manual's codes for which fdl_wire.h has no name. */
static const struct {
    const char *name;
    uint8_t fc;
} prosoft_fc[] = {
    {"SDAL", FDL_FC_REQUEST | FDL_REQ_SDA_LOW},
    {"SDNL", FDL_FC_REQUEST | FDL_REQ_SDN_LOW},
    {"SDAH", FDL_FC_REQUEST | FDL_REQ_SDA_HIGH},
    {"SDNH", FDL_FC_REQUEST | FDL_REQ_SDN_HIGH},
    {"RFDL", FDL_FC_REQUEST | FDL_REQ_FDL_STATUS},
    {"MDLY", 0x4A},
    {"MKEP", 0x4B},
    {"SRDL", FDL_FC_REQUEST | FDL_REQ_SRD_LOW},
    {"SRDH", FDL_FC_REQUEST | FDL_REQ_SRD_HIGH},
    {"RIR", FDL_FC_REQUEST | FDL_REQ_IDENT},
    {"RLSR", FDL_FC_REQUEST | FDL_REQ_LSAP_STATUS},
    {"MTM2", 0xC0},
    {"OK", FDL_RSP_OK},
    {"UE", FDL_RSP_UE},
    {"RR", FDL_RSP_RR},
    {"RS", FDL_RSP_RS},
    {"DL", FDL_RSP_DL},
    {"NR", FDL_RSP_NR},
    {"DH", FDL_RSP_DH},
    {"RDL", FDL_RSP_RDL},
    {"RDH", FDL_RSP_RDH},
};

/* Detailed status columns (DetailSts): '.' or the column's letter. */
static const char prosoft_status_letters[STATUS_COLUMNS] = {'s', 'p', 'd', 'r',
                                                             'u', 'o', 'c', 'e'};
static const char *const prosoft_status_names[STATUS_COLUMNS] = {
    "stop bit", "parity", "start delimiter", "SD repeat", "underrun", "overrun", "checksum",
    "end delimiter"};

/* ---- tokens ------------------------------------------------------------------------------- */

static bool prosoft_status(span_t t)
{
    if (t.n < STATUS_COLUMNS) {
        return false;
    }
    for (size_t i = 0; i < STATUS_COLUMNS; i++) {
        if (t.p[i] != '.' && t.p[i] != prosoft_status_letters[i]) {
            return false;
        }
    }
    return true;
}

/* A gap or delta value ("0,027", "0.002,975", "5,666"). */
static bool prosoft_number(span_t t)
{
    if (t.n == 0u || !char_is_digit(t.p[0])) {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        char c = t.p[i];
        if (!char_is_digit(c) && c != '.' && c != ',' && c != ':') {
            return false;
        }
    }
    return true;
}

/* A gap/delta graph: 'g' or 'd', then '.' or '*' only, maybe ending in the '|' that closes it. */
static bool prosoft_graph(span_t t)
{
    if (t.n < 2u || (t.p[0] != 'g' && t.p[0] != 'd')) {
        return false;
    }
    for (size_t i = 1; i < t.n; i++) {
        if (t.p[i] != '.' && t.p[i] != '*' && !(t.p[i] == '|' && i + 1u == t.n)) {
            return false;
        }
    }
    return true;
}

/* "120<0", "*255<", "<0": returns false when t is not shaped like that. */
static bool prosoft_addresses(span_t t, span_t *da, span_t *sa)
{
    size_t lt = 0;
    while (lt < t.n && t.p[lt] != '<') {
        lt++;
    }
    if (lt == t.n) {
        return false;
    }
    *da = (span_t){t.p, lt};
    *sa = span_from(t, lt + 1u);
    if ((da->n == 0u && sa->n == 0u) || (da->n > 0u && !span_all_digits(*da)) ||
        (sa->n > 0u && !span_all_digits(*sa))) {
        return false;
    }
    return true;
}

static bool prosoft_fc_lookup(span_t t, uint8_t *fc)
{
    for (size_t i = 0; i < sizeof prosoft_fc / sizeof prosoft_fc[0]; i++) {
        if (span_is(t, prosoft_fc[i].name)) {
            *fc = prosoft_fc[i].fc;
            return true;
        }
    }
    return false;
}

static bool upper_word(span_t t)
{
    if (t.n == 0u || t.p[0] < 'A' || t.p[0] > 'Z') {
        return false;
    }
    for (size_t i = 0; i < t.n; i++) {
        char c = t.p[i];
        if (!((c >= 'A' && c <= 'Z') || char_is_digit(c))) {
            return false;
        }
    }
    return true;
}

static bool reference_number(span_t t)
{
    return t.n >= 2u && t.p[t.n - 1u] == ':' && span_all_digits((span_t){t.p, t.n - 1u});
}

/* Its reference "46:", its timestamp "a 3.040,029" / "a11.000,517" (a '.', ':' or ',' keeps
 * "a2 04 ..." hex out), "120<0" or a delimiter name first. */
bool prosoft_line(span_t line)
{
    size_t pos = 0;
    span_t first = span_next_token(line, &pos);
    span_t second = span_next_token(line, &pos);
    if (reference_number(first)) {
        return true;
    }
    if (span_is(first, "a")) {
        return second.n > 0u && char_is_digit(second.p[0]);
    }
    if (first.n >= 2u && first.p[0] == 'a' && char_is_digit(first.p[1])) {
        for (size_t i = 1; i < first.n; i++) {
            if (first.p[i] == '.' || first.p[i] == ':' || first.p[i] == ',') {
                return true;
            }
        }
        return false;
    }
    span_t da;
    span_t sa;
    span_t f = (first.n > 0u && first.p[0] == '*') ? span_from(first, 1u) : first;
    if (prosoft_addresses(f, &da, &sa)) {
        return true;
    }
    return start_delimiter_named(first) >= 0;
}

/* ---- reading the line --------------------------------------------------------------------- */

typedef struct prosoft_frame {
    int sd; /* -1: not written */
    bool have_da, have_sa, have_dsap, have_ssap, have_fc, have_fcs;
    unsigned da, sa, dsap, ssap;
    uint8_t fc, fcs;
    bool end_delimiter;
    bool marked_bad; /* '*' instead of the detailed status */
    uint8_t status;  /* detailed status columns with a letter, bit i = column i+1 */
    span_t data;     /* the data tokens as one span, from the first to the last */
    size_t data_octets;
    bool e5; /* "e5" alone: a short acknowledgement without delimiter names */
} prosoft_frame_t;

/* Where the frame's tokens are read: the analyser prints them in this order. */
typedef enum prosoft_phase {
    BEFORE_ADDRESSES,
    SAPS,
    DATA,
} prosoft_phase_t;

typedef struct prosoft_reader {
    prosoft_frame_t f;
    prosoft_phase_t phase;
} prosoft_reader_t;

/* A '?' is how the analyser marks what it could not decode ("FrmLen?(1)1e", "LE?(46)",
 * "SD?54"): nothing to rebuild from. */
static bool prosoft_decoded(span_t line, cap_record_t *rec)
{
    size_t pos = 0;
    for (span_t t = span_next_token(line, &pos); t.n > 0u; t = span_next_token(line, &pos)) {
        if (memchr(t.p, '?', t.n) != NULL) {
            return text_refuse(rec, "analyser reports a malformed frame: '%s'", quote_span(t).s);
        }
    }
    return true;
}

/* Past the reference, the time ("a 3.040,029"), gaps and deltas with their graphs and the
 * graph's closing '|'; *t becomes the first token of the frame (empty at the line's end). */
static bool prosoft_skip_header(span_t line, size_t *pos, span_t *t, cap_record_t *rec)
{
    *t = span_next_token(line, pos);
    if (reference_number(*t)) {
        *t = span_next_token(line, pos);
    }
    for (; t->n > 0u; *t = span_next_token(line, pos)) {
        if (t->p[0] == 'a' && !rec->has_time && (t->n == 1u || char_is_digit(t->p[1]))) {
            span_t value = t->n == 1u ? span_next_token(line, pos) : span_from(*t, 1u);
            parsed_time_t pt;
            time_parse_t r = text_parse_time(value, true, &pt);
            if (r != TIME_OK) {
                (void)text_bad_time(rec, r, value);
                return false;
            }
            rec->has_time = true;
            rec->t_ns = pt.ns;
        } else if ((span_is(*t, "d") || span_is(*t, "g"))) {
            size_t peek = *pos;
            span_t value = span_next_token(line, &peek);
            if (prosoft_number(value)) {
                *pos = peek;
            }
        } else if ((t->p[0] == 'd' || t->p[0] == 'g') && prosoft_number(span_from(*t, 1u))) {
            /* a gap or delta glued to its letter */
        } else if (!prosoft_graph(*t) && !span_is(*t, "|")) {
            break;
        }
    }
    return true;
}

/* The '|' closing a graph, the detailed status columns and the '*' of a bad frame, glued to
 * what follows them ("|........SD2", "s.d....e4<0"). */
static span_t prosoft_take_status(prosoft_frame_t *f, span_t t)
{
    while (t.n > 0u && t.p[0] == '|') {
        t = span_from(t, 1u);
    }
    if (prosoft_status(t)) {
        for (unsigned i = 0; i < STATUS_COLUMNS; i++) {
            if (t.p[i] != '.') {
                f->status = (uint8_t)(f->status | (1u << i));
            }
        }
        t = span_from(t, STATUS_COLUMNS);
    }
    if (t.n > 0u && t.p[0] == '*') {
        f->marked_bad = true;
        t = span_from(t, 1u);
    }
    return t;
}

static bool prosoft_take_addresses(prosoft_frame_t *f, span_t da, span_t sa, cap_record_t *rec)
{
    if (da.n > 0u) {
        if (!span_small_decimal(da, FDL_ADDR_MASK, &f->da)) {
            return text_refuse(rec, "destination '%s' is not a station address (0..127)",
                               quote_span(da).s);
        }
        f->have_da = true;
    }
    if (sa.n > 0u) {
        if (!span_small_decimal(sa, FDL_ADDR_MASK, &f->sa)) {
            return text_refuse(rec, "source '%s' is not a station address (0..127)",
                               quote_span(sa).s);
        }
        f->have_sa = true;
    }
    return true;
}

/* Status, start delimiter name, "e5" or the addresses (which end this phase). */
static bool prosoft_before_addresses(prosoft_reader_t *r, span_t t, cap_record_t *rec)
{
    prosoft_frame_t *f = &r->f;
    t = prosoft_take_status(f, t);
    if (t.n == 0u) {
        return true;
    }
    int sd = start_delimiter_named(t);
    if (sd >= 0) {
        if (f->sd >= 0) {
            return text_refuse(rec, "two start delimiters: '%s'", quote_span(t).s);
        }
        f->sd = sd;
        return true;
    }
    span_t da;
    span_t sa;
    if (prosoft_addresses(t, &da, &sa)) {
        r->phase = SAPS;
        return prosoft_take_addresses(f, da, sa, rec);
    }
    if ((span_is(t, "e5") || span_is(t, "E5")) && !f->e5) {
        f->e5 = true;
        return true;
    }
    if (upper_word(t) && prosoft_fc_lookup(t, &f->fc)) {
        return text_refuse(rec, "frame control %s without addresses (written with NoDst/NoSrc?)",
                           quote_span(t).s);
    }
    return text_refuse(rec, "unexpected '%s' before the addresses", quote_span(t).s);
}

/* "60^" (DSAP) and "62-" (SSAP), then the frame control mnemonic (which ends this phase). */
static bool prosoft_saps(prosoft_reader_t *r, span_t t, cap_record_t *rec)
{
    prosoft_frame_t *f = &r->f;
    span_t num = {t.p, t.n - 1u};
    char mark = t.p[t.n - 1u];
    if ((mark == '^' || mark == '-') && span_all_digits(num)) {
        unsigned sap;
        if (!span_small_decimal(num, FDL_AE_SAP_MASK, &sap)) {
            return text_refuse(rec, "SAP '%s' outside 0..63", quote_span(t).s);
        }
        if (mark == '^') {
            if (f->have_dsap || f->have_ssap) {
                return text_refuse(rec, "destination SAP out of place: '%s'", quote_span(t).s);
            }
            f->have_dsap = true;
            f->dsap = sap;
        } else {
            if (f->have_ssap) {
                return text_refuse(rec, "two source SAPs: '%s'", quote_span(t).s);
            }
            f->have_ssap = true;
            f->ssap = sap;
        }
        return true;
    }
    if (prosoft_fc_lookup(t, &f->fc)) {
        f->have_fc = true;
        r->phase = DATA;
        return true;
    }
    if (upper_word(t) && !span_all_hex(t)) {
        return text_refuse(rec, "unknown frame control '%s'", quote_span(t).s);
    }
    return text_refuse(rec, "no frame control before '%s'", quote_span(t).s);
}

/* Hex octets, then maybe "ED" (only written with the delimiter names) and the FCS "[3e]"
 * (ShowFcs) in either order. */
static bool prosoft_data(prosoft_reader_t *r, span_t t, cap_record_t *rec)
{
    prosoft_frame_t *f = &r->f;
    if (t.n >= 3u && t.p[0] == '[' && t.p[t.n - 1u] == ']') {
        span_t hex = {t.p + 1, t.n - 2u};
        if (f->have_fcs || hex.n > 2u || !span_all_hex(hex)) {
            return text_refuse(rec, "not an FCS: '%s'", quote_span(t).s);
        }
        f->have_fcs = true;
        f->fcs = (uint8_t)(hex.n == 2u ? char_hex_value(hex.p[0]) * 16 + char_hex_value(hex.p[1])
                                       : char_hex_value(hex.p[0]));
        return true;
    }
    if (f->sd >= 0 && span_is(t, "ED")) {
        f->end_delimiter = true;
        return true;
    }
    if (f->have_fcs || f->end_delimiter) {
        return text_refuse(rec, "data after the FCS or end delimiter: '%s'", quote_span(t).s);
    }
    sink_t count = {0};
    if (!hex_word(t, &count, rec->problem, sizeof rec->problem)) {
        rec->len = 0;
        rec->orig_len = 0;
        return false;
    }
    if (f->data_octets == 0u) {
        f->data.p = t.p;
    }
    f->data.n = (size_t)(t.p + t.n - f->data.p);
    f->data_octets += count.n;
    return true;
}

/* ---- rebuilding the frame ----------------------------------------------------------------- */

static void prosoft_problem_from_status(const prosoft_frame_t *f, cap_record_t *rec)
{
    if (rec->problem[0] != '\0') {
        return;
    }
    if (f->marked_bad) {
        (void)snprintf(rec->problem, sizeof rec->problem, "analyser marked the frame bad ('*')");
        return;
    }
    if (f->status == 0u) {
        return;
    }
    size_t n = (size_t)snprintf(rec->problem, sizeof rec->problem, "analyser status:");
    const char *separator = " ";
    for (unsigned i = 0; i < STATUS_COLUMNS && n < sizeof rec->problem; i++) {
        if ((f->status & (1u << i)) != 0u) {
            n += (size_t)snprintf(&rec->problem[n], sizeof rec->problem - n, "%s%s", separator,
                                  prosoft_status_names[i]);
            separator = ", ";
        }
    }
}

/* The telegram's own problem first; a rebuilt frame is usually clean, then the analyser's. */
static text_line_result_t prosoft_done(text_import_state_t *st, const prosoft_frame_t *f,
                                       cap_record_t *rec)
{
    text_line_result_t r = text_record_done(st, rec, TEXT_SHAPE_PROSOFT);
    if (r == TEXT_LINE_RECORD) {
        prosoft_problem_from_status(f, rec);
    }
    return r;
}

/* The start delimiter as written, else SD1 without a data unit and SD2 with one (SD3 only when
 * written: the analyser names it). False when the data unit does not fit it. */
static bool prosoft_frame_sd(const prosoft_frame_t *f, size_t du, uint8_t *sd, cap_record_t *rec)
{
    *sd = f->sd >= 0 ? (uint8_t)f->sd : (du == 0u ? FDL_SD1 : FDL_SD2);
    if (*sd == FDL_SD1 && du != 0u) {
        return text_refuse(rec, "SD1 with %zu data octets", du);
    }
    if (*sd == FDL_SD3 && du != FDL_SD3_DU_LEN) {
        return text_refuse(rec, "SD3 with %zu data octets, not 8", du);
    }
    if (*sd == FDL_SD2 && du + 3u > FDL_LE_MAX) {
        return text_refuse(rec, "%zu data octets, more than an SD2 holds", du);
    }
    return true;
}

/* SD1, SD2 or SD3 with the SAPs that were written (the analyser may show only one) and the FCS
 * over DA to the data's end. A written FCS that differs from it only in FC bits 5-4 restores
 * them; any other written FCS is kept as written, and the check reports it. */
static text_line_result_t prosoft_build_frame(text_import_state_t *st, const prosoft_frame_t *f,
                                              cap_record_t *rec)
{
    size_t du = (f->have_dsap ? 1u : 0u) + (f->have_ssap ? 1u : 0u) + f->data_octets;
    uint8_t sd;
    if (!prosoft_frame_sd(f, du, &sd, rec)) {
        return TEXT_LINE_BAD;
    }
    sink_t out = {.rec = rec};
    if (sd == FDL_SD2) {
        sink_put(&out, FDL_SD2);
        sink_put(&out, (uint8_t)(du + 3u));
        sink_put(&out, (uint8_t)(du + 3u));
    }
    sink_put(&out, sd);
    size_t da_at = out.n;
    sink_put(&out, (uint8_t)(f->da | (f->have_dsap ? FDL_ADDR_EXT : 0u)));
    sink_put(&out, (uint8_t)(f->sa | (f->have_ssap ? FDL_ADDR_EXT : 0u)));
    sink_put(&out, f->fc);
    if (f->have_dsap) {
        sink_put(&out, (uint8_t)f->dsap);
    }
    if (f->have_ssap) {
        sink_put(&out, (uint8_t)f->ssap);
    }
    char ignored[8];
    (void)hex_octets(f->data, &out, false, ignored, sizeof ignored);
    uint8_t fcs = sink_fcs(&out, da_at);
    if (f->have_fcs && f->fcs != fcs) {
        uint8_t diff = (uint8_t)(f->fcs - fcs);
        if ((diff & ~FC_HIDDEN_BITS) == 0u && (f->fc & FC_HIDDEN_BITS) == 0u) {
            rec->data[da_at + 2u] = (uint8_t)(f->fc | diff);
        }
        fcs = f->fcs;
    }
    sink_put(&out, fcs);
    sink_put(&out, FDL_ED);
    return prosoft_done(st, f, rec);
}

static text_line_result_t prosoft_build(text_import_state_t *st, const prosoft_frame_t *f,
                                        cap_record_t *rec)
{
    sink_t out = {.rec = rec};
    if (!f->have_da && !f->have_sa) {
        if (f->sd == FDL_SC || (f->sd < 0 && f->e5 && !f->have_fc)) {
            sink_put(&out, FDL_SC);
            return prosoft_done(st, f, rec);
        }
        return text_bad(rec, "no addresses (written with NoDst/NoSrc?)");
    }
    if (!f->have_da) {
        return text_bad(rec, "no destination address (written with NoDst?)");
    }
    if (!f->have_sa) {
        return text_bad(rec, "no source address (written with NoSrc?)");
    }
    if (f->sd == FDL_SC) {
        return text_bad(rec, "SC with addresses");
    }
    bool token = !f->have_fc && !f->have_dsap && !f->have_ssap && f->data_octets == 0u;
    if (f->sd == FDL_SD4 || (f->sd < 0 && token)) {
        if (!token) {
            return text_bad(rec, "SD4 token with frame control or data");
        }
        if (f->have_fcs) {
            return text_bad(rec, "SD4 token with an FCS");
        }
        sink_put(&out, FDL_SD4);
        sink_put(&out, (uint8_t)f->da);
        sink_put(&out, (uint8_t)f->sa);
        return prosoft_done(st, f, rec);
    }
    if (!f->have_fc) {
        return text_bad(rec, "no frame control");
    }
    return prosoft_build_frame(st, f, rec);
}

text_line_result_t import_prosoft(text_import_state_t *st, span_t line, cap_record_t *rec)
{
    if (!prosoft_decoded(line, rec)) {
        return TEXT_LINE_BAD;
    }
    size_t pos = 0;
    span_t t;
    if (!prosoft_skip_header(line, &pos, &t, rec)) {
        return TEXT_LINE_BAD;
    }
    prosoft_reader_t r = {.f = {.sd = -1, .data = {line.p, 0}}, .phase = BEFORE_ADDRESSES};
    for (; t.n > 0u; t = span_next_token(line, &pos)) {
        bool ok;
        switch (r.phase) {
        case BEFORE_ADDRESSES:
            ok = prosoft_before_addresses(&r, t, rec);
            break;
        case SAPS:
            ok = prosoft_saps(&r, t, rec);
            break;
        default:
            ok = prosoft_data(&r, t, rec);
            break;
        }
        if (!ok) {
            return TEXT_LINE_BAD;
        }
    }
    return prosoft_build(st, &r.f, rec);
}
