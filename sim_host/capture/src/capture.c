/* Capture files: pcap and pcapng opened by libpcap (standard pcap records then read by
 * cap_pcap), text through text_import, LCM logs through cap_lcm; writing pcap (pcap_writer),
 * pcapng and text here.
 *
 * libpcap reads pcapng and checks its record headers, but it neither writes pcapng nor
 * exposes pcapng options; the one option replay needs (if_speed, the baud rate) is read here
 * from the interface description block before libpcap takes over. */
#include "capture/capture.h"

#include <errno.h>
#include <inttypes.h>
#include <pcap/pcap.h>
#include <string.h>
#include <sys/stat.h>

#include "capture/pcap_writer.h"
#include "cap_lcm.h"
#include "cap_pcap.h"
#include "hal/hal_uart.h"
#include "sim_hal/path.h"

#define PCAPNG_SHB 0x0A0D0D0Au
#define PCAPNG_IDB 0x00000001u
#define PCAPNG_EPB 0x00000006u
#define PCAPNG_BOM 0x1A2B3C4Du
#define PCAPNG_OPT_IF_SPEED 8u
#define PCAPNG_OPT_IF_TSRESOL 9u
#define PCAPNG_OPT_EPB_FLAGS 2u

const char *cap_format_name(cap_format_t f)
{
    switch (f) {
    case CAP_FORMAT_AUTO: return "auto";
    case CAP_FORMAT_PCAP: return "pcap";
    case CAP_FORMAT_PCAPNG: return "pcapng";
    case CAP_FORMAT_TEXT: return "text";
    case CAP_FORMAT_LCM: return "lcm";
    }
    return "?";
}

uint32_t cap_profibus_rate(uint64_t v)
{
    /* Anything else (another tool's idea of the interface speed, or damage) says nothing. */
    for (size_t k = 0; k < HAL_UART_NUM_BAUDS; k++) {
        if (v == hal_uart_bauds[k]) {
            return hal_uart_bauds[k];
        }
    }
    return 0;
}

const char *cap_position_unit(cap_format_t f)
{
    return f == CAP_FORMAT_TEXT ? "line" : f == CAP_FORMAT_LCM ? "event" : "byte";
}

bool cap_format_parse(const char *name, cap_format_t *out)
{
    static const cap_format_t all[] = {CAP_FORMAT_AUTO, CAP_FORMAT_PCAP, CAP_FORMAT_PCAPNG,
                                       CAP_FORMAT_TEXT, CAP_FORMAT_LCM};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        if (strcmp(name, cap_format_name(all[i])) == 0) {
            *out = all[i];
            return true;
        }
    }
    return false;
}

static uint32_t get32(const uint8_t *p, bool big)
{
    return big ? ((uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3])
               : ((uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0]);
}

static uint16_t get16(const uint8_t *p, bool big)
{
    return (uint16_t)(big ? (p[0] << 8 | p[1]) : (p[1] << 8 | p[0]));
}

static cap_format_t sniff(const uint8_t *head, size_t n)
{
    if (n >= 4) {
        uint32_t le = get32(head, false);
        if (le == 0xA1B2C3D4u || le == 0xD4C3B2A1u || le == 0xA1B23C4Du || le == 0x4D3CB2A1u) {
            return CAP_FORMAT_PCAP;
        }
        if (le == PCAPNG_SHB) {
            return CAP_FORMAT_PCAPNG;
        }
    }
    if (cap_lcm_sniff(head, n)) {
        return CAP_FORMAT_LCM;
    }
    /* Text: no NUL and mostly printable in the first block. A binary file of some other kind
     * would otherwise turn into thousands of "bad line" reports. */
    size_t odd = 0;
    for (size_t i = 0; i < n; i++) {
        if (head[i] == 0) {
            return CAP_FORMAT_AUTO;
        }
        if (head[i] < 0x20 && head[i] != '\n' && head[i] != '\r' && head[i] != '\t') {
            odd++;
        }
    }
    return odd * 20 > n ? CAP_FORMAT_AUTO : CAP_FORMAT_TEXT;
}

/* The baud rate from the first interface description block's if_speed, if any. Walks the
 * blocks before the first packet; every length is checked against what was read. */
static uint32_t pcapng_if_speed(FILE *f)
{
    uint8_t hdr[12];
    if (fread(hdr, 1, sizeof hdr, f) != sizeof hdr || get32(hdr, false) != PCAPNG_SHB) {
        return 0;
    }
    bool big = get32(&hdr[8], true) == PCAPNG_BOM;
    uint32_t len = get32(&hdr[4], big);
    long pos = (long)len;
    for (int blocks = 0; blocks < 16; blocks++) {
        if (fseek(f, pos, SEEK_SET) != 0 || fread(hdr, 1, 8, f) != 8) {
            return 0;
        }
        uint32_t type = get32(hdr, big);
        len = get32(&hdr[4], big);
        if (len < 12 || len > 65536u || (len & 3u) != 0) {
            return 0;
        }
        if (type == PCAPNG_IDB) {
            uint8_t body[65536];
            size_t body_len = len - 12u; /* without type, length and trailing length */
            if (fread(body, 1, body_len, f) != body_len || body_len < 8) {
                return 0;
            }
            for (size_t o = 8; o + 4 <= body_len;) {
                uint16_t code = get16(&body[o], big);
                uint16_t olen = get16(&body[o + 2], big);
                if (code == 0 || o + 4u + olen > body_len) {
                    break;
                }
                if (code == PCAPNG_OPT_IF_SPEED && olen == 8) {
                    uint64_t lo = get32(&body[o + 4], big);
                    uint64_t hi = get32(&body[o + 8], big);
                    uint64_t v = big ? (lo << 32 | hi) : (hi << 32 | lo);
                    return cap_profibus_rate(v);
                }
                o += 4u + ((olen + 3u) & ~3u);
            }
            return 0;
        }
        if (type != PCAPNG_SHB) {
            return 0; /* packets start: no interface said its speed */
        }
        pos += (long)len;
    }
    return 0;
}

static int open_pcap(cap_reader_t *r, char *err, size_t errlen)
{
    if (r->format == CAP_FORMAT_PCAPNG) {
        FILE *f = fopen(r->path, "rb");
        if (f != NULL) {
            r->if_baud = pcapng_if_speed(f);
            (void)fclose(f); /* opened for reading: nothing to lose */
        }
    }
    char perr[PCAP_ERRBUF_SIZE] = "";
    pcap_t *p = pcap_open_offline_with_tstamp_precision(r->path, PCAP_TSTAMP_PRECISION_NANO,
                                                        perr);
    if (p == NULL) {
        snprintf(err, errlen, "%s: not a readable %s file: %s", r->path,
                 cap_format_name(r->format), perr);
        return -1;
    }
    int dlt = pcap_datalink(p);
    if (dlt != 257 && dlt != 147) {
        const char *name = pcap_datalink_val_to_name(dlt);
        snprintf(err, errlen, "%s: link type %d (%s) is not PROFIBUS: expected 257 "
                 "(PROFIBUS_DL) or 147 (USER0)", r->path, dlt, name != NULL ? name : "unknown");
        pcap_close(p);
        return -1;
    }
    r->linktype = (uint32_t)dlt;
    r->pcap = p;
    if (r->format == CAP_FORMAT_PCAP) {
        r->file_pos = PCAP_FILE_HEADER_LEN; /* positions follow from the lengths (next_pcap) */
        (void)cap_pcap_chunked_start(r);
    }
    return 0;
}

int cap_reader_open(cap_reader_t *r, const char *path, cap_format_t format, char *err,
                    size_t errlen)
{
    return cap_reader_open_channel(r, path, format, NULL, err, errlen);
}

int cap_reader_open_channel(cap_reader_t *r, const char *path, cap_format_t format,
                            const char *lcm_channel, char *err, size_t errlen)
{
    memset(r, 0, sizeof *r);
    if (strlen(path) >= sizeof r->path) {
        snprintf(err, errlen, "capture file name too long (%zu characters)", strlen(path));
        return -1;
    }
    snprintf(r->path, sizeof r->path, "%s", path);
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        snprintf(err, errlen, "cannot open %s: %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode)) {
        r->file_size = (uint64_t)st.st_size;
    } else if (format != CAP_FORMAT_TEXT) {
        /* libpcap and the format sniffing reopen or seek; a pipe can only be read as text. */
        snprintf(err, errlen, "%s: not a regular file (only --format text reads a pipe)", path);
        (void)fclose(f); /* opened for reading: nothing to lose */
        return -1;
    }
    if (format == CAP_FORMAT_AUTO) {
        uint8_t head[512];
        size_t n = fread(head, 1, sizeof head, f);
        if (n == 0) {
            snprintf(err, errlen, "%s: empty file", path);
            (void)fclose(f); /* opened for reading: nothing to lose */
            return -1;
        }
        format = sniff(head, n);
        if (format == CAP_FORMAT_AUTO) {
            snprintf(err, errlen, "%s: unknown format (starts %02X %02X %02X %02X): not pcap, "
                     "pcapng, an LCM log or text", path, head[0], n > 1 ? head[1] : 0,
                     n > 2 ? head[2] : 0, n > 3 ? head[3] : 0);
            (void)fclose(f); /* opened for reading: nothing to lose */
            return -1;
        }
        rewind(f);
    }
    r->format = format;
    switch (format) {
    case CAP_FORMAT_PCAP:
    case CAP_FORMAT_PCAPNG:
        (void)fclose(f); /* opened for reading: nothing to lose */
        return open_pcap(r, err, errlen);
    case CAP_FORMAT_TEXT:
        r->file = f;
        text_import_init(&r->text);
        return 0;
    case CAP_FORMAT_LCM:
        (void)fclose(f); /* opened for reading: nothing to lose */
        return cap_lcm_open(r, lcm_channel, err, errlen);
    case CAP_FORMAT_AUTO:
        break;
    }
    (void)fclose(f); /* opened for reading: nothing to lose */
    snprintf(err, errlen, "%s: no format", path);
    return -1;
}

static void fill_record(cap_reader_t *r, cap_record_t *rec, const uint8_t *data, size_t len)
{
    rec->orig_len = len;
    rec->len = len > CAP_MAX_RECORD ? CAP_MAX_RECORD : len;
    memcpy(rec->data, data, rec->len);
    if (len > CAP_MAX_RECORD) {
        snprintf(rec->problem, sizeof rec->problem, "%zu octets, longer than any telegram", len);
    } else {
        (void)cap_check_telegram(rec->data, rec->len, rec->problem, sizeof rec->problem);
    }
    r->records++;
    rec->index = r->records;
}

void cap_pcap_fill(cap_reader_t *r, cap_record_t *rec, uint64_t t_ns, const uint8_t *data,
                   uint32_t caplen, uint32_t wire_len)
{
    /* Every field set here or in fill_record: clearing the record first was a tenth of the
     * reading. */
    rec->error_flags = 0;
    rec->dir = CAP_DIR_UNKNOWN;
    rec->position = r->file_pos;
    rec->has_time = true;
    rec->t_ns = t_ns;
    rec->baud = r->if_baud;
    fill_record(r, rec, data, caplen);
    if (wire_len > caplen) {
        snprintf(rec->problem, sizeof rec->problem, "cut when captured: %u of %u octets",
                 caplen, wire_len);
        rec->orig_len = wire_len;
    } else if (wire_len < caplen) {
        /* libpcap lets this through; the record header itself is damaged. */
        snprintf(rec->problem, sizeof rec->problem,
                 "record header damaged: %u octets captured of %u on the wire", caplen,
                 wire_len);
    }
}

static int next_pcap(cap_reader_t *r, cap_record_t *rec)
{
    if (r->chunk.on) {
        return cap_pcap_next(r, rec);
    }
    pcap_t *p = r->pcap;
    /* pcapng has blocks libpcap skips, so the position comes from the file. */
    FILE *f = r->format == CAP_FORMAT_PCAPNG ? pcap_file(p) : NULL;
    long at = f != NULL ? ftell(f) : (long)r->file_pos;
    struct pcap_pkthdr *h;
    const u_char *data;
    int rc = pcap_next_ex(p, &h, &data);
    if (rc == PCAP_ERROR_BREAK) {
        return 0;
    }
    if (rc != 1) {
        snprintf(r->error, sizeof r->error, "%s: record %" PRIu64 " at byte %ld: %s", r->path,
                 r->records + 1, at, pcap_geterr(p));
        return -1;
    }
    r->file_pos = at >= 0 ? (uint64_t)at : 0;
    cap_pcap_fill(r, rec, (uint64_t)h->ts.tv_sec * 1000000000ull + (uint64_t)h->ts.tv_usec, data,
                  h->caplen, h->len);
    if (f == NULL) {
        r->file_pos += PCAP_RECORD_HEADER_LEN + h->caplen;
    } else {
        long after = ftell(f);
        r->file_pos = after >= 0 ? (uint64_t)after : r->file_pos;
    }
    return 1;
}

static int next_text(cap_reader_t *r, cap_record_t *rec)
{
    char *line = r->line_buf;
    for (;;) {
        size_t n = 0;
        size_t len = 0;
        int c;
        bool any = false;
        while ((c = getc(r->file)) != EOF) {
            any = true;
            r->file_pos++;
            if (c == '\n') {
                break;
            }
            if (n < sizeof r->line_buf) {
                line[n++] = (char)c;
            }
            len++; /* the true length, so that an overlong line is reported, not cut */
        }
        if (!any) {
            if (ferror(r->file)) {
                snprintf(r->error, sizeof r->error, "%s: line %" PRIu64 ": read error: %s",
                         r->path, r->text.line + 1, strerror(errno));
                return -1;
            }
            return 0;
        }
        memset(rec, 0, offsetof(cap_record_t, data));
        text_line_result_t res =
            text_import_line(&r->text, line, len > n ? TEXT_IMPORT_MAX_LINE + 1 : len, rec);
        if (res == TEXT_LINE_SKIP) {
            continue;
        }
        rec->position = r->text.line;
        r->records++;
        rec->index = r->records;
        if (res == TEXT_LINE_RECORD && rec->problem[0] == '\0') {
            (void)cap_check_telegram(rec->data, rec->len, rec->problem, sizeof rec->problem);
        }
        return 1;
    }
}

int cap_reader_next(cap_reader_t *r, cap_record_t *rec)
{
    if (r->error[0] != '\0') {
        return -1;
    }
    switch (r->format) {
    case CAP_FORMAT_PCAP:
    case CAP_FORMAT_PCAPNG:
        return r->pcap != NULL ? next_pcap(r, rec) : 0;
    case CAP_FORMAT_TEXT:
        return r->file != NULL ? next_text(r, rec) : 0;
    case CAP_FORMAT_LCM:
        return cap_lcm_next(r, rec);
    case CAP_FORMAT_AUTO:
        break;
    }
    return 0;
}

void cap_reader_close(cap_reader_t *r)
{
    if (r->pcap != NULL) {
        pcap_close(r->pcap);
        r->pcap = NULL;
    }
    if (r->file != NULL) {
        (void)fclose(r->file); /* read only */
        r->file = NULL;
    }
    if (r->format == CAP_FORMAT_LCM) {
        cap_lcm_close(r);
    }
}

/* ---- writing ------------------------------------------------------------------------------ */

static void put32le(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static void put16le(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static bool write_all(cap_writer_t *w, const void *p, size_t n)
{
    return fwrite(p, 1, n, w->f) == n;
}

static bool write_pcapng_head(cap_writer_t *w)
{
    uint8_t shb[28];
    put32le(&shb[0], PCAPNG_SHB);
    put32le(&shb[4], sizeof shb);
    put32le(&shb[8], PCAPNG_BOM);
    put16le(&shb[12], 1);
    put16le(&shb[14], 0);
    memset(&shb[16], 0xFF, 8); /* section length unknown */
    put32le(&shb[24], sizeof shb);

    uint8_t idb[48];
    size_t o = 8;
    put16le(&idb[o], (uint16_t)w->opt.linktype);
    put16le(&idb[o + 2], 0);
    put32le(&idb[o + 4], 65535u);
    o += 8;
    put16le(&idb[o], PCAPNG_OPT_IF_TSRESOL);
    put16le(&idb[o + 2], 1);
    idb[o + 4] = w->opt.nanosecond ? 9 : 6;
    idb[o + 5] = idb[o + 6] = idb[o + 7] = 0;
    o += 8;
    if (w->opt.baud != 0) {
        put16le(&idb[o], PCAPNG_OPT_IF_SPEED);
        put16le(&idb[o + 2], 8);
        put32le(&idb[o + 4], w->opt.baud);
        put32le(&idb[o + 8], 0);
        o += 12;
    }
    put32le(&idb[o], 0); /* opt_endofopt */
    o += 4;
    put32le(&idb[0], PCAPNG_IDB);
    put32le(&idb[4], (uint32_t)(o + 4));
    put32le(&idb[o], (uint32_t)(o + 4));
    o += 4;
    return write_all(w, shb, sizeof shb) && write_all(w, idb, o);
}

static cap_format_t format_by_extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (dot != NULL && strcmp(dot, ".pcapng") == 0) {
        return CAP_FORMAT_PCAPNG;
    }
    if (dot != NULL && strcmp(dot, ".txt") == 0) {
        return CAP_FORMAT_TEXT;
    }
    return CAP_FORMAT_PCAP;
}

int cap_writer_open(cap_writer_t *w, const char *path, const cap_writer_options_t *opt,
                    uint64_t base_ns, char *err, size_t errlen)
{
    memset(w, 0, sizeof *w);
    w->opt = *opt;
    if (w->opt.format == CAP_FORMAT_AUTO) {
        w->opt.format = format_by_extension(path);
    }
    if (w->opt.linktype == 0) {
        w->opt.linktype = PCAP_LINKTYPE_PROFIBUS_DL;
    }
    if (w->opt.format == CAP_FORMAT_LCM) {
        snprintf(err, errlen, "%s: dfp-sim does not write LCM logs itself (use --lcm and "
                 "lcm-logger)", path);
        return -1;
    }
    if (w->opt.linktype != PCAP_LINKTYPE_PROFIBUS_DL && w->opt.linktype != PCAP_LINKTYPE_USER0) {
        snprintf(err, errlen, "link type %u: only 257 (PROFIBUS_DL) and 147 (USER0)",
                 w->opt.linktype);
        return -1;
    }
    w->base_ns = base_ns;
    snprintf(w->path, sizeof w->path, "%s", path);
    if (w->opt.format == CAP_FORMAT_PCAP) {
        pcap_writer_t pw;
        if (pcap_writer_open(&pw, path, w->opt.linktype, w->opt.nanosecond, base_ns, err,
                             errlen) != 0) {
            return -1;
        }
        w->f = pw.f;
        return 0;
    }
    char why[160];
    w->f = sim_fopen_write(path, why, sizeof why);
    if (w->f == NULL) {
        snprintf(err, errlen, "cannot write capture file %s: %s", path, why);
        return -1;
    }
    if (w->opt.format == CAP_FORMAT_PCAPNG && !write_pcapng_head(w)) {
        snprintf(err, errlen, "cannot write capture file %s: %s", path, strerror(errno));
        (void)fclose(w->f);
        w->f = NULL;
        return -1;
    }
    return 0;
}

static int write_epb(cap_writer_t *w, uint64_t t, const uint8_t *frame, size_t len,
                     cap_dir_t dir)
{
    uint64_t ts = w->opt.nanosecond ? t : t / 1000u;
    size_t padded = (len + 3u) & ~(size_t)3u;
    size_t opts = dir != CAP_DIR_UNKNOWN ? 8u + 4u : 0u;
    uint32_t total = (uint32_t)(28u + padded + opts + 4u);
    uint8_t hdr[28];
    put32le(&hdr[0], PCAPNG_EPB);
    put32le(&hdr[4], total);
    put32le(&hdr[8], 0); /* interface 0 */
    put32le(&hdr[12], (uint32_t)(ts >> 32));
    put32le(&hdr[16], (uint32_t)ts);
    put32le(&hdr[20], (uint32_t)len);
    put32le(&hdr[24], (uint32_t)len);
    static const uint8_t pad[4];
    uint8_t tail[16];
    size_t n = 0;
    if (dir != CAP_DIR_UNKNOWN) {
        put16le(&tail[0], PCAPNG_OPT_EPB_FLAGS);
        put16le(&tail[2], 4);
        put32le(&tail[4], dir == CAP_DIR_RX ? 1u : 2u); /* inbound / outbound */
        put32le(&tail[8], 0);                           /* opt_endofopt */
        n = 12;
    }
    put32le(&tail[n], total);
    n += 4;
    return write_all(w, hdr, sizeof hdr) && write_all(w, frame, len) &&
                   write_all(w, pad, padded - len) && write_all(w, tail, n)
               ? 0
               : -1;
}

int cap_writer_frame(cap_writer_t *w, uint64_t t_ns, const uint8_t *frame, size_t len,
                     cap_dir_t dir)
{
    if (w->f == NULL || len > 65535u) {
        return -1;
    }
    uint64_t t = w->base_ns + t_ns;
    int rc = -1;
    switch (w->opt.format) {
    case CAP_FORMAT_PCAP: {
        pcap_writer_t pw = {.f = w->f, .nanosecond = w->opt.nanosecond, .base_ns = 0};
        rc = pcap_writer_frame(&pw, t, frame, len);
        break;
    }
    case CAP_FORMAT_PCAPNG:
        rc = write_epb(w, t, frame, len, dir);
        break;
    case CAP_FORMAT_TEXT: {
        char line[3u * CAP_MAX_RECORD + 64u];
        size_t n = text_export_line(line, sizeof line - 1u, t, dir, frame, len);
        if (n > 0) {
            line[n++] = '\n';
            rc = write_all(w, line, n) ? 0 : -1;
        }
        break;
    }
    case CAP_FORMAT_AUTO:
    case CAP_FORMAT_LCM:
        break;
    }
    if (rc == 0) {
        w->records++;
    }
    return rc;
}

int cap_writer_close(cap_writer_t *w)
{
    /* The same flush-and-close for every format: pcap_writer's. */
    pcap_writer_t pw = {.f = w->f};
    w->f = NULL;
    return pcap_writer_close(&pw);
}
