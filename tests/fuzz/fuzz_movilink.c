/* Target movilink: the cyclic 8-byte MOVILINK channel (ml_channel) on top of the service client
 * (ml_client), against a fake inverter link the input drives: it answers correctly, late, with
 * another index or service, with garbage, twice, or not at all, and may refuse requests.
 *
 * Input: a 32-bit start time, then operations (op octet, low 3 bits select):
 *   0  the master's cyclic request: 8 octets from the input; op bit 3 set: take the previous
 *      request with its handshake toggled and a fresh index/value (a well-behaved master)
 *   1  the link answers the oldest request it holds on channel u8 % 5: op bits 3..4 pick a
 *      correct answer (value or error from the input), another index, another service, or 8
 *      octets of garbage; bit 5 keeps the request held (a duplicate answer later)
 *   2  time passes: u16 µs << (op bits 3..5), then ml_client_poll
 *   3  a direct client request on channel 1..4 (data set 47 / status poll users), 8 octets
 *   4  the link refuses (or accepts again) further requests
 *   5  the link forgets everything it holds (the inverter restarted)
 *
 * Properties:
 *  - the channel starts a service only on a handshake edge the master made: services started
 *    <= the master's handshake toggles (each toggle at most once);
 *  - while a service runs the reply stays byte for byte the previous one; a reply changes at
 *    most once per started service, carries the handshake and the index of the request that
 *    started it, and the card's own answers are the documented ones (class 5 code 5, class 6
 *    code 8, class 6 code 2);
 *  - the client: one request per channel at a time, handshake and error bits cleared towards
 *    the link, exactly one completion per accepted request, by a response whose service and
 *    index match it, or by class 6 code 2 not before its deadline; nothing after that;
 *  - known finding (FUZZ_KNOWN=ml_late_answer, README.md): a completion is the answer to
 *    that request, not a late answer to an earlier one with the same service and index. */
#include "fuzz_common.h"
#include "movilink/movilink_channel.h"
#include "movilink/movilink_client.h"

#define HELD_MAX 8u

typedef struct held {
    uint8_t req[ML_TELEGRAM_LEN];
    uint32_t tag; /* which client request this is the link's copy of */
} held_t;

typedef struct fake_link {
    held_t held[ML_MAX_CHANNELS][HELD_MAX];
    uint8_t n_held[ML_MAX_CHANNELS];
    bool refuse;
} fake_link_t;

typedef struct user { /* a direct client user on channels 1..4 */
    bool outstanding;
    uint8_t req[ML_TELEGRAM_LEN];
    hal_time_us_t started;
    uint32_t tag;
} user_t;

typedef struct rig {
    ml_client_t client;
    ml_channel_t ch;
    fake_link_t link;
    user_t user[ML_MAX_CHANNELS];
    hal_time_us_t now;
    uint32_t next_tag;
    uint32_t tag_sent[ML_MAX_CHANNELS]; /* tag of the client's current request per channel */
    /* delivering_tag: the tag of the held request whose answer is being delivered (0: none) */
    uint32_t delivering_tag;
    bool delivering;
    /* master side of channel 0 */
    uint8_t last_req[ML_TELEGRAM_LEN];
    uint8_t last_hs;
    uint32_t master_toggles;
    uint32_t services_seen;
    uint32_t completions_seen;
    uint8_t running_req[ML_TELEGRAM_LEN];
    hal_time_us_t running_since;
    bool running;
    uint32_t running_tag;
} rig_t;

static rig_t r;
static bool known_late_answer;

static int link_param_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    (void)ctx;
    PROPERTY(channel < ML_MAX_CHANNELS, "request on channel %u", channel);
    PROPERTY((req[ML_OFF_MANAGEMENT] & (ML_MGMT_HANDSHAKE | ML_MGMT_ERROR)) == 0u,
             "handshake or error bit sent to the inverter: %02X", req[ML_OFF_MANAGEMENT]);
    if (r.link.refuse) {
        return -1;
    }
    r.tag_sent[channel] = ++r.next_tag;
    if (r.link.n_held[channel] < HELD_MAX) {
        held_t *h = &r.link.held[channel][r.link.n_held[channel]++];
        memcpy(h->req, req, ML_TELEGRAM_LEN);
        h->tag = r.next_tag;
    }
    return 0;
}

static const ml_link_ops_t link_ops = {.param_request = link_param_request};

static void user_done(void *ctx, uint8_t channel, const uint8_t rsp[ML_TELEGRAM_LEN])
{
    user_t *u = ctx;
    PROPERTY(channel >= 1u && channel < ML_MAX_CHANNELS && u == &r.user[channel],
             "completion for the wrong user");
    PROPERTY(u->outstanding, "a second completion of one request on channel %u", channel);
    u->outstanding = false;
    uint8_t svc = (uint8_t)(u->req[0] & ML_MGMT_SERVICE_MASK);
    PROPERTY(ml_index(rsp) == ml_index(u->req), "completed by an answer for index %u, asked %u",
             ml_index(rsp), ml_index(u->req));
    PROPERTY((rsp[0] & ML_MGMT_SERVICE_MASK) == svc, "completed by another service");
    if (r.delivering) {
        if (known_late_answer) {
            PROPERTY(r.delivering_tag == u->tag, "channel %u: request %u completed by the late "
                     "answer to request %u (same service and index)", channel, u->tag,
                     r.delivering_tag);
        }
    } else {
        /* not from a link answer: the client's own class 6 code 2 */
        PROPERTY((rsp[0] & ML_MGMT_ERROR) != 0u && rsp[4] == ML_CLASS_ACCESS &&
                     rsp[5] == ML_CODE_HARDWARE_FAULT,
                 "a completion without an answer that is not class 6 code 2");
        PROPERTY(r.link.refuse || hal_time_diff(r.now, u->started) >= (int32_t)ML_RESPONSE_TIMEOUT_US,
                 "timed out after %d us", hal_time_diff(r.now, u->started));
    }
}

/* Observes the channel after every step: what changed and whether it may have. */
static void observe(const uint8_t before[ML_TELEGRAM_LEN], uint32_t services_before,
                    bool may_complete)
{
    uint32_t started = r.ch.services - services_before;
    PROPERTY(started <= 1u, "%u services started at once", started);
    if (started == 1u) {
        r.services_seen++;
    }
    PROPERTY(r.services_seen <= r.master_toggles,
             "%u services for %u handshake toggles of the master", r.services_seen,
             r.master_toggles);
    bool changed = memcmp(before, r.ch.reply, ML_TELEGRAM_LEN) != 0 ||
                   (r.running && !r.ch.busy);
    if (!changed) {
        return;
    }
    PROPERTY(may_complete, "the reply changed in a step that cannot complete a service");
    PROPERTY(r.running, "the reply changed with no service running");
    r.completions_seen++;
    r.running = false;
    PROPERTY(r.completions_seen <= r.services_seen, "%u completions for %u services",
             r.completions_seen, r.services_seen);
    const uint8_t *rep = r.ch.reply;
    PROPERTY((rep[0] & ML_MGMT_HANDSHAKE) == (r.running_req[0] & ML_MGMT_HANDSHAKE),
             "the reply does not carry the request's handshake");
    PROPERTY(ml_index(rep) == ml_index(r.running_req), "reply index %u for a request of %u",
             ml_index(rep), ml_index(r.running_req));
    PROPERTY(!r.ch.busy, "a reply while the channel is busy");
}

static void master_request(fz_t *f, uint8_t op)
{
    uint8_t req[ML_TELEGRAM_LEN];
    if ((op & 0x08u) != 0u) {
        memcpy(req, r.last_req, sizeof req);
        req[0] = (uint8_t)((req[0] & ~ML_MGMT_HANDSHAKE) ^ (r.last_hs ^ ML_MGMT_HANDSHAKE));
        req[0] = (uint8_t)((req[0] & 0xC0u) | (fz_u8(f) & 0x3Fu));
        req[2] = fz_u8(f);
        req[3] = fz_u8(f);
        fz_bytes(f, &req[4], 4);
    } else {
        fz_bytes(f, req, sizeof req);
    }
    uint8_t hs = (uint8_t)(req[0] & ML_MGMT_HANDSHAKE);
    if (hs != r.last_hs) {
        r.master_toggles++;
    }
    r.last_hs = hs;
    memcpy(r.last_req, req, sizeof req);
    uint8_t before[ML_TELEGRAM_LEN];
    memcpy(before, r.ch.reply, sizeof before);
    uint32_t s0 = r.ch.services;
    bool was_busy = r.ch.busy;
    uint8_t done_hs = (uint8_t)(r.ch.reply[0] & ML_MGMT_HANDSHAKE);
    uint32_t tag0 = r.next_tag;
    ml_channel_request(&r.ch, req, r.now);
    if (r.ch.services != s0) {
        PROPERTY(!was_busy && hs != done_hs, "a service started without an edge (busy %d)",
                 was_busy);
        PROPERTY(!r.running, "a service started while one runs");
        r.running = true;
        memcpy(r.running_req, req, sizeof req);
        r.running_since = r.now;
        r.running_tag = r.next_tag != tag0 ? r.next_tag : 0u;
        /* answered by the card itself? */
        uint8_t mgmt = req[0];
        uint8_t svc = (uint8_t)(mgmt & ML_MGMT_SERVICE_MASK);
        bool bad = svc > ML_SVC_LAST || (mgmt & ML_MGMT_ERROR) != 0u || req[1] != 0u;
        bool wr = svc == ML_SVC_WRITE || svc == ML_SVC_WRITE_VOLATILE;
        if (bad) {
            PROPERTY(!r.ch.busy && (r.ch.reply[0] & ML_MGMT_ERROR) != 0u && r.ch.reply[4] == 5u &&
                         r.ch.reply[5] == 5u, "wrong management/reserved octet: not class 5 code 5");
        } else if (wr && (mgmt & ML_MGMT_LENGTH_MASK) != ML_MGMT_LENGTH_4) {
            PROPERTY(!r.ch.busy && (r.ch.reply[0] & ML_MGMT_ERROR) != 0u && r.ch.reply[4] == 6u &&
                         r.ch.reply[5] == 8u, "write of another length: not class 6 code 8");
        } else if (svc != ML_SVC_NONE && !r.link.refuse) {
            PROPERTY(r.ch.busy && r.next_tag != tag0, "a service that did not reach the inverter");
        }
    } else {
        /* The channel may defer an edge while the client drains a timed-out service. */
        PROPERTY(was_busy || hs == done_hs || ml_client_busy(&r.client, 0),
                 "an edge (handshake %02X, last reply %02X) while idle started no service", hs,
                 done_hs);
    }
    observe(before, s0, true);
}

static void link_answer(fz_t *f, uint8_t op)
{
    uint8_t c = (uint8_t)(fz_u8(f) % ML_MAX_CHANNELS);
    if (r.link.n_held[c] == 0u) {
        return;
    }
    held_t h = r.link.held[c][0];
    bool keep = (op & 0x20u) != 0u;
    if (!keep) {
        memmove(&r.link.held[c][0], &r.link.held[c][1], (size_t)(r.link.n_held[c] - 1u) * sizeof h);
        r.link.n_held[c]--;
    }
    uint8_t rsp[ML_TELEGRAM_LEN];
    memcpy(rsp, h.req, sizeof rsp);
    switch ((op >> 3) & 3u) {
    case 0:
        if (fz_bool(f)) {
            ml_put_error(rsp, 8u, 0, (uint16_t)(0x10u + fz_u8(f) % 0x11u));
        } else {
            ml_put_data(rsp, fz_u32(f));
        }
        break;
    case 1:
        rsp[3] = (uint8_t)(rsp[3] + 1u + fz_u8(f) % 200u);
        break;
    case 2:
        rsp[0] = (uint8_t)((rsp[0] & 0xF0u) | ((rsp[0] + 1u) & 0x0Fu));
        break;
    default:
        fz_bytes(f, rsp, sizeof rsp);
        break;
    }
    uint8_t before[ML_TELEGRAM_LEN];
    memcpy(before, r.ch.reply, sizeof before);
    uint32_t s0 = r.ch.services;
    bool ch0_running = r.running;
    uint32_t tag_running = r.running_tag;
    r.delivering = true;
    r.delivering_tag = h.tag;
    ml_client_response(&r.client, c, rsp);
    r.delivering = false;
    bool completed0 = ch0_running && !r.ch.busy;
    if (completed0 && known_late_answer) {
        PROPERTY(tag_running == h.tag, "channel 0: request %u completed by the late answer to "
                 "request %u (same service and index)", tag_running, h.tag);
    }
    observe(before, s0, true);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static bool once;
    if (!once) {
        /* On by default since the core fix; FUZZ_KNOWN=none switches it off. */
        /* Strict form opt-in only: see fz_known() in fuzz_link.h. */
        const char *k = getenv("FUZZ_KNOWN");
        known_late_answer = k != NULL && (strcmp(k, "all") == 0 ||
                                          (strcmp(k, "none") != 0 &&
                                           strstr(k, "ml_late_answer") != NULL));
        once = true;
    }
    fz_t f = {data, size, 0};
    memset(&r, 0, sizeof r);
    r.now = fz_u32(&f);
    ml_client_init(&r.client, (ml_link_t){.ops = &link_ops, .ctx = &r.link}, 0);
    ml_channel_init(&r.ch, &r.client, 0);

    while (fz_more(&f)) {
        uint8_t op = fz_u8(&f);
        switch (op & 7u) {
        case 0:
            master_request(&f, op);
            break;
        case 1:
            link_answer(&f, op);
            break;
        case 2: {
            uint32_t dt = (uint32_t)fz_u16(&f) << ((op >> 3) & 7u);
            r.now += dt;
            uint8_t before[ML_TELEGRAM_LEN];
            memcpy(before, r.ch.reply, sizeof before);
            uint32_t s0 = r.ch.services;
            bool run0 = r.running && r.ch.busy;
            hal_time_us_t next = ml_client_poll(&r.client, r.now);
            if (run0 && !r.ch.busy) {
                PROPERTY(hal_time_diff(r.now, r.running_since) >= (int32_t)ML_RESPONSE_TIMEOUT_US,
                         "the cyclic service timed out after %d us",
                         hal_time_diff(r.now, r.running_since));
                PROPERTY(r.ch.reply[4] == ML_CLASS_ACCESS && r.ch.reply[5] == ML_CODE_HARDWARE_FAULT,
                         "a timeout that is not class 6 code 2");
            }
            PROPERTY(hal_time_diff(next, r.now) > 0, "next deadline not in the future");
            observe(before, s0, true);
            break;
        }
        case 3: {
            uint8_t c = (uint8_t)(1u + fz_u8(&f) % (ML_MAX_CHANNELS - 1u));
            user_t *u = &r.user[c];
            uint8_t req[ML_TELEGRAM_LEN];
            fz_bytes(&f, req, sizeof req);
            uint8_t before[ML_TELEGRAM_LEN];
            memcpy(before, r.ch.reply, sizeof before);
            uint32_t s0 = r.ch.services;
            bool busy = u->outstanding;
            if (busy) {
                int rc = ml_client_request(&r.client, c, req, user_done, u, r.now);
                PROPERTY(rc != 0, "a second request accepted on busy channel %u", c);
            } else if (r.client.ch[c].quarantine) {
                /* Draining a timed-out service: the client must refuse, the user retries. */
                int rc = ml_client_request(&r.client, c, req, user_done, u, r.now);
                PROPERTY(rc != 0, "a request accepted on quarantined channel %u", c);
            } else {
                u->outstanding = true; /* may complete at once (link refuses) */
                memcpy(u->req, req, sizeof req);
                u->req[0] &= (uint8_t)~(ML_MGMT_HANDSHAKE | ML_MGMT_ERROR);
                u->started = r.now;
                u->tag = r.next_tag + 1u;
                int rc = ml_client_request(&r.client, c, req, user_done, u, r.now);
                PROPERTY(rc == 0, "a request on idle channel %u refused", c);
            }
            observe(before, s0, false);
            break;
        }
        case 4:
            r.link.refuse = fz_bool(&f);
            break;
        case 5:
            memset(r.link.n_held, 0, sizeof r.link.n_held);
            break;
        default:
            break;
        }
        for (uint8_t c = 0; c < ML_MAX_CHANNELS; c++) {
            if (c > 0u) {
                /* A request in flight is exactly what a user waits for; after a timeout the
                 * channel may stay quarantined (busy to new requests) with nobody waiting. */
                PROPERTY(r.client.ch[c].busy == r.user[c].outstanding,
                         "channel %u: request in flight %d, user waits %d", c,
                         r.client.ch[c].busy, r.user[c].outstanding);
                PROPERTY(!r.client.ch[c].quarantine || !r.client.ch[c].busy,
                         "channel %u: quarantined and in flight at once", c);
            }
        }
        PROPERTY(r.client.ch[0].busy == r.ch.busy, "cyclic channel and client disagree");
    }
    return 0;
}
