/* --ignore: octets of the card's answers the check leaves out (replay/mask.h). */
#include "replay/mask.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Short names for the services a plant's values show up in most. */
static const struct {
    const char *alias;
    replay_service_t service;
} aliases[] = {
    {"dx", REPLAY_SVC_DATA_EXCHANGE}, {"diag", REPLAY_SVC_SLAVE_DIAG},
    {"status", REPLAY_SVC_FDL_STATUS}, {"prm", REPLAY_SVC_SET_PRM},
    {"cfg", REPLAY_SVC_CHK_CFG},
};

/* Names compare in lower case with blanks and '-' as '_'. */
static char key_char(char c)
{
    if (c == ' ' || c == '-') {
        return '_';
    }
    return (char)tolower((unsigned char)c);
}

static void normalise(const char *in, size_t len, char *out, size_t max)
{
    size_t i = 0;
    for (; i < len && in[i] != '\0' && i + 1u < max; i++) {
        out[i] = key_char(in[i]);
    }
    if (max > 0u) {
        out[i] = '\0';
    }
}

const char *replay_service_key(replay_service_t s, char *buf, size_t max)
{
    const char *name = replay_service_name(s);
    normalise(name, strlen(name), buf, max);
    return buf;
}

static bool service_from(const char *name, size_t len, replay_service_t *out)
{
    char want[64];
    char key[64];
    if (len == 0u || len >= sizeof want) {
        return false;
    }
    normalise(name, len, want, sizeof want);
    for (size_t i = 0; i < sizeof aliases / sizeof aliases[0]; i++) {
        if (strcmp(want, aliases[i].alias) == 0) {
            *out = aliases[i].service;
            return true;
        }
    }
    for (unsigned s = 0; s < REPLAY_SVC_COUNT; s++) {
        if (strcmp(want, replay_service_key((replay_service_t)s, key, sizeof key)) == 0) {
            *out = (replay_service_t)s;
            return true;
        }
    }
    return false;
}

bool replay_service_parse(const char *name, replay_service_t *out)
{
    return service_from(name, strlen(name), out);
}

/* A decimal number, all of text; false for anything else (signs, blanks, hex, overflow). */
static bool number(const char *text, size_t len, unsigned long *out)
{
    char buf[16];
    if (len == 0u || len >= sizeof buf || !isdigit((unsigned char)text[0])) {
        return false;
    }
    memcpy(buf, text, len);
    buf[len] = '\0';
    char *end = NULL;
    errno = 0;
    *out = strtoul(buf, &end, 10);
    return errno == 0 && *end == '\0';
}

/* "N" or "N-M" (M may repeat the prefix: PI2-PI3) within lo..hi. */
static bool range(const char *item, const char *text, size_t len, const char *prefix,
                  unsigned long lo, unsigned long hi, unsigned long r[2], char *err, size_t max)
{
    const char *dash = memchr(text, '-', len);
    size_t first = dash != NULL ? (size_t)(dash - text) : len;
    const char *second = dash != NULL ? dash + 1 : text;
    size_t second_len = dash != NULL ? len - first - 1u : len;
    size_t plen = strlen(prefix);
    if (dash != NULL && plen > 0u && second_len > plen && strncasecmp(second, prefix, plen) == 0) {
        second += plen;
        second_len -= plen;
    }
    if (!number(text, first, &r[0]) || !number(second, second_len, &r[1])) {
        snprintf(err, max, "'%s': %s is not a number or a range N-M", item, text);
        return false;
    }
    if (r[1] < r[0]) {
        snprintf(err, max, "'%s': the range runs backwards (%lu after %lu)", item, r[1], r[0]);
        return false;
    }
    if (r[0] < lo || r[1] > hi) {
        snprintf(err, max, "'%s': %s%lu..%lu only", item, prefix, lo, hi);
        return false;
    }
    return true;
}

static void set_bits(uint8_t *bits, unsigned long from, unsigned long to)
{
    for (unsigned long n = from; n <= to; n++) {
        bits[n / 8u] = (uint8_t)(bits[n / 8u] | (1u << (n % 8u)));
    }
}

/* One item: PIn[-m] or SERVICE:n[-m]. */
static bool add_item(replay_mask_t *m, const char *item, char *err, size_t max)
{
    unsigned long r[2];
    size_t len = strlen(item);
    if (len == 0u) {
        snprintf(err, max, "an empty item (two commas?)");
        return false;
    }
    if (len > 2u && strncasecmp(item, "PI", 2) == 0 && isdigit((unsigned char)item[2])) {
        if (!range(item, item + 2, len - 2u, "PI", 1u, REPLAY_MASK_PI_WORDS, r, err, max)) {
            return false;
        }
        set_bits(m->pi, r[0] - 1u, r[1] - 1u);
        return true;
    }
    const char *colon = strchr(item, ':');
    if (colon == NULL) {
        snprintf(err, max, "'%s': neither PIn nor SERVICE:OCTETS (e.g. PI2, dx:4-7, diag:6)",
                 item);
        return false;
    }
    replay_service_t s;
    if (!service_from(item, (size_t)(colon - item), &s)) {
        snprintf(err, max, "'%s': unknown service '%.*s' (dx, diag, status, prm, cfg, or a "
                           "service of the report's table: data_exchange, msac1_read ...)",
                 item, (int)(colon - item), item);
        return false;
    }
    const char *octets = colon + 1;
    if (!range(item, octets, strlen(octets), "", 0u, REPLAY_MASK_OCTETS - 1u, r, err, max)) {
        return false;
    }
    set_bits(m->du[s], r[0], r[1]);
    return true;
}

static void add_text(replay_mask_t *m, const char *spec)
{
    size_t used = strlen(m->text);
    size_t room = sizeof m->text - used;
    int k = snprintf(m->text + used, room, "%s%s", used > 0u ? "," : "", spec);
    if (k < 0 || (size_t)k >= room) {
        memcpy(m->text + sizeof m->text - 4u, "...", 4u);
    }
}

bool replay_mask_add(replay_mask_t *m, const char *spec, char *err, size_t errlen)
{
    replay_mask_t work = *m;
    const char *p = spec;
    for (;;) {
        const char *comma = strchr(p, ',');
        size_t len = comma != NULL ? (size_t)(comma - p) : strlen(p);
        char item[64];
        if (len >= sizeof item) {
            snprintf(err, errlen, "'%.20s...': too long for an item", p);
            return false;
        }
        memcpy(item, p, len);
        item[len] = '\0';
        if (!add_item(&work, item, err, errlen)) {
            return false;
        }
        if (comma == NULL) {
            break;
        }
        p = comma + 1;
    }
    work.any = true;
    add_text(&work, spec);
    *m = work;
    return true;
}

unsigned replay_mask_answer(const replay_mask_t *m, replay_service_t service, int pi_offset,
                            const uint8_t *answer, size_t len, uint8_t *bits, size_t bits_len)
{
    memset(bits, 0, bits_len);
    if (m == NULL || !m->any) {
        return 0u;
    }
    replay_frame_t f;
    replay_frame_parse(answer, len, &f);
    if (f.du == NULL || f.du_len == 0u || len < 2u) {
        return 0u; /* no data unit: SC, a short answer, garbage */
    }
    size_t off = (size_t)(f.du - answer);
    bool pi = pi_offset >= 0 &&
              (service == REPLAY_SVC_DATA_EXCHANGE || service == REPLAY_SVC_RD_INP);
    unsigned n = 0;
    for (size_t i = 0; i < f.du_len && off + i < bits_len * 8u; i++) {
        bool masked = i < REPLAY_MASK_OCTETS && replay_bit(m->du[service], i);
        if (!masked && pi && i >= (size_t)pi_offset) {
            size_t word = (i - (size_t)pi_offset) / 2u;
            masked = word < REPLAY_MASK_PI_WORDS && replay_bit(m->pi, word);
        }
        if (masked) {
            bits[(off + i) / 8u] = (uint8_t)(bits[(off + i) / 8u] | (1u << ((off + i) % 8u)));
            n++;
        }
    }
    size_t fcs = len - 2u;
    if (n > 0u && fcs >= off + f.du_len && fcs < bits_len * 8u) {
        bits[fcs / 8u] = (uint8_t)(bits[fcs / 8u] | (1u << (fcs % 8u)));
        n++;
    }
    return n;
}
