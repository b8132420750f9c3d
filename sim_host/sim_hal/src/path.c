#include "sim_hal/path.h"

#include <stdio.h>
#include <string.h>

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
