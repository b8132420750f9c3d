/* What the command line gives the server: tokens (from a file, or made here), PEM files, and
 * whether an address is loopback (--http-no-auth is only allowed there). */
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
