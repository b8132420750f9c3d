#include "dpv1/ds47.h"
#include "hal/hal_byte_order.h"

#include <string.h>

#include "dp_slave/fdl_frame.h"
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
    d->generation++;
}

/* PROFIdrive error number for a MOVILINK class-8 additional code (docs/dpv1.md). */
static uint16_t profidrive_error(uint16_t movilink)
{
    if ((movilink >> 8) != ML_CLASS_OTHER) {
        return (uint16_t)(PD_ERR_MANUFACTURER_BASE + (movilink & 0xFFu));
    }
    switch (movilink & 0xFFu) {
    case ML_ADD_ILLEGAL_INDEX: return PD_ERR_PARAMETER_NUMBER;
    case ML_ADD_READ_ONLY: return PD_ERR_READ_ONLY;
    case ML_ADD_TOO_HIGH:
    case ML_ADD_TOO_LOW: return PD_ERR_LIMIT_EXCEEDED;
    case ML_ADD_VALUE_NOT_PERMITTED: return PD_ERR_VALUE_IMPERMISSIBLE;
    case ML_ADD_PARAMETER_LOCK:
    case ML_ADD_CONTROLLER_INHIBIT_REQUIRED:
    case ML_ADD_OUTPUT_STAGE_ENABLED: return PD_ERR_OPERATING_STATE;
    default: return (uint16_t)(PD_ERR_MANUFACTURER_BASE + (movilink & 0xFFu));
    }
}

static void fail(ds47_t *d, uint8_t i, uint16_t profidrive, uint16_t movilink)
{
    d->p[i].ok = false;
    d->p[i].service = ML_SVC_NONE;
    d->p[i].value = d->id == DS47_ID_MOVILINK ? movilink : profidrive;
}

static bool is_write(uint8_t service)
{
    return service == ML_SVC_WRITE || service == ML_SVC_WRITE_VOLATILE;
}

static bool writes(const ds47_t *d, const ds47_param_t *p)
{
    return d->id == DS47_ID_CHANGE || (d->id == DS47_ID_MOVILINK && is_write(p->service));
}

/* One address block: attribute, elements, number, subindex. */
/* The card has values only: neither description nor text (manual §6.3, PROFIdrive errors). */
static uint16_t attribute_error(uint8_t attr)
{
    switch (attr) {
    case DS47_ATTR_DESCRIPTION: return PD_ERR_NO_DESCRIPTION;
    case DS47_ATTR_TEXT: return PD_ERR_NO_TEXT;
    default: return PD_ERR_ADDRESS;
    }
}

static void parse_address(ds47_t *d, uint8_t i, const uint8_t *a)
{
    ds47_param_t *p = &d->p[i];
    *p = (ds47_param_t){.number = hal_get_be16(&a[2]), .ok = true};
    uint8_t attr = a[0];
    if (d->id == DS47_ID_MOVILINK) {
        uint8_t svc = (uint8_t)(attr >> DS47_ATTR_ML_SERVICE_SHIFT);
        p->service = svc;
        if (svc != ML_SVC_READ && svc != ML_SVC_WRITE && svc != ML_SVC_WRITE_VOLATILE) {
            fail(d, i, 0, ML_ERROR_ILLEGAL_PARAMETER);
            p->service = svc; /* still decides whether a value block follows */
        }
    } else {
        p->service = d->id == DS47_ID_CHANGE ? ML_SVC_WRITE : ML_SVC_READ;
        if (attr != DS47_ATTR_VALUE) {
            fail(d, i, attribute_error(attr), 0);
            p->service = d->id == DS47_ID_CHANGE ? ML_SVC_WRITE : ML_SVC_NONE;
        }
    }
    if (p->ok && hal_get_be16(&a[4]) != 0u) {
        fail(d, i, PD_ERR_SUBINDEX, ML_ERROR_ILLEGAL_INDEX);
    } else if (p->ok && a[1] > 1u) {
        fail(d, i, PD_ERR_NO_ARRAY, ML_ERROR_ILLEGAL_INDEX);
    }
}

/* Octets of a value block's values: count values of the format's size, padded to a word (a zero
 * octet after an odd count keeps the telegram's word structure, protocol.md §A5.2). False for
 * a format whose size is unknown: the rest of the request cannot be found. */
static bool value_octets(uint8_t format, uint8_t count, size_t *octets)
{
    size_t size;
    switch (format) {
    case DS47_FORMAT_BOOLEAN:
    case DS47_FORMAT_INTEGER8:
    case DS47_FORMAT_UNSIGNED8:
    case DS47_FORMAT_VISIBLE_STRING:
    case DS47_FORMAT_OCTET_STRING:
    case DS47_FORMAT_BYTE: size = 1u; break;
    case DS47_FORMAT_INTEGER16:
    case DS47_FORMAT_UNSIGNED16:
    case DS47_FORMAT_WORD:
    case DS47_FORMAT_ERROR: size = 2u; break;
    case DS47_FORMAT_INTEGER32:
    case DS47_FORMAT_UNSIGNED32:
    case DS47_FORMAT_FLOAT:
    case DS47_FORMAT_DWORD: size = 4u; break;
    case DS47_FORMAT_ZERO: size = 0u; break;
    default: return false;
    }
    size_t n = size * count;
    *octets = n + (n & 1u);
    return true;
}

/* The value block of a writing parameter (value blocks follow the address blocks, in order).
 * Returns false on a header error. */
static bool parse_value(ds47_t *d, uint8_t i, const uint8_t *req, size_t len)
{
    ds47_param_t *p = &d->p[i];
    if (!writes(d, p)) {
        return true;
    }
    size_t pos = d->pos;
    if (pos + DS47_VALUE_HEADER_LEN > len) {
        return false;
    }
    uint8_t format = req[pos];
    uint8_t count = req[pos + 1u];
    pos += DS47_VALUE_HEADER_LEN;
    size_t bytes = 0u;
    if (!value_octets(format, count, &bytes) || pos + bytes > len) {
        return false;
    }
    if (p->ok && format != DS47_FORMAT_DWORD) {
        fail(d, i, PD_ERR_FORMAT, ML_ERROR_ILLEGAL_INDEX);
    } else if (p->ok && count != 1u) {
        fail(d, i, PD_ERR_VALUE_COUNT, ML_ERROR_ILLEGAL_INDEX);
    } else if (p->ok) {
        p->value = hal_get_be32(&req[pos]);
    }
    d->pos = (uint8_t)(pos + bytes);
    return true;
}

/* Every service done: whether all succeeded decides the Response ID and whether writes get an
 * entry, and with it the response's length, which a Read checks before anything is written. */
static void finish(ds47_t *d)
{
    unsigned failed = 0;
    unsigned read = 0;
    unsigned written = 0;
    for (uint8_t i = 0; i < d->n; i++) {
        const ds47_param_t *p = &d->p[i];
        if (!p->ok) {
            failed++;
        } else if (writes(d, p)) {
            written++;
        } else {
            read++;
        }
    }
    d->all_ok = failed == 0u;
    d->rsp_len = (uint8_t)(DS47_HEADER_LEN + DS47_ERROR_ENTRY_LEN * failed +
                          DS47_READ_ENTRY_LEN * read +
                          (d->all_ok ? 0u : DS47_WRITE_ENTRY_LEN * written));
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
        /* Class 8 carries its reason in the additional code; the card's own classes 5 and 6
         * in the code octet (0x0505, 0x0602, 0x0608). */
        uint16_t movilink = ML_ERROR_WORD(rsp[ML_OFF_ERROR_CLASS], rsp[ML_OFF_ERROR_ADD_LOW]);
        if (rsp[ML_OFF_ERROR_CLASS] != ML_CLASS_OTHER) {
            movilink = ML_ERROR_WORD(rsp[ML_OFF_ERROR_CLASS], rsp[ML_OFF_ERROR_CODE]);
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
        finish(d);
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

/* The four header octets: Request Reference, Request ID, Axis, number of parameters. */
static uint8_t start_write(ds47_t *d, const uint8_t *req, size_t len)
{
    if (d->state == DS47_BUSY) {
        return DPV1_ERR_STATE_CONFLICT;
    }
    d->state = DS47_IDLE; /* a new request drops an unread response */
    if (len < DS47_HEADER_LEN) {
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
    d->ref = req[0];
    d->id = id;
    d->axis = req[2];
    d->n = n;
    d->next = 0;
    d->parse_pass = 0;
    d->pos = DS47_HEADER_LEN;
    d->state = DS47_PARSING;
    return 0;
}

static uint8_t refuse(ds47_t *d)
{
    d->state = DS47_IDLE;
    return DPV1_ERR_INVALID_RANGE;
}

/* Every block checked and nothing left over: the services start. */
static uint8_t accept(ds47_t *d, size_t len, hal_time_us_t now)
{
    if (d->pos != len) {
        return refuse(d);
    }
    if (d->axis != 0u) {
        for (uint8_t i = 0; i < d->n; i++) {
            d->p[i].ok = false;
            d->p[i].value = PD_ERR_AXIS_NONEXISTENT; /* the MOVIDRIVE has no sub-axes */
        }
    }
    d->generation++;
    d->state = DS47_BUSY;
    d->waiting = false;
    d->next = 0;
    run_next(d, now);
    return 0;
}

uint8_t ds47_write_step(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now)
{
    if (d->state != DS47_PARSING) {
        uint8_t rc = start_write(d, req, len);
        if (rc != 0u) {
            return rc;
        }
    }
    for (uint8_t k = 0; k < DS47_PARSE_STEP; k++) {
        if (d->parse_pass == 0u && d->next == d->n) {
            d->parse_pass = 1;
            d->next = 0;
        }
        if (d->parse_pass == 0u) {
            if ((size_t)d->pos + DS47_ADDRESS_LEN > len) {
                return refuse(d);
            }
            parse_address(d, d->next, &req[d->pos]);
            d->pos = (uint8_t)(d->pos + DS47_ADDRESS_LEN);
        } else if (d->next == d->n) {
            /* Starting the first service is a step of its own (it sends a MOVILINK request). */
            return k == 0u ? accept(d, len, now) : DS47_IN_PROGRESS;
        } else if (!parse_value(d, d->next, req, len)) {
            return refuse(d);
        }
        d->next++;
    }
    return DS47_IN_PROGRESS;
}

uint8_t ds47_write(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now)
{
    uint8_t rc;
    do {
        rc = ds47_write_step(d, req, len, now);
    } while (rc == DS47_IN_PROGRESS);
    return rc;
}

uint8_t ds47_read_begin(const ds47_t *d, uint8_t *out, size_t max, ds47_read_cursor_t *cur)
{
    if (d->state != DS47_DONE) {
        return DPV1_ERR_STATE_CONFLICT;
    }
    if (max < d->rsp_len) {
        return DPV1_ERR_INVALID_RANGE;
    }
    out[0] = d->ref;
    out[1] = d->all_ok ? d->id : (uint8_t)(d->id | DS47_ID_ERROR);
    out[2] = d->axis;
    out[3] = d->n;
    cur->entry = 0;
    cur->len = DS47_HEADER_LEN;
    cur->sum = fdl_fcs(out, DS47_HEADER_LEN);
    return 0;
}

bool ds47_read_step(const ds47_t *d, uint8_t *out, ds47_read_cursor_t *cur)
{
    size_t n = cur->len;
    uint8_t end = (uint8_t)(d->n - cur->entry) > DS47_BUILD_STEP
                      ? (uint8_t)(cur->entry + DS47_BUILD_STEP)
                      : d->n;
    for (uint8_t i = cur->entry; i < end; i++) {
        const ds47_param_t *p = &d->p[i];
        if (!p->ok) {
            out[n++] = DS47_FORMAT_ERROR;
            out[n++] = 1;
            hal_put_be16(&out[n], (uint16_t)p->value);
            n += 2u;
        } else if (!writes(d, p)) {
            out[n++] = DS47_FORMAT_DWORD;
            out[n++] = 1;
            hal_put_be32(&out[n], p->value);
            n += 4u;
        } else if (!d->all_ok) {
            out[n++] = DS47_FORMAT_ZERO;
            out[n++] = 0;
        }
    }
    cur->sum = (uint8_t)(cur->sum + fdl_fcs(&out[cur->len], n - cur->len));
    cur->len = (uint8_t)n;
    cur->entry = end;
    return end < d->n;
}

void ds47_read_done(ds47_t *d)
{
    d->state = DS47_IDLE;
}

uint8_t ds47_read(ds47_t *d, uint8_t *out, size_t max, size_t *len)
{
    ds47_read_cursor_t cur;
    uint8_t rc = ds47_read_begin(d, out, max, &cur);
    if (rc != 0u) {
        return rc;
    }
    while (ds47_read_step(d, out, &cur)) {
    }
    ds47_read_done(d);
    *len = cur.len;
    return 0;
}
