/* A PROFIBUS-DP (DP-V0) slave: FDL station, DP state machine, watchdog and baud search.
 *
 * The caller owns the dp_slave_t (no heap, no globals), feeds it every received character with
 * dp_slave_rx_char() (or every telegram a receiver collected, dp_slave_rx_telegram()) and calls dp_slave_poll() at or after the deadline it returned. Replies go
 * out through the HAL UART's transmit(), timed at end-of-request + min TSDR. What the device
 * does with the data (which configurations and parameters it accepts, what the outputs mean,
 * what the inputs are) is supplied through dp_slave_hooks_t; the DFP21B personality in
 * firmware/dfp21b is one such device. */
#ifndef DP_SLAVE_DP_SLAVE_H
#define DP_SLAVE_DP_SLAVE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/dp_config.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_rx.h"
#include "hal/hal_time.h"
#include "hal/hal_uart.h"

typedef enum dp_state {
    DP_STATE_WAIT_PRM = 0,
    DP_STATE_WAIT_CFG,
    DP_STATE_DATA_EXCH,
} dp_state_t;

typedef enum dp_baud_state {
    DP_BAUD_SEARCH = 0, /* trying rates from 12 Mbit/s down until a good telegram arrives */
    DP_BAUD_CONTROL,    /* rate found; lost again if nothing reaches this station for a while */
    DP_BAUD_FIXED,      /* configured rate, no search */
} dp_baud_state_t;

typedef enum dp_event_type {
    DP_EV_STATE = 0,       /* old_state -> new_state */
    DP_EV_BAUD_SET,        /* value = rate now selected (search step) */
    DP_EV_BAUD_FOUND,      /* value = rate */
    DP_EV_BAUD_LOST,       /* baud control expired: searching again */
    DP_EV_WD_EXPIRED,      /* DP watchdog ran out: outputs cleared, back to Wait_Prm */
    DP_EV_PRM_OK,          /* value = watchdog time in ms (0 = off) */
    DP_EV_PRM_FAULT,       /* value = dp_prm_fault_t */
    DP_EV_CFG_OK,          /* value = output length << 8 | input length */
    DP_EV_CFG_FAULT,
    DP_EV_GLOBAL_CONTROL,  /* value = Control_Command */
    DP_EV_LOCKED_OUT,      /* a request of another master was refused; master = its address */
    DP_EV_RX_ERROR,        /* value = fdl_rx_error_t */
    DP_EV_FCB_REPEAT,      /* a retry was answered from the reply cache */
    /* The first valid telegram for this station (any service) since start-up, since the rate
     * was lost or since the DP watchdog expired: what tells the bus fault LED that a master is
     * back. Not one per telegram, which would put a hook call on every reply path;
     * telegrams_for_me counts them all. */
    DP_EV_ADDRESSED,
} dp_event_type_t;

typedef enum dp_prm_fault {
    DP_PRM_FAULT_LENGTH = 1,
    DP_PRM_FAULT_IDENT,
    DP_PRM_FAULT_WATCHDOG,
    DP_PRM_FAULT_RESERVED_BITS,
    DP_PRM_FAULT_USER, /* rejected by the device's prm_check */
    DP_PRM_FAULT_UNSUPPORTED, /* Sync/Freeze requested but not supported */
} dp_prm_fault_t;

typedef struct dp_event {
    dp_event_type_t type;
    hal_time_us_t t;
    dp_state_t old_state;
    dp_state_t new_state;
    uint8_t master;
    uint32_t value;
} dp_event_t;

typedef enum dp_outputs_reason {
    DP_OUTPUTS_DATA = 0,    /* new outputs from Data_Exchange (or released by Sync/Unsync) */
    DP_OUTPUTS_CLEAR,       /* Global_Control Clear_Data, an empty (fail-safe) telegram, or
                             * a Data_Exchange (its octets as sent) while the master is in
                             * Clear: substitute values, not the master's application data */
    DP_OUTPUTS_SAFE_STATE,  /* left Data_Exch (watchdog, new parameterisation, unlock) */
} dp_outputs_reason_t;

/* Answer of a SAP served outside the DP-V0 core (DP-V1: 0..54). */
typedef enum dp_sap_answer {
    DP_SAP_NOT_SERVED = 0, /* RS: SAP not activated */
    DP_SAP_ANSWER_SC,      /* short acknowledge: request taken, or no response ready yet */
    DP_SAP_ANSWER_DATA,    /* reply with the octets written to reply (SAPs swapped) */
} dp_sap_answer_t;

#define DP_SAP_REPLY_MAX 244u
/* Octets a SAP may always write for a short reply (DP-V1 Abort, RM, Idle, Initiate.res). */
#define DP_SAP_REPLY_SHORT 12u

/* Where the reply to a SAP request is. The DU lies at buf + FDL_TX_HEADROOM (fdl_frame.h) and
 * is framed there in place, so a response the device prepared ahead goes out without a copy. */
typedef struct dp_sap_reply {
    /* In: a buffer with DP_SAP_REPLY_SHORT octets free for the DU. Out: that buffer, or the
     * device's own with FDL_TX_HEADROOM octets before the DU and FDL_TRAILER_LEN after it. */
    uint8_t *buf;
    size_t len; /* DU octets, at most DP_SAP_REPLY_MAX */
    /* The DU's octet sum mod 256 when the device knows it (sum_known), so the reply path does
     * not add it up. */
    bool sum_known;
    uint8_t sum;
    /* The device's own buffer stays unchanged while *guard == guard_value; a retry of the
     * request is answered from it only then (else it is a new request). NULL: no guard. */
    const volatile uint8_t *guard;
    uint8_t guard_value;
} dp_sap_reply_t;

typedef struct dp_slave_hooks {
    void *ctx;
    /* A request (SRD) to a SAP below 55, i.e. everything DP-V1 uses. Called on the receive path:
     * copy, do not work. Optional (without it: RS). */
    dp_sap_answer_t (*sap_request)(void *ctx, uint8_t master, uint8_t dsap, uint8_t ssap,
                                   const uint8_t *data, size_t len, dp_sap_reply_t *reply,
                                   hal_time_us_t t);
    /* Set_Prm octets from index 7 on (DP-V1 status and user parameters), len may be 0. */
    bool (*prm_check)(void *ctx, const uint8_t *prm, size_t len);
    /* Chk_Cfg identifiers; on success the output and input lengths in octets. */
    bool (*cfg_check)(void *ctx, const uint8_t *cfg, size_t len, uint8_t *out_len,
                      uint8_t *in_len);
    /* Outputs for the application (out is dp_slave_outputs()). Called on the receive path:
     * note it, do not work. */
    void (*outputs)(void *ctx, const uint8_t *out, size_t len, dp_outputs_reason_t reason);
    /* Everything that happens, for LEDs, logs and monitoring. Optional. */
    void (*event)(void *ctx, const dp_event_t *ev);
} dp_slave_hooks_t;

typedef struct dp_slave_cfg {
    uint8_t address; /* 0..125 */
    uint16_t ident;
    uint32_t fixed_baud; /* 0 = automatic baud detection */
    bool strict_timing;  /* see fdl_rx.h */
    uint32_t baud_control_ms; /* 0 = DP_BAUD_CONTROL_MS_DEFAULT */
    bool sync_supported;
    bool freeze_supported;
    /* Get_Cfg answer before any Chk_Cfg was accepted. */
    const uint8_t *default_cfg;
    uint8_t default_cfg_len;
    hal_uart_t uart;
    dp_slave_hooks_t hooks;
} dp_slave_cfg_t;

#define DP_BAUD_CONTROL_MS_DEFAULT 1000u

/* The largest DU a reply is built from in a slot's own buffer: Get_Cfg, RD_Inp, RD_Outp, a
 * short SAP reply (Data_Exchange, Slave_Diag and DP-V1 responses are framed where they lie). */
#define DP_MAX2_(a, b) ((a) > (b) ? (a) : (b))
#define FDL_SLOT_DU_MAX DP_MAX2_(DP_MAX2_(DP_MAX_CFG_LEN, DP_SAP_REPLY_SHORT + 2u), DP_MAX_IO_LEN)

/* One master's FCB state and its last reply (IEC 61158-4-3 frame count bit): a retry is
 * answered by pointing the transmitter at the same octets again, never by building it anew. */
#define FDL_FCB_FREE 0xFFu /* the master of a slot no master used yet */
typedef struct fdl_fcb_slot {
    bool fcb_valid;
    uint8_t master;
    uint8_t fcb;
    uint8_t guard_value;
    uint16_t reply_len; /* 0: no reply cached */
    uint32_t stamp; /* dp_slave_t.fcb_clock when this master was last served */
    const uint8_t *reply; /* into buf, a Data_Exchange buffer or the device's (SAP) buffer */
    const volatile uint8_t *guard; /* see dp_sap_reply_t */
    uint8_t buf[FDL_TX_BUF_LEN(FDL_SLOT_DU_MAX)];
} fdl_fcb_slot_t;

/* Data_Exchange replies are framed ahead: dp_slave_set_inputs() frames the inputs in a buffer
 * that no cached reply points at; the reply path only writes the master's address and the FC.
 * Three buffers: the newest inputs, the one the owner's last reply (and a retry) points at, and
 * one to write. */
#define DP_DX_BUFFERS 3u
typedef struct dp_dx_buffer {
    uint8_t start;    /* the frame's first octet in buf */
    uint8_t len;      /* its length */
    uint8_t sum_base; /* its check octet without the master's address and the FC */
    uint8_t buf[FDL_TX_BUF_LEN(DP_MAX_IO_LEN)];
} dp_dx_buffer_t;

/* The Slave_Diag reply is framed ahead too, by dp_slave_prepare() in the main loop, for no
 * master in particular: the reply path writes the requester's address and SAP into it and adds
 * them to the check octet, as an ASIC inserts the header. Two buffers: the one a cached reply
 * (a retry, or the transmitter) may be reading and the one to write. */
#define DP_DIAG_BUFFERS 2u
/* The diagnosis is always SD2 and fills the headroom exactly: the frame starts at buf[0], the
 * requester's address goes at buf[FDL_SD2_HEADER_LEN]. */
typedef struct dp_diag_buffer {
    uint8_t len;      /* the frame's length */
    uint8_t sum_base; /* its check octet without the requester's address and SAP */
    uint8_t buf[FDL_TX_BUF_LEN(DP_DIAG_STD_LEN + DP_MAX_EXT_DIAG_LEN)];
} dp_diag_buffer_t;

typedef struct dp_slave {
    dp_slave_cfg_t cfg;
    fdl_rx_t rx;

    /* baud */
    dp_baud_state_t baud_state;
    uint8_t baud_index;
    uint32_t baud;
    hal_time_us_t baud_deadline;
    uint32_t baud_control_us; /* how long the rate holds without a telegram for this station */
    uint32_t baud_control_base_us; /* the same without a watchdog */

    /* FDL */
    uint8_t min_tsdr_bits;
    uint32_t min_tsdr_us; /* min_tsdr_bits at baud, kept so the reply path does not divide */
    fdl_fcb_slot_t fcb[FDL_FCB_SLOTS];
    uint8_t fcb_last; /* the slot served last: the one fcb_slot() tries first */
    uint8_t fcb_victim; /* the least recently used slot, which a new master takes over */
    bool fcb_victim_stale;
    uint32_t fcb_clock; /* ticks when the master served changes (least recently used order) */
    /* The reply of the request being served: where it is built (a slot's buffer, or scratch for
     * replies that are never repeated) and, once built, the octets to send. */
    uint8_t *tx_buf;
    const uint8_t *tx;
    uint16_t tx_len;
    bool tx_sent; /* the SRD's reply went out early (fdl_station_send_now) */
    const uint8_t *tx_last; /* the frame last handed to the transmitter */
    const volatile uint8_t *tx_guard;
    uint8_t tx_guard_value;
    uint8_t tx_scratch[FDL_TX_BUF_LEN(0u)];

    /* DP */
    dp_state_t state;
    uint8_t master_add;
    uint8_t group_ident;
    uint8_t station_status; /* Set_Prm octet 0 as accepted */
    uint8_t dpv1_status[3];
    bool wd_on;
    uint32_t wd_time_ms;
    uint32_t wd_time_us; /* kept, like baud_control_us, so the receive path does not multiply */
    hal_time_us_t wd_deadline;
    bool prm_fault;
    bool cfg_fault;
    bool not_supported;
    bool stat_diag;
    bool diag_pending; /* new diagnosis not yet read: Data_Exchange answers DH */
    bool sync_mode;
    bool freeze_mode;
    bool sync_latched;
    bool master_clear; /* the owner's last Global_Control had Clear_Data: it is in Clear */

    uint8_t cfg_data[DP_MAX_CFG_LEN];
    uint8_t cfg_len;
    uint8_t out_len;
    uint8_t in_len;
    union { /* words, so clear_outputs() zeroes four octets a step */
        uint8_t outputs[DP_MAX_IO_LEN];
        uint32_t outputs_words[(DP_MAX_IO_LEN + 3u) / 4u];
    };
    uint8_t latched_outputs[DP_MAX_IO_LEN];
    uint8_t inputs[DP_MAX_IO_LEN];
    uint8_t frozen_inputs[DP_MAX_IO_LEN];
    dp_dx_buffer_t dx[DP_DX_BUFFERS];
    uint8_t dx_current; /* the buffer with the newest inputs */

    uint8_t ext_diag[DP_MAX_EXT_DIAG_LEN];
    uint8_t ext_diag_len;
    uint8_t ext_diag_sum; /* octet sum of ext_diag, so a Slave_Diag reply adds up only 6 octets */
    bool ext_diag_overflow;
    dp_diag_buffer_t diag[DP_DIAG_BUFFERS];
    uint8_t diag_current;  /* the buffer with the newest framed diagnosis */
    bool diag_framed; /* diag[diag_current] is the diagnosis as it is now: cleared by any
                       * change made outside the receive path (which frames after each reply) */
    uint32_t diag_status;  /* the status octets and Master_Add framed there (diag_status_word) */

    bool dpv1_mode;   /* accepted Set_Prm had >= 10 octets and DPV1_Enable */
    bool line_active; /* an error-free telegram was heard since power-up or the last baud loss */
    bool addressed_reported; /* DP_EV_ADDRESSED went out since the last loss */
    uint32_t telegrams_for_me;
} dp_slave_t;

/* Power-on: Wait_Prm, Master_Add none, baud search started (or fixed rate selected). */
void dp_slave_init(dp_slave_t *s, const dp_slave_cfg_t *cfg, hal_time_us_t now);
/* One received character; t = end of its stop bit. May transmit a reply. */
#if FDL_RX_CHAR_INPUT
void dp_slave_rx_char(dp_slave_t *s, uint8_t byte, uint8_t flags, hal_time_us_t t);
#endif
/* Instead of rx_char: a whole telegram a receiver collected (fdl_rx.h). May transmit a reply. */
void dp_slave_rx_telegram(dp_slave_t *s, const fdl_rx_telegram_t *tg);
/* Runs timers (watchdog, baud search/control). Returns the next deadline (absolute). */
hal_time_us_t dp_slave_poll(dp_slave_t *s, hal_time_us_t now);

/* The application's input image; copied, used from the next Data_Exchange on. */
void dp_slave_set_inputs(dp_slave_t *s, const uint8_t *in, size_t len);
/* Device-related diagnosis after the six standard octets (len 0 clears Ext_Diag). Any change
 * makes the next Data_Exchange reply DH so the master reads it. */
void dp_slave_set_ext_diag(dp_slave_t *s, const uint8_t *diag, size_t len);
void dp_slave_set_stat_diag(dp_slave_t *s, bool on);

/* Frames ahead the replies whose content changed (the diagnosis), so the reply path only
 * addresses them, and picks the FCB slot a new master would take over. The receive path calls it after each reply; the main loop calls it after
 * changing the extended diagnosis. Without it the replies are right, only slower. */
void dp_slave_prepare(dp_slave_t *s);

/* Builds the Slave_Diag DU as the master would read it now. Returns its length. */
size_t dp_slave_build_diag(const dp_slave_t *s, uint8_t *out, size_t max);

static inline dp_state_t dp_slave_state(const dp_slave_t *s) { return s->state; }
/* The output image the latest outputs hook call handed over (zeros when cleared), valid until
 * the next; DP_MAX_IO_LEN octets. */
static inline const uint8_t *dp_slave_outputs(const dp_slave_t *s) { return s->outputs; }
static inline uint32_t dp_slave_baud(const dp_slave_t *s) { return s->baud; }
static inline dp_baud_state_t dp_slave_baud_state(const dp_slave_t *s) { return s->baud_state; }
/* True once an error-free telegram was received at the current rate (the "baud found" of a
 * fixed-rate slave); false again after the baud control time expires. */
static inline bool dp_slave_line_active(const dp_slave_t *s) { return s->line_active; }
static inline uint8_t dp_slave_master(const dp_slave_t *s) { return s->master_add; }
/* DP-V1 parameterised: MSAC1 may be opened (with Data_Exch). */
static inline bool dp_slave_dpv1_mode(const dp_slave_t *s) { return s->dpv1_mode; }
static inline uint32_t dp_slave_wd_time_ms(const dp_slave_t *s)
{
    return s->wd_on ? s->wd_time_ms : 0u;
}

const char *dp_state_name(dp_state_t st);
const char *dp_baud_state_name(dp_baud_state_t st);

/* Dwell time on one rate during the baud search: long enough for two longest telegrams, and
 * never below DP_BAUD_SEARCH_DWELL_MIN_US. */
#define DP_BAUD_SEARCH_DWELL_MIN_US 20000u
/* The resolution of the receive timestamps the HAL gives (hal_time_us_t). */
#define FDL_TIMESTAMP_RESOLUTION_US 1u
uint32_t dp_baud_search_dwell_us(uint32_t baud);

#endif
