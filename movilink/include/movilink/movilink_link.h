/* The card's link to its inverter, the one boundary between the fieldbus card and the drive.
 *
 * Everything crosses it in the inverter's own terms: 8-byte MOVILINK parameter telegrams (as on
 * SBus) and process-data words. It is asynchronous: a parameter request is sent now and its
 * response arrives later through ml_client_response(), possibly many bus cycles later; nothing
 * on the card waits for it. Implementations: in-process (the emulated MOVIDRIVE in sim_host/),
 * SBus over CAN (sim_host/, SocketCAN), and on the MCU the option-card connector.
 *
 * Channel numbers let several users share the link: channel 0 is the cyclic PROFIBUS parameter
 * channel, 1..ML_MAX_CHANNELS-1 are for DP-V1 data set 47 requests. */
#ifndef MOVILINK_MOVILINK_LINK_H
#define MOVILINK_MOVILINK_LINK_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_time.h"
#include "movilink/movilink_wire.h"

#ifndef ML_MAX_CHANNELS
#define ML_MAX_CHANNELS 5u /* cyclic channel, MSAC1, two MSAC2, the card's status poll */
#endif
#define ML_MAX_PD 10u

/* What the fieldbus side tells the inverter: the monitor values P090..P093, the DP watchdog time
 * (P819) and whether the fieldbus timed out (P831 reaction). */
typedef struct ml_fieldbus_status {
    uint8_t pd_config;       /* P090 code: 0 P+1PD,1 1PD,2 P+2PD,3 2PD,4 P+3PD,5 3PD,6 P+6PD,7 6PD,
                                8 P+10PD,9 10PD; 255 = no valid configuration ("0PD") */
    uint8_t pd_words;        /* 0 when no valid configuration */
    bool param_channel;
    uint32_t baud;           /* P092, bit/s; 0 = none detected */
    uint8_t address;         /* P093 */
    uint32_t watchdog_ms;    /* P819 */
    uint8_t prm_count;       /* accepted Set_Prm so far, 0 = none yet, wraps 255 -> 1: P819 can be
                                written elsewhere and is overwritten only at the next
                                parameterisation (protocol.md §B5), so the inverter takes
                                watchdog_ms only when this is non-zero and changed */
    bool data_exchange;      /* the master exchanges process data */
    bool timeout;            /* DP watchdog expired: perform the P831 reaction */
} ml_fieldbus_status_t;

typedef struct ml_link_ops {
    /* Send one parameter request on a channel. Returns 0, or negative if the link cannot take it
     * (link down): the client then reports class 6 code 2 at once. */
    int (*param_request)(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN]);
    /* New process output words (host order), n = 0..10. */
    void (*process_outputs)(void *ctx, const uint16_t *po, uint8_t n);
    /* Fieldbus state changed (monitor values, timeout). Optional. */
    void (*fieldbus_status)(void *ctx, const ml_fieldbus_status_t *status);
    /* The client gave up on the channel's request and answered class 6 code 2, which tells the
     * master to repeat it. A request the link still holds unsent must now never be sent, or
     * the repetition would make it run twice. One already sent keeps its answer routed to the
     * channel (the client drops it). Optional: a link that sends at once holds nothing. */
    void (*param_cancel)(void *ctx, uint8_t channel);
} ml_link_ops_t;

typedef struct ml_link {
    const ml_link_ops_t *ops;
    void *ctx;
} ml_link_t;

#endif
