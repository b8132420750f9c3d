#include <stdio.h>
#include <string.h>

#include "http_internal.h"

/* Parses the body as a JSON object whose keys are all in `allowed`; NULL with a message sent. */
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
    for (const cJSON *f = o->child; f != NULL; f = f->next) {
        bool ok = false;
        for (const char *const *a = allowed; *a != NULL; a++) {
            if (strcmp(*a, f->string) == 0) {
                ok = true;
            }
        }
        if (!ok) {
            *rc = http_send_error(conn, 400, "unknown field '%s'", f->string);
            cJSON_Delete(o);
            return NULL;
        }
    }
    return o;
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
    if (!cJSON_IsNumber(v) || d != (double)(long)d || d < (double)lo || d > (double)hi) {
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
        if (d != (double)(long long)d || d < -2147483648.0 || d > 4294967295.0) {
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
