/* Credentials (docs/api.md "Security"): the operator's and the viewer's token, sent as
 * "Authorization: Bearer TOKEN", and the sessions of the panel's logins, sent as the cookie
 * dfp_session. Tokens are compared as hashes in constant time (libsodium); sessions live in the
 * server, at most HTTP_SESSIONS of them, as long as the process. */
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "http_internal.h"

#define COOKIE_NAME "dfp_session"

static void token_hash(uint8_t out[HTTP_HASH_LEN], const char *token)
{
    crypto_generichash(out, HTTP_HASH_LEN, (const unsigned char *)token, strlen(token), NULL, 0);
}

static bool copy_names(char (*dst)[HTTP_NAME_MAX], size_t *n, const char *const *src,
                       size_t count, const char *option, char *err, size_t errlen)
{
    if (count > HTTP_MAX_ALLOWED) {
        snprintf(err, errlen, "%s: at most %u", option, HTTP_MAX_ALLOWED);
        return false;
    }
    for (size_t i = 0; i < count; i++) {
        if (src[i] == NULL || src[i][0] == '\0' || strlen(src[i]) >= HTTP_NAME_MAX) {
            snprintf(err, errlen, "%s: give a name of 1..%u characters", option,
                     HTTP_NAME_MAX - 1u);
            return false;
        }
        snprintf(dst[i], HTTP_NAME_MAX, "%s", src[i]);
    }
    *n = count;
    return true;
}

bool http_auth_init(http_auth_t *a, const http_config_t *cfg, char *err, size_t errlen)
{
    memset(a, 0, sizeof *a);
    pthread_mutex_init(&a->lock, NULL);
    if (sodium_init() < 0) {
        snprintf(err, errlen, "--http: libsodium did not start");
        return false;
    }
    a->no_auth = cfg->no_auth;
    if (!cfg->no_auth && (cfg->token == NULL || !http_token_valid(cfg->token))) {
        snprintf(err, errlen, "--http: no valid operator token");
        return false;
    }
    if (cfg->token != NULL) {
        token_hash(a->operator_hash, cfg->token);
    }
    a->has_viewer = cfg->viewer_token != NULL;
    if (a->has_viewer) {
        token_hash(a->viewer_hash, cfg->viewer_token);
    }
    if (!copy_names(a->allow_host, &a->n_allow_host, cfg->allow_host, cfg->n_allow_host,
                    "--http-allow-host", err, errlen) ||
        !copy_names(a->allow_origin, &a->n_allow_origin, cfg->allow_origin,
                    cfg->n_allow_origin, "--http-allow-origin", err, errlen)) {
        return false;
    }
    a->tls = cfg->cert_pem != NULL;
    if (a->tls) {
        a->cert_pem = strdup(cfg->cert_pem);
        a->key_pem = strdup(cfg->key_pem);
        if (a->cert_pem == NULL || a->key_pem == NULL) {
            snprintf(err, errlen, "--http: out of memory");
            http_auth_destroy(a);
            return false;
        }
    }
    return true;
}

void http_auth_destroy(http_auth_t *a)
{
    free(a->cert_pem);
    if (a->key_pem != NULL) {
        sodium_memzero(a->key_pem, strlen(a->key_pem));
        free(a->key_pem);
    }
    a->cert_pem = NULL;
    a->key_pem = NULL;
    pthread_mutex_destroy(&a->lock);
}

static http_role_t token_role(const http_auth_t *a, const char *token)
{
    if (a->no_auth || token == NULL) {
        return HTTP_ROLE_NONE;
    }
    uint8_t h[HTTP_HASH_LEN];
    token_hash(h, token);
    if (sodium_memcmp(h, a->operator_hash, sizeof h) == 0) {
        return HTTP_ROLE_OPERATOR;
    }
    if (a->has_viewer && sodium_memcmp(h, a->viewer_hash, sizeof h) == 0) {
        return HTTP_ROLE_VIEWER;
    }
    return HTTP_ROLE_NONE;
}

/* The session with this id: its index, or -1. Every entry is compared, in constant time. */
static int session_find(http_auth_t *a, const char *id)
{
    if (id == NULL || strlen(id) != HTTP_SESSION_ID_LEN) {
        return -1;
    }
    int found = -1;
    for (size_t i = 0; i < HTTP_SESSIONS; i++) {
        bool same = sodium_memcmp(a->sessions[i].id, id, HTTP_SESSION_ID_LEN) == 0;
        if (same && a->sessions[i].role != HTTP_ROLE_NONE) {
            found = (int)i;
        }
    }
    return found;
}

static http_role_t cookie_role(http_auth_t *a, const char *id)
{
    pthread_mutex_lock(&a->lock);
    int k = session_find(a, id);
    http_role_t role = k >= 0 ? a->sessions[k].role : HTTP_ROLE_NONE;
    pthread_mutex_unlock(&a->lock);
    return role;
}

http_role_t http_credential(http_server_t *srv, struct MHD_Connection *conn)
{
    const char *h = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Authorization");
    if (h != NULL && strncasecmp(h, "Bearer ", 7) == 0) {
        http_role_t role = token_role(&srv->auth, h + 7 + strspn(h + 7, " "));
        if (role != HTTP_ROLE_NONE) {
            return role;
        }
    }
    return cookie_role(&srv->auth,
                       MHD_lookup_connection_value(conn, MHD_COOKIE_KIND, COOKIE_NAME));
}

bool http_credential_given(struct MHD_Connection *conn)
{
    return MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Authorization") != NULL ||
           MHD_lookup_connection_value(conn, MHD_COOKIE_KIND, COOKIE_NAME) != NULL;
}

/* A new session with role: its id into id; false when no random id could be made. Each role
 * has half the table: when its half is full, its own oldest session makes room, so logins with
 * the viewer token can never end an operator's session (nor the reverse). */
static bool session_new(http_auth_t *a, http_role_t role, char *id, size_t n)
{
    if (!http_token_generate(id, n)) {
        return false;
    }
    pthread_mutex_lock(&a->lock);
    size_t pick = HTTP_SESSIONS;
    size_t oldest = HTTP_SESSIONS;
    size_t mine = 0;
    for (size_t i = 0; i < HTTP_SESSIONS; i++) {
        const http_session_t *e = &a->sessions[i];
        if (e->role == HTTP_ROLE_NONE) {
            pick = pick < HTTP_SESSIONS ? pick : i;
        } else if (e->role == role) {
            mine++;
            oldest = oldest < HTTP_SESSIONS && a->sessions[oldest].born <= e->born ? oldest : i;
        }
    }
    if (mine >= HTTP_SESSIONS / 2u || pick == HTTP_SESSIONS) {
        pick = oldest; /* a full table holds a half of this role: there is one */
    }
    if (pick == HTTP_SESSIONS) {
        pick = 0u;
    }
    http_session_t *s = &a->sessions[pick];
    snprintf(s->id, sizeof s->id, "%s", id);
    s->role = role;
    s->born = a->born_next++;
    pthread_mutex_unlock(&a->lock);
    return true;
}

enum MHD_Result http_login(http_server_t *srv, struct MHD_Connection *conn, const request_t *req)
{
    cJSON *o = cJSON_CreateObject();
    if (srv->auth.no_auth) {
        http_audit(srv, RIG_LOG_INFO, "%s login operator -> 200", req->client);
        cJSON_AddStringToObject(o, "role", "operator");
        return http_send_json(conn, 200, o);
    }
    static const char *const allowed[] = {"token", NULL};
    enum MHD_Result rc = MHD_NO;
    cJSON *body = http_parse_body(conn, req, allowed, &rc);
    if (body == NULL) {
        cJSON_Delete(o);
        http_audit(srv, RIG_LOG_WARN, "%s login -> 400", req->client);
        return rc;
    }
    const char *token = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(body, "token"));
    http_role_t role = token_role(&srv->auth, token);
    cJSON_Delete(body);
    char id[HTTP_SESSION_ID_LEN + 1u];
    if (role == HTTP_ROLE_NONE || !session_new(&srv->auth, role, id, sizeof id)) {
        http_audit(srv, RIG_LOG_WARN, "%s login -> 401", req->client);
        cJSON_Delete(o);
        return http_send_unauthorized(conn);
    }
    char cookie[128];
    snprintf(cookie, sizeof cookie, COOKIE_NAME "=%s; Path=/; HttpOnly; SameSite=Strict%s", id,
             srv->auth.tls ? "; Secure" : "");
    sodium_memzero(id, sizeof id);
    const char *const headers[] = {"Set-Cookie", cookie, NULL};
    http_audit(srv, RIG_LOG_INFO, "%s login %s -> 200", req->client, http_role_name(role));
    cJSON_AddStringToObject(o, "role", http_role_name(role));
    enum MHD_Result sent = http_send_json_with(conn, 200, o, headers);
    sodium_memzero(cookie, sizeof cookie);
    return sent;
}

enum MHD_Result http_logout(http_server_t *srv, struct MHD_Connection *conn,
                            const request_t *req)
{
    const char *id = MHD_lookup_connection_value(conn, MHD_COOKIE_KIND, COOKIE_NAME);
    http_auth_t *a = &srv->auth;
    pthread_mutex_lock(&a->lock);
    int k = session_find(a, id);
    if (k >= 0) {
        memset(&a->sessions[k], 0, sizeof a->sessions[k]);
    }
    pthread_mutex_unlock(&a->lock);
    http_audit(srv, RIG_LOG_INFO, "%s logout %s -> 200", req->client, http_role_name(req->role));
    static const char *const headers[] = {
        "Set-Cookie", COOKIE_NAME "=; Path=/; Max-Age=0; HttpOnly; SameSite=Strict", NULL};
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "ok", true);
    return http_send_json_with(conn, 200, o, headers);
}

enum MHD_Result http_session_info(http_server_t *srv, struct MHD_Connection *conn,
                                  const request_t *req)
{
    if (req->role == HTTP_ROLE_NONE && http_credential_given(conn)) {
        /* It answers whether a token is right, like every route: such a try is told too. */
        http_audit(srv, RIG_LOG_WARN, "%s %s GET /api/v1/session -> 200 a wrong credential",
                   req->client, http_role_name(req->role));
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "auth", !srv->auth.no_auth);
    if (req->role == HTTP_ROLE_NONE) {
        cJSON_AddNullToObject(o, "role");
    } else {
        cJSON_AddStringToObject(o, "role", http_role_name(req->role));
    }
    return http_send_json(conn, 200, o);
}
