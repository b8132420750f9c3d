#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "http/www_files.h"
#include "http_internal.h"

#define LOG_LIMIT_DEFAULT 500u

bool http_starts(const char *s, const char *prefix, const char **rest)
{
    size_t n = strlen(prefix);
    if (strncmp(s, prefix, n) != 0) {
        return false;
    }
    *rest = s + n;
    return true;
}

static bool parse_address(const char *text, size_t len, uint8_t *out)
{
    if (len == 0u || len > 3u) {
        return false;
    }
    unsigned v = 0;
    for (size_t i = 0; i < len; i++) {
        if (text[i] < '0' || text[i] > '9') {
            return false;
        }
        v = v * 10u + (unsigned)(text[i] - '0');
    }
    if (v > 127u) {
        return false;
    }
    *out = (uint8_t)v;
    return true;
}

/* How many cards answer to address now (two after a DIP change and a power cycle). */
static unsigned cards_at(http_server_t *srv, uint8_t address)
{
    rig_snapshot_t *s = http_snapshot(srv->ctl);
    unsigned n = 0;
    for (unsigned i = 0; s != NULL && i < s->num_cards; i++) {
        n += s->cards[i].address == address ? 1u : 0u;
    }
    free(s);
    return n;
}

static enum MHD_Result serve_card(http_server_t *srv, struct MHD_Connection *conn,
                                  uint8_t address)
{
    rig_snapshot_t *s = http_snapshot(srv->ctl);
    if (s == NULL) {
        return MHD_NO;
    }
    cJSON *o = NULL;
    for (unsigned i = 0; i < s->num_cards; i++) {
        if (s->cards[i].address == address) {
            o = http_json_card(&s->cards[i]);
        }
    }
    free(s);
    return http_send_json(conn, 200, o);
}

static enum MHD_Result route_card(http_server_t *srv, struct MHD_Connection *conn,
                                  const char *rest, const char *method, const request_t *req)
{
    const char *slash = strchr(rest, '/');
    size_t alen = slash != NULL ? (size_t)(slash - rest) : strlen(rest);
    uint8_t address;
    if (!parse_address(rest, alen, &address)) {
        return http_send_error(conn, 404, "'%.*s' is not a card address (0..127)", (int)alen,
                               rest);
    }
    unsigned same = cards_at(srv, address);
    if (same == 0u) {
        return http_send_error(conn, 404, "no card with address %u", address);
    }
    if (same > 1u) {
        /* Refused for reads too: showing one card while an action reaches the other would
         * make the API contradict itself. */
        return http_send_error(conn, 409, RIG_CTL_AMBIGUOUS_FMT, same, address);
    }
    if (slash == NULL || slash[1] == '\0') {
        if (strcmp(method, "GET") != 0) {
            return http_send_error(conn, 405, "use GET");
        }
        return serve_card(srv, conn, address);
    }
    const char *what = slash + 1;
    const char *pname;
    if (http_starts(what, "params/", &pname)) {
        if (strcmp(method, "GET") != 0 && strcmp(method, "PUT") != 0) {
            return http_send_error(conn, 405, "use GET or PUT");
        }
        if (strcmp(method, "PUT") == 0 && srv->ctl->read_only) {
            return http_send_error(conn, 403, "this server is read-only");
        }
        return http_card_param(srv, conn, address, pname, method, req);
    }
    if (strcmp(method, "POST") != 0) {
        return http_send_error(conn, 405, "use POST");
    }
    if (srv->ctl->read_only) {
        return http_send_error(conn, 403, "this server is read-only");
    }
    return http_card_action(srv, conn, address, what, req);
}

static enum MHD_Result route_master(http_server_t *srv, struct MHD_Connection *conn,
                                    const char *rest, const char *method, const request_t *req)
{
    if (strcmp(method, "POST") != 0) {
        return http_send_error(conn, 405, "use POST");
    }
    if (srv->ctl->read_only) {
        return http_send_error(conn, 403, "this server is read-only");
    }
    const char *sub;
    if (strcmp(rest, "run") == 0) {
        return http_master_run(srv, conn, req);
    }
    if (strcmp(rest, "param") == 0) {
        return http_master_param(srv, conn, req);
    }
    if (http_starts(rest, "slaves/", &sub)) {
        const char *slash = strchr(sub, '/');
        uint8_t address;
        if (slash != NULL && strcmp(slash, "/outputs") == 0 &&
            parse_address(sub, (size_t)(slash - sub), &address)) {
            return http_master_outputs(srv, conn, address, req);
        }
    }
    return http_send_error(conn, 404, "no such master endpoint");
}

static enum MHD_Result serve_state(http_server_t *srv, struct MHD_Connection *conn)
{
    rig_snapshot_t *s = http_snapshot(srv->ctl);
    if (s == NULL) {
        return MHD_NO;
    }
    cJSON *o = http_json_state(srv->ctl, s);
    free(s);
    return http_send_json(conn, 200, o);
}

static enum MHD_Result serve_log(http_server_t *srv, struct MHD_Connection *conn)
{
    const char *since = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "since");
    const char *limit = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "limit");
    char *end = NULL;
    unsigned long long from = since != NULL ? strtoull(since, &end, 10) : 0u;
    if (since != NULL && (end == since || *end != '\0')) {
        return http_send_error(conn, 400, "'since' must be an event number");
    }
    unsigned long lim = limit != NULL ? strtoul(limit, &end, 10) : LOG_LIMIT_DEFAULT;
    if (limit != NULL && (end == limit || *end != '\0' || lim == 0u || lim > 4096u)) {
        return http_send_error(conn, 400, "'limit' must be 1..4096");
    }
    rig_ctl_event_t *ev = malloc(lim * sizeof *ev);
    if (ev == NULL) {
        return MHD_NO;
    }
    uint64_t lost = 0;
    size_t n = rig_ctl_events(srv->ctl, from, ev, lim, &lost);
    cJSON *a = cJSON_CreateArray();
    for (size_t i = 0; i < n; i++) {
        cJSON_AddItemToArray(a, http_json_event(&ev[i]));
    }
    free(ev);
    return http_send_json(conn, 200, a);
}

/* The monitor's document as the loop last published it, sent as it is (it is JSON already). */
static enum MHD_Result serve_bus(http_server_t *srv, struct MHD_Connection *conn)
{
    if (srv->ctl->bus == NULL) {
        return http_send_error(conn, 404, "this process has no bus monitor");
    }
    size_t len = 0;
    char *doc = rig_doc_copy(srv->ctl->bus, &len);
    if (doc == NULL) {
        return http_send_error(conn, 503, "the bus monitor has published nothing yet; try "
                               "again");
    }
    enum MHD_Result rc = http_send_text(conn, 200, "application/json", doc, len, true);
    free(doc);
    return rc;
}

static enum MHD_Result serve_params(struct MHD_Connection *conn)
{
    const char *q = MHD_lookup_connection_value(conn, MHD_GET_ARGUMENT_KIND, "q");
    cJSON *a = cJSON_CreateArray();
    for (size_t i = 0; i < movidrive_param_count(); i++) {
        const movidrive_param_info_t *p = movidrive_param_at(i);
        char idx[8];
        (void)snprintf(idx, sizeof idx, "%u", p->index);
        if (q == NULL || q[0] == '\0' || strcasestr(p->p_number, q) != NULL ||
            strcasestr(p->name, q) != NULL || strcmp(idx, q) == 0) {
            cJSON_AddItemToArray(a, http_json_param_info(p));
        }
    }
    return http_send_json(conn, 200, a);
}

enum MHD_Result http_route_api(http_server_t *srv, struct MHD_Connection *conn,
                               const char *path, const char *method, const request_t *req)
{
    bool read = strcmp(path, "state") == 0 || strcmp(path, "log") == 0 ||
                strcmp(path, "events") == 0 || strcmp(path, "params") == 0 ||
                strcmp(path, "bus") == 0;
    if (read && strcmp(method, "GET") != 0) {
        return http_send_error(conn, 405, "use GET");
    }
    if (strcmp(path, "state") == 0) {
        return serve_state(srv, conn);
    }
    if (strcmp(path, "events") == 0) {
        return http_serve_events(srv, conn);
    }
    if (strcmp(path, "log") == 0) {
        return serve_log(srv, conn);
    }
    if (strcmp(path, "params") == 0) {
        return serve_params(conn);
    }
    if (strcmp(path, "bus") == 0) {
        return serve_bus(srv, conn);
    }
    if (strcmp(path, "session") == 0) {
        return strcmp(method, "GET") == 0 ? http_session_info(srv, conn, req)
                                          : http_send_error(conn, 405, "use GET");
    }
    if (strcmp(path, "login") == 0 || strcmp(path, "logout") == 0) {
        if (strcmp(method, "POST") != 0) {
            return http_send_error(conn, 405, "use POST");
        }
        return strcmp(path, "login") == 0 ? http_login(srv, conn, req)
                                          : http_logout(srv, conn, req);
    }
    const char *rest;
    if (http_starts(path, "cards/", &rest)) {
        return route_card(srv, conn, rest, method, req);
    }
    if (http_starts(path, "master/", &rest)) {
        return route_master(srv, conn, rest, method, req);
    }
    return http_send_error(conn, 404, "no such endpoint: /api/v1/%s", path);
}

enum MHD_Result http_serve_file(struct MHD_Connection *conn, const char *url)
{
    const char *name = strcmp(url, "/") == 0 ? "index.html" : url + 1;
    for (size_t i = 0; i < www_file_count; i++) {
        if (strcmp(www_files[i].name, name) == 0) {
            return http_send_text(conn, 200, www_files[i].mime, (const char *)www_files[i].data,
                                  www_files[i].size, false);
        }
    }
    return http_send_error(conn, 404, "no file '%s'", url);
}

