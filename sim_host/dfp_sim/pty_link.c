/* The card's own PTY pair and its link. See pty_link.h. Built with _GNU_SOURCE (ptsname_r). */
#include "pty_link.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

bool pty_link_usable(const char *link, char *why, size_t n)
{
    struct stat st;
    if (link[0] == '\0') {
        (void)snprintf(why, n, "an empty path");
        return false;
    }
    if (lstat(link, &st) != 0) {
        return true; /* nothing there yet; whether it can be made shows when it is made */
    }
    if (S_ISLNK(st.st_mode)) {
        return true;
    }
    (void)snprintf(why, n, "'%s' exists and is %s, not a symbolic link", link,
                   S_ISDIR(st.st_mode)   ? "a directory"
                   : S_ISREG(st.st_mode) ? "a regular file"
                                         : "a special file");
    return false;
}

/* Raw, so the slave side neither echoes nor holds back what the card sends until a master
 * configures it (most do; cat or a terminal program would not). */
static int make_raw(int fd)
{
    struct termios t;
    if (tcgetattr(fd, &t) != 0) {
        return -1;
    }
    cfmakeraw(&t);
    t.c_cflag |= CLOCAL | CREAD;
    return tcsetattr(fd, TCSANOW, &t);
}

/* symlink(), replacing an old symbolic link (a run that was killed leaves its link behind). A
 * link whose target is gone and one that still points somewhere are replaced alike: the path
 * was named for this card. */
static int make_link(const pty_link_t *l, const char *link)
{
    for (int attempt = 0; attempt < 2; attempt++) {
        if (symlink(l->pts, link) == 0) {
            return 0;
        }
        struct stat st;
        if (errno != EEXIST || lstat(link, &st) != 0 || !S_ISLNK(st.st_mode)) {
            return -1;
        }
        if (unlink(link) != 0 && errno != ENOENT) {
            return -1;
        }
    }
    errno = EEXIST; /* something made it again in between */
    return -1;
}

static int fail(pty_link_t *l, char *err, size_t errlen, const char *what)
{
    int e = errno;
    (void)snprintf(err, errlen, "slave: --pty: %s: %s", what, strerror(e));
    pty_link_close(l);
    return -1;
}

int pty_link_open(pty_link_t *l, const char *link, char *err, size_t errlen)
{
    *l = (pty_link_t){.master_fd = -1, .slave_fd = -1};
    if (strlen(link) >= sizeof l->link) {
        (void)snprintf(err, errlen, "slave: --pty: the path is longer than %zu octets",
                       sizeof l->link - 1u);
        return -1;
    }
    l->master_fd = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (l->master_fd < 0 || grantpt(l->master_fd) != 0 || unlockpt(l->master_fd) != 0 ||
        ptsname_r(l->master_fd, l->pts, sizeof l->pts) != 0) {
        return fail(l, err, errlen, "cannot create a PTY pair");
    }
    l->slave_fd = open(l->pts, O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (l->slave_fd < 0) {
        char what[96];
        (void)snprintf(what, sizeof what, "cannot open %s", l->pts);
        return fail(l, err, errlen, what);
    }
    if (make_raw(l->slave_fd) != 0) {
        return fail(l, err, errlen, "cannot make the slave side raw");
    }
    if (make_link(l, link) != 0) {
        char what[700];
        (void)snprintf(what, sizeof what, "cannot make the link %s -> %s", link, l->pts);
        return fail(l, err, errlen, what);
    }
    (void)snprintf(l->link, sizeof l->link, "%s", link);
    return 0;
}

void pty_link_hand_over(pty_link_t *l)
{
    l->master_fd = -1;
}

void pty_link_close(pty_link_t *l)
{
    if (l->link[0] != '\0') {
        char target[sizeof l->pts];
        ssize_t n = readlink(l->link, target, sizeof target - 1u);
        if (n > 0) {
            target[n] = '\0';
            if (strcmp(target, l->pts) == 0) {
                (void)unlink(l->link);
            }
        }
        l->link[0] = '\0';
    }
    if (l->slave_fd >= 0) {
        (void)close(l->slave_fd);
        l->slave_fd = -1;
    }
    if (l->master_fd >= 0) {
        (void)close(l->master_fd);
        l->master_fd = -1;
    }
}
