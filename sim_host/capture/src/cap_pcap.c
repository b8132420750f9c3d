/* Classic pcap records, read a chunk at a time (cap_pcap.h). The layout is the one of the PCAP
 * capture file format (draft-ietf-opsawg-pcap, §4 file header, §5 packet record): after the
 * 24-octet file header, each record is a 16-octet header (seconds, microseconds or nanoseconds
 * as the magic says, captured length, length on the wire) and the captured octets, in the byte
 * order of the magic. */
#include "cap_pcap.h"

#include <inttypes.h>
#include <pcap/pcap.h>
#include <stdio.h>
#include <string.h>

#define MAGIC_MICRO 0xA1B2C3D4u
#define MAGIC_NANO 0xA1B23C4Du
/* libpcap's bound on a record's captured length for the PROFIBUS link types: a longer one is a
 * damaged record header, not a record. */
#define CAPLEN_MAX 262144u
#define NS_PER_US 1000u
#define NS_PER_S 1000000000u

static uint32_t get32(const uint8_t *p, bool big_endian)
{
    if (big_endian) {
        return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
    }
    return (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

bool cap_pcap_chunked_start(cap_reader_t *r)
{
    if (pcap_file(r->pcap) == NULL) {
        return false; /* not a savefile libpcap reads through stdio: it reads the records */
    }
    FILE *f = fopen(r->path, "rb");
    if (f == NULL) {
        return false; /* libpcap has it open: it reads the records then */
    }
    uint8_t m[4];
    size_t n = fread(m, 1, sizeof m, f);
    (void)fclose(f); /* opened for reading: nothing to lose */
    if (n != sizeof m) {
        return false;
    }
    for (int big = 0; big < 2; big++) {
        uint32_t v = get32(m, big != 0);
        if (v == MAGIC_MICRO || v == MAGIC_NANO) {
            r->chunk.big_endian = big != 0;
            r->chunk.nano = v == MAGIC_NANO;
            r->chunk.len = 0;
            r->chunk.pos = 0;
            r->chunk.on = true;
            return true;
        }
    }
    return false;
}

static size_t left(const cap_reader_t *r)
{
    return r->chunk.len - r->chunk.pos;
}

/* At least want octets from chunk.pos on, if the file has them: the rest of the chunk moves to
 * its start and the file fills it up. False when the file ends first (left() says how many
 * there are then). */
static bool have(cap_reader_t *r, size_t want)
{
    if (left(r) >= want) {
        return true;
    }
    memmove(r->chunk.buf, r->chunk.buf + r->chunk.pos, left(r));
    r->chunk.len = left(r);
    r->chunk.pos = 0;
    FILE *f = pcap_file(r->pcap);
    while (r->chunk.len < want) {
        size_t got = fread(r->chunk.buf + r->chunk.len, 1, sizeof r->chunk.buf - r->chunk.len, f);
        if (got == 0u) {
            return false;
        }
        r->chunk.len += got;
    }
    return true;
}

/* The record that starts at r->file_pos, number `record`, ends before its length says. */
static int fail(cap_reader_t *r, uint64_t record, const char *what, size_t got, uint32_t of)
{
    FILE *f = pcap_file(r->pcap);
    if (f != NULL && ferror(f)) {
        snprintf(r->error, sizeof r->error, "%s: record %" PRIu64 " at byte %" PRIu64
                 ": read error", r->path, record, r->file_pos);
    } else {
        snprintf(r->error, sizeof r->error, "%s: record %" PRIu64 " at byte %" PRIu64
                 ": truncated %s: %zu of %" PRIu32 " octets", r->path, record, r->file_pos,
                 what, got, of);
    }
    return -1;
}

/* A record longer than a chunk: its first octets are in rec already; the rest is passed over. */
static bool skip(cap_reader_t *r, uint32_t n)
{
    while (n > 0u) {
        if (!have(r, 1)) {
            return false;
        }
        size_t step = left(r) < n ? left(r) : n;
        r->chunk.pos += step;
        n -= (uint32_t)step;
    }
    return true;
}

int cap_pcap_next(cap_reader_t *r, cap_record_t *rec)
{
    if (!have(r, PCAP_RECORD_HEADER_LEN)) {
        FILE *f = pcap_file(r->pcap);
        if (left(r) == 0u && (f == NULL || !ferror(f))) {
            return 0;
        }
        return fail(r, r->records + 1, "record header", left(r), PCAP_RECORD_HEADER_LEN);
    }
    const uint8_t *h = r->chunk.buf + r->chunk.pos;
    bool be = r->chunk.big_endian;
    uint64_t frac = get32(h + 4, be);
    uint64_t t_ns = (uint64_t)get32(h, be) * NS_PER_S + (r->chunk.nano ? frac : frac * NS_PER_US);
    uint32_t caplen = get32(h + 8, be);
    uint32_t wire_len = get32(h + 12, be);
    if (caplen > CAPLEN_MAX) {
        snprintf(r->error, sizeof r->error, "%s: record %" PRIu64 " at byte %" PRIu64
                 ": record header damaged: %" PRIu32 " octets captured, more than %u",
                 r->path, r->records + 1, r->file_pos, caplen, CAPLEN_MAX);
        return -1;
    }
    r->chunk.pos += PCAP_RECORD_HEADER_LEN;
    uint32_t first = caplen < CAP_PCAP_CHUNK ? caplen : CAP_PCAP_CHUNK;
    if (!have(r, first)) {
        return fail(r, r->records + 1, "record", left(r), caplen);
    }
    cap_pcap_fill(r, rec, t_ns, r->chunk.buf + r->chunk.pos, caplen, wire_len);
    r->chunk.pos += first;
    if (!skip(r, caplen - first)) {
        return fail(r, r->records, "record", first, caplen); /* counted by cap_pcap_fill */
    }
    r->file_pos += PCAP_RECORD_HEADER_LEN + (uint64_t)caplen;
    return 1;
}
