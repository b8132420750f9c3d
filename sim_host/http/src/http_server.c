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
    /* ---- access control: docs/api.md "Security" (http_auth.c) ---- */
    enum MHD_Result rc = MHD_NO;
    if (!http_guard(srv, conn, url, method, req, &rc)) {
        return rc;
    }
    const char *path;
    if (http_starts(url, "/api/v1/", &path)) {
        bool action = strcmp(method, "GET") != 0 && strcmp(method, "HEAD") != 0 &&
                      strcmp(path, "login") != 0 && strcmp(path, "logout") != 0;
        http_clear_error(conn);
        rc = http_route_api(srv, conn, path, method, req);
        if (action) {
            http_audit_result(srv, conn, req, method, url);
        }
        return rc;
    }
    /* ---- end of access control ---- */
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

/* ---- TLS: MHD_USE_TLS with GnuTLS; the PEM texts stay in srv->auth while the daemon runs */
static bool tls_options(const http_auth_t *a, struct MHD_OptionItem *opts, unsigned *flags,
                        char *err, size_t errlen)
{
    opts[0] = (struct MHD_OptionItem){MHD_OPTION_END, 0, NULL};
    if (!a->tls) {
        return true;
    }
    if (MHD_is_feature_supported(MHD_FEATURE_TLS) != MHD_YES) {
        snprintf(err, errlen, "--http-cert: this libmicrohttpd was built without TLS (GnuTLS), "
                 "so there is no HTTPS");
        return false;
    }
    *flags |= MHD_USE_TLS;
    opts[0] = (struct MHD_OptionItem){MHD_OPTION_HTTPS_MEM_CERT, 0, a->cert_pem};
    opts[1] = (struct MHD_OptionItem){MHD_OPTION_HTTPS_MEM_KEY, 0, a->key_pem};
    opts[2] = (struct MHD_OptionItem){MHD_OPTION_END, 0, NULL};
    return true;
}

/* After MHD_stop_daemon, if it ran: the limits hear of every connection it closes. */
static void server_free(http_server_t *s)
{
    http_limits_free(s->limits);
    http_auth_destroy(&s->auth);
    free(s);
}

http_server_t *http_server_start(rig_ctl_t *ctl, const http_config_t *cfg, char *err,
                                 size_t errlen)
{
    char host[64];
    uint16_t port;
    if (!http_parse_listen(cfg->listen, host, sizeof host, &port, err, errlen)) {
        return NULL;
    }
    http_server_t *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(err, errlen, "--http: out of memory");
        return NULL;
    }
    s->ctl = ctl;
    atomic_init(&s->streams, 0u);
    struct MHD_OptionItem tls[3];
    unsigned flags =
        MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION | MHD_USE_ERROR_LOG;
    if (!http_auth_init(&s->auth, cfg, err, errlen) ||
        !tls_options(&s->auth, tls, &flags, err, errlen)) {
        server_free(s);
        return NULL;
    }
    s->limits = http_limits_new(ctl);
    s->listen_fd = s->limits != NULL ? open_listener(host, port, err, errlen, &s->port) : -1;
    if (s->listen_fd < 0) {
        if (s->limits == NULL) {
            snprintf(err, errlen, "--http: cannot start the server's threads");
        }
        server_free(s);
        return NULL;
    }
    s->daemon = MHD_start_daemon(
        flags, 0, NULL, NULL, on_request, s, MHD_OPTION_LISTEN_SOCKET, s->listen_fd,
        MHD_OPTION_CONNECTION_LIMIT, (unsigned)MAX_CONNECTIONS, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)IDLE_TIMEOUT_S, MHD_OPTION_NOTIFY_COMPLETED, on_completed, NULL,
        MHD_OPTION_ARRAY, http_limits_options(s->limits), MHD_OPTION_ARRAY, tls,
        MHD_OPTION_END);
    if (s->daemon == NULL) {
        if (s->auth.tls) {
            snprintf(err, errlen, "--http-cert/--http-key: the HTTPS server did not start on "
                     "%s:%u: the certificate or the key is not valid, or they do not match",
                     host, s->port);
        } else {
            snprintf(err, errlen, "--http: the HTTP server did not start on %s:%u", host,
                     s->port);
        }
        close(s->listen_fd);
        server_free(s);
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
    server_free(s);
}

