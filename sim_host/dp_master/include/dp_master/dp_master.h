/* A class-1 DP master for the host: brings DP-V0 slaves up (FDL status, Slave_Diag, Set_Prm,
 * Chk_Cfg, Slave_Diag) and keeps them in cyclic Data_Exchange; Global_Control on demand.
 * It runs as a station on any medium (in-memory bus, tty, PTY) like the card does, and keeps
 * only one request outstanding, as a single master on a segment does.
 *
 * Fault handling: a missing reply is retried with the same FCB (max_retry times); then the
 * slave counts as lost and its start-up is repeated: a silent address is asked again every
 * lost_poll_us (like a GAP update), a slave that answers but refuses after a back-off that
 * doubles from backoff_min_us to backoff_max_us, so a broken slave is not hammered. RS to
 * Data_Exchange, Prm_Fault, Cfg_Fault and Not_Supported in the diagnosis do the same. DH makes
 * the master read the diagnosis before the next Data_Exchange.
 *
 * DP-V1 (docs/dpv1.md): a slave parameterised for DP-V1 (dp_master_build_prm_dpv1) takes class-1
 * Read/Write requests (dp_master_c1_submit, queue depth 1). They travel between Data_Exchange
 * cycles, at most one acyclic telegram between two Data_Exchange of that slave: the request as
 * SRD to DSAP 51 / SSAP 51, then empty polls with the same SAPs until the response or the C1
 * response timeout. Class-2 connections (dpv1_c2.h) attached with dp_master_add_c2 share the
 * station: one of their telegrams, then the cyclic slaves that are due, and so on. */
#ifndef DP_MASTER_DP_MASTER_H
#define DP_MASTER_DP_MASTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_master/dpv1_xfer.h"
#include "dp_slave/fdl_rx.h"
#include "fdl_active/fdl_active.h"
#include "dp_master/rx_whole.h"
#include "hal/hal_time.h"
#include "hal/hal_uart.h"

#ifndef DP_MASTER_MAX_SLAVES
#define DP_MASTER_MAX_SLAVES 32u
#endif
#define DP_MASTER_MAX_PRM 244u
#define DP_MASTER_MAX_CFG 244u
#define DP_MASTER_MAX_IO 244u
#ifndef DP_MASTER_MAX_C2
#define DP_MASTER_MAX_C2 4u
#endif
#define DP_MASTER_C1_TIMEOUT_US_DEFAULT 1000000u

typedef enum dp_master_phase {
    DP_MASTER_PHASE_BACKOFF = 0, /* waiting before the next start-up attempt */
    DP_MASTER_PHASE_FDL_STATUS,
    DP_MASTER_PHASE_DIAG_1,
    DP_MASTER_PHASE_SET_PRM,
    DP_MASTER_PHASE_CHK_CFG,
    DP_MASTER_PHASE_DIAG_2,
    DP_MASTER_PHASE_DATA_EXCH,
    DP_MASTER_PHASE_DIAG_DX, /* reading a diagnosis announced by DH */
} dp_master_phase_t;

typedef enum dp_master_event_type {
    DP_MASTER_EV_PHASE = 0, /* a slave moved from old_phase to new_phase */
    DP_MASTER_EV_DIAG,      /* a Slave_Diag answer: data/len */
    DP_MASTER_EV_FAULT,     /* text says why the slave is restarted */
    DP_MASTER_EV_RETRY,
    DP_MASTER_EV_INPUTS,    /* Data_Exchange answer: data/len */
    DP_MASTER_EV_GLOBAL_CONTROL_SENT,
} dp_master_event_type_t;

typedef struct dp_master_event {
    dp_master_event_type_t type;
    hal_time_us_t t;
    uint8_t slave;
    dp_master_phase_t old_phase;
    dp_master_phase_t new_phase;
    const uint8_t *data;
    size_t len;
    const char *text;
} dp_master_event_t;

typedef struct dp_master_slave_cfg {
    uint8_t address;
    uint8_t prm[DP_MASTER_MAX_PRM]; /* complete Set_Prm DU */
    uint8_t prm_len;
    uint8_t cfg[DP_MASTER_MAX_CFG];
    uint8_t cfg_len;
} dp_master_slave_cfg_t;

typedef struct dp_master_cfg {
    uint8_t address;
    uint32_t baud;
    bool strict_timing;
    uint32_t slot_time_us;   /* 0: TSL default for the rate (100..1000 bit times) */
    uint32_t cycle_us;       /* minimum time between two Data_Exchange of one slave */
    uint8_t max_retry;       /* 0: 1 retry */
    uint32_t backoff_min_us; /* 0: 10 ms */
    uint32_t backoff_max_us; /* 0: 1 s */
    uint32_t lost_poll_us;   /* 0: 5 ms between FDL status requests to a silent address */
    uint32_t c1_timeout_us;  /* 0: 1 s, DP-V1 class-1 response timeout (request to response) */
    hal_uart_t uart;
    void (*event)(void *ctx, const dp_master_event_t *ev);
    void *event_ctx;
    /* The master as an FDL active station (fdl_active.h): it sends only while it holds the
     * token, and takes part in the ring with bus (bus.baud 0: the DP profile at baud). The
     * reply deadline is then TSL and max_retry the bus's retry limit (when 0 here). Without
     * it the master owns the line and sends whenever it likes (a bus of its own only). */
    bool token_ring;
    fdl_bus_params_t bus;
    void (*ring_event)(void *ctx, const fdl_active_event_t *ev); /* gets event_ctx */
} dp_master_cfg_t;

typedef struct dp_master_slave {
    dp_master_slave_cfg_t cfg;
    uint16_t out_len;
    uint16_t in_len;
    dp_master_phase_t phase;
    bool fcb_first; /* next request carries FCV=0, FCB=1 */
    bool fcb;
    hal_time_us_t due; /* earliest time of the next request */
    uint32_t backoff_us;
    uint8_t stat_diag_repeats;
    uint8_t outputs[DP_MASTER_MAX_IO];
    uint8_t inputs[DP_MASTER_MAX_IO];
    uint16_t inputs_len;
    uint8_t last_diag[DP_MASTER_MAX_IO];
    uint8_t last_diag_len;
    uint32_t cycles;
    uint32_t restarts;
    /* Why the slave was last restarted ("" before that): kept so a timeout can say what
     * held the slave back instead of only the phase it ended in. */
    char fault[64];
    /* DP-V1 class 1 */
    dp_master_xfer_t c1;
    bool c1_turn; /* a Data_Exchange completed since the last acyclic telegram */
    uint32_t served_visit; /* token ring: the token visit of its last cyclic telegram */
} dp_master_slave_t;

struct dp_master_c2;

typedef enum dp_master_wait_kind {
    DP_MASTER_WAIT_CYCLIC = 0, /* start-up, Data_Exchange, diagnosis */
    DP_MASTER_WAIT_C1,
    DP_MASTER_WAIT_C2,
} dp_master_wait_kind_t;

/* FCB state of one (our address, slave address) pair that no dp_master_slave_t carries (class-2
 * connections from another address, or to a slave that is not in cyclic exchange). */
typedef struct dp_master_fcb {
    bool used;
    uint8_t own;
    uint8_t slave;
    bool first;
    bool fcb;
} dp_master_fcb_t;

typedef struct dp_master {
    dp_master_cfg_t cfg;
    fdl_rx_t rx;
    dp_master_slave_t slaves[DP_MASTER_MAX_SLAVES];
    uint8_t num_slaves;
    uint8_t next_slave; /* round robin */
    bool running;
    bool waiting;       /* a request is outstanding */
    uint8_t waiting_for; /* slave index */
    uint8_t retries;
    hal_time_us_t reply_deadline;
    hal_time_us_t next_send;
    uint8_t request[FDL_FRAME_MAX];
    uint16_t request_len;
    bool gc_pending;
    uint8_t gc_command;
    uint8_t gc_group;
    uint32_t timeouts;
    uint32_t total_retries;
    /* DP-V1 */
    dp_master_wait_kind_t waiting_kind;
    uint8_t waiting_c2;  /* index into c2[] */
    uint8_t expect_da;   /* the reply must come to this address ... */
    uint8_t expect_sa;   /* ... from this one */
    struct dp_master_c2 *c2[DP_MASTER_MAX_C2];
    uint8_t num_c2;
    uint8_t next_c2;
    bool c2_turn;        /* a cyclic telegram went out since the last class-2 one */
    dp_master_fcb_t fcbs[2u * DP_MASTER_MAX_C2];
    uint32_t acyclic_telegrams;
    /* Medium access (cfg.token_ring). */
    fdl_active_t mac;
    bool leaving; /* dp_master_leave */
} dp_master_t;

void dp_master_init(dp_master_t *m, const dp_master_cfg_t *cfg, hal_time_us_t now);
/* Returns the slave index or -1 (table full, malformed configuration). */
int dp_master_add_slave(dp_master_t *m, const dp_master_slave_cfg_t *sc);
/* New parameters/configuration for a slave: its start-up is repeated with them. */
int dp_master_reconfigure(dp_master_t *m, unsigned idx, const dp_master_slave_cfg_t *sc,
                          hal_time_us_t now);
void dp_master_set_outputs(dp_master_t *m, unsigned idx, const uint8_t *out, size_t len);
/* Sent as SDN to address 127 at the next free moment. */
void dp_master_global_control(dp_master_t *m, uint8_t command, uint8_t group_select);
/* A stopped master sends nothing (to show what the slave's watchdog does). start() brings every
 * slave up again from the beginning. */
void dp_master_stop(dp_master_t *m);
void dp_master_start(dp_master_t *m, hal_time_us_t now);
/* The program ends: in a token ring the master finishes the message cycle on the wire, passes
 * the token on if it holds it and goes off the bus (fdl_active_leave), so the others need not
 * wait for the lost-token time-out. dp_master_left() says when that is done. */
void dp_master_leave(dp_master_t *m);
bool dp_master_left(const dp_master_t *m);

void dp_master_rx_char(dp_master_t *m, uint8_t byte, uint8_t flags, hal_time_us_t t);
/* Instead of rx_char for each character: a whole telegram for which dp_master_whole_clean() said
 * yes (rx_whole.h). */
void dp_master_rx_telegram(dp_master_t *m, const dp_master_whole_t *w);
hal_time_us_t dp_master_poll(dp_master_t *m, hal_time_us_t now);
/* The FDL active station (LAS, live list, rotation figures); meaningful with cfg.token_ring. */
static inline const fdl_active_t *dp_master_ring(const dp_master_t *m) { return &m->mac; }

const char *dp_master_phase_name(dp_master_phase_t p);
/* Standard DP-V0 Set_Prm: Lock_Req, WD_On with the given time (10 ms base), min TSDR 11. */
size_t dp_master_build_prm(uint8_t *out, uint16_t ident, uint32_t wd_ms, const uint8_t *user,
                     size_t user_len);
/* The same for a DP-V1 slave: user[0..2] are DPV1_Status_1..3 (octets 7..9; zeros if user is
 * shorter), and DPV1_Status_1 gets DPV1_Enable (0x80). For the DFP21B the user parameters
 * 00 00 00 06 81 00 00 01 01 go out as 80 00 00 06 81 00 00 01 01. */
size_t dp_master_build_prm_dpv1(uint8_t *out, uint16_t ident, uint32_t wd_ms, const uint8_t *user,
                          size_t user_len);
/* Set_Prm asks for DP-V1 (>= 10 octets and DPV1_Enable): MSAC1 opens with Data_Exch. */
bool dp_master_prm_is_dpv1(const uint8_t *prm, size_t len);

/* ---- DP-V1 class 1 ------------------------------------------------------------------------ */

/* Queues a Read/Write (any) request PDU for the slave; it goes out once the slave is in
 * Data_Exchange, between two cycles. done runs with the response PDU (possibly a negative
 * response), or with an error: C1 response timeout, RS (MSAC1 closed), no answer, the slave
 * restarted while the request was in the card. -1: not a DP-V1 slave (see dp_master_prm_is_dpv1),
 * a request is already queued, or the PDU is empty or longer than 244 octets. */
int dp_master_c1_submit(dp_master_t *m, unsigned idx, const uint8_t *pdu, size_t len,
                        dp_master_acyc_done_t done, void *ctx);
bool dp_master_c1_busy(const dp_master_t *m, unsigned slave);
/* The slave as a path for dpv1_ds47.h jobs. */
dp_master_acyc_port_t dp_master_c1_port(dp_master_t *m, unsigned idx);

/* ---- DP-V1 class 2 ------------------------------------------------------------------------ */

/* Attaches a class-2 connection (dpv1_c2.h) to this station; its telegrams go out in the
 * gaps of the cyclic traffic. Returns 0, or -1 when DP_MASTER_MAX_C2 are attached. */
int dp_master_add_c2(dp_master_t *m, struct dp_master_c2 *c);

#endif
