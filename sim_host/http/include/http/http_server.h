/* The control API and front panel over HTTP (docs/api.md): libmicrohttpd serves it from its own
 * threads, cJSON reads and writes the JSON. Everything goes through a rig_ctl bridge, so the
 * bus loop never waits for a client. */
#ifndef DFP_HTTP_HTTP_SERVER_H
#define DFP_HTTP_HTTP_SERVER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rig/rig_ctl.h"

typedef struct http_server http_server_t;

/* "8080", "127.0.0.1:8080", "0.0.0.0:8080", "[::1]:8080". Without an address: 127.0.0.1.
 * Returns false with a reason. */
bool http_parse_listen(const char *text, char *host, size_t hostlen, uint16_t *port, char *err,
                       size_t errlen);
/* Starts serving; NULL with a one-line reason in err (port taken, bad address). */
http_server_t *http_server_start(rig_ctl_t *ctl, const char *listen, char *err, size_t errlen);
/* The port actually bound (useful with port 0). */
uint16_t http_server_port(const http_server_t *s);
void http_server_stop(http_server_t *s);

#endif
