/* The checks every request passes before it is routed (docs/api.md "Security"), in order:
 * the Host allow-list (DNS rebinding), Origin and Content-Type of a state-changing request
 * (cross-site requests), the credential and the role. Each refusal is answered and audited. */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>

#include "http_internal.h"

const char *http_role_name(http_role_t role)
{
    switch (role) {
    case HTTP_ROLE_OPERATOR:
        return "operator";
    case HTTP_ROLE_VIEWER:
        return "viewer";
    case HTTP_ROLE_NONE:
        break;
    }
    return "none";
}

/* A text from the request made fit for one log line: control characters (the URL is decoded,
 * so %0A is a newline) become '?', and it is cut at n - 1. */
static void printable(char *out, size_t n, const char *text)
{
    size_t k = 0;
    for (; text != NULL && text[k] != '\0' && k + 1u < n; k++) {
        unsigned char ch = (unsigned char)text[k];
        out[k] = text[k];
        if (ch < 0x20u || ch == 0x7fu) {
            out[k] = '?';
        }
    }
    out[k] = '\0';
}

static void client_address(struct MHD_Connection *conn, char *out, size_t n)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    char ip[INET6_ADDRSTRLEN] = "?";
    const struct sockaddr *sa = ci != NULL ? ci->client_addr : NULL;
    if (sa != NULL && sa->sa_family == AF_INET) {
        const struct sockaddr_in *v4 = (const struct sockaddr_in *)(const void *)sa;
        (void)inet_ntop(AF_INET, &v4->sin_addr, ip, sizeof ip);
        snprintf(out, n, "%s:%u", ip, (unsigned)ntohs(v4->sin_port));
    } else if (sa != NULL && sa->sa_family == AF_INET6) {
        const struct sockaddr_in6 *v6 = (const struct sockaddr_in6 *)(const void *)sa;
        (void)inet_ntop(AF_INET6, &v6->sin6_addr, ip, sizeof ip);
        snprintf(out, n, "[%s]:%u", ip, (unsigned)ntohs(v6->sin6_port));
    } else {
        snprintf(out, n, "?");
    }
}

/* The event's time: the rig's, as the last published state has it (the loop owns the clock). */
void http_audit(http_server_t *srv, rig_log_level_t level, const char *fmt, ...)
{
    char text[RIG_CTL_TEXT];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    rig_ctl_event(srv->ctl, rig_ctl_time_us(srv->ctl), level, "http", "audit", text);
}

void http_audit_result(http_server_t *srv, struct MHD_Connection *conn, const request_t *req,
                       const char *method, const char *url)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_HTTP_STATUS);
    unsigned status = ci != NULL ? ci->http_status : 0u;
    char path[128];
    char verb[16];
    char error[RIG_CTL_TEXT];
    printable(path, sizeof path, url);
    printable(verb, sizeof verb, method);
    /* An error may repeat what the client sent (a path, a key of its body). */
    printable(error, sizeof error, http_last_error(conn));
    http_audit(srv, status < 400u ? RIG_LOG_INFO : RIG_LOG_WARN, "%s %s %s %s -> %u%s%s",
               req->client, http_role_name(req->role), verb, path, status,
               error[0] != '\0' ? " " : "", error);
}

/* ":PORT" with up to 5 digits, or nothing (RFC 9110 7.2: uri-host [ ":" port ], port =
 * *DIGIT). */
static bool port_part(const char *p)
{
    if (*p == '\0') {
        return true;
    }
    size_t digits = strspn(p + 1, "0123456789");
    return p[0] == ':' && digits <= 5u && p[1u + digits] == '\0';
}

/* "NAME" of "NAME:PORT", "[V6]:PORT", "[V6]", "NAME"; false when it does not fit or anything
 * but a port follows the name. */
static bool host_name(const char *host, char *name, size_t n)
{
    const char *end;
    const char *after;
    if (host[0] == '[') {
        host++;
        end = strchr(host, ']');
        if (end == NULL) {
            return false;
        }
        after = end + 1;
    } else {
        end = strchr(host, ':');
        end = end != NULL ? end : host + strlen(host);
        after = end;
    }
    size_t len = (size_t)(end - host);
    if (len == 0u || len >= n || !port_part(after)) {
        return false;
    }
    memcpy(name, host, len);
    name[len] = '\0';
    return true;
}

static enum MHD_Result count_host(void *cls, enum MHD_ValueKind kind, const char *key,
                                  const char *value)
{
    (void)kind;
    (void)value;
    *(unsigned *)cls += strcasecmp(key, "Host") == 0 ? 1u : 0u;
    return MHD_YES;
}

/* RFC 9112 3.2: a request with more than one Host is refused (400); each proxy or server on
 * the way might take another one. */
static unsigned host_fields(struct MHD_Connection *conn)
{
    unsigned n = 0;
    (void)MHD_get_connection_values(conn, MHD_HEADER_KIND, count_host, &n);
    return n;
}

static bool host_allowed(const http_auth_t *a, const char *host)
{
    char name[HTTP_NAME_MAX];
    if (host == NULL || !host_name(host, name, sizeof name)) {
        return false;
    }
    unsigned char addr[sizeof(struct in6_addr)];
    if (inet_pton(AF_INET, name, addr) == 1 || inet_pton(AF_INET6, name, addr) == 1 ||
        strcasecmp(name, "localhost") == 0) {
        return true;
    }
    for (size_t i = 0; i < a->n_allow_host; i++) {
        if (strcasecmp(name, a->allow_host[i]) == 0) {
            return true;
        }
    }
    return false;
}

/* Same-origin (the scheme and the Host this request used) or an --http-allow-origin. */
static bool origin_allowed(const http_auth_t *a, const char *origin, const char *host)
{
    if (strcmp(origin, "null") == 0) {
        return false;
    }
    if (host != NULL) {
        char own[HTTP_NAME_MAX + 16u];
        snprintf(own, sizeof own, "%s://%s", a->tls ? "https" : "http", host);
        if (strcasecmp(origin, own) == 0) {
            return true;
        }
    }
    for (size_t i = 0; i < a->n_allow_origin; i++) {
        if (strcasecmp(origin, a->allow_origin[i]) == 0) {
            return true;
        }
    }
    return false;
}

/* application/json, with parameters or not (a form, text/plain or multipart body is what a
 * page of another site can send without asking: those are refused). */
static bool json_type(const char *type)
{
    static const char want[] = "application/json";
    if (type == NULL) {
        return false;
    }
    type += strspn(type, " \t");
    size_t n = sizeof want - 1u;
    if (strncasecmp(type, want, n) != 0) {
        return false;
    }
    type += n + strspn(type + n, " \t");
    return *type == '\0' || *type == ';';
}

static bool reads_only(const char *method)
{
    return strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
}

/* Paths that answer without a credential: the panel's files (so the login form can load),
 * the login and the question whether one is needed. */
static bool needs_credential(const char *url, const char *method)
{
    const char *rest;
    if (!http_starts(url, "/api/", &rest)) {
        return false;
    }
    return !(strcmp(url, "/api/v1/login") == 0 && strcmp(method, "POST") == 0) &&
           !(strcmp(url, "/api/v1/session") == 0 && strcmp(method, "GET") == 0);
}

static bool is_action(const char *url, const char *method)
{
    const char *rest;
    return !reads_only(method) && http_starts(url, "/api/", &rest) &&
           strcmp(url, "/api/v1/login") != 0 && strcmp(url, "/api/v1/logout") != 0;
}

/* The refusal's status and message, or 0 when the request passes. */
static unsigned refusal(http_server_t *srv, struct MHD_Connection *conn, const char *url,
                        const char *method, const request_t *req, char *msg, size_t n)
{
    const http_auth_t *a = &srv->auth;
    const char *host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Host");
    char name[HTTP_NAME_MAX];
    if (host_fields(conn) > 1u) {
        snprintf(msg, n, "more than one Host header");
        return 400u;
    }
    if (host != NULL && !host_name(host, name, sizeof name)) {
        printable(name, 80u, host);
        snprintf(msg, n, "Host '%s' is not NAME[:PORT]", name);
        return 400u;
    }
    if (!host_allowed(a, host)) {
        printable(name, 80u, host != NULL && host_name(host, name, sizeof name) ? name : "");
        snprintf(msg, n, "Host '%s' is not allowed; start dfp-sim with --http-allow-host %s to "
                 "allow it", name, name[0] != '\0' ? name : "NAME");
        return 403u;
    }
    if (!reads_only(method)) {
        const char *origin = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Origin");
        if (origin != NULL && !origin_allowed(a, origin, host)) {
            printable(name, 120u, origin);
            snprintf(msg, n, "Origin '%s' is not allowed", name);
            return 403u;
        }
        const char *type = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Content-Type");
        if (!json_type(type)) {
            snprintf(msg, n, "Content-Type must be application/json");
            return 415u;
        }
    }
    if (needs_credential(url, method) && req->role == HTTP_ROLE_NONE) {
        snprintf(msg, n, "%s", HTTP_NEED_TOKEN);
        return 401u;
    }
    if (is_action(url, method) && req->role == HTTP_ROLE_VIEWER) {
        snprintf(msg, n, "this needs the operator role; this client is a viewer");
        return 403u;
    }
    return 0u;
}

bool http_guard(http_server_t *srv, struct MHD_Connection *conn, const char *url,
                const char *method, request_t *req, enum MHD_Result *rc)
{
    client_address(conn, req->client, sizeof req->client);
    req->role = srv->auth.no_auth ? HTTP_ROLE_OPERATOR : http_credential(srv, conn);
    char msg[300];
    unsigned status = refusal(srv, conn, url, method, req, msg, sizeof msg);
    if (status == 0u) {
        return true;
    }
    char path[128];
    printable(path, sizeof path, url);
    char verb[16];
    printable(verb, sizeof verb, method);
    http_audit(srv, RIG_LOG_WARN, "%s %s %s %s -> %u %s", req->client,
               http_role_name(req->role), verb, path, status, msg);
    *rc = status == 401u ? http_send_unauthorized(conn)
                         : http_send_error(conn, status, "%s", msg);
    return false;
}
