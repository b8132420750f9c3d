/* DP-V1 acyclic services of the card: MSAC1 (SAP 51), the MSAC2 resource manager (SAP 49) and
 * two class-2 connections (SAPs 0 and 1), data set 47 and I&M. docs/dpv1.md is the contract.
 *
 * The receive path (dpv1_sap_request) only copies a request PDU into the connection's mailbox
 * and answers SC, or hands out a response that is ready; the PDU is worked on in dpv1_poll() from
 * the main loop. On the MCU the mailbox state is shared between the UART interrupt and the main
 * loop: the interrupt only moves EMPTY/RESPONSE -> REQUEST and RESPONSE -> EMPTY, the main loop
 * only REQUEST -> RESPONSE, each after the data is in place. */
#ifndef DPV1_DPV1_H
#define DPV1_DPV1_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/dp_slave.h"
#include "dpv1/ds47.h"
#include "dpv1/im.h"
#include "hal/hal_time.h"

#define DPV1_C2_CONNECTIONS 2u

typedef enum dpv1_mailbox { DPV1_MB_EMPTY = 0, DPV1_MB_REQUEST, DPV1_MB_RESPONSE } dpv1_mailbox_t;

/* One buffer per connection holds the request PDU and then, in its place, the response PDU:
 * a connection has at most one service in progress (protocol.md §A4). */
typedef struct dpv1_conn {
    bool open;
    uint8_t master;
    uint8_t ssap;
    uint32_t send_timeout_us; /* C2 supervision; 0 for C1 */
    hal_time_us_t last_rx;
    volatile uint8_t mailbox; /* dpv1_mailbox_t */
    volatile uint8_t seq;     /* bumped by the receive path for every new PDU and on close */
    /* The PDU at FDL_TX_HEADROOM (dpv1_pdu()), so that the response is framed where it lies. */
    uint8_t frame[FDL_TX_BUF_LEN(DPV1_MAX_PDU)];
    uint8_t pdu_len;
    uint8_t pdu_sum; /* RESPONSE: the octet sum of the response PDU */
    ds47_t ds47;
    uint16_t im_selected; /* FI_Index this connection's next Read of index 255 returns */
} dpv1_conn_t;

static inline uint8_t *dpv1_pdu(dpv1_conn_t *c) { return &c->frame[FDL_TX_HEADROOM]; }

typedef struct dpv1_cfg {
    ml_client_t *ml;
    /* Called between bounded pieces of main-loop work (a data set 47 parse step, one connection)
     * so the caller may let the reply path run; the receive path may then have replaced or
     * closed what was being worked on, which dpv1_poll checks afterwards. Optional. */
    void (*preempt)(void *ctx);
    void *preempt_ctx;
    uint8_t ch_c1;                        /* service-client channel of MSAC1's data set 47 */
    uint8_t ch_c2[DPV1_C2_CONNECTIONS];   /* ... of each C2 connection */
    im_identity_t identity;
    hal_nvm_t nvm;                        /* I&M1..4; ops == NULL: not kept over power-off */
    size_t nvm_offset;
} dpv1_cfg_t;

typedef struct dpv1 {
    void (*preempt)(void *ctx);
    void *preempt_ctx;
    dpv1_conn_t c1;
    dpv1_conn_t c2[DPV1_C2_CONNECTIONS];
    im_t im;
    uint32_t c2_refused;
    uint32_t c2_timeouts;
    uint32_t c2_aborts;
} dpv1_t;

void dpv1_init(dpv1_t *d, const dpv1_cfg_t *cfg);
/* The dp_slave sap_request hook (receive path). A response is handed out where it lies, in the
 * connection's buffer, guarded by the connection's seq. */
dp_sap_answer_t dpv1_sap_request(dpv1_t *d, uint8_t master, uint8_t dsap, uint8_t ssap,
                                 const uint8_t *data, size_t len, dp_sap_reply_t *reply,
                                 hal_time_us_t t);
/* MSAC1 follows the DP state: open in Data_Exch after a DP-V1 parameterisation. */
void dpv1_dp_state(dpv1_t *d, bool data_exch, bool dpv1_mode, uint8_t master);
/* Main loop: PDUs, data set 47 progress, C2 supervision. Returns the next deadline. */
hal_time_us_t dpv1_poll(dpv1_t *d, hal_time_us_t now);

#endif
