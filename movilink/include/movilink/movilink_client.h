/* Parameter services card -> inverter, asynchronous, one outstanding request per channel, each
 * with a deadline. A response that does not match the pending request (another index or
 * service) is dropped. The 8-byte telegram has no room for a request tag, so after a timeout the
 * channel stays quarantined until the late answer has come and been dropped, or a second
 * timeout has passed: only then can a new request go out, and a late answer cannot complete a
 * repetition of the same request. */
#ifndef MOVILINK_MOVILINK_CLIENT_H
#define MOVILINK_MOVILINK_CLIENT_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_time.h"
#include "movilink/movilink_link.h"

/* How long the inverter may take for one service before the card answers class 6 code 2. */
#ifndef ML_RESPONSE_TIMEOUT_US
#define ML_RESPONSE_TIMEOUT_US 200000u
#endif

/* Completion: rsp is the 8-octet response (error bit and error bytes included). */
typedef void (*ml_done_fn)(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN]);

typedef struct ml_pending {
    bool busy;
    bool quarantine; /* timed out: waiting for the late answer before the channel is reused */
    uint8_t req[ML_TELEGRAM_LEN];
    hal_time_us_t deadline;
    ml_done_fn done;
    void *done_ctx;
} ml_pending_t;

typedef struct ml_client {
    ml_link_t link;
    uint32_t timeout_us;
    ml_pending_t ch[ML_MAX_CHANNELS];
    uint32_t timeouts;
    uint32_t stale_responses;
} ml_client_t;

void ml_client_init(ml_client_t *c, ml_link_t link, uint32_t timeout_us);
/* Starts a service. Returns 0; -1 if the channel is busy (or quarantined) or out of range: the
 * caller tries again later. done runs later, from
 * ml_client_response() or ml_client_poll() — or at once if the link refuses the request. The
 * handshake bit of req is cleared on the way out: towards the inverter it would mean SBus
 * synchronous mode. */
int ml_client_request(ml_client_t *c, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN],
                      ml_done_fn done, void *done_ctx, hal_time_us_t now);
bool ml_client_busy(const ml_client_t *c, uint8_t channel);
/* A response from the inverter. */
void ml_client_response(ml_client_t *c, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN]);
/* Deadlines: an overdue request completes with class 6 code 2. Returns the next deadline. */
hal_time_us_t ml_client_poll(ml_client_t *c, hal_time_us_t now);

#endif
