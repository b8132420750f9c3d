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
/* Response entries written per ds47_read_step() call. */
#ifndef DS47_BUILD_STEP
#define DS47_BUILD_STEP 6u
#endif
/* ds47_write_step(): the request is not fully checked yet (not a DP-V1 error code). */
#define DS47_IN_PROGRESS 0x01u
/* Header + one DWORD value block (format, count, 4 octets) per parameter. */
#define DS47_RSP_MAX (4u + 6u * DS47_MAX_PARAMS)
_Static_assert(DS47_RSP_MAX <= DPV1_MAX_DATA, "a data set 47 response fits one DP-V1 PDU");

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
    bool all_ok;  /* DONE: every parameter succeeded (Response ID, entries of writes) */
    uint8_t rsp_len; /* DONE: the response's length; it is written only when read */
    ds47_param_t p[DS47_MAX_PARAMS];
    uint32_t generation; /* bumps on reset, so a late completion of a dropped request is ignored */
    uint32_t running_generation;
} ds47_t;

/* Where ds47_read_step() goes on: the caller keeps it while it answers one Read. */
typedef struct ds47_read_cursor {
    uint8_t entry;
    uint8_t len;
    uint8_t sum; /* octet sum of what was written, mod 256 */
} ds47_read_cursor_t;

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
/* Main loop: starts the next parameter's service once the previous one completed. */
void ds47_poll(ds47_t *d, hal_time_us_t now);
/* A Read of data set 47: 0 with the response written to out (and consumed), or B5 (still
 * running or nothing to answer), or B7 (the master asked for fewer octets than it has). */
uint8_t ds47_read(ds47_t *d, uint8_t *out, size_t max, size_t *len);
/* The same in bounded steps. The response is not kept anywhere: it is written from the
 * parameters straight into the Read's response buffer, DS47_BUILD_STEP entries per step.
 * ds47_read_begin() checks (0, B5, B7) and writes the header; ds47_read_step() is called until
 * it returns false, then ds47_read_done() consumes the response. A Read abandoned between steps
 * leaves the response unread, for the next Read. */
uint8_t ds47_read_begin(const ds47_t *d, uint8_t *out, size_t max, ds47_read_cursor_t *cur);
bool ds47_read_step(const ds47_t *d, uint8_t *out, ds47_read_cursor_t *cur);
void ds47_read_done(ds47_t *d);

#endif
