/* Soak test: the built-in master (cyclic Data_Exchange with the 8-byte parameter channel, a
 * DP-V1 class-1 client and a class-2 connection) and the card with the emulated MOVIDRIVE on
 * the in-memory bus, in simulated time, with injected faults:
 *
 *   - corrupted characters towards the card (framing error or a flipped bit),
 *   - lost replies (the card's transmit is dropped) and corrupted replies (a flipped bit),
 *   - master restarts (stop + start at once: Set_Prm while the card is in Data_Exch),
 *   - watchdog expiries (the master stops for longer than the 50 ms watchdog),
 *   - DP-V1 aborts (the class-2 connection is aborted and opened again),
 *   - class-2 silence (the connection stays silent past its Send_Timeout; the card closes it).
 *
 * Parameter services run all the time on three paths, each a write-volatile of an IPOS
 * variable with a value that is never reused: H0 through the cyclic channel, H1 through data
 * set 47 on class 1, H2 through data set 47 on class 2. A shim on the card <-> inverter link
 * counts every service the inverter executes. Asserted:
 *
 *   - no stuck state: after every fault the card is back in Data_Exch within 2.5 s;
 *   - no lost or duplicated service: every value is executed at most once; every write the
 *     master saw succeed was executed exactly once; every service completes within 3 s;
 *   - the card's outputs are always either the data of the last Data_Exchange it received
 *     intact from the master, or cleared.
 *
 * SOAK_CYCLES (default 1000000) Data_Exchange cycles; SOAK_SEED. Any duplicated or lost service
 * fails, also on the cyclic channel across Data_Exch exits (the fixed finding "channel_reentry",
 * docs/quality.md); SOAK_STRICT=0 only counts those, for comparing with an older tree.
 * A hanging class-2 connection of the master fails too (check_c2(); the finding c2_abort_stuck is
 * fixed); SOAK_C2_STRICT=0 only counts and repairs it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "rig/rig.h"

#define CARD 4u
#define MASTER 2u
#define C2_MASTER 1u
#define WD_MS 50u
#define MAXV 4000000u /* values per path */
#define STUCK_US 2500000u
#define SERVICE_US 3000000u
#define C2_STUCK_US 3000000u

typedef struct path {
    const char *name;
    uint16_t index;
    uint32_t next_value;      /* last issued value */
    uint8_t *executed;        /* per value: executions at the inverter */
    uint8_t *outcome;         /* 0 issued, 1 succeeded, 2 failed, 3 given up */
    bool running;
    hal_time_us_t started;
    bool left_dx;             /* the card left Data_Exch while this service was pending */
    uint32_t issued, succeeded, failed, given_up;
    uint32_t duplicates, lost, known;
} path_t;

/* The test's own state; the bus, the card and the master are in the rig. */
typedef struct soak {
    sim_station_t card_inner; /* the rig's station of the card, behind the faulty receiver */
    hal_uart_t bus_uart;      /* the bus side of the faulty transmitter */
    dp_master_c2_t c2;
    dp_master_call_t call1, call2;
    dp_master_ds47_req_t req1, req2;
    dp_master_param_t param;
    uint8_t out[14];
    ml_link_t md;  /* the emulated inverter's own link */
    path_t p[3];
    uint64_t rng;
    /* what the card received */
    fdl_rx_t obs;
    uint8_t last_dx[14];
    bool have_dx;
    /* faults */
    uint32_t corrupt_chars, lost_replies, corrupt_replies, restarts, wd_faults, c2_aborts,
        c2_silences;
    bool master_stopped;
    hal_time_us_t master_resume;
    hal_time_us_t c2_pause_until;
    hal_time_us_t c2_ok_at;
    uint32_t c2_stuck;
    bool c2_strict;
    bool c2_silence_pending;
    /* state */
    bool in_dx;
    hal_time_us_t left_dx_at;
    uint32_t dx_entries;
    uint32_t max_recovery_us;
    uint32_t outputs_checks;
    uint64_t wd_expiries;
} soak_t;

static soak_t soak;
static rig_t rig; /* large: keep it off the stack */

static uint32_t rnd(void)
{
    soak.rng ^= soak.rng << 13;
    soak.rng ^= soak.rng >> 7;
    soak.rng ^= soak.rng << 17;
    return (uint32_t)(soak.rng >> 11);
}

static bool chance(uint32_t per_million) { return rnd() % 1000000u < per_million; }

static hal_time_us_t now(void) { return membus_now_us(&rig.bus); }

/* ---- the inverter link shim: counts what the inverter executes -------------------------- */

static int shim_request(void *ctx, uint8_t channel, const uint8_t req[ML_TELEGRAM_LEN])
{
    (void)ctx;
    int rc = soak.md.ops->param_request(soak.md.ctx, channel, req);
    if (rc == 0 && (req[0] & ML_MGMT_SERVICE_MASK) == ML_SVC_WRITE_VOLATILE) {
        uint16_t idx = ml_index(req);
        for (int i = 0; i < 3; i++) {
            path_t *p = &soak.p[i];
            if (idx == p->index) {
                uint32_t v = ml_data(req);
                CHECK(v >= 1u && v <= p->next_value);
                if (v >= 1u && v < MAXV && p->executed[v] < 255u) {
                    p->executed[v]++;
                }
            }
        }
    }
    return rc;
}

static void shim_outputs(void *ctx, const uint16_t *po, uint8_t n)
{
    (void)ctx;
    soak.md.ops->process_outputs(soak.md.ctx, po, n);
}

static void shim_status(void *ctx, const ml_fieldbus_status_t *st)
{
    (void)ctx;
    soak.md.ops->fieldbus_status(soak.md.ctx, st);
}

static const ml_link_ops_t shim_ops = {.param_request = shim_request,
                                       .process_outputs = shim_outputs,
                                       .fieldbus_status = shim_status};

/* ---- the faulty station around the card ------------------------------------------------- */

static void check_outputs(void)
{
    const dp_slave_t *s = &rig.cards[0].cs.card.dp;
    if (s->out_len == 0u || s->sync_mode) {
        return;
    }
    static const uint8_t zeros[sizeof soak.last_dx];
    bool ok = memcmp(s->outputs, zeros, sizeof zeros) == 0 ||
              (soak.have_dx && memcmp(s->outputs, soak.last_dx, sizeof soak.last_dx) == 0);
    soak.outputs_checks++;
    if (!ok) {
        CHECK(ok);
        fprintf(stderr, "    t=%u: the card's outputs are neither the last received nor cleared\n",
                now());
    }
}

static void card_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    (void)ctx;
    if (chance(150)) { /* 1.5e-4 per character */
        soak.corrupt_chars++;
        if (rnd() & 1u) {
            flags |= HAL_UART_RX_FRAMING_ERR;
        } else {
            byte ^= (uint8_t)(1u << (rnd() % 8u));
        }
    }
    bool frame = fdl_rx_char(&soak.obs, byte, flags, t) == FDL_RX_FRAME;
    if (frame) {
        fdl_msg_t m;
        if (fdl_parse(soak.obs.buf, soak.obs.frame_len, &m) == FDL_PARSE_OK && m.da == CARD &&
            m.sa == MASTER && !m.has_dsap && (m.fc & FDL_FC_REQUEST) != 0u &&
            m.data_len == sizeof soak.last_dx) {
            memcpy(soak.last_dx, m.data, sizeof soak.last_dx);
            soak.have_dx = true;
        }
    }
    soak.card_inner.rx_char(soak.card_inner.ctx, byte, flags, t);
    if (frame) {
        check_outputs();
    }
}

static hal_time_us_t card_poll(void *ctx, hal_time_us_t t)
{
    (void)ctx;
    hal_time_us_t next = soak.card_inner.poll(soak.card_inner.ctx, t);
    check_outputs();
    return next;
}

static int faulty_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t nb)
{
    (void)ctx;
    if (chance(2000)) {
        soak.lost_replies++;
        return 0;
    }
    uint8_t copy[FDL_FRAME_MAX];
    memcpy(copy, frame, len);
    if (chance(2000)) {
        soak.corrupt_replies++;
        copy[rnd() % len] ^= (uint8_t)(1u << (rnd() % 8u));
    }
    return soak.bus_uart.ops->transmit(soak.bus_uart.ctx, copy, len, nb);
}

static int faulty_set_baud(void *ctx, uint32_t baud)
{
    (void)ctx;
    return soak.bus_uart.ops->set_baud(soak.bus_uart.ctx, baud);
}

static const hal_uart_ops_t faulty_uart_ops = {.set_baud = faulty_set_baud,
                                               .transmit = faulty_transmit};

/* The rig calls this with the medium's UART of the card: the card transmits through the faults
 * and then the rig's cable onto the bus, as it did into the bus directly before. */
static hal_uart_t wrap_faulty(void *ctx, hal_uart_t inner)
{
    soak.bus_uart = inner;
    return (hal_uart_t){.ops = &faulty_uart_ops, .ctx = ctx};
}

/* The card's station on the bus: card_rx and card_poll corrupt and watch the characters before
 * the rig's own station gets them. */
static sim_station_t wrap_card_station(void *ctx, sim_station_t inner)
{
    soak.card_inner = inner;
    return (sim_station_t){.ctx = ctx, .rx_char = card_rx, .poll = card_poll};
}

static void on_card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    (void)ctx;
    (void)card;
    if (ev->type == DP_EV_WD_EXPIRED) {
        soak.wd_expiries++;
    }
    if (ev->type != DP_EV_STATE) {
        return;
    }
    if (ev->old_state == DP_STATE_DATA_EXCH) {
        soak.in_dx = false;
        soak.left_dx_at = ev->t;
        for (int i = 0; i < 3; i++) {
            if (soak.p[i].running) {
                soak.p[i].left_dx = true;
                soak.p[i].outcome[soak.p[i].next_value] |= 0x10u;
            }
        }
    }
    if (ev->new_state == DP_STATE_DATA_EXCH) {
        uint32_t d = (uint32_t)hal_time_diff(ev->t, soak.left_dx_at);
        if (soak.dx_entries > 0u && d > soak.max_recovery_us) soak.max_recovery_us = d;
        soak.in_dx = true;
        soak.dx_entries++;
    }
}

/* ---- the three parameter paths ---------------------------------------------------------- */

static void finish(path_t *p, bool ok)
{
    p->running = false;
    uint8_t *o = &p->outcome[p->next_value];
    if (ok) {
        *o = (uint8_t)((*o & 0x10u) | 1u);
        p->succeeded++;
    } else {
        *o = (uint8_t)((*o & 0x10u) | 2u);
        p->failed++;
    }
}

static void issue(path_t *p)
{
    p->next_value++;
    p->issued++;
    p->running = true;
    p->left_dx = false;
    p->started = now();
}

static void call_done(void *ctx, dp_master_call_t *call, hal_time_us_t t)
{
    (void)t;
    path_t *p = ctx;
    bool ok = false;
    if (call->ok) {
        dp_master_ds47_rsp_t rsp;
        char err[160];
        const dp_master_ds47_req_t *req = p == &soak.p[1] ? &soak.req1 : &soak.req2;
        ok = dp_master_ds47_parse(req, call->data, call->len, &rsp, err, sizeof err) && rsp.p[0].ok;
    }
    finish(p, ok);
}

static void drive_cyclic(void)
{
    path_t *p = &soak.p[0];
    const uint8_t *in = rig.master.slaves[0].inputs;
    if (p->running && dp_master_param_done(&soak.param, in)) {
        finish(p, (in[0] & ML_MGMT_ERROR) == 0u);
    }
    if (p->running && hal_time_diff(now(), p->started) > (int32_t)SERVICE_US) {
        p->outcome[p->next_value] = (uint8_t)((p->outcome[p->next_value] & 0x10u) | 3u);
        p->given_up++;
        p->running = false;
    }
    if (!p->running) {
        issue(p);
        dp_master_param_start(&soak.param, ML_SVC_WRITE_VOLATILE, p->index, p->next_value,
                              soak.out);
        dp_master_set_outputs(&rig.master, 0, soak.out, sizeof soak.out);
    }
}

static void drive_ds47(path_t *p, dp_master_call_t *call, dp_master_ds47_req_t *req,
                       dp_master_acyc_port_t port)
{
    if (p->running && hal_time_diff(now(), p->started) > (int32_t)(2u * SERVICE_US)) {
        /* the call's own time limit (5 s) ends it first; this only guards against a hang */
        CHECK(!"a data set 47 call did not end");
        p->running = false;
    }
    if (p->running) {
        return;
    }
    /* Request Reference 1..255: 0 is refused as a header error (B7). */
    *req = (dp_master_ds47_req_t){.ref = (uint8_t)(1u + p->next_value % 255u),
                            .id = DS47_ID_MOVILINK, .n = 1};
    req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_WRITE_VOLATILE,
                                   .number = p->index, .value = p->next_value + 1u};
    if (dp_master_ds47_start(call, port, req, call_done, p, now()) == 0) {
        issue(p);
    }
}

/* The master's class-2 connection must not hang: once it left OPEN it is open again (or at
 * least trying) within C2_STUCK_US, unless the test keeps it silent. Known finding
 * "c2_abort_stuck" (docs/quality.md): dp_master_stop()/dp_master_start() drop a class-2
 * telegram on the wire without telling the connection, whose on_wire stays set; a later
 * dp_master_c2_abort() then waits for that answer for ever in DP_MASTER_C2_ABORTING. Counted,
 * printed and repaired here (the connection is initialised again); fatal with SOAK_C2_STRICT=1. */
static void check_c2(hal_time_us_t t)
{
    dp_master_c2_state_t st = dp_master_c2_state(&soak.c2);
    if (st == DP_MASTER_C2_OPEN || soak.master_stopped ||
        hal_time_diff(t, soak.c2_pause_until) < 0) {
        soak.c2_ok_at = t;
        return;
    }
    if (hal_time_diff(t, soak.c2_ok_at) <= (int32_t)C2_STUCK_US) {
        return;
    }
    soak.c2_stuck++;
    if (soak.c2_strict) {
        CHECK(!"the master's class-2 connection is stuck");
    }
    fprintf(stderr, "    t=%u: class-2 connection %s for %d ms (%s; on_wire %d, abort_pending %d, "
            "master waiting %d)%s\n", t, dp_master_c2_state_name(st),
            hal_time_diff(t, soak.c2_ok_at) / 1000, dp_master_c2_error(&soak.c2), soak.c2.on_wire,
            soak.c2.abort_pending,
            rig.master.waiting && rig.master.waiting_kind == DP_MASTER_WAIT_C2,
            soak.c2_strict ? "" : ": known finding c2_abort_stuck, connection re-initialised");
    if (!soak.c2.on_wire || rig.master.waiting_kind != DP_MASTER_WAIT_C2 || !rig.master.waiting) {
        dp_master_c2_cfg_t cfg = soak.c2.cfg;
        dp_master_c2_init(&soak.c2, &cfg);
    }
    soak.c2_ok_at = t;
}

static void drive_c2(void)
{
    hal_time_us_t t = now();
    check_c2(t);
    if (hal_time_diff(t, soak.c2_pause_until) < 0) {
        return; /* silent */
    }
    dp_master_c2_state_t st = dp_master_c2_state(&soak.c2);
    if (st == DP_MASTER_C2_CLOSED) {
        (void)dp_master_c2_open(&soak.c2, NULL, NULL, t);
        return;
    }
    if (st != DP_MASTER_C2_OPEN) {
        return;
    }
    if (chance(700)) { /* about every 1.4 s; a running call fails */
        if (dp_master_c2_abort(&soak.c2, 0, NULL, NULL, t) == 0) soak.c2_aborts++;
        return;
    }
    if (chance(150)) { /* about every 7 s: silence past Send_Timeout once the call ended */
        soak.c2_silence_pending = true;
    }
    if (soak.c2_silence_pending && !soak.p[2].running) {
        soak.c2_silence_pending = false;
        soak.c2_silences++;
        soak.c2_pause_until = t + 300000u;
        return;
    }
    drive_ds47(&soak.p[2], &soak.call2, &soak.req2, dp_master_c2_port(&soak.c2));
}

static void faults(void)
{
    hal_time_us_t t = now();
    if (soak.master_stopped) {
        if (hal_time_diff(t, soak.master_resume) >= 0) {
            dp_master_start(&rig.master, t);
            membus_wake(rig.master_port);
            soak.master_stopped = false;
        }
        return;
    }
    if (chance(500)) { /* about every 2 s: restart at once */
        soak.restarts++;
        dp_master_stop(&rig.master);
        dp_master_start(&rig.master, t);
        membus_wake(rig.master_port);
    } else if (chance(200)) { /* about every 5 s: silent past the watchdog */
        soak.wd_faults++;
        dp_master_stop(&rig.master);
        soak.master_stopped = true;
        soak.master_resume = t + 2u * WD_MS * 1000u + rnd() % 100000u;
    }
}

static void check_not_stuck(void)
{
    if (!soak.in_dx && !soak.master_stopped &&
        hal_time_diff(now(), soak.left_dx_at) > (int32_t)STUCK_US) {
        CHECK(!"the card is stuck outside Data_Exch");
        fprintf(stderr, "    t=%u: state %s since %u\n", now(),
                dp_state_name(dp_slave_state(&rig.cards[0].cs.card.dp)), soak.left_dx_at);
        soak.left_dx_at = now(); /* report once per bound */
    }
}

/* ---- set-up and the run ----------------------------------------------------------------- */

static void setup(uint64_t seed)
{
    memset(&soak, 0, sizeof soak);
    soak.rng = seed;
    static const uint16_t idx[3] = {11000, 11001, 11002};
    static const char *const names[3] = {"cyclic channel (H0)", "data set 47 class 1 (H1)",
                                         "data set 47 class 2 (H2)"};
    for (int i = 0; i < 3; i++) {
        soak.p[i].name = names[i];
        soak.p[i].index = idx[i];
        soak.p[i].executed = calloc(MAXV, 1);
        soak.p[i].outcome = calloc(MAXV, 1);
    }
    /* Card first, then master: the order the bus polls them in, which the figures rest on. */
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .wrap_card_uart = wrap_faulty,
                    .wrap_card_station = wrap_card_station, .wrap_ctx = &soak};
    rig_init(&rig, &rc);
    rig_tap_t tap = {.ctx = &soak, .card_event = on_card_event};
    (void)rig_add_tap(&rig, &tap);
    card_options_t co = {.address = CARD, .fixed_baud = 1500000, .strict_timing = true,
                         .inverter = CARD_INVERTER_SIM, .inverter_delay_us = 2000};
    char err[256] = "no room for the card on the bus"; /* rig_open overwrites it on failure */
    rig_card_t *card = rig_open(&rig, err, sizeof err) == 0 ? rig_add_card(&rig, &co, now()) : NULL;
    /* The note is empty unless card_station_init failed. */
    CHECK_STR(card != NULL ? card->nvm_note : err, "");
    if (card == NULL) {
        exit(check_report()); /* nothing to soak */
    }
    /* put the counting shim between the card and the emulated inverter */
    soak.md = card->cs.card.cfg.inverter;
    ml_link_t shim = {.ops = &shim_ops, .ctx = NULL};
    card->cs.card.cfg.inverter = shim;
    card->cs.card.ml.link = shim;
    fdl_rx_init(&soak.obs, 1500000, true);

    dp_master_cfg_t mc = {.address = MASTER, .baud = 1500000, .strict_timing = true,
                          .cycle_us = 1000};
    (void)rig_add_master(&rig, &mc, now());
    dp_master_slave_cfg_t sc = {.address = CARD};
    sc.prm_len =
        (uint8_t)dp_master_build_prm_dpv1(sc.prm, DFP21B_IDENT, WD_MS, dfp21b_user_prm_default,
                                          sizeof dfp21b_user_prm_default);
    sc.cfg[0] = 0xF3;
    sc.cfg[1] = 0xF2;
    sc.cfg_len = 2;
    CHECK_EQ(dp_master_add_slave(&rig.master, &sc), 0);
    dp_master_c2_cfg_t c2c = {.slave = CARD, .address = C2_MASTER, .send_timeout = 10 /* 100 ms */};
    dp_master_c2_init(&soak.c2, &c2c);
    CHECK_EQ(dp_master_add_c2(&rig.master, &soak.c2), 0);
    membus_run_for_us(&rig.bus, 30000);
    CHECK_EQ(rig.master.slaves[0].phase, DP_MASTER_PHASE_DATA_EXCH);
}

static void verify(path_t *p, bool strict)
{
    for (uint32_t v = 1; v <= p->next_value && v < MAXV; v++) {
        uint8_t n = p->executed[v];
        bool left_dx = (p->outcome[v] & 0x10u) != 0u;
        uint8_t o = (uint8_t)(p->outcome[v] & 0x0Fu);
        bool dup = n > 1u;
        bool lost = (o == 1u && n == 0u) || o == 3u;
        if (!dup && !lost) continue;
        /* a cyclic service pending while the card left Data_Exch: known finding */
        bool known = p == &soak.p[0] && left_dx;
        if (dup) p->duplicates++;
        if (lost) p->lost++;
        if (known && !strict) {
            p->known++;
            continue;
        }
        CHECK(!dup && !lost);
        fprintf(stderr, "    %s: value %u executed %u times, outcome %u\n", p->name, v, n, o);
    }
    printf("  %-26s issued %7u  succeeded %7u  failed %5u  given up %3u  duplicated %3u  "
           "lost %3u%s\n", p->name, p->issued, p->succeeded, p->failed, p->given_up,
           p->duplicates, p->lost, p->known ? "  (known finding channel_reentry)" : "");
}

int main(void)
{
    const char *e = getenv("SOAK_CYCLES");
    uint32_t cycles = e != NULL ? (uint32_t)strtoul(e, NULL, 10) : 1000000u;
    e = getenv("SOAK_SEED");
    uint64_t seed = e != NULL ? strtoull(e, NULL, 10) : 0x5EED0001u;
    e = getenv("SOAK_STRICT");
    bool strict = e == NULL || e[0] != '0';
    e = getenv("SOAK_C2_STRICT");
    bool c2_strict = e == NULL || e[0] != '0'; /* fixed in dp_master_start(): strict */
    check_test_name_ = "soak";
    setup(seed);
    soak.c2_strict = c2_strict;
    uint64_t t0 = rig.bus.now_ns;
    while (rig.master.slaves[0].cycles < cycles) {
        faults();
        drive_cyclic();
        drive_ds47(&soak.p[1], &soak.call1, &soak.req1, dp_master_c1_port(&rig.master, 0));
        drive_c2();
        membus_run_for_us(&rig.bus, 1000);
        check_not_stuck();
        if (check_failed_ > 20) break;
    }
    double sim_s = (double)(rig.bus.now_ns - t0) / 1e9;
    printf("soak: %u Data_Exchange cycles in %.1f s of simulated time, %llu telegrams, seed %llu\n",
           rig.master.slaves[0].cycles, sim_s, (unsigned long long)rig.bus.frames_sent,
           (unsigned long long)seed);
    printf("  faults: %u corrupted characters, %u lost and %u corrupted replies, %u master "
           "restarts, %u master silences (%llu watchdog expiries), %u C2 aborts, %u C2 "
           "silences\n", soak.corrupt_chars, soak.lost_replies, soak.corrupt_replies, soak.restarts,
           soak.wd_faults, (unsigned long long)soak.wd_expiries, soak.c2_aborts, soak.c2_silences);
    printf("  class-2 connection stuck %u times (known finding c2_abort_stuck)\n", soak.c2_stuck);
    printf("  Data_Exch entered %u times, longest recovery %.1f ms, %u output checks\n",
           soak.dx_entries, soak.max_recovery_us / 1000.0, soak.outputs_checks);
    for (int i = 0; i < 3; i++) {
        verify(&soak.p[i], strict);
        CHECK(soak.p[i].succeeded > 0u);
    }
    CHECK(soak.restarts > 0u && soak.wd_faults > 0u && soak.c2_aborts > 0u &&
          soak.lost_replies > 0u && soak.c2_silences > 0u);
    printf("  wall-clock: see ctest; simulated %.0f cycles/s of bus time\n",
           rig.master.slaves[0].cycles / sim_s);
    return check_report();
}
