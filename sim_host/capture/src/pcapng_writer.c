#include "capture/pcapng_writer.h"
#include "capture/pcap_writer.h" /* PCAP_LINKTYPE_* */
#include "sim_hal/path.h"

#include <errno.h>
#include <string.h>

#define BLOCK_SHB 0x0A0D0D0Au
#define BLOCK_IDB 0x00000001u
#define BLOCK_EPB 0x00000006u
#define BYTE_ORDER_MAGIC 0x1A2B3C4Du
#define OPT_END 0u
#define OPT_COMMENT 1u
#define OPT_SHB_USERAPPL 4u
#define OPT_IF_NAME 2u
#define OPT_IF_DESCRIPTION 3u
#define OPT_IF_SPEED 8u
#define OPT_IF_TSRESOL 9u
#define OPT_EPB_FLAGS 2u
/* Text options are cut here: names and descriptions, not documents. */
#define TEXT_OPT_MAX 256u
/* The largest block: an EPB with PCAPNG_MAX_OCTETS, its flags and a cut comment. */
#define BLOCK_MAX (32u + PCAPNG_MAX_OCTETS + 12u + 4u + TEXT_OPT_MAX + 4u)

/* A block being built: little-endian whatever the host, so files are identical everywhere and
 * tests can compare bytes. */
typedef struct block {
    uint8_t b[BLOCK_MAX];
    size_t n;
} block_t;

static void put16(block_t *k, uint32_t v)
{
    k->b[k->n++] = (uint8_t)v;
    k->b[k->n++] = (uint8_t)(v >> 8);
}

static void put32(block_t *k, uint32_t v)
{
    put16(k, v & 0xFFFFu);
    put16(k, v >> 16);
}

static void put_octets(block_t *k, const void *p, size_t len)
{
    memcpy(&k->b[k->n], p, len);
    k->n += len;
    while (k->n % 4u != 0u) {
        k->b[k->n++] = 0;
    }
}

static void put_text_opt(block_t *k, uint32_t code, const char *text)
{
    if (text == NULL) {
        return;
    }
    size_t len = strnlen(text, TEXT_OPT_MAX);
    put16(k, code);
    put16(k, (uint32_t)len);
    put_octets(k, text, len);
}

static void block_begin(block_t *k, uint32_t type)
{
    k->n = 0;
    put32(k, type);
    put32(k, 0); /* total length, set by block_end */
}

static void block_end(block_t *k)
{
    uint32_t total = (uint32_t)k->n + 4u;
    put32(k, total);
    for (unsigned i = 0; i < 4u; i++) {
        k->b[4 + i] = (uint8_t)(total >> (8u * i));
    }
}

static void fail(pcapng_writer_t *w, int err)
{
    if (!w->failed) {
        w->failed = true;
        snprintf(w->error, sizeof w->error, "cannot write capture file %s: %s", w->path,
                 strerror(err != 0 ? err : EIO));
    }
}

/* The buffer to the file, whole (the stream is unbuffered: this is one write). */
static int drain(pcapng_writer_t *w)
{
    if (w->failed) {
        return -1;
    }
    if (w->used > 0u) {
        errno = 0;
        size_t n = fwrite(w->buf, 1, w->used, w->f);
        if (n != w->used) {
            fail(w, errno);
            return -1;
        }
        w->used = 0;
    }
    return 0;
}

static int append(pcapng_writer_t *w, const block_t *k)
{
    if (w->failed) {
        return -1;
    }
    if (w->used + k->n > sizeof w->buf && drain(w) != 0) {
        return -1;
    }
    memcpy(&w->buf[w->used], k->b, k->n);
    w->used += k->n;
    return 0;
}

static void build_head(block_t *shb, block_t *idb, const pcapng_writer_opt_t *opt)
{
    block_begin(shb, BLOCK_SHB);
    put32(shb, BYTE_ORDER_MAGIC);
    put16(shb, 1); /* version 1.0 */
    put16(shb, 0);
    put32(shb, 0xFFFFFFFFu); /* section length unknown: the file grows as it is written */
    put32(shb, 0xFFFFFFFFu);
    put_text_opt(shb, OPT_SHB_USERAPPL, opt->userappl != NULL ? opt->userappl : "dfp-sim");
    put32(shb, OPT_END);
    block_end(shb);

    block_begin(idb, BLOCK_IDB);
    put16(idb, opt->linktype != 0u ? opt->linktype : PCAP_LINKTYPE_PROFIBUS_DL);
    put16(idb, 0);
    put32(idb, PCAPNG_MAX_OCTETS); /* snaplen */
    put_text_opt(idb, OPT_IF_NAME, opt->if_name);
    put_text_opt(idb, OPT_IF_DESCRIPTION, opt->if_description);
    if (opt->baud != 0u) {
        put16(idb, OPT_IF_SPEED);
        put16(idb, 8);
        put32(idb, opt->baud);
        put32(idb, 0);
    }
    put16(idb, OPT_IF_TSRESOL);
    put16(idb, 1);
    const uint8_t ns = 9; /* 10^-9 s */
    put_octets(idb, &ns, 1);
    put32(idb, OPT_END);
    block_end(idb);
}

int pcapng_writer_open(pcapng_writer_t *w, const char *path, const pcapng_writer_opt_t *opt,
                       char *err, size_t errlen)
{
    memset(w, 0, sizeof *w);
    if (opt->linktype != 0u && opt->linktype != PCAP_LINKTYPE_PROFIBUS_DL &&
        opt->linktype != PCAP_LINKTYPE_USER0) {
        snprintf(err, errlen, "link type %u: only 257 (PROFIBUS_DL) and 147 (USER0)",
                 opt->linktype);
        return -1;
    }
    char why[160];
    w->f = sim_fopen_write(path, why, sizeof why);
    if (w->f == NULL) {
        snprintf(err, errlen, "cannot write capture file %s: %s", path, why);
        return -1;
    }
    /* The writer's own buffer decides what reaches the file, and when: stdio's would split a
     * block across two writes. */
    (void)setvbuf(w->f, NULL, _IONBF, 0);
    snprintf(w->path, sizeof w->path, "%s", path);
    w->base_ns = opt->base_ns;
    block_t shb;
    block_t idb;
    build_head(&shb, &idb, opt);
    if (append(w, &shb) != 0 || append(w, &idb) != 0 || drain(w) != 0) {
        snprintf(err, errlen, "%s", w->error);
        (void)fclose(w->f); /* the write error is the one reported */
        w->f = NULL;
        return -1;
    }
    return 0;
}

int pcapng_writer_packet(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *octets, size_t len,
                         cap_dir_t dir, const char *comment)
{
    if (w->f == NULL || w->failed) {
        w->dropped++;
        return -1;
    }
    size_t kept = len < PCAPNG_MAX_OCTETS ? len : PCAPNG_MAX_OCTETS;
    uint64_t t = w->base_ns + t_ns;
    block_t k;
    block_begin(&k, BLOCK_EPB);
    put32(&k, 0); /* interface 0 */
    put32(&k, (uint32_t)(t >> 32));
    put32(&k, (uint32_t)t);
    put32(&k, (uint32_t)kept);
    put32(&k, len > UINT32_MAX ? UINT32_MAX : (uint32_t)len);
    put_octets(&k, octets, kept);
    if (dir != CAP_DIR_UNKNOWN) {
        put16(&k, OPT_EPB_FLAGS);
        put16(&k, 4);
        put32(&k, dir == CAP_DIR_RX ? 1u : 2u); /* inbound / outbound */
    }
    put_text_opt(&k, OPT_COMMENT, comment);
    if (dir != CAP_DIR_UNKNOWN || comment != NULL) {
        put32(&k, OPT_END);
    }
    block_end(&k);
    if (append(w, &k) != 0) {
        w->dropped++;
        return -1;
    }
    w->records++;
    return 0;
}

int pcapng_writer_telegram(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *f, size_t len)
{
    return pcapng_writer_packet(w, t_ns, f, len, CAP_DIR_UNKNOWN, NULL);
}

int pcapng_writer_garbled(pcapng_writer_t *w, uint64_t t_ns, const uint8_t *f, size_t len)
{
    return pcapng_writer_packet(w, t_ns, f, len, CAP_DIR_UNKNOWN, PCAPNG_COMMENT_GARBLED);
}

int pcapng_writer_flush(pcapng_writer_t *w)
{
    if (w->f == NULL) {
        return -1;
    }
    return drain(w);
}

int pcapng_writer_tick(pcapng_writer_t *w, uint64_t now_ns)
{
    if (now_ns - w->last_flush_ns < PCAPNG_FLUSH_NS && now_ns >= w->last_flush_ns) {
        return 0;
    }
    w->last_flush_ns = now_ns;
    return pcapng_writer_flush(w);
}

const char *pcapng_writer_error(pcapng_writer_t *w)
{
    if (!w->failed || w->error_told) {
        return NULL;
    }
    w->error_told = true;
    return w->error;
}

int pcapng_writer_close(pcapng_writer_t *w)
{
    if (w->f == NULL) {
        return 0;
    }
    int rc = drain(w);
    if (fclose(w->f) != 0) {
        fail(w, errno);
        rc = -1;
    }
    w->f = NULL;
    return rc;
}
