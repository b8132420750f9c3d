/* Is a record exactly one FDL telegram? Replay hands damaged records to the card all the same, so
 * this only turns the core's verdict (fdl_check, protocol.md §A1.2) into the reason shown next
 * to them. */
#include <stdarg.h>
#include <stdio.h>

#include "capture/record.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"

static bool fail(char *problem, size_t max, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
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

static const char *octets_word(size_t n)
{
    return n == 1u ? "octet" : "octets";
}

static const char *telegram_name(uint8_t sd)
{
    switch (sd) {
    case FDL_SD1: return "SD1";
    case FDL_SD2: return "SD2";
    case FDL_SD3: return "SD3";
    case FDL_SD4: return "SD4 token";
    default: return "short acknowledgement";
    }
}

static bool fail_length(const uint8_t *frame, size_t len, const fdl_check_info_t *info,
                        char *problem, size_t max)
{
    const char *name = telegram_name(frame[0]);
    if (len < info->frame_len) {
        return fail(problem, max, "truncated %s: %zu of %s%zu octets", name, len,
                    info->frame_len_min ? "at least " : "", info->frame_len);
    }
    size_t extra = len - info->frame_len;
    bool has_ed = frame[0] != FDL_SD4 && frame[0] != FDL_SC;
    return fail(problem, max, "%zu %s after the %s", extra, octets_word(extra),
                has_ed ? "end delimiter" : name);
}

bool cap_check_telegram(const uint8_t *frame, size_t len, char *problem, size_t max)
{
    if (problem != NULL && max > 0u) {
        problem[0] = '\0';
    }
    fdl_check_info_t info;
    switch (fdl_check(frame, len, &info, NULL)) {
    case FDL_CHECK_OK: return true;
    case FDL_CHECK_EMPTY: return fail(problem, max, "empty");
    case FDL_CHECK_UNKNOWN_SD:
        return fail(problem, max, "unknown start delimiter 0x%02X", frame[0]);
    case FDL_CHECK_SHORT:
    case FDL_CHECK_LONG: return fail_length(frame, len, &info, problem, max);
    case FDL_CHECK_LE_MISMATCH:
        return fail(problem, max, "length octets differ (LE 0x%02X, LEr 0x%02X)", info.expected,
                    info.found);
    case FDL_CHECK_LE_RANGE:
        return fail(problem, max, "LE %u outside %u..%u", info.found, FDL_LE_MIN, FDL_LE_MAX);
    case FDL_CHECK_SD2_REPEAT:
        return fail(problem, max, "start delimiter repeated as 0x%02X, expected 0x%02X",
                    info.found, info.expected);
    case FDL_CHECK_ED:
        return fail(problem, max, "end delimiter 0x%02X, expected 0x%02X", info.found,
                    info.expected);
    case FDL_CHECK_FCS:
        return fail(problem, max, "bad FCS (0x%02X, computed 0x%02X)", info.found,
                    info.expected);
    }
    return fail(problem, max, "unchecked");
}
