#include <stdio.h>
#include <string.h>

#include "http_internal.h"

/* true when a JSON text holds the escape \u0000. cJSON decodes it into its C strings, which
 * then end there: "DI00\u0000junk" would be taken as the key DI00. The body parsed, so every
 * backslash is inside a string, and a "u0000" is an escape when an odd run of backslashes comes
 * right before it ("\\u0000" is a backslash, then the text u0000). */
static bool has_nul_escape(const char *body, size_t len)
{
    for (size_t i = 1; i + 5u <= len; i++) {
        if (memcmp(body + i, "u0000", 5) != 0) {
            continue;
        }
        size_t run = 0;
        while (run < i && body[i - 1u - run] == '\\') {
            run++;
        }
        if (run % 2u == 1u) {
            return true;
        }
    }
    return false;
}

/* The first problem with the fields of o, or NULL: a key not in allowed, or one given twice
 * (cJSON keeps both and lookups take the first, so the second would be silently ignored). */
static const char *field_problem(const cJSON *o, const char *const *allowed, const char **key)
{
    for (const cJSON *f = o->child; f != NULL; f = f->next) {
        bool ok = false;
        for (const char *const *a = allowed; *a != NULL; a++) {
            ok = ok || strcmp(*a, f->string) == 0;
        }
        *key = f->string;
        if (!ok) {
            return "unknown field '%s'";
        }
        for (const cJSON *g = f->next; g != NULL; g = g->next) {
            if (strcmp(f->string, g->string) == 0) {
                return "field '%s' given twice";
            }
        }
    }
    return NULL;
}

/* Parses the body as exactly one JSON object whose keys are all in `allowed`, each once; NULL
 * with a message sent. */
cJSON *http_parse_body(struct MHD_Connection *conn, const request_t *req,
                       const char *const *allowed, enum MHD_Result *rc)
{
    if (req->too_large) {
        *rc = http_send_error(conn, 413, "request body over %u octets", BODY_MAX);
        return NULL;
    }
    const char *end = NULL;
    cJSON *o = cJSON_ParseWithLengthOpts(req->body, req->len, &end, false);
    if (o == NULL || !cJSON_IsObject(o)) {
        cJSON_Delete(o);
        *rc = http_send_error(conn, 400, "the body must be a JSON object%s",
                         req->len == 0u ? " (it is empty)" : "");
        return NULL;
    }
    /* Two bodies run together by a client's framing bug must not pass as the first one. A NUL
     * octet stops strspn, so one in the body counts as something after the object. */
    size_t after = (size_t)(end - req->body) + strspn(end, " \t\r\n");
    const char *key = NULL;
    const char *problem = field_problem(o, allowed, &key);
    if (after != req->len) {
        *rc = http_send_error(conn, 400, "the body must be one JSON object with nothing after "
                              "it (more follows at octet %zu)", after);
    } else if (has_nul_escape(req->body, req->len)) {
        *rc = http_send_error(conn, 400, "a text in the body holds a NUL character (U+0000)");
    } else if (problem != NULL) {
        *rc = http_send_error(conn, 400, problem, key);
    } else {
        return o;
    }
    cJSON_Delete(o);
    return NULL;
}

bool http_get_bool(const cJSON *o, const char *key, bool required, bool *out, char *err,
                   size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (v == NULL) {
        if (required) {
            snprintf(err, n, "'%s' is required (true or false)", key);
        }
        return !required;
    }
    if (!cJSON_IsBool(v)) {
        snprintf(err, n, "'%s' must be true or false", key);
        return false;
    }
    *out = cJSON_IsTrue(v);
    return true;
}

bool http_get_int(const cJSON *o, const char *key, bool required, long lo, long hi, long *out,
                  char *err, size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (v == NULL) {
        if (required) {
            snprintf(err, n, "'%s' is required (an integer %ld..%ld)", key, lo, hi);
        }
        return !required;
    }
    double d = cJSON_GetNumberValue(v);
    /* The range first: converting a double outside long's range (1e20) is undefined. */
    if (!cJSON_IsNumber(v) || !(d >= (double)lo && d <= (double)hi) || d != (double)(long)d) {
        snprintf(err, n, "'%s' must be an integer %ld..%ld", key, lo, hi);
        return false;
    }
    *out = (long)d;
    return true;
}

/* A parameter value: a number or a text the parameter knows ("FIELDBUS", "300.5"). */
bool http_get_value(const cJSON *o, const movidrive_param_info_t *p, int32_t *raw, char *err,
                    size_t n)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, "value");
    if (v == NULL) {
        snprintf(err, n, "'value' is required (a number, or a text such as \"FIELDBUS\")");
        return false;
    }
    if (cJSON_IsNumber(v)) {
        double d = cJSON_GetNumberValue(v);
        if (!(d >= -2147483648.0 && d <= 4294967295.0) || d != (double)(long long)d) {
            snprintf(err, n, "'value' must be an integer that fits 32 bits");
            return false;
        }
        *raw = (int32_t)(uint32_t)(long long)d;
        return true;
    }
    if (cJSON_IsString(v) && p != NULL) {
        return movidrive_value_parse(p, v->valuestring, raw, err, n);
    }
    snprintf(err, n, "'value' must be a number or a text");
    return false;
}
