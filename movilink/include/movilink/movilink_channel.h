/* The cyclic 8-byte parameter channel of the PROFIBUS process data (protocol.md §B6).
 *
 * A service starts on an edge of the handshake bit (bit 6 of the management byte), never on the
 * content: a request that arrives again and again with unchanged handshake is executed once.
 * Until the service completes, the card keeps returning its previous reply; the reply carrying
 * the new handshake value carries the result. The card checks what it can itself (management and
 * reserved byte: class 5 code 5; write with data length other than 4 octets: class 6 code 8);
 * everything else is the inverter's answer, or class 6 code 2 if it does not answer in time. */
#ifndef MOVILINK_MOVILINK_CHANNEL_H
#define MOVILINK_MOVILINK_CHANNEL_H

#include <stdbool.h>
#include <stdint.h>

#include "movilink/movilink_client.h"

typedef struct ml_channel {
    ml_client_t *client;
    uint8_t channel;
    uint8_t handshake;   /* handshake value of the last completed service */
    bool busy;
    uint8_t running_handshake;
    uint8_t reply[ML_TELEGRAM_LEN];
    uint32_t services;   /* executed services, for tests and monitoring */
} ml_channel_t;

/* Reply starts as 8 zero octets with handshake 0, so a master whose first request carries
 * handshake 1 gets it executed. */
void ml_channel_init(ml_channel_t *ch, ml_client_t *client, uint8_t channel);
/* The request octets of the current cyclic telegram (call on every new output image). */
void ml_channel_request(ml_channel_t *ch, const uint8_t req[ML_TELEGRAM_LEN], hal_time_us_t now);
static inline const uint8_t *ml_channel_reply(const ml_channel_t *ch) { return ch->reply; }

#endif
