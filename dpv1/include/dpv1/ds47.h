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

typedef enum ds47_state { DS47_IDLE = 0, DS47_BUSY, DS47_DONE } ds47_state_t;

typedef struct ds47_param {
    uint16_t number;   /* MOVILINK index */
    uint8_t service;   /* ML_SVC_* to run, ML_SVC_NONE if refused before */
    uint32_t value;    /* to write, or read */
    bool ok;
    uint16_t error;    /* error value for the response */
} ds47_param_t;

typedef struct ds47 {
    ml_client_t *ml;
    uint8_t channel;
    ds47_state_t state;
    uint8_t ref;
    uint8_t id;
    uint8_t axis;
    uint8_t n;
    uint8_t next; /* parameter whose service runs */
    bool waiting; /* its MOVILINK service is outstanding */
    ds47_param_t p[DS47_MAX_PARAMS];
    uint8_t rsp[DPV1_MAX_DATA];
    uint8_t rsp_len;
    uint32_t generation; /* bumps on reset, so a late completion of a dropped request is ignored */
    uint32_t running_generation;
} ds47_t;

void ds47_init(ds47_t *d, ml_client_t *ml, uint8_t channel);
/* Drops whatever runs or waits (connection closed). */
void ds47_reset(ds47_t *d);
/* A Write of data set 47. Returns 0 when accepted, or the DP-V1 Error_Code_1: B5 while the
 * previous request still runs, B7 for a header error. An unread response is replaced. */
uint8_t ds47_write(ds47_t *d, const uint8_t *req, size_t len, hal_time_us_t now);
/* Main loop: starts the next parameter's service once the previous one completed. */
void ds47_poll(ds47_t *d, hal_time_us_t now);
/* A Read of data set 47: 0 with the response copied (and consumed), or B5 (still running or
 * nothing to answer), or B7 (the master asked for fewer octets than the response has). */
uint8_t ds47_read(ds47_t *d, uint8_t *out, size_t max, size_t *len);

#endif
