/* Fuzz target for the capture readers (sim_host/capture): the input is a whole file — pcap,
 * pcapng, an LCM log or text, told apart by the reader itself, as `dfp-sim replay FILE` does.
 * The file lives in a memfd so that libpcap and the LCM log reader read it through their own
 * FILE paths, as they would a file on disk.
 *
 * Properties (abort on violation):
 *   - the reader ends (0 or -1) after at most one record per input octet, and stays ended;
 *   - records are numbered 1, 2, 3 ...; len <= CAP_MAX_RECORD and len <= orig_len; pcap/pcapng
 *     positions rise strictly and lie inside the file; text positions are line numbers that rise;
 *   - an error names the position ("at byte", "line", "event");
 *   - a record without a problem is exactly one telegram by the independent check of
 *     fuzz_common.h, parses inside its bounds and (canonical frames) re-encodes to itself; a
 *     record with a problem fails that check unless the problem is about the record (cut
 *     when captured, a damaged record header, an analyser's bad status);
 *   - text: every record read back through text_export_line + text_import_line is the same
 *     (octets, time, direction). */
#define _GNU_SOURCE
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "capture/capture.h"
#include "fuzz_common.h"

static int memfd = -1;
static char memfd_path[64];

static void check_text_round_trip(const cap_record_t *rec)
{
    char line[3u * CAP_MAX_RECORD + 64u];
    size_t n = text_export_line(line, sizeof line, rec->t_ns, rec->dir, rec->data, rec->len);
    PROPERTY(n > 0 && n < sizeof line, "text_export_line gave %zu for %zu octets", n, rec->len);
    text_import_state_t st;
    text_import_init(&st);
    static cap_record_t back;
    memset(&back, 0, sizeof back);
    text_line_result_t res = text_import_line(&st, line, n, &back);
    PROPERTY(res == TEXT_LINE_RECORD, "own export line not read back (%d): %s", (int)res, line);
    PROPERTY(back.len == rec->len && memcmp(back.data, rec->data, rec->len) == 0,
             "octets differ after the round trip: %s", line);
    PROPERTY(back.has_time && back.t_ns == rec->t_ns, "time differs after the round trip: %s",
             line);
    PROPERTY(back.dir == rec->dir, "direction differs after the round trip: %s", line);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (memfd < 0) {
        memfd = memfd_create("fuzz_capture", 0);
        if (memfd < 0) {
            abort();
        }
        snprintf(memfd_path, sizeof memfd_path, "/proc/self/fd/%d", memfd);
    }
    if (ftruncate(memfd, 0) != 0 || pwrite(memfd, data, size, 0) != (ssize_t)size) {
        abort();
    }
    static cap_reader_t r;
    static cap_record_t rec;
    char err[1200];
    if (cap_reader_open(&r, memfd_path, CAP_FORMAT_AUTO, err, sizeof err) != 0) {
        PROPERTY(err[0] != '\0', "open failed without a reason");
        return 0;
    }
    uint64_t last_pos = 0;
    uint64_t n = 0;
    int rc;
    while ((rc = cap_reader_next(&r, &rec)) == 1) {
        n++;
        PROPERTY(n <= size + 1u, "more records (%llu) than input octets (%zu)",
                 (unsigned long long)n, size);
        PROPERTY(rec.index == n, "record %llu numbered %llu", (unsigned long long)n,
                 (unsigned long long)rec.index);
        PROPERTY(rec.len <= CAP_MAX_RECORD && rec.len <= rec.orig_len,
                 "len %zu orig_len %zu", rec.len, rec.orig_len);
        if (r.format == CAP_FORMAT_PCAP || r.format == CAP_FORMAT_PCAPNG) {
            PROPERTY(rec.position < size && (n == 1 || rec.position > last_pos),
                     "position %llu after %llu in a %zu-octet file",
                     (unsigned long long)rec.position, (unsigned long long)last_pos, size);
        } else if (r.format == CAP_FORMAT_TEXT) {
            PROPERTY(n == 1 || rec.position > last_pos, "line %llu after %llu",
                     (unsigned long long)rec.position, (unsigned long long)last_pos);
        }
        last_pos = rec.position;
        bool valid = fz_frame_valid(rec.data, rec.len);
        if (rec.problem[0] == '\0') {
            PROPERTY(valid, "record %llu has no problem but is not one telegram (%zu octets, "
                     "first %02X)", (unsigned long long)n, rec.len, rec.len ? rec.data[0] : 0);
            fdl_msg_t m;
            (void)fz_parse_checked(rec.data, rec.len, &m); /* parse + canonical re-encode */
        } else if (strstr(rec.problem, "cut when captured") == NULL &&
                   strstr(rec.problem, "record header damaged") == NULL &&
                   strncmp(rec.problem, "analyser", 8) != 0) {
            /* Problems about the record, not its octets, may come with a valid telegram. */
            PROPERTY(!valid, "record %llu is a valid telegram but marked: %s",
                     (unsigned long long)n, rec.problem);
        }
        if (r.format == CAP_FORMAT_TEXT && rec.len > 0 && rec.has_time) {
            check_text_round_trip(&rec);
        }
    }
    PROPERTY(rc == 0 || rc == -1, "next returned %d", rc);
    if (rc < 0) {
        PROPERTY(strstr(r.error, "byte") != NULL || strstr(r.error, "line") != NULL ||
                     strstr(r.error, "event") != NULL,
                 "error without a position: %s", r.error);
    }
    PROPERTY(cap_reader_next(&r, &rec) == rc, "the reader did not stay ended");
    cap_reader_close(&r);
    return 0;
}
