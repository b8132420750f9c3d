/* Robustness: every prefix of a real GSD file, and the file with each of a few thousand
 * single octets changed (a fixed pseudo-random sequence), is read without a crash or a hang:
 * either it parses (and then gsd_check runs) or it fails with one "line N: ..." error whose N
 * lies within the text. A prefix that ends inside a module fails naming that module's line. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gsd/gsd.h"

static gsd_t g;
static char text[1 << 16];
static char copy[1 << 16];

static size_t lines_in(const char *s, size_t len)
{
    size_t n = 1;
    for (size_t i = 0; i < len; i++) n += s[i] == '\n';
    return n;
}

/* 0 parsed, 1 failed with a well-formed error. */
static int read_one(const char *s, size_t len, unsigned *err_line)
{
    char err[GSD_ERR_LEN];
    gsd_problem_t p[4];
    if (gsd_parse_text(s, len, &g, err, sizeof err) == 0) {
        (void)gsd_check(&g, p, 4);
        return 0;
    }
    unsigned line = 0;
    if (strcmp(err, "no #Profibus_DP line") == 0) {
        *err_line = 0;
        return 1;
    }
    int matched = sscanf(err, "line %u: ", &line);
    CHECK(matched == 1 && line >= 1u && line <= lines_in(s, len));
    *err_line = line;
    return 1;
}

/* The line of the last "Module" line that starts before n. */
static size_t last_module_line(const char *s, size_t n)
{
    size_t at = 0;
    for (size_t i = 0; i + 7u <= n; i++) {
        if ((i == 0u || s[i - 1u] == '\n') && strncmp(s + i, "Module ", 7) == 0) at = i;
    }
    return lines_in(s, at);
}

static void prefixes(const char *path)
{
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    if (f == NULL) return;
    size_t len = fread(text, 1, sizeof text, f);
    (void)fclose(f);
    unsigned line = 0, ok = 0, failed = 0, in_module = 0, end_modules = 0;
    for (size_t n = 0; n <= len; n++) {
        int r = read_one(text, n, &line);
        ok += r == 0;
        failed += r == 1;
        /* cut right before an EndModule line: the error names its Module line */
        if (n >= 2u && text[n - 1u] == '\n' && strncmp(text + n, "EndModule", 9) == 0) {
            CHECK_EQ(r, 1);
            in_module++;
            CHECK_EQ(line, last_module_line(text, n));
        }
        end_modules += n < len && (n == 0u || text[n - 1u] == '\n') &&
                       strncmp(text + n, "EndModule", 9) == 0;
    }
    CHECK_EQ(ok + failed, len + 1u);
    CHECK(in_module == end_modules && end_modules > 0u);
    CHECK_EQ(read_one(text, len, &line), 0); /* the whole file */
}

/* The same file with one octet changed at a time. */
static void mutations(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) return;
    size_t len = fread(text, 1, sizeof text, f);
    (void)fclose(f);
    uint32_t x = 0x2545F491u; /* xorshift32: the same sequence every run */
    static const char specials[] = "\\\";=(),-#\n\r\0x0123456789";
    unsigned parsed = 0;
    for (unsigned i = 0; i < 4000u; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        memcpy(copy, text, len);
        size_t at = x % len;
        copy[at] = (x & 0x100u) ? specials[(x >> 9) % (sizeof specials - 1u)] : (char)(x >> 24);
        unsigned line;
        parsed += read_one(copy, len, &line) == 0;
    }
    /* both outcomes occur: a changed comment still parses, a changed keyword may not */
    CHECK(parsed > 0u && parsed < 4000u);
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        check_test_name_ = argv[i];
        prefixes(argv[i]);
        mutations(argv[i]);
    }
    return check_report();
}
