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

typedef struct dpv1_conn {
    bool open;
    uint8_t master;
    uint8_t ssap;
    uint32_t send_timeout_us; /* C2 supervision; 0 for C1 */
    hal_time_us_t last_rx;
    volatile uint8_t mailbox; /* dpv1_mailbox_t */
    uint8_t req[DPV1_MAX_PDU];
    uint8_t req_len;
    uint8_t rsp[DPV1_MAX_PDU];
    uint8_t rsp_len;
    ds47_t ds47;
    uint16_t im_selected; /* FI_Index this connection's next Read of index 255 returns */
} dpv1_conn_t;

typedef struct dpv1_cfg {
    ml_client_t *ml;
    uint8_t ch_c1;                        /* service-client channel of MSAC1's data set 47 */
    uint8_t ch_c2[DPV1_C2_CONNECTIONS];   /* ... of each C2 connection */
    im_identity_t identity;
    hal_nvm_t nvm;                        /* I&M1..4; ops == NULL: not kept over power-off */
    size_t nvm_offset;
} dpv1_cfg_t;

typedef struct dpv1 {
    dpv1_conn_t c1;
    dpv1_conn_t c2[DPV1_C2_CONNECTIONS];
    im_t im;
    uint32_t c2_refused;
    uint32_t c2_timeouts;
    uint32_t c2_aborts;
} dpv1_t;

void dpv1_init(dpv1_t *d, const dpv1_cfg_t *cfg);
/* The dp_slave sap_request hook (receive path). */
dp_sap_answer_t dpv1_sap_request(dpv1_t *d, uint8_t master, uint8_t dsap, uint8_t ssap,
                                 const uint8_t *data, size_t len, uint8_t *reply,
                                 size_t *reply_len, hal_time_us_t t);
/* MSAC1 follows the DP state: open in Data_Exch after a DP-V1 parameterisation. */
void dpv1_dp_state(dpv1_t *d, bool data_exch, bool dpv1_mode, uint8_t master);
/* Main loop: PDUs, data set 47 progress, C2 supervision. Returns the next deadline. */
hal_time_us_t dpv1_poll(dpv1_t *d, hal_time_us_t now);

#endif
