/* The master's side of the cyclic 8-byte MOVILINK channel: put a request into the first 8
 * output octets with the handshake toggled, and recognise the reply that completes it (same
 * handshake, same index). */
#ifndef DP_MASTER_PARAM_CHANNEL_H
#define DP_MASTER_PARAM_CHANNEL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "movilink/movilink_wire.h"

typedef struct dp_master_param {
    uint8_t handshake; /* of the request in flight */
    uint8_t req[ML_TELEGRAM_LEN];
    bool busy;
} dp_master_param_t;

/* Takes the handshake of the reply the card shows now (in = the first 8 input octets), so the
 * next request toggles relative to it. A master that starts talking to a card which already ran
 * services (another master, an earlier session) must do this after its first Data_Exchange: the
 * card keeps its handshake across masters, and a request carrying the card's current handshake is
 * not an edge. */
void dp_master_param_sync(dp_master_param_t *p, const uint8_t in[ML_TELEGRAM_LEN]);
/* Starts a service: writes the request into out[0..7] (the output image). */
void dp_master_param_start(dp_master_param_t *p, uint8_t service, uint16_t index, uint32_t value,
                     uint8_t out[ML_TELEGRAM_LEN]);
/* in = the first 8 input octets. True when they carry the answer to the running request. */
bool dp_master_param_done(dp_master_param_t *p, const uint8_t in[ML_TELEGRAM_LEN]);
/* "class 8, additional code 0x15: value too high" etc. */
size_t ml_error_text(const uint8_t rsp[ML_TELEGRAM_LEN], char *out, size_t max);
const char *ml_service_name(uint8_t service);

#endif
