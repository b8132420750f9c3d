/* What the control API's source files share (private to dfp_http): the server, a request's
 * body, replies, the JSON of the rig's state, request-body readers and the actions. Every
 * handler runs in one of libmicrohttpd's connection threads and reaches the rig only through
 * rig_ctl. */
#ifndef DFP_HTTP_HTTP_INTERNAL_H
#define DFP_HTTP_HTTP_INTERNAL_H

#include <cjson/cJSON.h>
#include <microhttpd.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "http/http_server.h"
#include "movidrive/movidrive_names.h"
#include "rig/rig_ctl.h"

#define BODY_MAX 16384u
#define ACTION_TIMEOUT_MS 2000u
#define SERVICE_TIMEOUT_MS 7000u
/* One thread per connection, so the limit is the server's size. Past it new connections wait
 * unanswered in the listen backlog, so whatever holds a connection for long is bounded below
 * it: event streams (held for ever) by MAX_STREAMS, a connection that sends no request by
 * IDLE_TIMEOUT_S, one between two requests by KEEPALIVE_TIMEOUT_S. docs/api.md gives them. */
#define MAX_CONNECTIONS 64u
#define MAX_STREAMS 32u
#define IDLE_TIMEOUT_S 5u
#define KEEPALIVE_TIMEOUT_S 30u
_Static_assert(MAX_STREAMS < MAX_CONNECTIONS, "event streams must leave connections for requests");
/* Per client (http_limits.c, docs/api.md): connections from one address, the time to deliver a
 * whole request, and the nice value of the threads serving them (the bus loop runs at 0). */
#define PER_ADDRESS_CONNECTIONS 8u
#define REQUEST_LIMIT_S 10u
/* Connections still to deliver a request (opened, or idle after an answer): past this many the
 * oldest of them is closed for a new one. Slow clients from many addresses then hold at most
 * these, never all MAX_CONNECTIONS, and an honest request (delivered within milliseconds of
 * its connection) still finds a place. */
#define PENDING_CONNECTIONS 16u
_Static_assert(PENDING_CONNECTIONS + MAX_STREAMS < MAX_CONNECTIONS,
               "slow clients and event streams must leave connections for requests");
#define REQUEST_NICE 10

/* ---- access control (http_auth.c, http_session.c; docs/api.md "Security") ----------------- */

typedef enum http_role {
    HTTP_ROLE_NONE = 0, /* no valid credential */
    HTTP_ROLE_VIEWER,
    HTTP_ROLE_OPERATOR,
} http_role_t;

#define HTTP_SESSIONS 64u
#define HTTP_SESSION_ID_LEN HTTP_TOKEN_GENERATED_LEN
#define HTTP_NAME_MAX 256u /* a Host name or an Origin of the allow-lists */
#define HTTP_HASH_LEN 32u

typedef struct http_session {
    char id[HTTP_SESSION_ID_LEN + 1u]; /* "": a free entry */
    http_role_t role;
    uint64_t born; /* creation order: when the table is full the oldest goes */
} http_session_t;

typedef struct http_auth {
    bool no_auth;
    bool tls;
    bool has_viewer;
    /* Tokens are kept as hashes: comparing two hashes of one length in constant time says
     * nothing about a token's length or its first differing octet. */
    uint8_t operator_hash[HTTP_HASH_LEN];
    uint8_t viewer_hash[HTTP_HASH_LEN];
    char allow_host[HTTP_MAX_ALLOWED][HTTP_NAME_MAX];
    size_t n_allow_host;
    char allow_origin[HTTP_MAX_ALLOWED][HTTP_NAME_MAX];
    size_t n_allow_origin;
    char *cert_pem; /* kept for the daemon's life */
    char *key_pem;
    pthread_mutex_t lock; /* the sessions */
    http_session_t sessions[HTTP_SESSIONS];
    uint64_t born_next;
} http_auth_t;

struct http_server {
    struct MHD_Daemon *daemon;
    rig_ctl_t *ctl;
    struct http_limits *limits;
    atomic_uint streams; /* event streams open now */
    int listen_fd;
    uint16_t port;
    volatile int stopping;
    http_auth_t auth;
};

typedef struct request {
    char body[BODY_MAX + 1u];
    size_t len;
    bool too_large;
    http_role_t role;
    char client[64]; /* "127.0.0.1:45122", for the audit */
} request_t;

/* One per connection (libmicrohttpd's socket context, an entry of http_limits.c's table): its
 * deadline, and what its last answer's error said, so the audit line of an action can give it. */
typedef struct http_conn {
    struct http_limits *owner;
    bool used;
    int fd;
    uint64_t deadline_ns; /* 0: none (its request is being answered) */
    bool answered;        /* a request of it was answered: idle now is keep-alive */
    char peer[64];
    char error[RIG_CTL_TEXT];
} http_conn_t;

/* ---- limits per client (http_limits.c) ---------------------------------------------------- */

typedef struct http_limits http_limits_t;
/* Starts the reaper; NULL when out of memory or threads. */
http_limits_t *http_limits_new(rig_ctl_t *ctl);
/* Options for MHD_start_daemon (MHD_OPTION_ARRAY); they live as long as l. */
struct MHD_OptionItem *http_limits_options(http_limits_t *l);
/* After MHD_stop_daemon (it tells l of the connections it closes). NULL: nothing. */
void http_limits_free(http_limits_t *l);
/* The request is complete (headers and body): no deadline until its answer ends. */
void http_limits_delivered(struct MHD_Connection *conn);
/* Its answer ended: the next request has REQUEST_LIMIT_S. */
void http_limits_request_end(struct MHD_Connection *conn);

/* ---- replies (http_reply.c) ---------------------------------------------------------------- */

/* Adds the headers every answer carries (docs/api.md: framing, sniffing, CSP, caching), queues
 * r and releases it. Every answer goes through here. */
enum MHD_Result http_queue(struct MHD_Connection *conn, unsigned status, struct MHD_Response *r);
/* Sends obj and frees it, with more headers: NULL-terminated name, value pairs. */
enum MHD_Result http_send_json_with(struct MHD_Connection *conn, unsigned status, cJSON *obj,
                                    const char *const *headers);
#define HTTP_NEED_TOKEN "a token is needed: open the URL dfp-sim printed at start, or send " \
                        "Authorization: Bearer TOKEN"
/* 401 {"error": HTTP_NEED_TOKEN} with WWW-Authenticate. */
enum MHD_Result http_send_unauthorized(struct MHD_Connection *conn);
/* The error text of the last answer on this connection ("" after a success). */
const char *http_last_error(struct MHD_Connection *conn);
void http_clear_error(struct MHD_Connection *conn);

/* copy: MHD copies text; otherwise text must outlive the response (the embedded files). */
enum MHD_Result http_send_text(struct MHD_Connection *conn, unsigned status, const char *type,
                               const char *text, size_t len, bool copy);
/* Sends obj and frees it. */
enum MHD_Result http_send_json(struct MHD_Connection *conn, unsigned status, cJSON *obj);
/* {"error": "..."} */
enum MHD_Result http_send_error(struct MHD_Connection *conn, unsigned status, const char *fmt,
                                ...) __attribute__((format(printf, 3, 4)));

/* ---- the rig's state as JSON (http_json.c) ------------------------------------------------- */

/* A heap copy of the published snapshot (it is large); NULL when out of memory. */
rig_snapshot_t *http_snapshot(rig_ctl_t *ctl);
cJSON *http_json_state(rig_ctl_t *ctl, const rig_snapshot_t *s);
cJSON *http_json_card(const rig_snap_card_t *c);
cJSON *http_json_event(const rig_ctl_event_t *e);
cJSON *http_json_param_info(const movidrive_param_info_t *p);

/* ---- the event stream (http_stream.c) ------------------------------------------------------ */

enum MHD_Result http_serve_events(http_server_t *srv, struct MHD_Connection *conn);

/* ---- request bodies (http_body.c) ---------------------------------------------------------- */

/* The body as a JSON object whose keys are all in `allowed` (NULL-terminated); NULL with the
 * error already sent (*rc). */
cJSON *http_parse_body(struct MHD_Connection *conn, const request_t *req,
                       const char *const *allowed, enum MHD_Result *rc);
/* Optional fields leave *out as it is when absent. false with a message in err. */
bool http_get_bool(const cJSON *o, const char *key, bool required, bool *out, char *err,
                   size_t n);
bool http_get_int(const cJSON *o, const char *key, bool required, long lo, long hi, long *out,
                  char *err, size_t n);
/* "value": a number, or a text the parameter knows ("FIELDBUS", "300.5"). */
bool http_get_value(const cJSON *o, const movidrive_param_info_t *p, int32_t *raw, char *err,
                    size_t n);

/* ---- actions (http_actions.c) -------------------------------------------------------------- */

/* Runs cmd in the bus loop and answers {"ok": true} or its error. */
enum MHD_Result http_submit(http_server_t *srv, struct MHD_Connection *conn, rig_cmd_t *cmd,
                            unsigned timeout_ms);
enum MHD_Result http_card_action(http_server_t *srv, struct MHD_Connection *conn,
                                 uint8_t address, const char *what, const request_t *req);
enum MHD_Result http_card_param(http_server_t *srv, struct MHD_Connection *conn,
                                uint8_t address, const char *name, const char *method,
                                const request_t *req);
enum MHD_Result http_master_run(http_server_t *srv, struct MHD_Connection *conn,
                                const request_t *req);
enum MHD_Result http_master_param(http_server_t *srv, struct MHD_Connection *conn,
                                  const request_t *req);
enum MHD_Result http_master_outputs(http_server_t *srv, struct MHD_Connection *conn,
                                    uint8_t address, const request_t *req);

/* ---- access control (http_auth.c, http_session.c) ----------------------------------------- */

/* Copies what the server keeps from cfg; false with a reason. */
bool http_auth_init(http_auth_t *a, const http_config_t *cfg, char *err, size_t errlen);
void http_auth_destroy(http_auth_t *a);
/* The checks of docs/api.md in order (Host, Origin, Content-Type, credential, role). true: the
 * request may go on (req->role and req->client set); false: refused, answered (*rc), audited. */
bool http_guard(http_server_t *srv, struct MHD_Connection *conn, const char *url,
                const char *method, request_t *req, enum MHD_Result *rc);
/* The role the request's credential (Bearer token or session cookie) gives. */
http_role_t http_credential(http_server_t *srv, struct MHD_Connection *conn);
/* Whether the request carries a credential at all (a Bearer token or the session cookie). */
bool http_credential_given(struct MHD_Connection *conn);
const char *http_role_name(http_role_t role);
/* One audit event (source "http", kind "audit") into the rig's log. */
void http_audit(http_server_t *srv, rig_log_level_t level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The audit line of an action, once its answer is queued. */
void http_audit_result(http_server_t *srv, struct MHD_Connection *conn, const request_t *req,
                       const char *method, const char *url);
/* POST /api/v1/login, POST /api/v1/logout, GET /api/v1/session. */
enum MHD_Result http_login(http_server_t *srv, struct MHD_Connection *conn, const request_t *req);
enum MHD_Result http_logout(http_server_t *srv, struct MHD_Connection *conn,
                            const request_t *req);
enum MHD_Result http_session_info(http_server_t *srv, struct MHD_Connection *conn,
                                  const request_t *req);

/* ---- routing (http_routes.c) --------------------------------------------------------------- */

/* path: what follows /api/v1/. */
enum MHD_Result http_route_api(http_server_t *srv, struct MHD_Connection *conn,
                               const char *path, const char *method, const request_t *req);
/* An embedded panel file ("/" is index.html). */
enum MHD_Result http_serve_file(struct MHD_Connection *conn, const char *url);
/* true and *rest after the prefix when s starts with it. */
bool http_starts(const char *s, const char *prefix, const char **rest);

#endif
