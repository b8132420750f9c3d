/* The front panel's static files, compiled into dfp-sim (generated from sim_host/http/www/ by
 * cmake/embed_files.cmake), so the panel works from any directory and offline. */
#ifndef DFP_HTTP_WWW_FILES_H
#define DFP_HTTP_WWW_FILES_H

#include <stddef.h>
#include <stdint.h>

typedef struct www_file {
    const char *name; /* "index.html" */
    const char *mime;
    const uint8_t *data;
    size_t size;
} www_file_t;

extern const www_file_t www_files[];
extern const size_t www_file_count;

#endif
