/* SBus: MOVILINK over CAN (protocol.md §C2.1). Freestanding: no OS, no allocation.
 *
 * Identifiers (11 bit): bits 0..2 function, bits 3..8 address 0..63, bit 9 = parameter data.
 *   8·a + 3        process output data PO, master -> inverter, 6 octets PO1..PO3
 *   8·a + 4        process input data PI, inverter -> master, 6 octets PI1..PI3
 *   8·a + 512 + 3  parameter request, channel 1, the 8-octet MOVILINK telegram
 *   8·a + 512 + 4  parameter response, channel 1
 *   8·a + 512 + 5  parameter request, channel 2 (MOVIDRIVE B only; direction inferred, docs/protocol.md §C6 item 5)
 *   8·a + 512 + 7  parameter response, channel 2
 * Words are big-endian (PO1 high octet first). Example, address 33: PO 267, PI 268, PO sync 269,
 * request 779, response 780.
 *
 * Process data on SBus are 3 words, whatever the fieldbus configuration: a card configured for
 * 6 or 10 PD sends PO1..PO3 only (PD4..PD10 would be IPOSplus business), and words it does not
 * have (1 or 2 PD) go out as 0.
 *
 * Card side (sbus_card_link_t): an ml_link_t over a hal_can_t for the card's service client.
 *   - param_request(channel 0..3): a parameter request frame to the inverter's address. Card
 *     channels 0 and 1 use SBus parameter channel 1; channels 2 and 3 use SBus channel 2 when
 *     cfg.use_channel2 is set, otherwise channel 1 as well (a MOVIDRIVE A has only channel 1, and
 *     the channel-2 identifiers are inferred). Each SBus channel carries one request at a time:
 *     requests for the other card channels wait in the link (in arrival order) until the
 *     response arrives or SBUS_PARAM_TIMEOUT_US passes without one, and then go out.
 *   - param_cancel(channel): the client gave up; a request of that channel still waiting is
 *     dropped unsent, and the late answer of one already sent only frees the SBus channel: the
 *     client may have sent the channel's next request by then, which must get its own answer.
 *   - process_outputs: one PO frame per call (PO1..PO3).
 *   - fieldbus_status: nothing on the wire; SBus has no telegram for it. When the DP watchdog
 *     expires (status.timeout), the card stops sending PO frames until the timeout clears, so
 *     the inverter's own SBus timeout (P815, reaction P836; P88x/P89x on MOVIDRIVE B) reacts
 *     the way P831 would.
 *   - sbus_card_link_rx(): response and PI frames from the inverter, into the callbacks
 *     param_response(card, channel, rsp) and process_inputs(card, pi, 3).
 *   - sbus_card_link_poll(): the per-channel response deadline; call it from the main loop.
 *
 * Inverter side (sbus_inverter_t): receives request and PO frames for its address, answers
 * through callbacks: param(ctx, req, rsp) → response frame on the same SBus channel (requests
 * with the handshake bit set ask for synchronous mode, which needs a SYNC telegram this side
 * does not implement: they are answered at once as well); process_outputs(ctx, po, 3) and then
 * process_inputs(ctx, pi, 3) → a PI frame (an asynchronous PO is answered with PI). The SBus
 * timeout P815 is watched by sbus_inverter_poll(): no PO for timeout_us after the first one
 * → timeout(ctx, true); the next PO → timeout(ctx, false). */
#ifndef MOVILINK_SBUS_H
#define MOVILINK_SBUS_H

#include <stdbool.h>
#include <stdint.h>

#include "hal/hal_can.h"
#include "hal/hal_time.h"
#include "movilink/movilink_client.h"
#include "movilink/movilink_link.h"
#include "movilink/movilink_wire.h"

#define SBUS_MAX_ADDRESS 63u
#define SBUS_PD_WORDS 3u
#define SBUS_PD_LEN 6u
#define SBUS_PARAM_BIT 0x200u
/* Identifier: parameter bit, the 6-bit address in bits 8..3, the function in bits 2..0
 * (protocol.md §C2.1). */
#define SBUS_ADDRESS_MASK 0x3Fu
#define SBUS_ADDRESS_SHIFT 3u
#define SBUS_FN_MASK 7u
#define SBUS_FN_PO 3u
#define SBUS_FN_PI 4u
#define SBUS_FN_PO_SYNC 5u
#define SBUS_FN_GROUP_PO 6u
#define SBUS_FN_PARAM_REQ 3u
#define SBUS_FN_PARAM_RSP 4u
#define SBUS_FN_PARAM2_REQ 5u
#define SBUS_FN_GROUP_PARAM 6u
#define SBUS_FN_PARAM2_RSP 7u

/* How long a request without a response holds its SBus channel. The telegram has no tag, so an
 * answer is known only by service and index: the channel must stay closed to the other card
 * channels for as long as the service client waits for the answer and then for a late one
 * (ML_RESPONSE_TIMEOUT_US each), or a late answer could complete another channel's request
 * for the same index. What the master sees is decided by the client's own deadline. */
#ifndef SBUS_PARAM_TIMEOUT_US
#define SBUS_PARAM_TIMEOUT_US (2u * ML_RESPONSE_TIMEOUT_US)
#endif

/* Identifier helpers; a = SBus address 0..63 (P813) or group address (P814). */
static inline uint16_t sbus_id(uint8_t a, bool param, uint8_t fn)
{
    return (uint16_t)((param ? SBUS_PARAM_BIT : 0u) | ((a & SBUS_ADDRESS_MASK) << SBUS_ADDRESS_SHIFT) |
                      (fn & SBUS_FN_MASK));
}
static inline uint16_t sbus_id_po(uint8_t a) { return sbus_id(a, false, SBUS_FN_PO); }
static inline uint16_t sbus_id_pi(uint8_t a) { return sbus_id(a, false, SBUS_FN_PI); }
static inline uint16_t sbus_id_po_sync(uint8_t a) { return sbus_id(a, false, SBUS_FN_PO_SYNC); }
static inline uint16_t sbus_id_group_po(uint8_t g) { return sbus_id(g, false, SBUS_FN_GROUP_PO); }
static inline uint16_t sbus_id_param_req(uint8_t a) { return sbus_id(a, true, SBUS_FN_PARAM_REQ); }
static inline uint16_t sbus_id_param_rsp(uint8_t a) { return sbus_id(a, true, SBUS_FN_PARAM_RSP); }
static inline uint16_t sbus_id_param2_req(uint8_t a) { return sbus_id(a, true, SBUS_FN_PARAM2_REQ); }
static inline uint16_t sbus_id_param2_rsp(uint8_t a) { return sbus_id(a, true, SBUS_FN_PARAM2_RSP); }
static inline uint16_t sbus_id_group_param(uint8_t g)
{
    return sbus_id(g, true, SBUS_FN_GROUP_PARAM);
}
static inline uint8_t sbus_id_address(uint16_t id)
{
    return (uint8_t)((id >> SBUS_ADDRESS_SHIFT) & SBUS_ADDRESS_MASK);
}
static inline uint8_t sbus_id_function(uint16_t id) { return (uint8_t)(id & SBUS_FN_MASK); }
static inline bool sbus_id_is_param(uint16_t id) { return (id & SBUS_PARAM_BIT) != 0u; }

/* PD words <-> the 6 octets of a PO/PI frame, big-endian. n < 3 pads with 0; n > 3 is cut. */
void sbus_pack_pd(hal_can_frame_t *f, uint16_t id, const uint16_t *words, uint8_t n);
/* Returns the number of words (len / 2, at most 3). */
uint8_t sbus_unpack_pd(const hal_can_frame_t *f, uint16_t words[SBUS_PD_WORDS]);

/* ---------------------------------------------------------------------------------------------
 * Card side */

typedef struct sbus_card_link_cfg {
    hal_can_t can;
    uint8_t address;      /* the inverter's SBus address (P813) */
    bool use_channel2;    /* card channels 2, 3 on SBus parameter channel 2 */
    uint32_t timeout_us;  /* 0 = SBUS_PARAM_TIMEOUT_US */
    void (*param_response)(void *card, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN]);
    void (*process_inputs)(void *card, const uint16_t *pi, uint8_t n);
    void *card;
} sbus_card_link_cfg_t;

typedef struct sbus_outstanding {
    bool busy;
    bool armed;            /* deadline set (at the first poll after sending) */
    bool given_up;         /* the client cancelled it: its late answer is nobody's */
    uint8_t channel;       /* card channel */
    uint8_t req[ML_TELEGRAM_LEN];
    hal_time_us_t deadline;
} sbus_outstanding_t;

typedef struct sbus_queued {
    bool waiting;
    uint32_t seq;          /* arrival order */
    uint8_t req[ML_TELEGRAM_LEN];
} sbus_queued_t;

typedef struct sbus_card_link {
    sbus_card_link_cfg_t cfg;
    sbus_outstanding_t out[2];             /* SBus parameter channels 1 and 2 */
    sbus_queued_t queue[ML_MAX_CHANNELS];  /* per card channel */
    uint32_t seq;
    bool po_stopped;                       /* DP watchdog expired: no PO frames */
    /* Counters. */
    uint32_t requests_sent;
    uint32_t responses;
    uint32_t stale_responses;  /* matched no outstanding request */
    uint32_t timeouts;
    uint32_t po_frames;
    uint32_t po_withheld;      /* process_outputs calls while po_stopped */
    uint32_t pi_frames;
    uint32_t send_errors;
    uint32_t bad_frames;       /* our identifiers with a wrong length */
} sbus_card_link_t;

void sbus_card_link_init(sbus_card_link_t *l, const sbus_card_link_cfg_t *cfg);
ml_link_t sbus_card_link(sbus_card_link_t *l);
/* Every received frame (other identifiers are ignored). */
void sbus_card_link_rx(sbus_card_link_t *l, const hal_can_frame_t *f, hal_time_us_t now);
/* Gives up overdue requests and sends what was waiting. Returns the next deadline. */
hal_time_us_t sbus_card_link_poll(sbus_card_link_t *l, hal_time_us_t now);
/* The SBus parameter channel (1 or 2) a card channel uses. */
uint8_t sbus_card_link_sbus_channel(const sbus_card_link_t *l, uint8_t channel);

/* ---------------------------------------------------------------------------------------------
 * Inverter side */

typedef struct sbus_inverter_cfg {
    hal_can_t can;
    uint8_t address;        /* P813 */
    bool channel2;          /* also serve SBus parameter channel 2 */
    uint32_t timeout_us;    /* P815 SBus timeout; 0 = off */
    void *ctx;
    void (*param)(void *ctx, const uint8_t req[ML_TELEGRAM_LEN], uint8_t rsp[ML_TELEGRAM_LEN]);
    void (*process_outputs)(void *ctx, const uint16_t *po, uint8_t n);
    void (*process_inputs)(void *ctx, uint16_t *pi, uint8_t n);
    void (*timeout)(void *ctx, bool active); /* optional */
} sbus_inverter_cfg_t;

typedef struct sbus_inverter {
    sbus_inverter_cfg_t cfg;
    bool po_seen;
    bool timed_out;
    hal_time_us_t po_deadline;
    uint32_t requests;
    uint32_t po_frames;
    uint32_t send_errors;
    uint32_t bad_frames;
} sbus_inverter_t;

void sbus_inverter_init(sbus_inverter_t *inv, const sbus_inverter_cfg_t *cfg);
void sbus_inverter_rx(sbus_inverter_t *inv, const hal_can_frame_t *f, hal_time_us_t now);
/* The SBus timeout. Returns the next deadline. */
hal_time_us_t sbus_inverter_poll(sbus_inverter_t *inv, hal_time_us_t now);

#endif
