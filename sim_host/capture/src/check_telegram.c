/* Is a record exactly one FDL telegram? Replay hands damaged records to the card all the same, so
 * this only produces the reason shown next to them. It is written against protocol.md §A1.2
 * rather than reusing the core's fdl_rx, which assembles a byte stream with timing and would
 * have to be fed octet by octet to learn what is wrong with a finished record. */
#include <stdarg.h>
#include <stdio.h>

#include "capture/record.h"

#include "fdl_octets.h"

#define SD1_LEN 6u
#define SD3_LEN 14u
#define SD4_LEN 3u
#define SD2_HEADER 4u     /* 68 LE LEr 68 */
#define SD2_LE_MIN 4u     /* DA SA FC and at least one DU octet */
#define SD2_LE_MAX 249u

static bool fail(char *problem, size_t max, const char *fmt, ...)
{
    if (problem != NULL && max > 0u) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(problem, max, fmt, ap);
        va_end(ap);
    }
    return false;
}

static uint8_t sum_octets(const uint8_t *p, size_t n)
{
    uint8_t sum = 0;
    for (size_t i = 0; i < n; i++) {
        sum = (uint8_t)(sum + p[i]);
    }
    return sum;
}

static const char *octets_word(size_t n)
{
    return n == 1u ? "octet" : "octets";
}

/* A telegram of fixed or known total length: FCS over [fcs_from, total - 2), ED last. */
static bool check_framed(const uint8_t *frame, size_t len, size_t total, size_t fcs_from,
                         const char *name, char *problem, size_t max)
{
    if (len < total) {
        return fail(problem, max, "truncated %s: %zu of %zu octets", name, len, total);
    }
    if (frame[total - 1u] != ED) {
        return fail(problem, max, "end delimiter 0x%02X, expected 0x16", frame[total - 1u]);
    }
    uint8_t fcs = sum_octets(&frame[fcs_from], total - 2u - fcs_from);
    if (frame[total - 2u] != fcs) {
        return fail(problem, max, "bad FCS (0x%02X, computed 0x%02X)", frame[total - 2u], fcs);
    }
    if (len > total) {
        return fail(problem, max, "%zu %s after the end delimiter", len - total,
                    octets_word(len - total));
    }
    return true;
}

static bool check_unframed(size_t len, size_t total, const char *name, char *problem, size_t max)
{
    if (len < total) {
        return fail(problem, max, "truncated %s: %zu of %zu octets", name, len, total);
    }
    if (len > total) {
        return fail(problem, max, "%zu %s after the %s", len - total, octets_word(len - total),
                    name);
    }
    return true;
}

bool cap_check_telegram(const uint8_t *frame, size_t len, char *problem, size_t max)
{
    if (problem != NULL && max > 0u) {
        problem[0] = '\0';
    }
    if (frame == NULL || len == 0u) {
        return fail(problem, max, "empty");
    }
    switch (frame[0]) {
    case SD1:
        return check_framed(frame, len, SD1_LEN, 1u, "SD1", problem, max);
    case SD3:
        return check_framed(frame, len, SD3_LEN, 1u, "SD3", problem, max);
    case SD4:
        return check_unframed(len, SD4_LEN, "SD4 token", problem, max);
    case SC:
        return check_unframed(len, 1u, "short acknowledgement", problem, max);
    case SD2:
        break;
    default:
        return fail(problem, max, "unknown start delimiter 0x%02X", frame[0]);
    }
    if (len < SD2_HEADER) {
        return fail(problem, max, "truncated SD2: %zu of at least %u octets", len,
                    SD2_HEADER + SD2_LE_MIN + 2u);
    }
    uint8_t le = frame[1];
    if (frame[2] != le) {
        return fail(problem, max, "length octets differ (LE 0x%02X, LEr 0x%02X)", le, frame[2]);
    }
    if (le < SD2_LE_MIN || le > SD2_LE_MAX) {
        return fail(problem, max, "LE %u outside %u..%u", le, SD2_LE_MIN, SD2_LE_MAX);
    }
    if (frame[3] != SD2) {
        return fail(problem, max, "start delimiter repeated as 0x%02X, expected 0x68", frame[3]);
    }
    return check_framed(frame, len, (size_t)le + 6u, SD2_HEADER, "SD2", problem, max);
}
