#include "capture/pcap_writer.h"
#include "sim_hal/path.h"

#include <errno.h>
#include <string.h>

static void put32(uint8_t *p, uint32_t v)
{
    /* pcap is written in the writer's byte order; we fix little-endian so files are identical
     * on every host and tests can compare bytes. */
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

int pcap_writer_open(pcap_writer_t *w, const char *path, uint32_t linktype, bool nanosecond,
                     uint64_t base_ns, char *err, size_t errlen)
{
    memset(w, 0, sizeof *w);
    char why[160];
    w->f = sim_fopen_write(path, why, sizeof why);
    if (w->f == NULL) {
        snprintf(err, errlen, "cannot write capture file %s: %s", path, why);
        return -1;
    }
    snprintf(w->path, sizeof w->path, "%s", path);
    w->nanosecond = nanosecond;
    w->base_ns = base_ns;
    uint8_t hdr[24];
    put32(&hdr[0], nanosecond ? 0xA1B23C4Du : 0xA1B2C3D4u);
    hdr[4] = 2; /* version 2.4 */
    hdr[5] = 0;
    hdr[6] = 4;
    hdr[7] = 0;
    put32(&hdr[8], 0);  /* thiszone */
    put32(&hdr[12], 0); /* sigfigs */
    put32(&hdr[16], 65535u);
    put32(&hdr[20], linktype);
    if (fwrite(hdr, 1, sizeof hdr, w->f) != sizeof hdr) {
        snprintf(err, errlen, "cannot write capture file %s: %s", path, strerror(errno));
        (void)fclose(w->f); /* the write error is the one reported */
        w->f = NULL;
        return -1;
    }
    return 0;
}

int pcap_writer_frame(pcap_writer_t *w, uint64_t t_ns, const uint8_t *frame, size_t len)
{
    if (w->f == NULL) {
        return -1;
    }
    uint64_t t = w->base_ns + t_ns;
    uint8_t rec[16];
    put32(&rec[0], (uint32_t)(t / 1000000000u));
    put32(&rec[4], (uint32_t)(w->nanosecond ? t % 1000000000u : (t % 1000000000u) / 1000u));
    put32(&rec[8], (uint32_t)len);
    put32(&rec[12], (uint32_t)len);
    if (fwrite(rec, 1, sizeof rec, w->f) != sizeof rec || fwrite(frame, 1, len, w->f) != len) {
        return -1;
    }
    w->records++;
    return 0;
}

int pcap_writer_close(pcap_writer_t *w)
{
    if (w->f == NULL) {
        return 0;
    }
    int rc = 0;
    if (fflush(w->f) != 0 || ferror(w->f)) {
        rc = -1;
    }
    if (fclose(w->f) != 0) {
        rc = -1;
    }
    w->f = NULL;
    return rc;
}
