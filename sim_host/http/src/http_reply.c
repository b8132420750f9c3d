#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "http_internal.h"

enum MHD_Result http_send_text(struct MHD_Connection *conn, unsigned status, const char *type,
                               const char *text, size_t len, bool copy)
{
    void *buf; /* MHD takes a non-const pointer but only reads a PERSISTENT or copied buffer */
    memcpy(&buf, &text, sizeof buf);
    struct MHD_Response *r = MHD_create_response_from_buffer(
        len, buf, copy ? MHD_RESPMEM_MUST_COPY : MHD_RESPMEM_PERSISTENT);
    if (r == NULL) {
        return MHD_NO;
    }
    MHD_add_response_header(r, "Content-Type", type);
    MHD_add_response_header(r, "Cache-Control", "no-store");
    if (status == 503u) {
        /* Busy: a client told to come back later should not keep a connection slot meanwhile
         * (a refused event stream's client would otherwise hold one it cannot use). */
        MHD_add_response_header(r, "Connection", "close");
    }
    enum MHD_Result rc = MHD_queue_response(conn, status, r);
    MHD_destroy_response(r);
    return rc;
}

enum MHD_Result http_send_json(struct MHD_Connection *conn, unsigned status, cJSON *obj)
{
    char *text = cJSON_PrintUnformatted(obj);
    cJSON_Delete(obj);
    if (text == NULL) {
        return MHD_NO;
    }
    enum MHD_Result rc =
        http_send_text(conn, status, "application/json", text, strlen(text), true);
    cJSON_free(text);
    return rc;
}

enum MHD_Result http_send_error(struct MHD_Connection *conn, unsigned status, const char *fmt,
                                ...)
{
    char msg[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "error", msg);
    return http_send_json(conn, status, o);
}
