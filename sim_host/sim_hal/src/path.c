#define _POSIX_C_SOURCE 200809L // NOLINT(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp): feature-test macro

#include "sim_hal/path.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

const char *sim_path_split(const char *path, char *dir, size_t n)
{
    const char *slash = strrchr(path, '/');
    if (slash == NULL) {
        (void)snprintf(dir, n, ".");
        return path;
    }
    (void)snprintf(dir, n, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    return slash + 1;
}

FILE *sim_fopen_write(const char *path, char *why, size_t n)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
        int e = errno;
        struct stat st;
        /* ELOOP also stands for too many links in the directories: only a link here is ours. */
        bool link = e == ELOOP && lstat(path, &st) == 0 && S_ISLNK(st.st_mode);
        (void)snprintf(why, n, "%s", link ? SIM_LINK_REFUSED : strerror(e));
        return NULL;
    }
    FILE *f = fdopen(fd, "wb");
    if (f == NULL) {
        (void)snprintf(why, n, "%s", strerror(errno));
        (void)close(fd);
    }
    return f;
}
