/* capture_diff A B: do two captures hold the same telegrams at the same times (counted from
 * each file's first record)? Prints "same: N records" (exit 0) or the first difference with
 * record index, file positions, times and octets of both (exit 1); 2 when a file cannot be
 * read. The golden-capture test uses it to say which telegram changed when a capture made now
 * differs from the committed one. */
#include <inttypes.h>
#include <stdio.h>
#include <string.h>

#include "capture/capture.h"

static cap_reader_t ra;
static cap_reader_t rb;
static cap_record_t a;
static cap_record_t b;

static void show(const char *label, const char *path, const cap_record_t *r, uint64_t t0)
{
    printf("  %s %s record %" PRIu64 " at %" PRIu64 ", t = %.9f s:", label, path, r->index,
           r->position, (double)(r->t_ns - t0) / 1e9);
    for (size_t i = 0; i < r->len; i++) {
        printf(" %02X", r->data[i]);
    }
    printf("\n");
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: capture_diff A B\n");
        return 2;
    }
    char err[1024];
    if (cap_reader_open(&ra, argv[1], CAP_FORMAT_AUTO, err, sizeof err) != 0 ||
        cap_reader_open(&rb, argv[2], CAP_FORMAT_AUTO, err, sizeof err) != 0) {
        fprintf(stderr, "capture_diff: %s\n", err);
        return 2;
    }
    uint64_t t0a = 0;
    uint64_t t0b = 0;
    uint64_t n = 0;
    for (;;) {
        int ka = cap_reader_next(&ra, &a);
        int kb = cap_reader_next(&rb, &b);
        if (ka < 0 || kb < 0) {
            fprintf(stderr, "capture_diff: %s\n", ka < 0 ? ra.error : rb.error);
            return 2;
        }
        if (ka == 0 && kb == 0) {
            break;
        }
        if (ka == 0 || kb == 0) {
            printf("different length: %s ends after %" PRIu64 " records, the other goes on\n",
                   ka == 0 ? argv[1] : argv[2], n);
            show(ka == 0 ? "B" : "A", ka == 0 ? argv[2] : argv[1], ka == 0 ? &b : &a,
                 ka == 0 ? t0b : t0a);
            return 1;
        }
        if (n == 0u) {
            t0a = a.t_ns;
            t0b = b.t_ns;
        }
        n++;
        bool same = a.len == b.len && memcmp(a.data, b.data, a.len) == 0 &&
                    a.t_ns - t0a == b.t_ns - t0b;
        if (!same) {
            printf("first difference at telegram %" PRIu64 " (%s):\n", n,
                   a.len == b.len && memcmp(a.data, b.data, a.len) == 0 ? "time" : "octets");
            show("A", argv[1], &a, t0a);
            show("B", argv[2], &b, t0b);
            return 1;
        }
    }
    printf("same: %" PRIu64 " records\n", n);
    cap_reader_close(&ra);
    cap_reader_close(&rb);
    return 0;
}
