/* File-name arithmetic the host tools share, and the opening of the files they write. */
#ifndef SIM_HAL_PATH_H
#define SIM_HAL_PATH_H

#include <stddef.h>
#include <stdio.h>

/* The directory part of path into dir ("." for a bare name, "/" for a name in the root), cut to
 * n octets; returns the name after it. */
const char *sim_path_split(const char *path, char *dir, size_t n);

/* The text for a symbolic link where a file is to be written, after "PATH is " or "PATH: ". */
#define SIM_LINK_REFUSED "a symbolic link: refused (dfp-sim writes no file through a link)"

/* path, created (0644 before the umask) or emptied, open for writing as a stdio stream that is
 * closed on exec. A symbolic link at path's last component is refused, never followed: in a
 * directory another user can write to, one planted there would make us overwrite its target.
 * NULL with why set: SIM_LINK_REFUSED, or the system's reason. */
FILE *sim_fopen_write(const char *path, char *why, size_t n);

#endif
