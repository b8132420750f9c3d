/* dfp-sim slave --pty LINK: the card makes its own PTY pair and runs on the master side, and
 * LINK (a symbolic link to the slave side, /dev/pts/N) is the serial device another program
 * opens as a master -- a PLC tool, pyprofibus or dfp-sim master -- with no socat between them:
 * every octet goes straight from one process to the other.
 *
 * The card keeps the slave side open as well: with no process holding it, the master side of a
 * PTY reads EIO and polls as hung up, so a master that closes LINK and opens it again would end
 * the card's run. Holding it, the slave side's termios also outlives the masters: it is made raw
 * here (no echo, no line editing) before any master comes, so a master that does not configure
 * the port does not hear the card's replies echoed back into its own input. */
#ifndef DFP_SIM_PTY_LINK_H
#define DFP_SIM_PTY_LINK_H

#include <stdbool.h>
#include <stddef.h>

typedef struct pty_link {
    int master_fd;  /* for the card's port (tty_port_open_fd); -1 once handed over or closed */
    int slave_fd;   /* held, never read: the masters own what arrives there */
    char pts[64];   /* the slave side, /dev/pts/N */
    char link[512]; /* the link made, "" while there is none */
} pty_link_t;

/* Whether LINK may be used: it does not exist or is a symbolic link (an old one is replaced).
 * False with a reason in why (anything else there -- a file, a directory, a device -- is never
 * removed). Checked before anything is opened, so a bad LINK is a usage error. */
bool pty_link_usable(const char *link, char *why, size_t n);
/* The pair, raw, and LINK pointing at its slave side. Returns 0, or -1 with a reason in err and
 * nothing left open or made. */
int pty_link_open(pty_link_t *l, const char *link, char *err, size_t errlen);
/* The port took the master side over (it closes it). */
void pty_link_hand_over(pty_link_t *l);
/* Removes LINK (only while it still points at this pair: a link another program put there since
 * is left alone) and closes what is still open. Safe to call twice. */
void pty_link_close(pty_link_t *l);

#endif
