/* The control API and front panel over HTTP (docs/api.md): libmicrohttpd serves it from its own
 * threads, cJSON reads and writes the JSON. Everything goes through a rig_ctl bridge, so the
 * bus loop never waits for a client. Who may do what is docs/api.md's "Security": a Host
 * allow-list, Origin and Content-Type checks, a token or a session cookie, two roles, TLS. */
#ifndef DFP_HTTP_HTTP_SERVER_H
#define DFP_HTTP_HTTP_SERVER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rig/rig_ctl.h"

typedef struct http_server http_server_t;

#define HTTP_TOKEN_MIN 16u
#define HTTP_TOKEN_MAX 256u
/* A generated token: 32 random octets in URL-safe base64 without padding. */
#define HTTP_TOKEN_GENERATED_LEN 43u
#define HTTP_MAX_ALLOWED 8u /* --http-allow-host, --http-allow-origin: each at most this many */

/* What http_server_start needs; the server copies what it keeps. */
typedef struct http_config {
    const char *listen;       /* [ADDR:]PORT */
    const char *token;        /* the operator's; NULL only with no_auth */
    const char *viewer_token; /* NULL: there is no viewer role */
    bool no_auth;             /* every client is operator (loopback only) */
    const char *allow_host[HTTP_MAX_ALLOWED]; /* more Host names than IP literals, localhost */
    size_t n_allow_host;
    const char *allow_origin[HTTP_MAX_ALLOWED]; /* more Origins than the server's own */
    size_t n_allow_origin;
    const char *cert_pem; /* both, or neither: plain HTTP */
    const char *key_pem;
} http_config_t;

/* "8080", "127.0.0.1:8080", "0.0.0.0:8080", "[::1]:8080". Without an address: 127.0.0.1.
 * Returns false with a reason. */
bool http_parse_listen(const char *text, char *host, size_t hostlen, uint16_t *port, char *err,
                       size_t errlen);
/* 127.0.0.0/8 or ::1 (also ::ffff:127.x.y.z). */
bool http_is_loopback(const char *host);
/* Whether text may be a token: HTTP_TOKEN_MIN..HTTP_TOKEN_MAX printable ASCII characters
 * without spaces. */
bool http_token_valid(const char *text);
/* A new random token (libsodium) into out (at least HTTP_TOKEN_GENERATED_LEN + 1 octets);
 * false when libsodium cannot start. */
bool http_token_generate(char *out, size_t outlen);
/* The first line of the file at path (CR and LF stripped) into out; false with a reason naming
 * option and path. */
bool http_token_read_file(const char *option, const char *path, char *out, size_t outlen,
                          char *err, size_t errlen);
/* A whole PEM file (certificate or key) into a heap string (free it); NULL with a reason. */
char *http_pem_read_file(const char *option, const char *path, char *err, size_t errlen);
/* Where the credentials come from (a command line's options; NULL: not given). */
typedef struct http_credential_sources {
    bool no_auth;                  /* only on a loopback address */
    const char *token_file;        /* else $DFP_SIM_TOKEN, else a token is made */
    const char *viewer_token_file; /* else $DFP_SIM_VIEWER_TOKEN, else no viewer */
    const char *cert;              /* PEM files: both or neither */
    const char *key;
} http_credential_sources_t;

/* The tokens and PEM texts the server is started with (docs/api.md "Security"). */
typedef struct http_credentials {
    char token[HTTP_TOKEN_MAX + 1u];  /* "" with no_auth */
    char viewer[HTTP_TOKEN_MAX + 1u]; /* "": no viewer role */
    char *cert_pem;
    char *key_pem;
} http_credentials_t;

/* The rules between the sources (--http-no-auth only on loopback host, cert with key, two
 * different tokens), then the tokens and PEM texts into out. False with a one-line reason;
 * free out with http_credentials_free either way. */
bool http_credentials_load(const http_credential_sources_t *src, const char *host,
                           http_credentials_t *out, char *err, size_t errlen);
/* Wipes the tokens and the key and frees the PEM texts. */
void http_credentials_free(http_credentials_t *c);
/* Starts serving; NULL with a one-line reason in err (port taken, bad address, bad TLS files). */
http_server_t *http_server_start(rig_ctl_t *ctl, const http_config_t *cfg, char *err,
                                 size_t errlen);
/* The port actually bound (useful with port 0). */
uint16_t http_server_port(const http_server_t *s);
void http_server_stop(http_server_t *s);

#endif
