#include "replay/generator.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "rig/rig.h"
#include "sim_hal/membus.h"

#define GEN_DEFAULT_BAUD 1500000u
#define GEN_WATCHDOG_MS 100u
#define GEN_CYCLE_US 2000u
#define GEN_FOREIGN_CYCLE_US 4000u /* room for the second master's turn between cycles */
#define GEN_STEP_US 500u
#define GEN_FOREIGN_EVERY 10u      /* cycles between the second master's turns */
#define GEN_DS47_EVERY 20u         /* cycles between class-1 data set 47 calls */
#define GEN_OUT_LEN 14u            /* Param + 3 PD: the channel's 8 octets and PO1..PO3 */
#define GEN_PARAM_GIVE_UP 500u     /* cycles after which a channel service counts as lost */
#define GEN_FOREIGN_STEPS 5u

/* ---- the second master (--foreign) ------------------------------------------------------- */

/* A scripted master: when the class-1 master has the line quiet for long enough, it plays one
 * "token turn": takes the token from master 2, asks a free address for its FDL status (nobody
 * answers), asks the card for its FDL status and its diagnosis (the card answers), and hands the
 * token back. It watches the class-1 master's next poll time on the bus, so it never collides. */
typedef struct foreign {
    hal_uart_t uart;
    membus_t *bus;
    dp_master_t *master;
    membus_port_t *master_port;
    uint32_t baud;
    uint8_t card;
    uint8_t free_address;
    bool wanted;
    int step; /* -1: not playing */
    hal_time_us_t next; /* when the next step is due */
    bool diag_first;
    bool diag_fcb;
    uint32_t bursts;
} foreign_t;

typedef struct foreign_step {
    uint8_t frame[32];
    size_t len;
    uint32_t wait_bits; /* after the telegram: the answer, if any, and the idle before the next */
} foreign_step_t;

static foreign_step_t foreign_build(foreign_t *f, unsigned step)
{
    foreign_step_t s = {.len = 0};
    const uint8_t me = GEN_FOREIGN_MASTER_ADDRESS;
    switch (step) {
    case 0: /* master 2 passes the token to master 3 */
        s.frame[0] = 0xDC;
        s.frame[1] = me;
        s.frame[2] = GEN_MASTER_ADDRESS;
        s.len = 3;
        s.wait_bits = 50;
        break;
    case 1: /* a GAP update: is anybody at the free address? */
        s.len = fdl_encode(s.frame, f->free_address, me, FDL_FC_REQUEST | FDL_REQ_FDL_STATUS,
                           false, 0, 0, NULL, 0);
        s.wait_bits = 150;
        break;
    case 2:
        s.len = fdl_encode(s.frame, f->card, me, FDL_FC_REQUEST | FDL_REQ_FDL_STATUS, false, 0,
                           0, NULL, 0);
        s.wait_bits = 300;
        break;
    case 3: { /* a class-2 style diagnosis read, with its own FCB sequence */
        uint8_t fc = FDL_FC_REQUEST | FDL_REQ_SRD_HIGH;
        if (f->diag_first) {
            fc |= FDL_FC_FCB;
            f->diag_first = false;
            f->diag_fcb = true;
        } else {
            f->diag_fcb = !f->diag_fcb;
            fc |= (uint8_t)(FDL_FC_FCV | (f->diag_fcb ? FDL_FC_FCB : 0u));
        }
        s.len = fdl_encode(s.frame, f->card, me, fc, true, DP_SAP_SLAVE_DIAG, DP_SAP_MASTER, NULL,
                           0);
        s.wait_bits = 400;
        break;
    }
    default: /* the token back to master 2 */
        s.frame[0] = 0xDC;
        s.frame[1] = GEN_MASTER_ADDRESS;
        s.frame[2] = me;
        s.len = 3;
        s.wait_bits = 50;
        break;
    }
    return s;
}

static uint64_t foreign_turn_ns(foreign_t *f)
{
    uint64_t bits = 0;
    foreign_t copy = *f; /* building step 3 moves the FCB: work on a copy */
    for (unsigned i = 0; i < GEN_FOREIGN_STEPS; i++) {
        foreign_step_t s = foreign_build(&copy, i);
        bits += s.len * 11u + s.wait_bits;
    }
    return bits * 1000000000ull / f->baud;
}

static void foreign_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    (void)ctx;
    (void)byte;
    (void)flags;
    (void)t;
}

static hal_time_us_t foreign_poll(void *ctx, hal_time_us_t now)
{
    foreign_t *f = ctx;
    if (f->step < 0) {
        if (!f->wanted) {
            return now + HAL_TIME_NO_DEADLINE_US; /* polled again after the next telegram */
        }
        /* The master was polled before us in this round: its deadline is when it acts next
         * (right after a reply that is its idle time, then the next slave's turn). Look
         * again shortly until the gap is long enough. */
        uint64_t quiet_until = f->master_port->deadline_ns;
        if (f->master->waiting || f->master->gc_pending ||
            quiet_until < f->bus->now_ns + foreign_turn_ns(f) + 100000u) {
            return now + 20u;
        }
        f->step = 0;
        f->next = now;
    }
    /* Polled after every telegram on the bus, including the answers it waits for. */
    if (!hal_time_reached(now, f->next)) {
        return f->next;
    }
    foreign_step_t s = foreign_build(f, (unsigned)f->step);
    (void)f->uart.ops->transmit(f->uart.ctx, s.frame, s.len, now);
    uint64_t bits = s.len * 11u + s.wait_bits;
    f->step++;
    if (f->step >= (int)GEN_FOREIGN_STEPS) {
        f->step = -1;
        f->wanted = false;
        f->bursts++;
    }
    f->next = now + hal_uart_bits_us(f->baud, (uint32_t)bits);
    return f->next;
}

/* ---- the run ------------------------------------------------------------------------------ */

/* One run: the rig (the bus, both cards, the master) with the script's state. Large: gen_run
 * keeps it on the heap. */
typedef struct gen {
    gen_options_t opt;
    gen_result_t *res;
    rig_t rig;
    dp_master_t *master;
    membus_port_t *foreign_port;
    foreign_t foreign;
    cap_writer_t w;
    bool write_failed;
    /* cyclic channel */
    dp_master_param_t pc;
    bool pc_synced;
    uint32_t pc_next_cycle;
    uint32_t pc_started_cycle;
    unsigned pc_step;
    uint8_t out[GEN_OUT_LEN];
    /* DP-V1 */
    dp_master_call_t call;
    bool call_running;
    dp_master_ds47_req_t req;
    unsigned ds47_step;
    uint32_t ds47_next_cycle;
    dp_master_c2_t c2;
    int c2_stage; /* 0 not yet, 1 opening, 2 call running, 3 aborting, 4 done */
    dp_master_call_t c2_call;
    bool c2_open_done;
    bool c2_open_ok;
    bool c2_abort_done;
    /* faults */
    int fault_stage;
    uint64_t fault_until_ns;
    uint32_t wd_seen;
    uint32_t foreign_cycle; /* the cycle of the last turn asked for */
} gen_t;

static void gen_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len, bool local,
                    uint32_t baud)
{
    gen_t *g = ctx;
    (void)local;
    (void)baud;
    if (cap_writer_frame(&g->w, t_start_ns, frame, len, CAP_DIR_UNKNOWN) != 0) {
        g->write_failed = true;
    }
    g->res->telegrams++;
    g->res->octets += len;
}

/* Watchdog expiries of the card under test (the second card's are not counted). */
static void card_event(void *ctx, unsigned card, const dp_event_t *ev)
{
    gen_t *g = ctx;
    if (card == 0u && ev->type == DP_EV_WD_EXPIRED) {
        g->wd_seen++;
    }
}

static uint64_t bus_ns(const gen_t *g)
{
    return g->rig.bus.now_ns;
}

static hal_time_us_t now_us(const gen_t *g)
{
    return membus_now_us(&g->rig.bus);
}

static void wake_master(gen_t *g)
{
    membus_wake(g->rig.master_port);
}

static dp_master_slave_t *card_slave(gen_t *g)
{
    return &g->master->slaves[0];
}

static void slave_cfg(const gen_t *g, dp_master_slave_cfg_t *sc, uint8_t address,
                      const uint8_t *cfg, size_t len)
{
    memset(sc, 0, sizeof *sc);
    sc->address = address;
    if (g->opt.dpv1) {
        sc->prm_len = (uint8_t)dp_master_build_prm_dpv1(sc->prm, DFP21B_IDENT, GEN_WATCHDOG_MS,
                                                  dfp21b_user_prm_default,
                                                  sizeof dfp21b_user_prm_default);
    } else {
        sc->prm_len = (uint8_t)dp_master_build_prm(sc->prm, DFP21B_IDENT, GEN_WATCHDOG_MS,
                                             dfp21b_user_prm_default,
                                             sizeof dfp21b_user_prm_default);
    }
    memcpy(sc->cfg, cfg, len);
    sc->cfg_len = (uint8_t)len;
}

static const uint8_t cfg_param_3pd[] = {0xF3, 0xF2};
static const uint8_t cfg_wrong[] = {0xF3, 0xE2, 0xD1}; /* 3 PD out, 2 PD in: refused */

/* Step k of the channel's round of ten services. */
typedef struct pc_service {
    uint8_t svc;
    uint16_t index;
    uint32_t value;
} pc_service_t;

/* The cyclic channel's round: commissioning first (P100/P101 to FIELDBUS so the drive follows
 * PO2), then reads, writes, a volatile write and one the inverter refuses. */
static pc_service_t pc_round(unsigned step)
{
    uint32_t k = step / 10u;
    switch (step % 10u) {
    case 0: return (pc_service_t){ML_SVC_READ, 8300, 0};                    /* firmware */
    case 1: return (pc_service_t){ML_SVC_WRITE, 8461, 3};                   /* P100 FIELDBUS */
    case 2: return (pc_service_t){ML_SVC_WRITE, 8462, 2};                   /* P101 FIELDBUS */
    case 3: return (pc_service_t){ML_SVC_READ, 8318, 0};                    /* speed */
    case 4: return (pc_service_t){ML_SVC_WRITE, 8489, 1000u + k};           /* P160 */
    case 5: return (pc_service_t){ML_SVC_READ, 8489, 0};
    case 6: return (pc_service_t){ML_SVC_WRITE_VOLATILE, 11000, k};         /* IPOS H0 */
    case 7: return (pc_service_t){ML_SVC_READ, 11000, 0};
    case 8: return (pc_service_t){ML_SVC_WRITE_VOLATILE, 8517, 99000000u};  /* too high */
    default: return (pc_service_t){ML_SVC_READ_MIN, 8489, 0};
    }
}

/* The service in progress: counted when answered, given up when lost. */
static void pc_watch(gen_t *g, const dp_master_slave_t *s)
{
    if (dp_master_param_done(&g->pc, s->inputs)) {
        g->res->param_services++;
        if ((s->inputs[0] & ML_MGMT_ERROR) != 0u) {
            g->res->param_errors++;
        }
        g->pc_next_cycle = s->cycles + g->opt.param_every;
    } else if (s->cycles - g->pc_started_cycle > GEN_PARAM_GIVE_UP) {
        g->pc.busy = false;
        g->pc_synced = false;
    }
}

/* The card's outputs on the wire: the PLC's image, or zeros while the master is in Clear (what a
 * class-1 master sends a slave without Fail_Safe then; the image is kept for Operate). */
static void put_outputs(gen_t *g)
{
    static const uint8_t clear[GEN_OUT_LEN];
    dp_master_set_outputs(g->master, 0, g->fault_stage == 3 ? clear : g->out, sizeof g->out);
}

static void param_channel(gen_t *g)
{
    dp_master_slave_t *s = card_slave(g);
    if (g->opt.param_every == 0u || s->phase != DP_MASTER_PHASE_DATA_EXCH || s->inputs_len < 8u) {
        g->pc_synced = false;
        return;
    }
    if (!g->pc_synced) {
        /* The card keeps its handshake across start-ups: continue from what it shows. */
        if (((s->inputs[0] ^ g->out[0]) & ML_MGMT_HANDSHAKE) != 0u && g->pc.busy) {
            return;
        }
        dp_master_param_sync(&g->pc, s->inputs);
        g->pc_synced = true;
        g->pc_next_cycle = s->cycles + g->opt.param_every;
    }
    if (g->pc.busy) {
        pc_watch(g, s);
        return;
    }
    if (s->cycles < g->pc_next_cycle) {
        return;
    }
    pc_service_t p = pc_round(g->pc_step);
    g->pc_step++;
    dp_master_param_start(&g->pc, p.svc, p.index, p.value, g->out);
    put_outputs(g);
    g->pc_started_cycle = s->cycles;
}

static void ds47_done(void *ctx, dp_master_call_t *call, hal_time_us_t now)
{
    gen_t *g = ctx;
    (void)call;
    (void)now;
    g->call_running = false;
    g->res->ds47_calls++;
}

/* Step k of the class-1 round of six: data set 47 requests (one the inverter refuses), then
 * I&M0 (step 5: the request stays empty). */
static void ds47_round(dp_master_ds47_req_t *req, unsigned step)
{
    uint32_t k = step / 6u;
    memset(req, 0, sizeof *req);
    req->ref = (uint8_t)(1u + step % 255u);
    req->n = 1;
    switch (step % 6u) {
    case 0:
        req->id = DS47_ID_MOVILINK;
        req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 8300};
        break;
    case 1:
        req->id = DS47_ID_REQUEST;
        req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8489};
        break;
    case 2:
        req->id = DS47_ID_MOVILINK;
        req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_WRITE_VOLATILE,
                                       .number = 11000, .value = 500u + k};
        break;
    case 3:
        req->id = DS47_ID_CHANGE;
        req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_VALUE, .number = 8489,
                                       .value = 2000u + k};
        break;
    case 4: /* a parameter that does not exist: a negative data set 47 response */
        req->id = DS47_ID_MOVILINK;
        req->p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 1};
        break;
    default:
        break;
    }
}

static void dpv1_class1(gen_t *g)
{
    dp_master_slave_t *s = card_slave(g);
    if (!g->opt.dpv1 || g->call_running || s->phase != DP_MASTER_PHASE_DATA_EXCH ||
        s->cycles < g->ds47_next_cycle || dp_master_c1_busy(g->master, 0)) {
        return;
    }
    g->ds47_next_cycle = s->cycles + GEN_DS47_EVERY;
    memset(&g->call, 0, sizeof g->call);
    ds47_round(&g->req, g->ds47_step);
    int rc;
    if (g->ds47_step % 6u == 5u) {
        rc =
            dp_master_im0_start(&g->call, dp_master_c1_port(g->master, 0), ds47_done, g, now_us(g));
    } else {
        rc = dp_master_ds47_start(&g->call, dp_master_c1_port(g->master, 0), &g->req, ds47_done, g,
                            now_us(g));
    }
    g->ds47_step++;
    if (rc == 0) {
        g->call_running = true;
        wake_master(g);
    }
}

static void c2_opened(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    gen_t *g = ctx;
    (void)now;
    g->c2_open_done = true;
    g->c2_open_ok = r->ok;
}

static void c2_aborted(void *ctx, const dp_master_acyc_result_t *r, hal_time_us_t now)
{
    gen_t *g = ctx;
    (void)r;
    (void)now;
    g->c2_abort_done = true;
}

/* The connection is open: its one data set 47 read. Returns the next stage. */
static int c2_read(gen_t *g)
{
    if (!g->c2_open_ok) {
        return 4;
    }
    g->res->c2_connections++;
    memset(&g->c2_call, 0, sizeof g->c2_call);
    dp_master_ds47_req_t q = {.ref = 0x42, .id = DS47_ID_MOVILINK, .n = 1};
    q.p[0] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 8300};
    if (dp_master_ds47_start(&g->c2_call, dp_master_c2_port(&g->c2), &q, NULL, NULL,
                             now_us(g)) != 0) {
        return 4;
    }
    wake_master(g);
    return 2;
}

/* One class-2 connection in the middle of the run: Initiate, a data set 47 read, Abort. */
static void dpv1_class2(gen_t *g)
{
    dp_master_slave_t *s = card_slave(g);
    switch (g->c2_stage) {
    case 0:
        if (g->opt.dpv1 && s->cycles >= g->opt.cycles / 3u &&
            s->phase == DP_MASTER_PHASE_DATA_EXCH &&
            dp_master_c2_open(&g->c2, c2_opened, g, now_us(g)) == 0) {
            g->c2_stage = 1;
            wake_master(g);
        }
        return;
    case 1:
        if (g->c2_open_done) {
            g->c2_stage = c2_read(g);
        }
        return;
    case 2:
        if (!dp_master_call_done(&g->c2_call)) return;
        g->res->ds47_calls++;
        if (dp_master_c2_abort(&g->c2, 0, c2_aborted, g, now_us(g)) != 0) {
            g->c2_stage = 4;
            return;
        }
        g->c2_stage = 3;
        wake_master(g);
        return;
    case 3:
        if (g->c2_abort_done || dp_master_c2_state(&g->c2) == DP_MASTER_C2_CLOSED) g->c2_stage = 4;
        return;
    default:
        return;
    }
}

static bool c2_busy(const gen_t *g)
{
    return g->c2_stage == 1 || g->c2_stage == 2 || g->c2_stage == 3;
}

static void reconfigure(gen_t *g, const uint8_t *cfg, size_t len)
{
    dp_master_slave_cfg_t sc;
    slave_cfg(g, &sc, g->opt.address, cfg, len);
    dp_master_reconfigure(g->master, 0, &sc, now_us(g));
    wake_master(g);
}

/* The master falls silent until the card's watchdog expired, then starts again. */
static void fault_silence(gen_t *g, const dp_master_slave_t *s)
{
    if (g->fault_stage == 0) {
        if (s->cycles >= g->opt.cycles / 3u && !g->master->waiting && !g->call_running &&
            !c2_busy(g) && g->foreign.step < 0) {
            dp_master_stop(g->master);
            g->fault_until_ns = bus_ns(g) + 3ull * GEN_WATCHDOG_MS * 1000000ull;
            g->fault_stage = 1;
        }
    } else if (bus_ns(g) >= g->fault_until_ns) {
        dp_master_start(g->master, now_us(g));
        wake_master(g);
        g->res->restarts++;
        g->fault_stage = 2;
    }
}

/* Global_Control Clear_Data, 20 ms in Clear (zero outputs), then Operate. */
static void fault_clear_data(gen_t *g, const dp_master_slave_t *s)
{
    if (g->fault_stage == 2) {
        if (s->cycles >= g->opt.cycles / 2u && s->phase == DP_MASTER_PHASE_DATA_EXCH) {
            dp_master_global_control(g->master, DP_GC_CLEAR_DATA, 0);
            g->fault_stage = 3;
            put_outputs(g);
            wake_master(g);
            g->fault_until_ns = bus_ns(g) + 20000000ull;
        }
    } else if (bus_ns(g) >= g->fault_until_ns) {
        dp_master_global_control(g->master, 0x00, 0);
        g->fault_stage = 4;
        put_outputs(g);
        wake_master(g);
    }
}

/* A configuration the card refuses, then the right one again. */
static void fault_wrong_cfg(gen_t *g, const dp_master_slave_t *s)
{
    if (g->fault_stage == 4) {
        if (s->cycles >= 2u * g->opt.cycles / 3u && !g->master->waiting && !g->call_running) {
            reconfigure(g, cfg_wrong, sizeof cfg_wrong);
            g->fault_until_ns = bus_ns(g) + 100000000ull;
            g->fault_stage = 5;
        }
    } else if (bus_ns(g) >= g->fault_until_ns && !g->master->waiting) {
        reconfigure(g, cfg_param_3pd, sizeof cfg_param_3pd);
        g->res->restarts += 2u;
        g->fault_stage = 6;
    }
}

/* --faults: at a third of the run the master falls silent until the card's watchdog expired, at
 * half Global_Control Clear_Data then Operate, at two thirds a configuration the card refuses,
 * then the right one again. */
static void faults(gen_t *g)
{
    if (!g->opt.faults) return;
    const dp_master_slave_t *s = card_slave(g);
    switch (g->fault_stage) {
    case 0:
    case 1:
        fault_silence(g, s);
        return;
    case 2:
    case 3:
        fault_clear_data(g, s);
        return;
    case 4:
    case 5:
        fault_wrong_cfg(g, s);
        return;
    default:
        return;
    }
}

static bool quiet(const gen_t *g)
{
    return !g->master->waiting && !g->master->gc_pending && g->foreign.step < 0;
}

/* The second master, attached after the built-in one: in each round the master is polled first,
 * so its deadline is current when the second master looks at it. */
static void attach_foreign(gen_t *g)
{
    foreign_t *f = &g->foreign;
    sim_station_t fs = {.ctx = f, .rx_char = foreign_rx, .poll = foreign_poll};
    g->foreign_port = rig_attach_station(&g->rig, &fs, &f->uart);
    (void)f->uart.ops->set_baud(f->uart.ctx, g->opt.baud);
    f->bus = &g->rig.bus;
    f->master = g->master;
    f->master_port = g->rig.master_port;
    f->baud = g->opt.baud;
    f->card = g->opt.address;
    f->free_address = (uint8_t)(g->opt.address + 10u);
    f->diag_first = true;
}

/* The card (and with --foreign a second one at address + 1), then the master serving them. The
 * order of the stations on the bus decides who is polled first: it must stay as it is for the
 * goldens to stay byte-identical. */
static int assemble(gen_t *g, char *err, size_t errlen)
{
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .baud = g->opt.baud};
    rig_init(&g->rig, &rc);
    rig_tap_t tap = {.ctx = g, .frame = gen_tap, .card_event = card_event};
    (void)rig_add_tap(&g->rig, &tap);
    if (rig_open(&g->rig, err, errlen) != 0) {
        return -1;
    }
    card_options_t co = {.address = g->opt.address, .strict_timing = true,
                         .inverter = g->opt.inverter,
                         .inverter_delay_us = g->opt.inverter_delay_us};
    (void)rig_add_card(&g->rig, &co, 0);
    if (g->opt.foreign) {
        card_options_t co2 = {.address = (uint8_t)(g->opt.address + 1u), .strict_timing = true,
                              .inverter = CARD_INVERTER_NONE};
        (void)rig_add_card(&g->rig, &co2, 0);
    }
    dp_master_cfg_t mc = {.address = GEN_MASTER_ADDRESS, .baud = g->opt.baud,
                          .strict_timing = true,
                          .cycle_us = g->opt.foreign ? GEN_FOREIGN_CYCLE_US : GEN_CYCLE_US};
    g->master = rig_add_master(&g->rig, &mc, 0);
    g->foreign.step = -1;
    if (g->opt.foreign) {
        attach_foreign(g);
    }
    return 0;
}

/* The master's slaves and its DP-V1 class-2 side; the card's outputs ask for enable and 300 rpm
 * (the drive follows once P100/P101 say FIELDBUS). */
static void configure_master(gen_t *g)
{
    dp_master_slave_cfg_t sc;
    slave_cfg(g, &sc, g->opt.address, cfg_param_3pd, sizeof cfg_param_3pd);
    dp_master_add_slave(g->master, &sc);
    if (g->opt.foreign) {
        slave_cfg(g, &sc, (uint8_t)(g->opt.address + 1u), (const uint8_t[]){0xF2}, 1);
        dp_master_add_slave(g->master, &sc);
    }
    if (g->opt.dpv1) {
        dp_master_c2_cfg_t cc = {.slave = g->opt.address, .address = 1};
        dp_master_c2_init(&g->c2, &cc);
        dp_master_add_c2(g->master, &g->c2);
    }
    g->out[8] = 0x00;
    g->out[9] = 0x06;
    g->out[10] = 0x05;
    g->out[11] = 0xDC;
    dp_master_set_outputs(g->master, 0, g->out, sizeof g->out);
}

static bool finished(gen_t *g)
{
    const dp_master_slave_t *s = card_slave(g);
    bool dpv1_busy = g->opt.dpv1 && (g->call_running || g->c2_stage == 2 || g->c2_stage == 3);
    return s->cycles >= g->opt.cycles && g->fault_stage != 1 && quiet(g) && !dpv1_busy;
}

/* One step of the script after a slice of bus time. */
static void script_step(gen_t *g, uint32_t *last_progress)
{
    const dp_master_slave_t *s = card_slave(g);
    param_channel(g);
    dpv1_class1(g);
    dpv1_class2(g);
    faults(g);
    if (g->opt.foreign && s->phase == DP_MASTER_PHASE_DATA_EXCH &&
        s->cycles >= g->foreign_cycle + GEN_FOREIGN_EVERY && s->cycles < g->opt.cycles) {
        g->foreign_cycle = s->cycles;
        g->foreign.wanted = true;
    }
    if (g->opt.progress != NULL && s->cycles - *last_progress >= 10000u) {
        *last_progress = s->cycles;
        g->opt.progress(g->opt.ctx, s->cycles, g->res->telegrams);
    }
}

/* Start-up may take a baud search and back-offs; each cycle at most a few ms (more with the
 * faults' pauses). Returns 0, or -1 when the card never got through its cycles. */
static int run_cycles(gen_t *g, char *err, size_t errlen)
{
    uint64_t limit_ns = 10000000000ull + (uint64_t)g->opt.cycles * 50000000ull;
    uint32_t last_progress = 0;
    const dp_master_slave_t *s = card_slave(g);
    while (!finished(g)) {
        if (bus_ns(g) > limit_ns) {
            (void)snprintf(err, errlen, "the card did not complete %u Data_Exchange cycles (%u "
                           "done, master phase %s)", g->opt.cycles, s->cycles,
                           dp_master_phase_name(s->phase));
            return -1;
        }
        /* Short steps while finishing, so the capture ends right after the last answer. */
        membus_run_for_us(&g->rig.bus, s->cycles >= g->opt.cycles ? 20u : GEN_STEP_US);
        script_step(g, &last_progress);
    }
    return 0;
}

static int check_options(const gen_options_t *opt, char *err, size_t errlen)
{
    if (opt->address > DFP21B_MAX_ADDRESS || (opt->foreign && opt->address >= 114u)) {
        (void)snprintf(err, errlen, "address %u: the card needs 0..125%s", opt->address,
                       opt->foreign ? " (and --foreign address + 1 and + 10 below 126)" : "");
        return -1;
    }
    return 0;
}

static int gen_record(gen_t *g, char *err, size_t errlen)
{
    cap_writer_options_t wo = g->opt.writer;
    wo.baud = g->opt.baud; /* pcapng records it (if_speed): a replay then knows the rate */
    if (cap_writer_open(&g->w, g->opt.path, &wo, (uint64_t)GEN_EPOCH_S * 1000000000ull, err,
                        errlen) != 0) {
        return -1;
    }
    if (assemble(g, err, errlen) != 0) {
        cap_writer_close(&g->w);
        return -1;
    }
    configure_master(g);
    if (run_cycles(g, err, errlen) != 0) {
        cap_writer_close(&g->w);
        return -1;
    }
    gen_result_t *res = g->res;
    res->cycles = card_slave(g)->cycles;
    res->bus_ns = bus_ns(g);
    res->foreign_bursts = g->foreign.bursts;
    res->watchdog_expiries = g->wd_seen;
    if (cap_writer_close(&g->w) != 0 || g->write_failed) {
        (void)snprintf(err, errlen, "could not write the whole capture to %s", g->opt.path);
        return -1;
    }
    return 0;
}

int gen_run(const gen_options_t *opt, gen_result_t *res, char *err, size_t errlen)
{
    memset(res, 0, sizeof *res);
    if (check_options(opt, err, errlen) != 0) {
        return -1;
    }
    gen_t *g = calloc(1, sizeof *g);
    if (g == NULL) {
        (void)snprintf(err, errlen, "out of memory");
        return -1;
    }
    g->opt = *opt;
    g->res = res;
    if (g->opt.baud == 0u) g->opt.baud = GEN_DEFAULT_BAUD;
    int rc = gen_record(g, err, errlen);
    free(g);
    return rc;
}
