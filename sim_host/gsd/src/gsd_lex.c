/* Physical lines into logical ones: comments cut (a ';' outside quotes), continuation lines
 * ('\' at the end) joined, blanks trimmed; then each logical line to gsd_statement. The same
 * for a text in memory and for a file read line by line into a fixed buffer. */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "gsd_internal.h"

bool gsd_fail(gsd_parser_t *p, uint32_t line, const char *fmt, ...)
{
    if (p->failed) return false;
    p->failed = true;
    if (p->err == NULL || p->n == 0u) return false;
    int w;
    if (p->name != NULL) {
        w = line != 0u ? snprintf(p->err, p->n, "%s:%u: ", p->name, (unsigned)line)
                       : snprintf(p->err, p->n, "%s: ", p->name);
    } else {
        w = line != 0u ? snprintf(p->err, p->n, "line %u: ", (unsigned)line) : 0;
    }
    if (w < 0) w = 0;
    if ((size_t)w < p->n) {
        va_list ap;
        va_start(ap, fmt);
        (void)vsnprintf(p->err + w, p->n - (size_t)w, fmt, ap);
        va_end(ap);
    }
    return false;
}

/* A DOS end-of-file mark (Ctrl-Z) counts as a blank: old editors leave one. */
static bool is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\x1a' || c == '\f' || c == '\v';
}

/* The length of the line without its comment. */
static size_t cut_comment(const char *s, size_t len)
{
    bool quoted = false;
    for (size_t i = 0; i < len; i++) {
        if (s[i] == '"') {
            quoted = !quoted;
        } else if (s[i] == ';' && !quoted) {
            return i;
        }
    }
    return len;
}

static bool append(gsd_parser_t *p, const char *s, size_t len)
{
    if (p->len + len > GSD_MAX_LINE) {
        return gsd_fail(p, p->first_line,
                        "longer than %u characters (with its continuation lines)",
                        GSD_MAX_LINE);
    }
    memcpy(p->buf + p->len, s, len);
    p->len += len;
    p->buf[p->len] = '\0';
    return true;
}

static bool logical_line(gsd_parser_t *p)
{
    char *s = p->buf;
    size_t len = p->len;
    while (len > 0u && is_blank(*s)) {
        s++;
        len--;
    }
    while (len > 0u && is_blank(s[len - 1u])) len--;
    s[len] = '\0';
    p->len = 0;
    if (len == 0u) return true;
    return gsd_statement(p, s, p->first_line);
}

/* One physical line (without its line end). */
static bool feed_line(gsd_parser_t *p, const char *s, size_t len, uint32_t line)
{
    p->last_line = line;
    p->g->lines = line;
    /* a UTF-8 byte order mark, as some editors write one */
    if (line == 1u && len >= 3u && memcmp(s, "\xEF\xBB\xBF", 3) == 0) {
        s += 3;
        len -= 3u;
    }
    if (memchr(s, '\0', len) != NULL) {
        return gsd_fail(p, line, "a NUL character: not a text file");
    }
    len = cut_comment(s, len);
    while (len > 0u && is_blank(s[len - 1u])) len--;
    if (!p->continuing) p->first_line = line;
    bool more = len > 0u && s[len - 1u] == '\\';
    if (!append(p, s, more ? len - 1u : len)) return false;
    p->continuing = more;
    return more ? true : logical_line(p);
}

static bool end_of_input(gsd_parser_t *p)
{
    if (p->continuing) {
        return gsd_fail(p, p->last_line, "a continuation line ('\\') at the end of the file");
    }
    return gsd_finish(p);
}

static void parser_init(gsd_parser_t *p, gsd_t *g, const char *name, char *err, size_t n)
{
    memset(g, 0, sizeof *g);
    g->n_chars = 1u; /* offset 0: "" */
    for (size_t i = 0; i < GSD_RATE_COUNT; i++) g->rate[i].baud = gsd_rate_baud(i);
    p->g = g;
    p->name = name;
    p->err = err;
    p->n = n;
    p->failed = false;
    p->st = GSD_ST_BEFORE;
    p->len = 0;
    p->continuing = false;
    p->last_line = 0;
    if (err != NULL && n > 0u) err[0] = '\0';
}

int gsd_parse_text(const char *text, size_t len, gsd_t *out, char *err, size_t n)
{
    gsd_parser_t p;
    parser_init(&p, out, NULL, err, n);
    uint32_t line = 0;
    size_t i = 0;
    while (i < len) {
        const char *nl = memchr(text + i, '\n', len - i);
        size_t end = nl != NULL ? (size_t)(nl - text) : len;
        line++;
        if (end - i > GSD_MAX_LINE) {
            (void)gsd_fail(&p, line, "longer than %u characters", GSD_MAX_LINE);
            return -1;
        }
        if (!feed_line(&p, text + i, end - i, line)) return -1;
        i = end + 1u;
    }
    return end_of_input(&p) ? 0 : -1;
}

/* The next physical line of f into p->phys: its length, or -1 at the end (or an error). */
static long read_line(gsd_parser_t *p, FILE *f, uint32_t line, bool *too_long)
{
    size_t len = 0;
    int c;
    while ((c = getc(f)) != EOF && c != '\n') {
        if (len == GSD_MAX_LINE) {
            *too_long = true;
            (void)gsd_fail(p, line, "longer than %u characters", GSD_MAX_LINE);
            return -1;
        }
        p->phys[len++] = (char)c;
    }
    if (c == EOF && len == 0u) return -1;
    return (long)len;
}

int gsd_parse_file(const char *path, gsd_t *out, char *err, size_t n)
{
    gsd_parser_t p;
    parser_init(&p, out, path, err, n);
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        (void)gsd_fail(&p, 0, "%s", strerror(errno));
        return -1;
    }
    uint32_t line = 0;
    bool too_long = false;
    bool ok = true;
    long len;
    while (ok && (len = read_line(&p, f, line + 1u, &too_long)) >= 0) {
        line++;
        ok = feed_line(&p, p.phys, (size_t)len, line);
    }
    int read_errno = errno;
    bool read_error = ferror(f) != 0;
    (void)fclose(f);
    if (!ok || too_long) return -1;
    if (read_error) {
        (void)gsd_fail(&p, 0, "cannot read: %s", strerror(read_errno));
        return -1;
    }
    return end_of_input(&p) ? 0 : -1;
}
