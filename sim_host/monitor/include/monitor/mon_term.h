/* The terminal that shows the monitor's view (mon_view.h): raw keyboard, the alternate screen,
 * no cursor, and a redraw that writes only the lines that changed, so it does not flicker over
 * ssh. Plain ANSI escapes (any terminal of the last thirty years, a PTY): no curses.
 *
 * The caller's loop: mon_term_open, then poll its input fd, mon_term_poll_key until -1 (each
 * key to mon_view_key), mon_term_draw now and then; mon_term_close at the end. The keyboard
 * sends no signals while the view is up (Ctrl-C and Ctrl-\ are keys that quit, Ctrl-Z does
 * nothing). A caller that catches SIGTERM sets a flag and leaves its loop; mon_term_restore gives the terminal
 * back at once and is safe to call twice (and from a signal handler: it only writes and sets
 * the terminal's attributes). */
#ifndef MONITOR_MON_TERM_H
#define MONITOR_MON_TERM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <termios.h>

#include "monitor/mon_view.h"
#include "monitor/monitor.h"

/* An ESC with nothing after it for this long is the Esc key, not a sequence's start. */
#define MON_KEYS_ESC_NS 50000000ull

/* The escape-sequence decoder: bytes in as they were read, keys out. */
typedef struct mon_keys {
    uint8_t buf[32];
    unsigned len;
    uint64_t last_ns; /* when the last bytes came */
} mon_keys_t;

/* Bytes as read at now_ns (what does not fit in buf is dropped: a flood of keys). */
void mon_keys_feed(mon_keys_t *k, const uint8_t *p, size_t n, uint64_t now_ns);
/* The next key (ASCII or MON_KEY_*), or -1: none, or an unfinished sequence that may still
 * come whole. Unknown sequences are dropped whole. */
int mon_keys_next(mon_keys_t *k, uint64_t now_ns);

typedef struct mon_term {
    int in_fd;
    int out_fd;
    bool raw;          /* saved holds the attributes to put back */
    bool alt;          /* the alternate screen is on */
    struct termios saved;
    mon_keys_t keys;
    unsigned rows;     /* the size the grids are for (0: none yet) */
    unsigned cols;
    char *screen;      /* the rendered grid */
    char *shown;       /* what the terminal shows */
    uint8_t *shown_attr;
    bool repaint;      /* draw every line next time */
    char *out;         /* one draw's escapes and text, written at once */
    size_t out_cap;
    mon_t *frozen;     /* the monitor as it was when the view was paused */
    bool frozen_taken;
    uint64_t bytes_written; /* what draws wrote (for tests and benchmarks) */
} mon_term_t;

/* Take over the terminal: 0, or -1 with a one-line reason in err (not a tty, no memory). */
int mon_term_open(mon_term_t *t, int in_fd, int out_fd, char *err, size_t n);
/* The next key, without blocking; -1: none. */
int mon_term_poll_key(mon_term_t *t);
/* Render the view at the terminal's size (a resize is seen here) and write the lines that
 * changed. While v is paused it shows m as it was when the pause began. */
void mon_term_draw(mon_term_t *t, const mon_t *m, mon_view_t *v, uint64_t now_ns);
/* The terminal's modes put back (main screen, cursor, attributes); safe to call twice. */
void mon_term_restore(mon_term_t *t);
/* mon_term_restore and the buffers freed. */
void mon_term_close(mon_term_t *t);

#endif
