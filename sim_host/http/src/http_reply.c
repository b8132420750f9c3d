#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "http_internal.h"

/* Against framing (clickjacking), content sniffing, foreign scripts and leaking the address. */
static const char *const security_headers[] = {
    "Content-Security-Policy",
    "default-src 'self'; frame-ancestors 'none'; base-uri 'none'; form-action 'self'",
    "X-Frame-Options", "DENY",
    "X-Content-Type-Options", "nosniff",
    "Referrer-Policy", "no-referrer",
    "Cache-Control", "no-store",
    NULL,
};

enum MHD_Result http_queue(struct MHD_Connection *conn, unsigned status, struct MHD_Response *r)
{
    for (const char *const *h = security_headers; *h != NULL; h += 2) {
        MHD_add_response_header(r, h[0], h[1]);
    }
    if (status == 503u) {
        /* Busy: a client told to come back later should not keep a connection slot meanwhile
         * (a refused event stream's client would otherwise hold one it cannot use). */
        MHD_add_response_header(r, "Connection", "close");
    }
    enum MHD_Result rc = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return rc;
}

static enum MHD_Result send_text(struct MHD_Connection *conn, unsigned status, const char *type,
                                 const char *text, size_t len, bool copy,
                                 const char *const *headers)
{
    void *buf; /* MHD takes a non-const pointer but only reads a PERSISTENT or copied buffer */
    memcpy(&buf, &text, sizeof buf);
    struct MHD_Response *r = MHD_create_response_from_buffer(
        len, buf, copy ? MHD_RESPMEM_MUST_COPY : MHD_RESPMEM_PERSISTENT);
    if (r == NULL) {
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    for (const char *const *h = headers; h != NULL && *h != NULL; h += 2) {
        MHD_add_response_header(r, h[0], h[1]);
    }
    return http_queue(conn, status, r);
}

enum MHD_Result http_send_text(struct MHD_Connection *conn, unsigned status, const char *type,
                               const char *text, size_t len, bool copy)
{
    return send_text(conn, status, type, text, len, copy, NULL);
}

enum MHD_Result http_send_json_with(struct MHD_Connection *conn, unsigned status, cJSON *obj,
                                    const char *const *headers)
{
    char *text = cJSON_PrintUnformatted(obj);
    cJSON_Delete(obj);
    if (text == NULL) {
        return MHD_NO;
    }
    enum MHD_Result rc =
        send_text(conn, status, "application/json", text, strlen(text), true, headers);
    cJSON_free(text);
    return rc;
}

enum MHD_Result http_send_json(struct MHD_Connection *conn, unsigned status, cJSON *obj)
{
    return http_send_json_with(conn, status, obj, NULL);
}

enum MHD_Result http_send_unauthorized(struct MHD_Connection *conn)
{
    static const char *const challenge[] = {"WWW-Authenticate", "Bearer realm=\"dfp-sim\"",
                                            NULL};
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", HTTP_NEED_TOKEN);
    return http_send_json_with(conn, 401, o, challenge);
}

static http_conn_t *conn_context(struct MHD_Connection *conn)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci != NULL ? ci->socket_context : NULL;
}

const char *http_last_error(struct MHD_Connection *conn)
{
    const http_conn_t *c = conn_context(conn);
    return c != NULL ? c->error : "";
}

void http_clear_error(struct MHD_Connection *conn)
{
    http_conn_t *c = conn_context(conn);
    if (c != NULL) {
        c->error[0] = '\0';
    }
}

enum MHD_Result http_send_error(struct MHD_Connection *conn, unsigned status, const char *fmt,
                                ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    http_conn_t *c = conn_context(conn);
    if (c != NULL) {
        /* The audit line has room for RIG_CTL_TEXT: a longer message is cut there. */
        size_t len = strnlen(msg, sizeof c->error - 1u);
        memcpy(c->error, msg, len);
        c->error[len] = '\0';
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", msg);
    return http_send_json(conn, status, o);
}
