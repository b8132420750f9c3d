#include "cli.h"

#include <ctype.h>
#include <errno.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hal/hal_uart.h"
#include "sim_hal/error_text.h"
#include "sim_hal/path.h"

void cli_error(const char *fmt, ...)
{
    /* Errors quote LCM channel names and texts of captures: the terminal gets them escaped. */
    char text[2048];
    char shown[4u * sizeof text];
    va_list ap;
    va_start(ap, fmt);
    /* va_start is above; clang 14's analyzer says otherwise only for one compile of this file
     * (the unit test's). */
    // NOLINTNEXTLINE(clang-analyzer-valist.Uninitialized)
    (void)vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    sim_text_visible(text, shown, sizeof shown);
    fprintf(stderr, "dfp-sim: %s\n", shown);
}

/* Where a path that does not exist yet will be created: a dangling symbolic link (a chain of at
 * most 8) creates its target, relative to the link's own directory. */
static void creation_path(const char *path, char *out, size_t n)
{
    (void)snprintf(out, n, "%s", path);
    for (int hops = 0; hops < 8; hops++) {
        struct stat st;
        char target[4096];
        if (lstat(out, &st) != 0 || !S_ISLNK(st.st_mode)) {
            return;
        }
        ssize_t len = readlink(out, target, sizeof target - 1u);
        if (len <= 0) {
            return;
        }
        target[len] = '\0';
        char dir[4096];
        (void)sim_path_split(out, dir, sizeof dir);
        if (target[0] == '/') {
            (void)snprintf(out, n, "%s", target);
        } else {
            (void)snprintf(out, n, "%s/%s", dir, target);
        }
    }
}

bool cli_same_file(const char *a, const char *b)
{
    if (strcmp(a, b) == 0) {
        return true;
    }
    struct stat sa;
    struct stat sb;
    bool a_exists = stat(a, &sa) == 0;
    bool b_exists = stat(b, &sb) == 0;
    if (a_exists || b_exists) {
        return a_exists && b_exists && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    }
    /* Neither is there yet: whichever is created first is the other one as well, also through
     * a link that points at where the other will be. */
    char ca[4096];
    char cb[4096];
    creation_path(a, ca, sizeof ca);
    creation_path(b, cb, sizeof cb);
    char da[4096];
    char db[4096];
    const char *na = sim_path_split(ca, da, sizeof da);
    const char *nb = sim_path_split(cb, db, sizeof db);
    return strcmp(na, nb) == 0 && stat(da, &sa) == 0 && stat(db, &sb) == 0 &&
           sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

bool cli_files_distinct(const char *cmd, const cli_file_t *files, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        for (size_t k = i + 1u; files[i].path != NULL && k < n; k++) {
            if (files[k].path != NULL && cli_same_file(files[i].path, files[k].path)) {
                cli_error("%s: %s and %s are the same file (%s, %s): refused before anything "
                          "was opened (give each its own file)", cmd, files[i].option,
                          files[k].option, files[i].path, files[k].path);
                return false;
            }
        }
    }
    return cli_no_links(cmd, files, n);
}

bool cli_no_links(const char *cmd, const cli_file_t *files, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        struct stat st;
        if (files[i].path != NULL && !files[i].input && lstat(files[i].path, &st) == 0 &&
            S_ISLNK(st.st_mode)) {
            cli_error("%s: %s %s is " SIM_LINK_REFUSED, cmd, files[i].option, files[i].path);
            return false;
        }
    }
    return true;
}

const char *cli_lcm_log_written(const char *url, char *buf, size_t n)
{
    if (url == NULL || strncmp(url, "file://", 7) != 0) {
        return NULL;
    }
    const char *path = url + 7;
    const char *query = strchr(path, '?');
    /* LCM's file provider reads unless told mode=w (or a, appending). */
    if (query == NULL || (strstr(query, "mode=w") == NULL && strstr(query, "mode=a") == NULL)) {
        return NULL;
    }
    (void)snprintf(buf, n, "%.*s", (int)(query - path), path);
    return buf;
}

const char *cli_value(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) {
        cli_error("option %s needs a value (see dfp-sim --help)", argv[*i]);
        return NULL;
    }
    (*i)++;
    return argv[*i];
}

/* One "N" or "N-M" of an address list at p; *end after it. False when it is neither. */
static bool address_range(const char *p, unsigned long *lo, unsigned long *hi, char **end)
{
    *lo = strtoul(p, end, 10);
    *hi = *lo;
    bool ok = *end != p && *p >= '0' && *p <= '9';
    if (ok && **end == '-') {
        const char *q = *end + 1;
        *hi = strtoul(q, end, 10);
        ok = *end != q && *q >= '0' && *q <= '9';
    }
    return ok;
}

bool cli_address_list(const char *opt, const char *text, uint8_t *out, size_t max, size_t *n)
{
    bool seen[126] = {false};
    *n = 0;
    const char *p = text;
    for (;;) {
        char *end;
        unsigned long lo;
        unsigned long hi;
        bool ok = address_range(p, &lo, &hi, &end);
        if (!ok || (*end != ',' && *end != '\0') || lo > 125u || hi > 125u || hi < lo) {
            cli_error("%s '%s': use addresses 0..125 as N, N-M or a comma list "
                      "(3-34, 3,5,7-9)", opt, text);
            return false;
        }
        for (unsigned long a = lo; a <= hi; a++) {
            if (seen[a]) {
                cli_error("%s '%s': address %lu is given twice", opt, text, a);
                return false;
            }
            if (*n >= max) {
                cli_error("%s '%s': more than %zu slaves", opt, text, max);
                return false;
            }
            seen[a] = true;
            out[(*n)++] = (uint8_t)a;
        }
        if (*end == '\0') {
            return true;
        }
        p = end + 1;
    }
}

bool cli_u32(const char *opt, const char *text, uint32_t min, uint32_t max, uint32_t *out)
{
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(text, &end, 0);
    if (text[0] == '\0' || text[0] == '-' || *end != '\0' || errno != 0 || v < min || v > max) {
        cli_error("%s: '%s' is not a number from %u to %u", opt, text, min, max);
        return false;
    }
    *out = (uint32_t)v;
    return true;
}

static int hexval(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    c = tolower(c);
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
}

bool cli_hex(const char *opt, const char *text, uint8_t *out, size_t max, size_t *len)
{
    size_t n = 0;
    const char *p = text;
    while (*p != '\0') {
        if (*p == ' ' || *p == ',' || *p == ':' || *p == '-') {
            p++;
            continue;
        }
        if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
            p += 2;
            continue;
        }
        int hi = hexval((unsigned char)p[0]);
        int lo = p[1] != '\0' ? hexval((unsigned char)p[1]) : -1;
        if (hi < 0 || lo < 0) {
            cli_error("%s: '%s' is not a sequence of hex octets (e.g. F3F2)", opt, text);
            return false;
        }
        if (n >= max) {
            cli_error("%s: more than %zu octets", opt, max);
            return false;
        }
        out[n++] = (uint8_t)(hi * 16 + lo);
        p += 2;
    }
    if (n == 0) {
        cli_error("%s: no octets given", opt);
        return false;
    }
    *len = n;
    return true;
}

bool cli_baud(const char *opt, const char *text, bool allow_auto, uint32_t *out)
{
    if (allow_auto && strcmp(text, "auto") == 0) {
        *out = 0;
        return true;
    }
    char *end = NULL;
    double v = strtod(text, &end);
    if (end != text) {
        if (*end == 'k' || *end == 'K') {
            v *= 1000.0;
            end++;
        } else if (*end == 'M') {
            v *= 1000000.0;
            end++;
        }
    }
    if (end != text && *end == '\0') {
        for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
            double r = (double)hal_uart_bauds[i];
            if (v > r - 0.5 && v < r + 0.5) {
                *out = hal_uart_bauds[i];
                return true;
            }
        }
    }
    cli_error("%s: '%s' is not a PROFIBUS rate (9600 19200 45450 93750 187500 500000 1.5M 3M "
              "6M 12M%s)", opt, text, allow_auto ? " or auto" : "");
    return false;
}

volatile int cli_stop;

static void on_stop_signal(int sig)
{
    (void)sig;
    cli_stop = 1;
}

void cli_catch_stop_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}
