/* Parameter access through DP-V1 data set 47 and the I&M call service (index 255), on top of
 * either acyclic path (class-1 slave or class-2 connection, dp_master_acyc_port_t). docs/dpv1.md
 * fixes the formats; protocol.md §B7 the DFP21B's ids and error values.
 *
 * A record call is a Write.req of the request, then Read.req of the same index (length 240)
 * repeated while the card answers the negative "state conflict" (DE 80 B5 00), bounded by
 * max_reads and a time limit. Request building and response parsing are separate, pure
 * functions, so tests can hold them against the manual's bytes. */
#ifndef DP_MASTER_DPV1_DS47_H
#define DP_MASTER_DPV1_DS47_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_master/dpv1_xfer.h"

typedef struct dp_master_ds47_param {
    uint8_t attribute;
    uint8_t elements;  /* 0: non-indexed */
    uint16_t number;   /* the MOVILINK index */
    uint16_t subindex;
    uint32_t value;    /* for writes */
} dp_master_ds47_param_t;

typedef struct dp_master_ds47_request {
    uint8_t ref;
    uint8_t id;
    uint8_t axis;
    uint8_t n;
    dp_master_ds47_param_t p[DS47_MAX_PARAMS];
} dp_master_ds47_req_t;

/* Does parameter i of this request carry a value block (id 0x02, or 0x40 with a write)? */
bool dp_master_ds47_param_writes(const dp_master_ds47_req_t *r, unsigned i);
/* The request octets (without the DP-V1 header). 0 when n is 0 or above 19, or max is short. */
size_t dp_master_ds47_build(const dp_master_ds47_req_t *r, uint8_t *out, size_t max);

typedef struct dp_master_ds47_result {
    bool ok;           /* this parameter succeeded */
    bool has_value;    /* a read that returned a value */
    uint32_t value;
    uint8_t format;    /* of its block, 0 when it had none */
    uint16_t error;    /* the error value of a 44 block */
} dp_master_ds47_result_t;

typedef struct dp_master_ds47_response {
    uint8_t ref;
    uint8_t id;       /* as received, bit 7 = some parameter failed */
    uint8_t axis;
    uint8_t n;
    bool negative;
    dp_master_ds47_result_t p[DS47_MAX_PARAMS];
} dp_master_ds47_rsp_t;

/* Parses a DS47 response to req. Returns true when the octets are a well-formed answer to it
 * (reference, id, axis and count match, blocks complete); false with a reason in err. */
bool dp_master_ds47_parse(const dp_master_ds47_req_t *req, const uint8_t *d, size_t len,
                          dp_master_ds47_rsp_t *rsp, char *err, size_t errlen);
/* The meaning of an error value for a request id: MOVILINK values (0x08xx, 0x0505, 0x0602,
 * 0x0502) for id 0x40, PROFIdrive numbers for 0x01/0x02 (0x0080 + code: the manufacturer range,
 * a MOVILINK additional code). */
size_t dp_master_ds47_error_text(uint8_t id, uint16_t error, char *out, size_t max);

/* ---- I&M0 ---------------------------------------------------------------------------------- */

typedef struct dp_master_im0 {
    uint8_t header[10];
    uint16_t manufacturer_id;
    char order_id[21];      /* as sent, 20 octets, NUL added */
    char serial_number[17]; /* 16 octets */
    uint16_t hardware_revision;
    char sw_prefix;         /* 'V', 'R', 'P', 'U' or 'T' */
    uint8_t sw_major, sw_minor, sw_bugfix;
    uint16_t rev_counter;
    uint16_t profile_id;
    uint16_t profile_specific_type;
    uint8_t im_version_major, im_version_minor;
    uint16_t im_supported;
} dp_master_im0_t;

/* d: the Read.res data of index 255: 08 00 FD E8 + 64 octets. */
bool dp_master_im0_decode(const uint8_t *d, size_t len, dp_master_im0_t *out, char *err,
                          size_t errlen);

/* ---- the record call ----------------------------------------------------------------------- */

typedef enum dp_master_call_state {
    DP_MASTER_CALL_IDLE = 0,
    DP_MASTER_CALL_WRITE,
    DP_MASTER_CALL_READ,
    DP_MASTER_CALL_DONE,
} dp_master_call_state_t;

typedef struct dp_master_call dp_master_call_t;
typedef void (*dp_master_call_done_t)(void *ctx, dp_master_call_t *call, hal_time_us_t now);

struct dp_master_call {
    dp_master_acyc_port_t port;
    dp_master_call_state_t state;
    uint8_t slot;
    uint8_t index;
    uint8_t read_len;
    uint8_t wdata[DPV1_MAX_DATA];
    uint8_t wlen;
    uint32_t max_reads;  /* 0: 10000 */
    uint32_t timeout_us; /* whole call; 0: 5 s */
    hal_time_us_t t_start;
    hal_time_us_t deadline;
    /* Result, valid in DP_MASTER_CALL_DONE. */
    bool ok;             /* a positive Read.res arrived: data/len */
    bool dpv1_negative;  /* a negative Write.res/Read.res ended it: fn, code1 */
    uint8_t neg_fn;
    uint8_t neg_code1;
    uint8_t data[DPV1_MAX_DATA];
    uint8_t len;
    char error[200];
    /* Statistics. */
    uint32_t reads;      /* Read.req sent */
    uint32_t busy;       /* answered B5 */
    uint32_t telegrams;  /* SRDs of the whole call */
    uint32_t polls;
    hal_time_us_t t_end;
    dp_master_call_done_t done;
    void *ctx;
};

/* Write index (data), then Read index (read_len) until not B5. -1: the port refused the Write
 * (busy, closed) or the call is running. */
int dp_master_call_start(dp_master_call_t *c, dp_master_acyc_port_t port, uint8_t index,
                         const uint8_t *data, size_t len, uint8_t read_len,
                         dp_master_call_done_t done, void *ctx, hal_time_us_t now);
/* DS47: builds the request and runs the call (index 47, read length 240). */
int dp_master_ds47_start(dp_master_call_t *c, dp_master_acyc_port_t port,
                         const dp_master_ds47_req_t *req, dp_master_call_done_t done, void *ctx,
                         hal_time_us_t now);
/* I&M0: Write 255 "08 00 FD E8", Read 255. */
int dp_master_im0_start(dp_master_call_t *c, dp_master_acyc_port_t port, dp_master_call_done_t done,
                        void *ctx, hal_time_us_t now);
static inline bool dp_master_call_done(const dp_master_call_t *c)
{
    return c->state == DP_MASTER_CALL_DONE;
}

/* MOVILINK error value (class << 8 | code or additional code) as text, with ml_error_text. */
size_t dp_master_ml_error_value_text(uint16_t value, char *out, size_t max);

#endif
