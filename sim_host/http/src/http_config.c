/* The server's credentials: tokens (from a file, the environment, or made here), PEM files,
 * and the rules between them (--http-no-auth only on a loopback address). */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <sodium.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "http/http_server.h"

#define PEM_MAX ((size_t)64u * 1024u)

bool http_is_loopback(const char *host)
{
    struct in_addr v4;
    struct in6_addr v6;
    if (inet_pton(AF_INET, host, &v4) == 1) {
        return (ntohl(v4.s_addr) >> 24) == 127u;
    }
    if (inet_pton(AF_INET6, host, &v6) != 1) {
        return false;
    }
    if (IN6_IS_ADDR_V4MAPPED(&v6)) {
        return v6.s6_addr[12] == 127u;
    }
    return IN6_IS_ADDR_LOOPBACK(&v6);
}

bool http_token_valid(const char *text)
{
    size_t n = strlen(text);
    if (n < HTTP_TOKEN_MIN || n > HTTP_TOKEN_MAX) {
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        /* No spaces: the token follows "Bearer " in a header and stands alone in a form field. */
        if (text[i] <= ' ' || text[i] > '~') {
            return false;
        }
    }
    return true;
}

bool http_token_generate(char *out, size_t outlen)
{
    unsigned char raw[32];
    if (outlen < HTTP_TOKEN_GENERATED_LEN + 1u || sodium_init() < 0) {
        return false;
    }
    randombytes_buf(raw, sizeof raw);
    sodium_bin2base64(out, outlen, raw, sizeof raw, sodium_base64_VARIANT_URLSAFE_NO_PADDING);
    sodium_memzero(raw, sizeof raw);
    return true;
}

bool http_token_read_file(const char *option, const char *path, char *out, size_t outlen,
                          char *err, size_t errlen)
{
    FILE *f = fopen(path, "re");
    if (f == NULL) {
        snprintf(err, errlen, "%s '%s': %s", option, path, strerror(errno));
        return false;
    }
    char line[HTTP_TOKEN_MAX + 3u];
    bool got = fgets(line, sizeof line, f) != NULL;
    (void)fclose(f);
    if (got) {
        line[strcspn(line, "\r\n")] = '\0';
    }
    if (!got || !http_token_valid(line) || strlen(line) + 1u > outlen) {
        snprintf(err, errlen, "%s '%s': the first line must be the token, %u..%u printable ASCII "
                 "characters without spaces", option, path, HTTP_TOKEN_MIN, HTTP_TOKEN_MAX);
        sodium_memzero(line, sizeof line);
        return false;
    }
    memcpy(out, line, strlen(line) + 1u);
    sodium_memzero(line, sizeof line);
    return true;
}

char *http_pem_read_file(const char *option, const char *path, char *err, size_t errlen)
{
    FILE *f = fopen(path, "re");
    struct stat st;
    if (f == NULL || fstat(fileno(f), &st) != 0) {
        snprintf(err, errlen, "%s '%s': %s", option, path, strerror(errno));
        if (f != NULL) {
            (void)fclose(f);
        }
        return NULL;
    }
    char *text = NULL;
    if (S_ISREG(st.st_mode) && st.st_size > 0 && (size_t)st.st_size <= PEM_MAX) {
        text = calloc(1, (size_t)st.st_size + 1u);
    }
    size_t n = text != NULL ? fread(text, 1, (size_t)st.st_size, f) : 0u;
    (void)fclose(f);
    if (text == NULL || n != (size_t)st.st_size || strstr(text, "-----BEGIN ") == NULL) {
        snprintf(err, errlen, "%s '%s': not a PEM file (a regular file of at most %zu KiB with a "
                 "-----BEGIN line)", option, path, PEM_MAX / 1024u);
        free(text);
        return NULL;
    }
    return text;
}

void http_credentials_free(http_credentials_t *c)
{
    sodium_memzero(c->token, sizeof c->token);
    sodium_memzero(c->viewer, sizeof c->viewer);
    free(c->cert_pem);
    if (c->key_pem != NULL) {
        sodium_memzero(c->key_pem, strlen(c->key_pem));
        free(c->key_pem);
    }
    c->cert_pem = NULL;
    c->key_pem = NULL;
}

/* A token from --OPTION FILE, else from the environment variable; "" when neither. */
static bool token_from(const char *option, const char *file, const char *env, char *out,
                       size_t n, char *err, size_t errlen)
{
    if (file != NULL) {
        return http_token_read_file(option, file, out, n, err, errlen);
    }
    const char *v = getenv(env);
    if (v == NULL || v[0] == '\0') {
        out[0] = '\0';
        return true;
    }
    if (!http_token_valid(v) || strlen(v) >= n) {
        snprintf(err, errlen, "%s: the token must be %u..%u printable ASCII characters without "
                 "spaces", env, HTTP_TOKEN_MIN, HTTP_TOKEN_MAX);
        return false;
    }
    memcpy(out, v, strlen(v) + 1u);
    return true;
}

static bool tokens_load(const http_credential_sources_t *src, http_credentials_t *out,
                        char *err, size_t errlen)
{
    if (!token_from("--http-token-file", src->token_file, "DFP_SIM_TOKEN", out->token,
                    sizeof out->token, err, errlen) ||
        !token_from("--http-viewer-token-file", src->viewer_token_file, "DFP_SIM_VIEWER_TOKEN",
                    out->viewer, sizeof out->viewer, err, errlen)) {
        return false;
    }
    if (out->token[0] == '\0' && !http_token_generate(out->token, sizeof out->token)) {
        snprintf(err, errlen, "--http: no random token could be made (libsodium did not start)");
        return false;
    }
    if (strcmp(out->token, out->viewer) == 0) {
        snprintf(err, errlen, "--http: the viewer token must differ from the operator token");
        return false;
    }
    return true;
}

bool http_credentials_load(const http_credential_sources_t *src, const char *host,
                           http_credentials_t *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (src->no_auth && !http_is_loopback(host)) {
        snprintf(err, errlen, "--http-no-auth: refused on %s, which is not a loopback address "
                 "(127.0.0.0/8, ::1): anyone who reaches it could steer the rig; use a token",
                 host);
        return false;
    }
    if ((src->cert == NULL) != (src->key == NULL)) {
        snprintf(err, errlen, "--http-cert and --http-key go together: give both or neither");
        return false;
    }
    if (!src->no_auth && !tokens_load(src, out, err, errlen)) {
        return false;
    }
    if (src->cert != NULL) {
        out->cert_pem = http_pem_read_file("--http-cert", src->cert, err, errlen);
        out->key_pem = out->cert_pem != NULL
                           ? http_pem_read_file("--http-key", src->key, err, errlen)
                           : NULL;
        if (out->key_pem == NULL) {
            return false;
        }
    }
    return true;
}
