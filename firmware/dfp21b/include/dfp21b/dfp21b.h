/* The DFP21B personality: what makes the generic DP slave a DFP21B (DFP21B manual, edition 03/2004;
 * docs/protocol.md part B): ident 0x6003, the accepted configurations, the 9-byte user
 * parameters, the DIP-switch address, the RUN / BUS FAULT LEDs and the fieldbus monitor values
 * the inverter shows in P090..P099. What the process data and the parameter channel mean is the
 * inverter's business and reaches it through dfp21b_app_t. */
#ifndef DFP21B_DFP21B_H
#define DFP21B_DFP21B_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "dp_slave/dp_slave.h"
#include "dpv1/dpv1.h"
#include "hal/hal_dip.h"
#include "hal/hal_led.h"
#include "hal/hal_nvm.h"
#include "hal/hal_uart.h"
#include "movilink/movilink_channel.h"
#include "movilink/movilink_client.h"
#include "movilink/movilink_link.h"

#define DFP21B_IDENT 0x6003u
#define DFP21B_MAX_ADDRESS 125u
#define DFP21B_MAX_PD 10u
#define DFP21B_PARAM_LEN 8u
#define DFP21B_USER_PRM_LEN 9u
#define DFP21B_IO_MAX (DFP21B_PARAM_LEN + 2u * DFP21B_MAX_PD)

/* The process-data configuration as P090 shows it. */
typedef struct dfp21b_pd_cfg {
    bool valid;          /* false: "0PD" (configuration fault or none yet) */
    bool param_channel;  /* 8-byte MOVILINK channel in front of the PD words */
    uint8_t pd_words;    /* 1..10 */
} dfp21b_pd_cfg_t;

/* Channel numbers on the inverter link (movilink_link.h). */
#define DFP21B_CH_CYCLIC 0u      /* the 8-byte channel in the cyclic data */
#define DFP21B_CH_C1 1u          /* data set 47 over MSAC1 */
#define DFP21B_CH_C2_FIRST 2u    /* data set 47 over the two MSAC2 connections: 2 and 3 */
#define DFP21B_CH_STATUS_POLL 4u /* the card's own reads of the inverter status (fault number) */
#define DFP21B_MANUFACTURER_ID 0x010Au
#define DFP21B_ORDER_ID "824 240 2"
/* With diagnostic alarms on, the card reads the inverter status (index 8310) this often. */
#define DFP21B_STATUS_POLL_US 100000u

/* Test hooks replacing the inverter link. All optional; with neither a link nor these, PI words
 * echo the PO words and the parameter channel answers 8 zero octets. */
typedef struct dfp21b_app {
    void *ctx;
    /* From the main loop (dfp21b_poll), after new outputs arrived. po/pi are host-order words. */
    void (*process_data)(void *ctx, const uint16_t *po, uint16_t *pi, uint8_t n,
                         dp_outputs_reason_t why);
    void (*param_channel)(void *ctx, const uint8_t req[DFP21B_PARAM_LEN],
                          uint8_t rsp[DFP21B_PARAM_LEN]);
    /* DP watchdog expired: the inverter performs its P831 reaction. */
    void (*fieldbus_timeout)(void *ctx);
} dfp21b_app_t;

typedef struct dfp21b_cfg {
    hal_uart_t uart;
    hal_led_t led;
    hal_dip_t dip;
    uint32_t fixed_baud; /* 0 = automatic detection (the card's only mode; fixed is for tests) */
    bool strict_timing;
    uint32_t baud_control_ms;
    dfp21b_app_t app;
    /* The inverter: parameter telegrams and process data cross this link (in-process emulation,
     * SBus over CAN, or the option connector). ops == NULL: no inverter (loopback). Responses
     * come back through dfp21b_inverter_param_response() / dfp21b_inverter_process_inputs(). */
    ml_link_t inverter;
    /* The card's own non-volatile storage (I&M1..I&M4). ops == NULL: kept until power-off. */
    hal_nvm_t nvm;
    /* I&M0: serial number and revisions of this card. */
    const char *serial;
    uint16_t hardware_revision;
    uint8_t software_revision[3]; /* major, minor, bugfix */
    /* Every DP event, after the personality has acted on it. Optional. */
    void (*event)(void *ctx, const dp_event_t *ev);
    void *event_ctx;
    /* Called between the bounded pieces of dfp21b_poll's work, where the caller may let a
     * waiting reply be served (on the MCU: lower and raise BASEPRI) so that no piece of main-loop
     * work holds a reply off for longer than one piece. Optional. */
    void (*preempt)(void *ctx);
    void *preempt_ctx;
} dfp21b_cfg_t;

typedef struct dfp21b {
    dp_slave_t dp;
    dfp21b_cfg_t cfg;
    uint8_t address;
    bool on_bus;
    hal_led_mode_t led[HAL_LED_COUNT];
    bool leds_known;
    bool master_lost; /* watchdog expired and the master has not come back yet */
    bool diag_alarm;  /* user prm byte 8 = 00 in DP-V0 mode: inverter faults go out as Ext_Diag */
    dfp21b_pd_cfg_t pd;
    dfp21b_pd_cfg_t pd_candidate; /* result of the last cfg_check */
    bool outputs_new;
    dp_outputs_reason_t outputs_reason;
    uint8_t in_image[DFP21B_IO_MAX];
    uint16_t po[DFP21B_MAX_PD];
    uint16_t pi[DFP21B_MAX_PD];
    uint8_t param_req[DFP21B_PARAM_LEN];
    uint8_t param_rsp[DFP21B_PARAM_LEN];
    uint8_t inverter_fault;
    uint32_t p819_ms;
    uint8_t prm_count; /* accepted Set_Prm, for the inverter's P819 (ml_fieldbus_status_t) */
    ml_client_t ml;
    ml_channel_t param;
    dpv1_t dpv1;
    bool inputs_dirty;
    bool status_dirty;
    bool status_poll_busy;
    bool fieldbus_timeout;
    hal_time_us_t next_status_poll;
    hal_time_us_t now;
} dfp21b_t;

/* Power-up: reads the DIP switches once. Address > 125: the card stays off the bus. */
void dfp21b_init(dfp21b_t *c, const dfp21b_cfg_t *cfg, hal_time_us_t now);
#if FDL_RX_CHAR_INPUT
void dfp21b_rx_char(dfp21b_t *c, uint8_t byte, uint8_t flags, hal_time_us_t t);
#endif
void dfp21b_rx_telegram(dfp21b_t *c, const fdl_rx_telegram_t *tg);
/* Main-loop work: timers, process data to and from the inverter. Returns the next deadline. */
hal_time_us_t dfp21b_poll(dfp21b_t *c, hal_time_us_t now);

/* From the inverter link: a parameter response, and fresh process input words (host order). */
void dfp21b_inverter_param_response(dfp21b_t *c, uint8_t channel,
                                    const uint8_t rsp[ML_TELEGRAM_LEN]);
void dfp21b_inverter_process_inputs(dfp21b_t *c, const uint16_t *pi, uint8_t n);

/* Inverter fault number (0 = none). With diagnostic alarms enabled (user prm byte 8 = 00, in
 * DP-V0 mode only) a fault is reported as device-related Ext_Diag: header 0x02 + fault number
 * (8 octets in all). */
void dfp21b_set_inverter_fault(dfp21b_t *c, uint8_t fault);

/* The checks the card applies, usable without a running slave (tests, GSD check). */
bool dfp21b_check_cfg(const uint8_t *cfg, size_t len, dfp21b_pd_cfg_t *pd);
bool dfp21b_check_user_prm(const uint8_t *prm, size_t len, bool *diag_alarm);

/* Fieldbus monitor values. */
size_t dfp21b_p090_text(const dfp21b_pd_cfg_t *pd, char *out, size_t max); /* P090 */
static inline uint32_t dfp21b_p092_baud(const dfp21b_t *c)                    /* P092 */
{
    return dp_slave_baud_state(&c->dp) == DP_BAUD_SEARCH ? 0u : dp_slave_baud(&c->dp);
}
static inline uint8_t dfp21b_p093_address(const dfp21b_t *c) { return c->address; } /* P093 */
/* P819: the watchdog time of the last accepted Set_Prm; it stays after the watchdog expired. */
static inline uint32_t dfp21b_p819_timeout_ms(const dfp21b_t *c) { return c->p819_ms; }

/* Get_Cfg answer before a master configured the card: "Param + 3 PD". */
extern const uint8_t dfp21b_default_cfg[2];

#endif
