/* A DP-V1 class-2 (MSAC2) connection from our master station to one slave (docs/dpv1.md,
 * protocol.md §A4.4). It needs no Set_Prm: a class-2 master does not parameterise.
 *
 *   open:    SRD DSAP 49 / SSAP ssap  Initiate.req (20 octets)  ->  DL  56 SAP 00 00
 *            SRD DSAP SAP / SSAP ssap (no data), repeated      ->  SC ... DL  Initiate.res (57 ...)
 *   request: SRD DSAP SAP + Read/Write PDU -> SC; polls -> SC ... DL response   (as class 1)
 *   idle:    48 00 00 00 when nothing went to the slave for half the Send_Timeout; answer 48
 *   abort:   SRD DSAP SAP  58 00 20|reason 00  (any FDL answer; no DP-V1 answer; closed)
 *
 * A refusal by the resource manager (no free connection: an Abort PDU from SAP 49, or RS), a
 * negative Initiate (D7 ...), an Abort PDU from the slave and RS on the connection SAP close
 * the connection with an error text. The struct is driven by the master station it is attached
 * to (dp_master_add_c2); every address/FCB matter stays there. */
#ifndef DP_MASTER_DPV1_C2_H
#define DP_MASTER_DPV1_C2_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_master/dp_master.h"
#include "dp_master/dpv1_xfer.h"

#define DP_MASTER_C2_SEND_TIMEOUT_DEFAULT 200u          /* 10 ms units: 2 s */
/* protocol.md §B1: C2 response timeout 1 s */
#define DP_MASTER_C2_RESPONSE_TIMEOUT_US_DEFAULT 1000000u
#define DP_MASTER_C2_INITIATE_LEN 20u
#define DP_MASTER_C2_ABORT_USER 0x20u                   /* Instance "user" (protocol.md §A4.4) */

typedef enum dp_master_c2_state {
    DP_MASTER_C2_CLOSED = 0,
    DP_MASTER_C2_RM,         /* Initiate.req to the resource manager */
    DP_MASTER_C2_INITIATING, /* polling the connection SAP for the Initiate.res */
    DP_MASTER_C2_OPEN,
    DP_MASTER_C2_ABORTING,
} dp_master_c2_state_t;

typedef struct dp_master_c2_cfg {
    uint8_t slave;        /* station address of the slave */
    uint8_t address;      /* our station address on this connection (any master address) */
    uint8_t ssap;         /* 0: 50 */
    uint16_t send_timeout; /* Initiate Send_Timeout, 10 ms units; 0: 200 (2 s) */
    uint32_t response_timeout_us; /* 0: 1 s, for the Initiate and every request */
    bool no_idle;         /* do not send Idle keep-alives (to test the slave's supervision) */
} dp_master_c2_cfg_t;

typedef enum dp_master_c2_op {
    DP_MASTER_C2_OP_NONE = 0,
    DP_MASTER_C2_OP_OPEN,
    DP_MASTER_C2_OP_REQUEST,
    DP_MASTER_C2_OP_IDLE,
    DP_MASTER_C2_OP_ABORT,
} dp_master_c2_op_t;

typedef struct dp_master_c2 {
    dp_master_c2_cfg_t cfg;
    dp_master_c2_state_t state;
    uint8_t sap;        /* the connection SAP the resource manager named */
    dp_master_xfer_t x;       /* the exchange on the wire */
    dp_master_c2_op_t op;     /* what x is doing */
    dp_master_acyc_done_t user_done; /* the caller's callback for op */
    void *user_ctx;
    /* A user request that waits for an Idle exchange to end (depth 1). */
    bool queued;
    uint8_t queued_pdu[DPV1_MAX_PDU];
    uint16_t queued_len;
    dp_master_acyc_done_t queued_done;
    void *queued_ctx;
    uint8_t abort_code; /* Instance|Reason of the Abort to send */
    bool abort_pending; /* Abort asked for while a telegram was on the wire */
    bool on_wire;       /* the master waits for the answer to our telegram */
    bool last_tx_valid;
    hal_time_us_t last_tx; /* last telegram to the slave on this connection */
    uint8_t initiate_res[DPV1_MAX_PDU];
    uint8_t initiate_res_len;
    char error[160];
    /* Counters. */
    uint32_t idles;
    uint32_t requests;
    uint32_t opens;
} dp_master_c2_t;

void dp_master_c2_init(dp_master_c2_t *c, const dp_master_c2_cfg_t *cfg);
/* Initiate: done gets r->ok with the Initiate.res PDU when the connection is open, or !ok with
 * the reason (refused, negative Initiate, timeout ...). -1 when not closed. */
int dp_master_c2_open(dp_master_c2_t *c, dp_master_acyc_done_t done, void *ctx, hal_time_us_t now);
/* A Read/Write request on the open connection (queue depth 1). -1 when not open or busy. */
int dp_master_c2_submit(dp_master_c2_t *c, const uint8_t *pdu, size_t len,
                        dp_master_acyc_done_t done, void *ctx, hal_time_us_t now);
/* Abort PDU 58 00 instance_reason 00 (0: DP_MASTER_C2_ABORT_USER); a running request fails. done
 * (may be NULL) runs when the slave took it. -1 when there is no connection to abort. */
int dp_master_c2_abort(dp_master_c2_t *c, uint8_t instance_reason, dp_master_acyc_done_t done,
                       void *ctx, hal_time_us_t now);
static inline dp_master_c2_state_t dp_master_c2_state(const dp_master_c2_t *c) { return c->state; }
static inline bool dp_master_c2_busy(const dp_master_c2_t *c)
{
    return c->op != DP_MASTER_C2_OP_NONE || c->queued;
}
/* Why the connection closed or the last operation failed; "" if it did not. */
static inline const char *dp_master_c2_error(const dp_master_c2_t *c) { return c->error; }
const char *dp_master_c2_state_name(dp_master_c2_state_t s);
/* The connection as a path for dpv1_ds47.h jobs. */
dp_master_acyc_port_t dp_master_c2_port(dp_master_c2_t *c);
/* 57 00 00 00 SendTO Feat1 Feat2 PFeat1 PFeat2 ProfileIdent 00 02 00 02 API SCL API SCL. */
size_t dp_master_c2_build_initiate(uint8_t *out, uint16_t send_timeout);

/* ---- for the master station (dp_master.c) ------------------------------------------------ */

/* Runs the timers (response timeout, Idle due); true when a telegram is to go out now. */
bool dp_master_c2_ready(dp_master_c2_t *c, hal_time_us_t now);
/* The telegram: DSAP and DU (length returned, 0 for a poll). SSAP is cfg.ssap. */
size_t dp_master_c2_telegram(dp_master_c2_t *c, hal_time_us_t now, uint8_t *dsap,
                             const uint8_t **du);
void dp_master_c2_answer(dp_master_c2_t *c, const fdl_msg_t *msg, bool sc, hal_time_us_t t);
/* No answer after the retries: the connection is lost. */
void dp_master_c2_no_answer(dp_master_c2_t *c, hal_time_us_t t);
/* When dp_master_c2_ready may next become true by itself (Idle due, timeout). */
hal_time_us_t dp_master_c2_next_deadline(const dp_master_c2_t *c, hal_time_us_t now);

#endif
