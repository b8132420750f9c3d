/* pyprofibus PHY debug lines: "PHY-serial: TX   10 02 01 49 4C 16" (capture/text_import.h). */
#include "text_formats.h"

#define PHY_NAME_MAX 32u /* "serial", "fpga", ...: longer is no PHY name */

static bool phy_name_char(char c)
{
    char u = char_upper(c);
    return char_is_digit(c) || (u >= 'A' && u <= 'Z') || c == '_' || c == '-';
}

/* "PHY-serial: TX   10 02 01 49 4C 16": the prefix is the PHY's PFX ("PHY: ", "PHY-serial: ",
 * "PHY-fpga: "); returns false when the line does not start with one. */
bool phy_prefix(span_t line, size_t *after)
{
    if (!span_starts(line, "PHY")) {
        return false;
    }
    size_t i = 3;
    if (i < line.n && line.p[i] == '-') {
        i++;
        size_t start = i;
        while (i < line.n && i - start < PHY_NAME_MAX && phy_name_char(line.p[i])) {
            i++;
        }
        if (i == start) {
            return false;
        }
    }
    if (i >= line.n || line.p[i] != ':') {
        return false;
    }
    *after = i + 1u;
    return true;
}

text_line_result_t import_phy(text_import_state_t *st, span_t msg, cap_record_t *rec)
{
    msg = span_trim(msg);
    if (span_starts(msg, "RX (fragment)")) {
        return TEXT_LINE_SKIP;
    }
    size_t pos = 0;
    span_t tok = span_next_token(msg, &pos);
    if (span_is(tok, "TX")) {
        rec->dir = CAP_DIR_TX;
    } else if (span_is(tok, "RX")) {
        rec->dir = CAP_DIR_RX;
    } else {
        return text_bad(rec, "pyprofibus message, not a telegram: '%s'", quote_span(msg).s);
    }
    sink_t out = {.rec = rec};
    if (!hex_octets(span_rest(msg, pos), &out, false, rec->problem, sizeof rec->problem)) {
        rec->len = 0;
        rec->orig_len = 0;
        return TEXT_LINE_BAD;
    }
    return text_record_done(st, rec, TEXT_SHAPE_PHY);
}

