#include "dpv1/ds47.h"
#include "hal/hal_byte_order.h"

#include <string.h>

#include "movilink/movilink_wire.h"

void ds47_init(ds47_t *d, ml_client_t *ml, uint8_t channel)
{
    memset(d, 0, sizeof *d);
    d->ml = ml;
    d->channel = channel;
}

void ds47_reset(ds47_t *d)
{
    d->state = DS47_IDLE;
    d->rsp_len = 0;
    d->generation++;
}

/* PROFIdrive error number for a MOVILINK class-8 additional code (docs/dpv1.md). */
static uint16_t profidrive_error(uint16_t movilink)
{
    if ((movilink >> 8) != ML_CLASS_OTHER) {
        return (uint16_t)(0x0080u + (movilink & 0xFFu));
    }
    switch (movilink & 0xFFu) {
    case ML_ADD_ILLEGAL_INDEX: return 0x00u;
    case ML_ADD_READ_ONLY: return 0x01u;
    case ML_ADD_TOO_HIGH:
    case ML_ADD_TOO_LOW: return 0x02u;
    case ML_ADD_VALUE_NOT_PERMITTED: return 0x14u;
    case ML_ADD_PARAMETER_LOCK:
    case ML_ADD_CONTROLLER_INHIBIT_REQUIRED:
    case ML_ADD_OUTPUT_STAGE_ENABLED: return 0x11u;
    default: return (uint16_t)(0x0080u + (movilink & 0xFFu));
    }
}

static void fail(ds47_t *d, uint8_t i, uint16_t profidrive, uint16_t movilink)
{
    d->p[i].ok = false;
    d->p[i].service = ML_SVC_NONE;
    d->p[i].error = d->id == DS47_ID_MOVILINK ? movilink : profidrive;
}

static bool is_write(uint8_t service)
{
    return service == ML_SVC_WRITE || service == ML_SVC_WRITE_VOLATILE;
}

/* Address blocks: attribute, elements, number, subindex. Returns false on a header error. */
static bool parse_addresses(ds47_t *d, const uint8_t *req, size_t len, size_t *pos)
{
    for (uint8_t i = 0; i < d->n; i++) {
        if (*pos + 6u > len) {
            return false;
        }
        const uint8_t *a = &req[*pos];
        *pos += 6u;
        ds47_param_t *p = &d->p[i];
        *p = (ds47_param_t){.number = hal_get_be16(&a[2]), .ok = true};
        uint8_t attr = a[0];
        if (d->id == DS47_ID_MOVILINK) {
            uint8_t svc = (uint8_t)(attr >> DS47_ATTR_ML_SERVICE_SHIFT);
            p->service = svc;
            if (svc != ML_SVC_READ && svc != ML_SVC_WRITE && svc != ML_SVC_WRITE_VOLATILE) {
                fail(d, i, 0, 0x0505u);
                p->service = svc; /* still decides whether a value block follows */
            }
        } else {
            p->service = d->id == DS47_ID_CHANGE ? ML_SVC_WRITE : ML_SVC_READ;
            if (attr != DS47_ATTR_VALUE) {
                fail(d, i, 0x05u, 0);
                p->service = d->id == DS47_ID_CHANGE ? ML_SVC_WRITE : ML_SVC_NONE;
            }
        }
        if (p->ok && hal_get_be16(&a[4]) != 0u) {
            fail(d, i, 0x03u, 0x0810u);
        } else if (p->ok && a[1] > 1u) {
            fail(d, i, 0x04u, 0x0810u);
        }
    }
    return true;
}

/* Value blocks, one per writing parameter, in order. */
static bool parse_values(ds47_t *d, const uint8_t *req, size_t len, size_t *pos)
{
    for (uint8_t i = 0; i < d->n; i++) {
        bool writes = d->id == DS47_ID_CHANGE ||
                      (d->id == DS47_ID_MOVILINK && is_write(d->p[i].service));
        if (!writes) {
            continue;
        }
        if (*pos + 2u > len) {
            return false;
        }
        uint8_t format = req[*pos];
        uint8_t count = req[*pos + 1u];
        *pos += 2u;
        size_t bytes = format == DS47_FORMAT_DWORD ? 4u * count : 2u * count;
        if (*pos + bytes > len) {
            return false;
        }
        if (d->p[i].ok && format != DS47_FORMAT_DWORD) {
            fail(d, i, 0x17u, 0x0810u);
        } else if (d->p[i].ok && count != 1u) {
            fail(d, i, 0x18u, 0x0810u);
        } else if (d->p[i].ok) {
            const uint8_t *v = &req[*pos];
            d->p[i].value = ((uint32_t)hal_get_be16(v) << 16) | hal_get_be16(&v[2]);
        }
        *pos += bytes;
    }
    return true;
}

static void build_response(ds47_t *d)
{
    bool all_ok = true;
    for (uint8_t i = 0; i < d->n; i++) {
        all_ok = all_ok && d->p[i].ok;
    }
    uint8_t *r = d->rsp;
    size_t n = 0;
    r[n++] = d->ref;
    r[n++] = all_ok ? d->id : (uint8_t)(d->id | DS47_ID_ERROR);
    r[n++] = d->axis;
    r[n++] = d->n;
    for (uint8_t i = 0; i < d->n; i++) {
        const ds47_param_t *p = &d->p[i];
        bool wrote = d->id == DS47_ID_CHANGE ||
                     (d->id == DS47_ID_MOVILINK && is_write(p->service));
        if (!p->ok) {
            r[n++] = DS47_FORMAT_ERROR;
            r[n++] = 1;
            hal_put_be16(&r[n], p->error);
            n += 2u;
        } else if (!wrote) {
            r[n++] = DS47_FORMAT_DWORD;
            r[n++] = 1;
            hal_put_be16(&r[n], (uint16_t)(p->value >> 16));
            hal_put_be16(&r[n + 2u], (uint16_t)p->value);
            n += 4u;
        } else if (!all_ok) {
            r[n++] = DS47_FORMAT_ZERO;
            r[n++] = 0;
        }
    }
    d->rsp_len = (uint8_t)n;
    d->state = DS47_DONE;
}

static void run_next(ds47_t *d, hal_time_us_t now);

static void on_done(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    (void)channel;
    ds47_t *d = ctx;
    if (d->state != DS47_BUSY || d->running_generation != d->generation) {
        return; /* the request was dropped meanwhile */
    }
    ds47_param_t *p = &d->p[d->next];
    if ((rsp[ML_OFF_MANAGEMENT] & ML_MGMT_ERROR) != 0u) {
        uint16_t movilink = (uint16_t)((rsp[4] << 8) | rsp[7]);
        if (rsp[4] != ML_CLASS_OTHER) {
            movilink = (uint16_t)((rsp[4] << 8) | rsp[5]); /* 0x0505, 0x0602, 0x0608 */
        }
        fail(d, d->next, profidrive_error(movilink), movilink);
    } else if (!is_write(p->service)) {
        p->value = ml_data(rsp);
    }
    d->next++;
    d->waiting = false; /* ds47_poll() starts the next service with the time it knows */
}

/* Starts the next parameter's service, skipping those refused while parsing. Completion of a
 * service starts the one after it, so a request walks through its parameters on its own. */
static void run_next(ds47_t *d, hal_time_us_t now)
{
    while (d->next < d->n && !d->p[d->next].ok) {
        d->next++;
    }
    if (d->next >= d->n) {
        build_response(d);
        return;
    }
    ds47_param_t *p = &d->p[d->next];
    uint8_t req[ML_TELEGRAM_LEN] = {(uint8_t)(ML_MGMT_LENGTH_4 | p->service), 0,
                                    (uint8_t)(p->number >> 8), (uint8_t)p->number, 0, 0, 0, 0};
    ml_put_data(req, is_write(p->service) ? p->value : 0u);
    uint32_t outstanding = d->running_generation;
    d->running_generation = d->generation;
    d->waiting = true;
    if (ml_client_request(d->ml, d->channel, req, on_done, d, now) != 0) {
        /* A dropped request's service still occupies the channel: its late answer must keep
         * failing the generation check, so the generation it ran under stays recorded. */
        d->running_generation = outstanding;
        d->waiting = false;
    }
}

void ds47_poll(ds47_t *d, hal_time_us_t now)
{
    if (d->state == DS47_BUSY && !d->waiting) {
        run_next(d, now);
    }
}

uint8_t ds47_write(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now)
{
    if (d->state == DS47_BUSY) {
        return DPV1_ERR_STATE_CONFLICT;
    }
    if (len < 4u) {
        return DPV1_ERR_INVALID_RANGE;
    }
    uint8_t id = req[1];
    uint8_t n = req[3];
    /* Request Reference 0x01..0xFF (protocol.md §B7): 0 cannot tell two requests apart. */
    if (req[0] == 0u ||
        (id != DS47_ID_REQUEST && id != DS47_ID_CHANGE && id != DS47_ID_MOVILINK) || n == 0u ||
        n > DS47_MAX_PARAMS) {
        return DPV1_ERR_INVALID_RANGE;
    }
    ds47_t parsed = *d;
    parsed.ref = req[0];
    parsed.id = id;
    parsed.axis = req[2];
    parsed.n = n;
    parsed.next = 0;
    size_t pos = 4;
    if (!parse_addresses(&parsed, req, len, &pos) || !parse_values(&parsed, req, len, &pos) ||
        pos != len) {
        return DPV1_ERR_INVALID_RANGE;
    }
    if (parsed.axis != 0u) {
        for (uint8_t i = 0; i < n; i++) {
            parsed.p[i].ok = false;
            parsed.p[i].error = 0x0019u; /* axis nonexistent: the MOVIDRIVE has no sub-axes */
        }
    }
    *d = parsed;
    d->generation++;
    d->state = DS47_BUSY;
    d->waiting = false;
    run_next(d, now);
    return 0;
}

uint8_t ds47_read(ds47_t *d, uint8_t *out, size_t max, size_t *len)
{
    if (d->state != DS47_DONE) {
        return DPV1_ERR_STATE_CONFLICT;
    }
    if (max < d->rsp_len) {
        return DPV1_ERR_INVALID_RANGE;
    }
    memcpy(out, d->rsp, d->rsp_len);
    *len = d->rsp_len;
    d->state = DS47_IDLE;
    return 0;
}
