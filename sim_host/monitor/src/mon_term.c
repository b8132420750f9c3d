/* The monitor's terminal: see mon_term.h. Curses is not used: the view is one grid redrawn line
 * by line, which needs four escapes (position, attributes, alternate screen, cursor) that
 * every terminal since the VT100 and xterm understands; curses would add a library, its
 * terminfo lookup and its own idea of signals and the screen for no gain. */
/* clock_gettime under -std=c11. */
// NOLINTNEXTLINE(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro
#define _POSIX_C_SOURCE 200809L

#include "monitor/mon_term.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

/* A grid this wide is no terminal's; the cap bounds the buffers. */
#define MAX_COLS 1024u

static uint64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* ---- keys ---- */

void mon_keys_feed(mon_keys_t *k, const uint8_t *p, size_t n, uint64_t now_ns)
{
    size_t room = sizeof k->buf - k->len;
    size_t take = n < room ? n : room;
    memcpy(k->buf + k->len, p, take);
    k->len += (unsigned)take;
    if (n > 0u) {
        k->last_ns = now_ns;
    }
}

enum { KEY_MORE = -1, KEY_DROP = -2 };

static int csi_key(const uint8_t *params, unsigned n, uint8_t final)
{
    switch (final) {
    case 'A':
        return MON_KEY_UP;
    case 'B':
        return MON_KEY_DOWN;
    case 'C':
        return MON_KEY_RIGHT;
    case 'D':
        return MON_KEY_LEFT;
    case 'H':
        return MON_KEY_HOME;
    case 'F':
        return MON_KEY_END;
    case '~':
        break;
    default:
        return KEY_DROP;
    }
    /* ESC [ n ~ (and ESC [ n ; modifier ~): the number says which key. */
    unsigned num = 0;
    for (unsigned i = 0; i < n && params[i] >= '0' && params[i] <= '9'; i++) {
        num = num * 10u + (unsigned)(params[i] - '0');
    }
    switch (num) {
    case 1:
    case 7:
        return MON_KEY_HOME;
    case 4:
    case 8:
        return MON_KEY_END;
    case 5:
        return MON_KEY_PGUP;
    case 6:
        return MON_KEY_PGDN;
    default:
        return KEY_DROP;
    }
}

/* The key at the start of b: a key with *used bytes, KEY_MORE (a sequence not yet whole) or
 * KEY_DROP with *used bytes (a sequence of no key of the view). */
static int parse_key(const uint8_t *b, unsigned len, unsigned *used)
{
    *used = 1;
    if (b[0] != MON_KEY_ESC) {
        return b[0];
    }
    if (len < 2u) {
        return KEY_MORE;
    }
    if (b[1] == 'O') { /* SS3: the keypad in application mode */
        if (len < 3u) {
            return KEY_MORE;
        }
        *used = 3;
        return b[2] == '~' ? KEY_DROP : csi_key(b, 0, b[2]);
    }
    if (b[1] != '[') {
        return MON_KEY_ESC; /* Esc, then another key */
    }
    unsigned i = 2;
    while (i < len && b[i] >= 0x30u && b[i] <= 0x3fu) {
        i++;
    }
    if (i == len) {
        if (len - 2u > 16u) { /* no key has that many parameters */
            *used = len;
            return KEY_DROP;
        }
        return KEY_MORE;
    }
    *used = i + 1u;
    return csi_key(b + 2, i - 2u, b[i]);
}

int mon_keys_next(mon_keys_t *k, uint64_t now_ns)
{
    while (k->len > 0u) {
        unsigned used = 0;
        int key = parse_key(k->buf, k->len, &used);
        if (key == KEY_MORE) {
            if (now_ns - k->last_ns < MON_KEYS_ESC_NS) {
                return -1;
            }
            key = MON_KEY_ESC; /* nothing followed: the Esc key alone */
            used = 1;
        }
        memmove(k->buf, k->buf + used, k->len - used);
        k->len -= used;
        if (key != KEY_DROP) {
            return key;
        }
    }
    return -1;
}

/* ---- the terminal ---- */

static int write_all(int fd, const char *p, size_t n)
{
    while (n > 0u) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) {
            continue;
        }
        if (w <= 0) {
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

int mon_term_open(mon_term_t *t, int in_fd, int out_fd, char *err, size_t n)
{
    memset(t, 0, sizeof *t);
    t->in_fd = in_fd;
    t->out_fd = out_fd;
    if (!isatty(in_fd) || !isatty(out_fd)) {
        snprintf(err, n, "the terminal view needs a terminal on stdin and stdout");
        return -1;
    }
    if (tcgetattr(in_fd, &t->saved) != 0) {
        snprintf(err, n, "cannot read the terminal's settings: %s", strerror(errno));
        return -1;
    }
    t->frozen = malloc(sizeof *t->frozen);
    if (t->frozen == NULL) {
        snprintf(err, n, "out of memory");
        return -1;
    }
    /* Keys one by one, unechoed, without waiting; OPOST stays as the draws send no line ends.
     * ISIG off: Ctrl-C and Ctrl-\ come as keys that quit (mon_view_key), Ctrl-Z as one that
     * does nothing; as signals, SIGQUIT would kill the process and SIGTSTP stop it with the
     * terminal raw, on the alternate screen, without its cursor. */
    struct termios raw = t->saved;
    raw.c_lflag &= ~(tcflag_t)(ICANON | ECHO | IEXTEN | ISIG);
    raw.c_iflag &= ~(tcflag_t)(IXON | ICRNL | INLCR | ISTRIP);
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    if (tcsetattr(in_fd, TCSANOW, &raw) != 0) {
        snprintf(err, n, "cannot set the terminal's settings: %s", strerror(errno));
        free(t->frozen);
        t->frozen = NULL;
        return -1;
    }
    t->raw = true;
    static const char enter[] = "\x1b[?1049h\x1b[?25l\x1b[0m\x1b[2J";
    t->alt = true;
    t->repaint = true;
    (void)write_all(out_fd, enter, sizeof enter - 1u);
    return 0;
}

int mon_term_poll_key(mon_term_t *t)
{
    int key = mon_keys_next(&t->keys, mono_ns());
    if (key >= 0) {
        return key;
    }
    uint8_t b[sizeof t->keys.buf];
    size_t room = sizeof t->keys.buf - t->keys.len;
    ssize_t r = room > 0u ? read(t->in_fd, b, room) : 0;
    uint64_t now = mono_ns();
    if (r > 0) {
        mon_keys_feed(&t->keys, b, (size_t)r, now);
    }
    return mon_keys_next(&t->keys, now);
}

static void free_grids(mon_term_t *t)
{
    free(t->screen);
    free(t->shown);
    free(t->shown_attr);
    free(t->out);
    t->screen = t->shown = t->out = NULL;
    t->shown_attr = NULL;
    t->rows = t->cols = 0;
}

static bool size_grids(mon_term_t *t, unsigned rows, unsigned cols)
{
    if (rows == t->rows && cols == t->cols) {
        return true;
    }
    free_grids(t);
    size_t cells = (size_t)rows * cols;
    t->out_cap = cells + (size_t)rows * 32u + 64u;
    t->screen = malloc(cells);
    t->shown = malloc(cells);
    t->shown_attr = malloc(rows);
    t->out = malloc(t->out_cap);
    if (t->screen == NULL || t->shown == NULL || t->shown_attr == NULL || t->out == NULL) {
        free_grids(t);
        return false;
    }
    t->rows = rows;
    t->cols = cols;
    t->repaint = true; /* a resized terminal shows what it kept of the old lines */
    return true;
}

static size_t put_sgr(char *out, uint8_t attr)
{
    bool bold = (attr & (MON_ATTR_HEADING | MON_ATTR_WARNING)) != 0u;
    bool underline = (attr & MON_ATTR_HEADING) != 0u;
    bool reverse = (attr & MON_ATTR_SELECTED) != 0u;
    return (size_t)sprintf(out, "\x1b[0%s%s%sm", bold ? ";1" : "", underline ? ";4" : "",
                           reverse ? ";7" : "");
}

/* The lines that differ from what the terminal shows, as escapes and text in t->out. */
static size_t diff_lines(mon_term_t *t, const uint8_t *attr)
{
    size_t at = 0;
    if (t->repaint) {
        at += (size_t)sprintf(t->out, "\x1b[0m\x1b[2J");
    }
    for (unsigned r = 0; r < t->rows; r++) {
        char *line = t->screen + (size_t)r * t->cols;
        char *was = t->shown + (size_t)r * t->cols;
        uint8_t a = r < MON_VIEW_MAX_ROWS ? attr[r] : 0u;
        if (!t->repaint && a == t->shown_attr[r] && memcmp(line, was, t->cols) == 0) {
            continue;
        }
        at += (size_t)sprintf(t->out + at, "\x1b[%u;1H", r + 1u);
        if (a != 0u) {
            at += put_sgr(t->out + at, a);
        }
        memcpy(t->out + at, line, t->cols);
        at += t->cols;
        if (a != 0u) {
            at += (size_t)sprintf(t->out + at, "\x1b[0m");
        }
        memcpy(was, line, t->cols);
        t->shown_attr[r] = a;
    }
    return at;
}

void mon_term_draw(mon_term_t *t, const mon_t *m, mon_view_t *v, uint64_t now_ns)
{
    unsigned rows = 24;
    unsigned cols = 80;
    struct winsize ws;
    if (ioctl(t->out_fd, TIOCGWINSZ, &ws) == 0 && ws.ws_row > 0u && ws.ws_col > 0u) {
        rows = ws.ws_row;
        cols = ws.ws_col;
    }
    rows = rows > MON_VIEW_MAX_ROWS ? MON_VIEW_MAX_ROWS : rows;
    cols = cols > MAX_COLS ? MAX_COLS : cols;
    if (!size_grids(t, rows, cols)) {
        return;
    }
    const mon_t *shown = m;
    if (v->paused && t->frozen != NULL) {
        if (!t->frozen_taken) {
            memcpy(t->frozen, m, sizeof *m);
            t->frozen_taken = true;
        }
        shown = t->frozen;
    } else {
        t->frozen_taken = false;
    }
    mon_view_render(shown, v, now_ns, t->screen, rows, cols);
    size_t n = diff_lines(t, v->attr);
    t->repaint = false;
    if (write_all(t->out_fd, t->out, n) != 0) {
        t->repaint = true; /* the terminal has part of it: start again from a clear screen */
        return;
    }
    t->bytes_written += n;
}

void mon_term_restore(mon_term_t *t)
{
    if (t->alt) {
        static const char leave[] = "\x1b[0m\x1b[?25h\x1b[?1049l";
        t->alt = false;
        (void)write_all(t->out_fd, leave, sizeof leave - 1u);
    }
    if (t->raw) {
        t->raw = false;
        (void)tcsetattr(t->in_fd, TCSANOW, &t->saved);
    }
}

void mon_term_close(mon_term_t *t)
{
    mon_term_restore(t);
    free_grids(t);
    free(t->frozen);
    t->frozen = NULL;
}
