/* File-name arithmetic the host tools share. */
#ifndef SIM_HAL_PATH_H
#define SIM_HAL_PATH_H

#include <stddef.h>

/* The directory part of path into dir ("." for a bare name, "/" for a name in the root), cut to
 * n octets; returns the name after it. */
const char *sim_path_split(const char *path, char *dir, size_t n);

#endif
