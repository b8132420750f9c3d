/* Data set 47: PROFIdrive parameter access and SEW MOVILINK requests (protocol.md §B7,
 * docs/dpv1.md). One context per DP-V1 connection (C1, two C2). A request is checked and
 * accepted at once; its parameters then run one MOVILINK service each through the card's
 * service client, asynchronously; the response is built when the last one completes. */
#ifndef DPV1_DS47_H
#define DPV1_DS47_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dpv1/dpv1_wire.h"
#include "movilink/movilink_client.h"

/* PARSING: a Write is being checked in steps (ds47_write_step), so that a 19-parameter request
 * never holds the main loop for longer than DS47_PARSE_STEP parameters. */
typedef enum ds47_state { DS47_IDLE = 0, DS47_PARSING, DS47_BUSY, DS47_DONE } ds47_state_t;

/* Parameters checked per ds47_write_step() call. */
#ifndef DS47_PARSE_STEP
#define DS47_PARSE_STEP 5u
#endif
/* Response entries built per ds47_poll() call. */
#ifndef DS47_BUILD_STEP
#define DS47_BUILD_STEP 6u
#endif
/* ds47_write_step(): the request is not fully checked yet (not a DP-V1 error code). */
#define DS47_IN_PROGRESS 0x01u
/* Header + one DWORD value block (format, count, 4 octets) per parameter. */
#define DS47_RSP_MAX (4u + 6u * DS47_MAX_PARAMS)

typedef struct ds47_param {
    uint16_t number;   /* MOVILINK index */
    uint8_t service;   /* ML_SVC_* to run, ML_SVC_NONE if refused before */
    bool ok;
    uint32_t value;    /* to write, or read; when !ok the error value for the response */
} ds47_param_t;

typedef struct ds47 {
    ml_client_t *ml;
    uint8_t channel;
    ds47_state_t state;
    uint8_t ref;
    uint8_t id;
    uint8_t axis;
    uint8_t n;
    uint8_t next; /* parameter whose service runs, or (PARSING) the next to check */
    uint8_t parse_pass; /* PARSING: 0 address blocks, 1 value blocks */
    uint8_t pos;        /* PARSING: offset of the next block in the request */
    bool waiting; /* its MOVILINK service is outstanding */
    bool building; /* BUSY: every service done, the response being built (next = entry) */
    bool all_ok;
    ds47_param_t p[DS47_MAX_PARAMS];
    uint8_t rsp[DS47_RSP_MAX];
    uint8_t rsp_len;
    uint8_t rsp_sum; /* octet sum of rsp mod 256, added up entry by entry while it is built */
    uint32_t generation; /* bumps on reset, so a late completion of a dropped request is ignored */
    uint32_t running_generation;
} ds47_t;

void ds47_init(ds47_t *d, ml_client_t *ml, uint8_t channel);
/* Drops whatever runs or waits (connection closed). */
void ds47_reset(ds47_t *d);
/* A Write of data set 47. Returns 0 when accepted, or the DP-V1 Error_Code_1: B5 while the
 * previous request still runs, B7 for a header error. Any unread response is dropped. */
uint8_t ds47_write(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now);
/* The same in bounded steps: call with the same request until it returns something other than
 * DS47_IN_PROGRESS (then as ds47_write). Each call checks at most DS47_PARSE_STEP parameters.
 * A request replaced before its last step is dropped with ds47_reset(). */
uint8_t ds47_write_step(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now);
/* Main loop: starts the next parameter's service once the previous one completed, or builds
 * DS47_BUILD_STEP entries of the response once all have. True when it should be called again
 * at once (the response is not finished); the caller may serve replies in between. */
bool ds47_poll(ds47_t *d, hal_time_us_t now);
/* A Read of data set 47: 0 with the response copied (and consumed), or B5 (still running or
 * nothing to answer), or B7 (the master asked for fewer octets than the response has). */
uint8_t ds47_read(ds47_t *d, uint8_t *out, size_t max, size_t *len);

#endif
