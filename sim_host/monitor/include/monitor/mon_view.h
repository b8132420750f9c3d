/* The monitor's full-screen view, like top: a header with the line's figures, a table with one
 * row per station (stations down the side, states and counts across) and a lower pane with the
 * selected station's details or the newest events. Keyboard only.
 *
 * Pure: it renders a mon_t into a caller's character grid (rows lines of exactly cols
 * characters, no terminators) and an attribute per line; no I/O, no allocation. The terminal
 * that shows the grid is mon_term.h. While the view is paused the caller passes a frozen copy
 * of the monitor (mon_term keeps one); the view freezes its own clock and rates. */
#ifndef MONITOR_MON_VIEW_H
#define MONITOR_MON_VIEW_H

#include <stdbool.h>
#include <stdint.h>

#include "monitor/monitor.h"

/* Lines beyond this many are left blank (no terminal is that tall). */
#define MON_VIEW_MAX_ROWS 512u
/* The rates are figured over at least this long, so a redraw for a key press shows the last
 * figures instead of a rate over a few milliseconds. */
#define MON_VIEW_RATE_NS 250000000ull

/* Control keys, and keys beyond ASCII as mon_term decodes them from escape sequences. */
enum {
    MON_KEY_CTRL_C = 0x03,         /* the terminal sends no signals: these come as keys */
    MON_KEY_CTRL_BACKSLASH = 0x1c,
    MON_KEY_ESC = 0x1b,
    MON_KEY_UP = 0x100,
    MON_KEY_DOWN,
    MON_KEY_LEFT,
    MON_KEY_RIGHT,
    MON_KEY_PGUP,
    MON_KEY_PGDN,
    MON_KEY_HOME,
    MON_KEY_END,
};

/* A line's attribute (bits): how the terminal shows it. */
enum {
    MON_ATTR_PLAIN = 0,
    MON_ATTR_HEADING = 1u << 0, /* column headings, pane titles, the help line */
    MON_ATTR_SELECTED = 1u << 1,
    MON_ATTR_WARNING = 1u << 2, /* a station or an event worth a look */
};

typedef enum mon_pane {
    MON_PANE_EVENTS = 0,
    MON_PANE_DETAILS,
} mon_pane_t;

typedef enum mon_view_result {
    MON_VIEW_IGNORED = 0, /* not a key of the view */
    MON_VIEW_CHANGED,     /* draw again */
    MON_VIEW_QUIT,
} mon_view_result_t;

typedef struct mon_view {
    /* ---- set by the caller ---- */
    const char *source; /* what is monitored: "/dev/ttyUSB0", "run.pcapng" (NULL: "monitor") */
    uint32_t baud;      /* the line's rate (0: unknown) */

    /* ---- the keyboard's state ---- */
    mon_pane_t pane;
    bool paused;
    bool help;
    int32_t move;        /* rows to move the selection by at the next render */
    bool selected_known; /* selected: the address of the selected row */
    uint8_t selected;

    /* ---- kept by the renderer ---- */
    unsigned top;         /* the first station row shown */
    unsigned page;        /* station rows shown (PgUp/PgDn move by this) */
    bool frozen;          /* paused and frozen_ns taken */
    uint64_t frozen_ns;
    bool have_prev;       /* the rates' last sample */
    bool have_rate;       /* telegrams_per_s and load_permille were figured */
    uint64_t prev_ns;
    uint64_t prev_telegrams;
    uint64_t prev_busy_ns;
    uint64_t telegrams_per_s;
    uint32_t load_permille;
    uint8_t attr[MON_VIEW_MAX_ROWS]; /* MON_ATTR_* of each rendered line */
} mon_view_t;

/* Render m as the view sees it at now_ns (the monitor's clock) into screen: rows lines of cols
 * characters each, line r at screen + r * cols, padded with spaces. Applies the selection moves
 * the keys asked for, so it changes v. Any size works (1x1 shows what fits). */
void mon_view_render(const mon_t *m, mon_view_t *v, uint64_t now_ns, char *screen,
                     unsigned rows, unsigned cols);

/* One key (ASCII or MON_KEY_*): up/down/j/k/PgUp/PgDn/Home/End move the selection, Enter/d
 * show details, e events, p pause, ? the help line, q, Ctrl-C and Ctrl-\ quit. */
mon_view_result_t mon_view_key(mon_view_t *v, int key);

#endif
