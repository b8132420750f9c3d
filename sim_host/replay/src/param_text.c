#include "replay/param_text.h"

#include <stdio.h>
#include <string.h>

#include "dp_master/param_channel.h"
#include "dpv1/dpv1_wire.h"
#include "movidrive/movidrive_names.h"
#include "movidrive/movidrive.h"
#include "movilink/movilink_wire.h"

/* The DP-V1 header before a data set's octets: function, slot, index, length. */
#define DPV1_HEADER_LEN 4u
/* A data set 47 request: reference, id, axis, number of parameters; then 6 octets per parameter
 * (attribute, elements, number, subindex), then the values written (format, count, value). */
#define DS47_HEADER_LEN 4u
#define DS47_PARAM_LEN 6u

/* "P100 setpoint source (8461)", "H0 (11000)", "index 1". */
static void param_name(uint16_t index, char *out, size_t max)
{
    const movidrive_param_info_t *p = movidrive_param_info(index);
    if (p != NULL) {
        (void)snprintf(out, max, "%s %s (%u)", p->p_number, p->name, index);
    } else if (index >= MOVIDRIVE_IDX_IPOS_H0 &&
               index < MOVIDRIVE_IDX_IPOS_H0 + MOVIDRIVE_IPOS_VARS) {
        (void)snprintf(out, max, "H%u (%u)", index - MOVIDRIVE_IDX_IPOS_H0, index);
    } else {
        (void)snprintf(out, max, "index %u", index);
    }
}

/* The value in the parameter's unit or with its enumeration text for reads and writes; the
 * plain number for the other services (limits, scaling, attributes). */
static void param_value(uint16_t index, uint8_t service, uint32_t raw, char *out, size_t max)
{
    const movidrive_param_info_t *p = movidrive_param_info(index);
    if (p != NULL && (service == ML_SVC_READ || service == ML_SVC_WRITE ||
                      service == ML_SVC_WRITE_VOLATILE)) {
        (void)movidrive_value_text(p, (int32_t)raw, out, max);
    } else {
        (void)snprintf(out, max, "%d", (int32_t)raw);
    }
}

static bool writes(uint8_t service)
{
    return service == ML_SVC_WRITE || service == ML_SVC_WRITE_VOLATILE;
}

/* The request side: "read P160 ... (8489)", "write P100 ... (8461) = 3 (FIELDBUS)". */
static size_t request_text(uint8_t service, uint16_t index, bool has_value, uint32_t raw,
                           char *out, size_t max)
{
    char name[128];
    param_name(index, name, sizeof name);
    if (writes(service) && has_value) {
        char value[96];
        param_value(index, service, raw, value, sizeof value);
        return (size_t)snprintf(out, max, "%s %s = %s", ml_service_name(service), name, value);
    }
    return (size_t)snprintf(out, max, "%s %s", ml_service_name(service), name);
}

/* The cyclic channel: the first 8 octets of Data_Exchange when the configuration has one. */
static size_t channel_text(const uint8_t *m, bool reply, char *out, size_t max)
{
    uint8_t service = m[ML_OFF_MANAGEMENT] & ML_MGMT_SERVICE_MASK;
    if (service == ML_SVC_NONE) {
        return 0;
    }
    uint16_t index = ml_index(m);
    if (!reply) {
        return request_text(service, index, true, ml_data(m), out, max);
    }
    char name[128];
    param_name(index, name, sizeof name);
    if ((m[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        return (size_t)snprintf(out, max, "%s %s refused", ml_service_name(service), name);
    }
    char value[96];
    param_value(index, service, ml_data(m), value, sizeof value);
    return (size_t)snprintf(out, max, "%s %s = %s", ml_service_name(service), name, value);
}

/* The service a data set 47 parameter asks for: MOVILINK's in the attribute's high nibble, or
 * the PROFIdrive request/change. */
static uint8_t ds47_service(uint8_t id, uint8_t attribute)
{
    if (id == DS47_ID_MOVILINK) {
        return (uint8_t)(attribute >> DS47_ATTR_ML_SERVICE_SHIFT);
    }
    return id == DS47_ID_CHANGE ? ML_SVC_WRITE : ML_SVC_READ;
}

/* A data set 47 request (Write.req to index 47): its first parameter, and the value written. */
static size_t ds47_request_text(const uint8_t *d, size_t len, replay_param_ctx_t *ctx,
                                char *out, size_t max)
{
    if (len < DS47_HEADER_LEN + DS47_PARAM_LEN || d[3] == 0u) {
        return 0;
    }
    uint8_t id = d[1];
    const uint8_t *p = d + DS47_HEADER_LEN;
    uint8_t service = ds47_service(id, p[0]);
    uint16_t index = (uint16_t)((p[2] << 8) | p[3]);
    size_t values = DS47_HEADER_LEN + DS47_PARAM_LEN * (size_t)d[3];
    bool has_value = writes(service) && values + 6u <= len;
    uint32_t raw = 0;
    if (has_value) {
        const uint8_t *v = d + values + 2u;
        raw = (uint32_t)v[0] << 24 | (uint32_t)v[1] << 16 | (uint32_t)v[2] << 8 | v[3];
    }
    if (ctx != NULL) {
        *ctx = (replay_param_ctx_t){.ds47_pending = true, .ds47_id = id, .ds47_service = service,
                                    .ds47_index = index};
    }
    size_t n = request_text(service, index, has_value, raw, out, max);
    if (d[3] > 1u && n < max) {
        n += (size_t)snprintf(out + n, max - n, " (and %u more)", d[3] - 1u);
    }
    return n;
}

/* A data set 47 answer (Read.res of index 47): the first parameter's value or error, named after
 * the request before it. */
static size_t ds47_answer_text(const uint8_t *d, size_t len, replay_param_ctx_t *ctx, char *out,
                               size_t max)
{
    if (ctx == NULL || !ctx->ds47_pending || len < DS47_HEADER_LEN + 2u) {
        return 0;
    }
    ctx->ds47_pending = false;
    char name[128];
    param_name(ctx->ds47_index, name, sizeof name);
    const char *svc = ml_service_name(ctx->ds47_service);
    const uint8_t *b = d + DS47_HEADER_LEN;
    if ((d[1] & DS47_ID_ERROR) != 0u || b[0] == DS47_FORMAT_ERROR) {
        return (size_t)snprintf(out, max, "%s %s refused", svc, name);
    }
    if (b[0] != DS47_FORMAT_DWORD || len < DS47_HEADER_LEN + 6u) {
        return (size_t)snprintf(out, max, "%s %s done", svc, name);
    }
    uint32_t raw = (uint32_t)b[2] << 24 | (uint32_t)b[3] << 16 | (uint32_t)b[4] << 8 | b[5];
    char value[96];
    param_value(ctx->ds47_index, ctx->ds47_service, raw, value, sizeof value);
    return (size_t)snprintf(out, max, "%s %s = %s", svc, name, value);
}

static size_t dpv1_text(const replay_frame_t *fr, bool reply, replay_param_ctx_t *ctx, char *out,
                        size_t max)
{
    const uint8_t *d = fr->du;
    if (fr->du_len <= DPV1_HEADER_LEN || d[2] != DPV1_INDEX_DS47) {
        return 0;
    }
    if (!reply && d[0] == DPV1_FN_WRITE) {
        return ds47_request_text(d + DPV1_HEADER_LEN, fr->du_len - DPV1_HEADER_LEN, ctx, out,
                                 max);
    }
    if (reply && d[0] == DPV1_FN_READ) {
        return ds47_answer_text(d + DPV1_HEADER_LEN, fr->du_len - DPV1_HEADER_LEN, ctx, out,
                                max);
    }
    return 0;
}

size_t replay_param_text(const uint8_t *f, size_t len, const replay_dx_layout_t *lay,
                         replay_param_ctx_t *ctx, char *out, size_t max)
{
    if (max == 0u) {
        return 0;
    }
    out[0] = '\0';
    replay_frame_t fr;
    replay_frame_parse(f, len, &fr);
    bool reply = fr.kind == REPLAY_KIND_RESPONSE;
    if (!fr.has_header || (fr.kind != REPLAY_KIND_REQUEST && !reply) || fr.du == NULL) {
        return 0;
    }
    size_t n = 0;
    if (!fr.has_dsap && !fr.has_ssap) {
        if (lay != NULL && lay->known && lay->param_channel && fr.du_len >= ML_TELEGRAM_LEN) {
            n = channel_text(fr.du, reply, out, max);
        }
    } else {
        n = dpv1_text(&fr, reply, ctx, out, max);
    }
    if (n >= max) {
        n = max - 1u;
    }
    return n;
}

size_t replay_channel_text(const uint8_t *m, bool reply, char *out, size_t max)
{
    if (max == 0u) {
        return 0;
    }
    out[0] = '\0';
    size_t n = channel_text(m, reply, out, max);
    return n < max ? n : max - 1u;
}
