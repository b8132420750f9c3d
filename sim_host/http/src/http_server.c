#include "http/http_server.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "http_internal.h"

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_size, void **con_cls)
{
    (void)version;
    http_server_t *srv = cls;
    request_t *req = *con_cls;
    if (req == NULL) {
        req = calloc(1, sizeof *req);
        if (req == NULL) {
            return MHD_NO;
        }
        *con_cls = req;
        /* It sent a request: from now on it may idle between requests (keep-alive) longer
         * than a connection that never sends one. */
        (void)MHD_set_connection_option(conn, MHD_CONNECTION_OPTION_TIMEOUT,
                                        (unsigned)KEEPALIVE_TIMEOUT_S);
        return MHD_YES;
    }
    if (*upload_size != 0u) {
        if (req->len + *upload_size > BODY_MAX) {
            req->too_large = true;
        } else {
            memcpy(req->body + req->len, upload_data, *upload_size);
            req->len += *upload_size;
        }
        *upload_size = 0;
        return MHD_YES;
    }
    http_limits_delivered(conn);
    req->body[req->len] = '\0';
    const char *path;
    if (http_starts(url, "/api/v1/", &path)) {
        return http_route_api(srv, conn, path, method, req);
    }
    if (strcmp(method, "GET") != 0 && strcmp(method, "HEAD") != 0) {
        return http_send_error(conn, 405, "use GET");
    }
    return http_serve_file(conn, url);
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    (void)cls;
    (void)toe;
    http_limits_request_end(conn);
    free(*con_cls);
    *con_cls = NULL;
}

/* ---- start and stop ------------------------------------------------------------------------ */

bool http_parse_listen(const char *text, char *host, size_t hostlen, uint16_t *port, char *err,
                       size_t errlen)
{
    const char *colon = strrchr(text, ':');
    const char *p = colon != NULL ? colon + 1 : text;
    if (colon != NULL) {
        size_t n = (size_t)(colon - text);
        if (n >= 2u && text[0] == '[' && text[n - 1u] == ']') {
            text++;
            n -= 2u;
        }
        if (n == 0u || n >= hostlen) {
            snprintf(err, errlen, "--http '%s': the address before ':' is missing or too long",
                     text);
            return false;
        }
        memcpy(host, text, n);
        host[n] = '\0';
    } else {
        snprintf(host, hostlen, "127.0.0.1");
    }
    char *end;
    unsigned long v = strtoul(p, &end, 10);
    if (end == p || *end != '\0' || v > 65535u || *p < '0' || *p > '9') {
        snprintf(err, errlen, "--http '%s': use [ADDR:]PORT with PORT 0..65535 (e.g. 8080 or "
                 "0.0.0.0:8080)", text);
        return false;
    }
    *port = (uint16_t)v;
    return true;
}

static int open_listener(const char *host, uint16_t port, char *err, size_t errlen,
                         uint16_t *bound)
{
    struct sockaddr_storage ss;
    memset(&ss, 0, sizeof ss);
    socklen_t len;
    struct sockaddr_in *v4 = (struct sockaddr_in *)&ss;
    struct sockaddr_in6 *v6 = (struct sockaddr_in6 *)&ss;
    if (inet_pton(AF_INET, host, &v4->sin_addr) == 1) {
        v4->sin_family = AF_INET;
        v4->sin_port = htons(port);
        len = sizeof *v4;
    } else if (inet_pton(AF_INET6, host, &v6->sin6_addr) == 1) {
        v6->sin6_family = AF_INET6;
        v6->sin6_port = htons(port);
        len = sizeof *v6;
    } else {
        snprintf(err, errlen, "--http: '%s' is not an IPv4 or IPv6 address", host);
        return -1;
    }
    int fd = socket(ss.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(err, errlen, "--http: socket: %s", strerror(errno));
        return -1;
    }
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd, (struct sockaddr *)&ss, len) != 0 || listen(fd, 32) != 0) {
        snprintf(err, errlen, "--http: cannot listen on %s:%u: %s", host, port, strerror(errno));
        close(fd);
        return -1;
    }
    struct sockaddr_storage got;
    memset(&got, 0, sizeof got);
    socklen_t glen = sizeof got;
    if (getsockname(fd, (struct sockaddr *)&got, &glen) != 0) {
        got = ss;
    }
    *bound = ntohs(got.ss_family == AF_INET ? ((struct sockaddr_in *)&got)->sin_port
                                            : ((struct sockaddr_in6 *)&got)->sin6_port);
    return fd;
}

http_server_t *http_server_start(rig_ctl_t *ctl, const char *listen_text, char *err,
                                 size_t errlen)
{
    char host[64];
    uint16_t port;
    if (!http_parse_listen(listen_text, host, sizeof host, &port, err, errlen)) {
        return NULL;
    }
    http_server_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(err, errlen, "--http: out of memory");
        return NULL;
    }
    s->ctl = ctl;
    atomic_init(&s->streams, 0u);
    s->limits = http_limits_new(ctl);
    s->listen_fd = s->limits != NULL ? open_listener(host, port, err, errlen, &s->port) : -1;
    if (s->listen_fd < 0) {
        if (s->limits == NULL) {
            snprintf(err, errlen, "--http: cannot start the server's threads");
        }
        http_limits_free(s->limits);
        free(s);
        return NULL;
    }
    s->daemon = MHD_start_daemon(
        MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION | MHD_USE_ERROR_LOG, 0,
        NULL, NULL, on_request, s, MHD_OPTION_LISTEN_SOCKET, s->listen_fd,
        MHD_OPTION_CONNECTION_LIMIT, (unsigned)MAX_CONNECTIONS, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)IDLE_TIMEOUT_S, MHD_OPTION_NOTIFY_COMPLETED, on_completed, NULL,
        MHD_OPTION_ARRAY, http_limits_options(s->limits), MHD_OPTION_END);
    if (s->daemon == NULL) {
        snprintf(err, errlen, "--http: the HTTP server did not start on %s:%u", host, s->port);
        close(s->listen_fd);
        http_limits_free(s->limits);
        free(s);
        return NULL;
    }
    return s;
}

uint16_t http_server_port(const http_server_t *s)
{
    return s->port;
}

void http_server_stop(http_server_t *s)
{
    if (s == NULL) {
        return;
    }
    s->stopping = 1;
    rig_ctl_kick(s->ctl);
    MHD_stop_daemon(s->daemon); /* closes the listening socket it was given */
    http_limits_free(s->limits);
    free(s);
}

