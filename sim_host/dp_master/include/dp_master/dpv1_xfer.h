/* One DP-V1 request/response exchange at FDL level, as docs/dpv1.md fixes it for our card and
 * our master, shared by the class-1 client (dp_master.h) and the class-2 client (dpv1_c2.h):
 *
 *   SRD  DSAP/SSAP + request PDU      ->  SC   (the card copied it)
 *   SRD  DSAP/SSAP, no data (a poll)  ->  SC   (response not ready yet)   ... repeated
 *   SRD  DSAP/SSAP, no data           ->  DL   SAPs swapped + response PDU
 *
 * until the response arrives or the response timeout (from the first transmission of the
 * request) runs out. FCB and retries are the master station's business (dp_master.c); this
 * module only says what to send next and judges the answers. Nothing is allocated. */
#ifndef DP_MASTER_DPV1_XFER_H
#define DP_MASTER_DPV1_XFER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/fdl_frame.h"
#include "dpv1/dpv1_wire.h"
#include "hal/hal_time.h"

/* The SSAP our class-2 client uses by default (any free SAP would do; 50 is what real class-2
 * tools use). The wire codes themselves are the core's (dpv1/dpv1_wire.h). */
#define DP_MASTER_C2_SSAP_DEFAULT 50u

/* How an exchange ended. ok: a response PDU came back (it may be a negative DP-V1 response;
 * the layer above judges it). !ok: error says why (timeout, RS, no answer ...). */
typedef struct dp_master_acyc_result {
    bool ok;
    const uint8_t *pdu; /* valid during the callback only */
    size_t len;
    const char *error;
    uint32_t polls;      /* empty SRDs sent after the request */
    uint32_t telegrams;  /* every SRD of this exchange, request, polls and retries */
    hal_time_us_t t_start; /* first transmission of the request */
    hal_time_us_t t_end;
} dp_master_acyc_result_t;

typedef void (*dp_master_acyc_done_t)(void *ctx, const dp_master_acyc_result_t *r,
                                      hal_time_us_t now);

/* Where requests go: a class-1 slave of a master or a class-2 connection. submit returns 0, or
 * -1 when the path is busy (queue depth 1), closed, or the PDU too long. The callback may
 * submit the next request at once. */
typedef struct dp_master_acyc_port {
    int (*submit)(void *ctx, unsigned idx, const uint8_t *pdu, size_t len,
                  dp_master_acyc_done_t done, void *done_ctx, hal_time_us_t now);
    void *ctx;
    unsigned idx;
} dp_master_acyc_port_t;

static inline int dp_master_acyc_submit(const dp_master_acyc_port_t *p, const uint8_t *pdu,
                                        size_t len, dp_master_acyc_done_t done, void *done_ctx,
                                        hal_time_us_t now)
{
    return p->submit(p->ctx, p->idx, pdu, len, done, done_ctx, now);
}

typedef enum dp_master_xfer_state {
    DP_MASTER_XFER_IDLE = 0,
    DP_MASTER_XFER_REQUEST, /* the request PDU is (still) to be sent */
    DP_MASTER_XFER_POLL,    /* the request was taken (SC): empty SRDs until the response */
} dp_master_xfer_state_t;

typedef struct dp_master_xfer {
    dp_master_xfer_state_t state;
    bool no_response; /* any FDL answer ends it (Abort: the card sends no DP-V1 answer) */
    bool started;     /* the response timer runs (first telegram sent) */
    uint8_t dsap;
    uint8_t ssap;
    uint8_t pdu[DPV1_MAX_PDU];
    uint16_t len;
    uint32_t timeout_us;
    hal_time_us_t t_start;
    hal_time_us_t deadline;
    uint32_t polls;
    uint32_t telegrams;
    dp_master_acyc_done_t done;
    void *ctx;
    char error[128];
    /* Totals over the life of the struct. */
    uint32_t completed;
    uint32_t failed;
} dp_master_xfer_t;

/* A request PDU to DSAP/SSAP. -1 if busy or len is 0 or above DPV1_MAX_PDU. */
int dp_master_xfer_start(dp_master_xfer_t *x, uint8_t dsap, uint8_t ssap, const uint8_t *pdu,
                         size_t len, uint32_t timeout_us, dp_master_acyc_done_t done, void *ctx);
/* Only polls: the request reached the slave another way (an Initiate.req handed from the
 * resource manager to the connection SAP). */
int dp_master_xfer_start_polling(dp_master_xfer_t *x, uint8_t dsap, uint8_t ssap,
                                 uint32_t timeout_us, dp_master_acyc_done_t done, void *ctx);
static inline bool dp_master_xfer_busy(const dp_master_xfer_t *x)
{
    return x->state != DP_MASTER_XFER_IDLE;
}

/* The telegram to send now: returns the DU length (0 for a poll) and points *du at it. Starts
 * the response timer with the first call. */
size_t dp_master_xfer_telegram(dp_master_xfer_t *x, hal_time_us_t now, const uint8_t **du);
/* The slave's answer to the telegram just sent (sc: a short acknowledgement E5; else msg). */
void dp_master_xfer_answer(dp_master_xfer_t *x, const fdl_msg_t *msg, bool sc, hal_time_us_t t);
/* Ends the exchange with an error (no answer after the retries, slave restarted ...). */
void dp_master_xfer_fail(dp_master_xfer_t *x, hal_time_us_t now, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* The response timer: fails the exchange when it ran out. Returns the deadline to watch (or
 * now + HAL_TIME_NO_DEADLINE_US when none runs). */
hal_time_us_t dp_master_xfer_check_timeout(dp_master_xfer_t *x, hal_time_us_t now);

/* "invalid index", "state conflict" ... for Error_Code_1 (protocol.md §B8). */
const char *dp_master_v1_error_text(uint8_t code1);
/* True when pdu is a negative response (fn | 0x80); *code1 gets Error_Code_1. */
bool dp_master_v1_is_negative(const uint8_t *pdu, size_t len, uint8_t *code1);

#endif
