/* dfp-sim master: the built-in class-1 master against one slave or several on a real tty or a
 * PTY, or on a virtual segment over LCM (--bus lcm:CHANNEL), in wall-clock time. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "bus_opts.h"
#include "session.h"
#include "hal/hal_byte_order.h"
#include "sim_hal/host_clock.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

typedef struct master_opts {
    medium_opts_t med;
    bus_opts_t bus;
    capture_opts_t capture;
    instrument_opts_t io;
    const char *addresses;
    uint32_t own;
    uint32_t baud;
    uint32_t cycles;
    uint32_t timeout_s;
    uint32_t wd_ms;
    uint32_t ident;
    uint8_t cfg[DP_MASTER_MAX_CFG];
    size_t cfg_len;
    uint8_t user[DP_MASTER_MAX_PRM];
    size_t user_len;
    uint8_t outputs[DP_MASTER_MAX_IO];
    size_t out_given;
    bool verbose;
    bool timeout_given;
    bool reset_fault;
    bool echo;
    /* from the above */
    size_t control_word; /* offset of PO1, the control word, in the outputs */
    uint8_t slave_addr[DP_MASTER_MAX_SLAVES];
    size_t num_slaves;
    fdl_bus_params_t ring;
} master_opts_t;

#define MASTER(field) offsetof(master_opts_t, field)

static const cli_opt_t master_options[] = {
    {CLI_OPT("--address", "N|N-M,...", CLI_TEXT, MASTER(addresses))},
    {CLI_OPT("--config", "HEX", CLI_HEX, MASTER(cfg)),
     .aux = MASTER(cfg_len), .max = DP_MASTER_MAX_CFG},
    {CLI_OPT("--prm", "HEX", CLI_HEX, MASTER(user)),
     .aux = MASTER(user_len), .max = DP_MASTER_MAX_PRM - 7u},
    {CLI_OPT("--cycles", "N", CLI_U32, MASTER(cycles)), .min = 0, .max = 100000000u},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, MASTER(baud))},
    {CLI_OPT("--ident", "N", CLI_U32, MASTER(ident)), .min = 0, .max = 0xFFFF},
    {CLI_OPT("--watchdog", "MS", CLI_U32, MASTER(wd_ms)), .min = 0, .max = 650000u},
    {CLI_OPT("--master-address", "N", CLI_U32, MASTER(own)), .min = 0, .max = 126},
    {CLI_OPT("--outputs", "HEX", CLI_HEX, MASTER(outputs)),
     .aux = MASTER(out_given), .max = DP_MASTER_MAX_IO},
    {CLI_OPT("--timeout", "S", CLI_U32, MASTER(timeout_s)), .min = 1, .max = 86400u,
     .seen = CLI_SEEN(master_opts_t, timeout_given)},
    {CLI_OPT("--verbose", NULL, CLI_FLAG, MASTER(verbose))},
    {CLI_OPT("--reset-fault", NULL, CLI_FLAG, MASTER(reset_fault))},
    {CLI_OPT("--echo-suppress", NULL, CLI_FLAG, MASTER(echo))},
};

static const cli_group_t master_groups[] = {
    {medium_options, CLI_COUNT(medium_options), MASTER(med)},
    {master_options, CLI_COUNT(master_options), 0},
    {bus_options, CLI_COUNT(bus_options), MASTER(bus)},
    {capture_options, CLI_COUNT(capture_options), MASTER(capture)},
    {instrument_options, CLI_COUNT(instrument_options), MASTER(io)},
    {instrument_http_options, CLI_COUNT(instrument_http_options), MASTER(io.web)},
};

const cli_command_t cli_master = {.name = "master", .groups = master_groups,
                                  .n_groups = CLI_COUNT(master_groups)};

/* The command line into o: 0, or EXIT_USAGE after reporting. */
static int master_parse(master_opts_t *o, int argc, char **argv)
{
    *o = (master_opts_t){.own = 2, .baud = 19200, .cycles = 100, .timeout_s = 10,
                         .wd_ms = 1000, .ident = DFP21B_IDENT,
                         .user_len = SIZE_MAX};
    instrument_defaults(&o->io, RIG_LOG_TIME_BUS);
    bus_opts_defaults(&o->bus);
    if (cli_parse(&cli_master, argc, argv, o) != 0) {
        return EXIT_USAGE;
    }
    if ((o->med.dev == NULL && o->med.bus == NULL) || o->addresses == NULL || o->cfg_len == 0u) {
        cli_error("master: --port DEV (or --bus lcm:CHANNEL), --address N and --config HEX are "
                  "required");
        return EXIT_USAGE;
    }
    const cli_file_t capture = {"--capture", o->capture.path, false};
    if (!medium_check(&o->med, "master") ||
        !bus_opts_apply(&o->bus, "master", o->baud, true, &o->ring) ||
        !bus_opts_own_ok(&o->ring, "master", "--master-address", o->own) || !cli_no_links("master", &capture, 1u) ||
        !cli_address_list("--address", o->addresses, o->slave_addr, DP_MASTER_MAX_SLAVES, &o->num_slaves)) {
        return EXIT_USAGE;
    }
    dfp21b_pd_cfg_t pd = {0};
    if (o->reset_fault && !dfp21b_check_cfg(o->cfg, o->cfg_len, &pd)) {
        cli_error("master: --reset-fault needs a configuration the DFP21B accepts (its PO1 is "
                  "the drive's control word)");
        return EXIT_USAGE;
    }
    o->control_word = o->reset_fault && pd.param_channel ? ML_TELEGRAM_LEN : 0u;
    if (o->user_len == SIZE_MAX) {
        /* Without --prm: the DFP21B's user parameters for its ident, none for others. */
        o->user_len = o->ident == DFP21B_IDENT ? sizeof dfp21b_user_prm_default : 0u;
        memcpy(o->user, dfp21b_user_prm_default, o->user_len);
    }
    return 0;
}

/* The master on the medium with every slave. Returns 0, or EXIT_USAGE after reporting. */
static int master_build(session_t *s, const master_opts_t *o)
{
    dp_master_slave_cfg_t sc = {0};
    sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, (uint16_t)o->ident, o->wd_ms, o->user,
                                        o->user_len);
    memcpy(sc.cfg, o->cfg, o->cfg_len);
    sc.cfg_len = (uint8_t)o->cfg_len;
    s->in.log.show_inputs = o->verbose;
    dp_master_cfg_t mc = {.address = (uint8_t)o->own, .baud = o->baud, .strict_timing = false,
                          .token_ring = true, .bus = o->ring};
    dp_master_t *master = rig_add_master(&s->rig, &mc, tty_now_us());
    for (size_t i = 0; master != NULL && i < o->num_slaves; i++) {
        sc.address = o->slave_addr[i];
        if (dp_master_add_slave(master, &sc) < 0) {
            cli_error("master: configuration %s... cannot be decoded into I/O lengths",
                      "--config");
            return EXIT_USAGE;
        }
        dp_master_set_outputs(master, (unsigned)i, o->outputs, o->out_given);
    }
    return 0;
}

static void print_start_line(const session_t *s, const master_opts_t *o)
{
    char name[300];
    const dp_master_slave_t *first = &s->rig.master.slaves[0];
    printf("dfp-sim master: address %u on %s at %s; %s %s, ident 0x%04X, %zu cfg octets, "
           "%u out / %u in octets%s\n",
           o->own, session_medium_name(s, &o->med, name, sizeof name),
           report_baud_text(o->baud), o->num_slaves == 1u ? "slave" : "slaves", o->addresses,
           o->ident, o->cfg_len, first->out_len, first->in_len,
           o->cycles == 0u ? "; runs until stopped" : "");
    (void)fflush(stdout);
}

/* ---- the run ------------------------------------------------------------------------------ */

static bool all_in_data_exchange(const dp_master_t *m)
{
    for (uint8_t i = 0; i < m->num_slaves; i++) {
        if (m->slaves[i].phase != DP_MASTER_PHASE_DATA_EXCH) {
            return false;
        }
    }
    return true;
}

static bool all_cycled(const dp_master_t *m, uint32_t cycles)
{
    for (uint8_t i = 0; i < m->num_slaves; i++) {
        if (m->slaves[i].cycles < cycles) {
            return false;
        }
    }
    return true;
}

static uint64_t total_cycles(const dp_master_t *m)
{
    uint64_t n = 0;
    for (uint8_t i = 0; i < m->num_slaves; i++) {
        n += m->slaves[i].cycles;
    }
    return n;
}

/* When every slave reached data exchange, and the cycles then: the rate report's start. */
typedef struct run_times {
    uint64_t t_start;
    uint64_t t_all;
    uint64_t cycles_at_all;
} run_times_t;

static void report_done(session_t *s, const run_times_t *t)
{
    const dp_master_t *m = &s->rig.master;
    if (m->num_slaves == 1u) {
        const dp_master_slave_t *sl = &m->slaves[0];
        char hex[3 * DP_MASTER_MAX_IO + 1];
        size_t n = 0;
        for (size_t i = 0; i < sl->inputs_len; i++) {
            n += (size_t)snprintf(hex + n, sizeof hex - n, "%02X", sl->inputs[i]);
        }
        hex[n] = '\0';
        rig_log(&s->in.log, RIG_LOG_INFO, "master", "master",
                "done: slave %u in data exchange, %u cycles, last inputs %s", sl->cfg.address,
                sl->cycles, n > 0 ? hex : "(none)");
        return;
    }
    uint64_t t_all = t->t_all != 0u ? t->t_all : host_clock_mono_ns();
    uint64_t now = host_clock_mono_ns();
    double span = (double)(now - t_all) / 1e9;
    uint64_t dx = total_cycles(m) - t->cycles_at_all;
    rig_log(&s->in.log, RIG_LOG_INFO, "master", "master",
            "done: %u slaves in data exchange, each at least the given cycles; all reached "
            "data exchange %.3f s after start; since then %llu Data_Exchange telegrams in "
            "%.3f s (%.0f/s, %.1f full bus cycles/s)",
            m->num_slaves, (double)(t_all - t->t_start) / 1e9, (unsigned long long)dx, span,
            span > 0 ? (double)dx / span : 0.0,
            span > 0 ? (double)dx / span / m->num_slaves : 0.0);
}

static void report_missing(const dp_master_t *m, uint32_t cycles, const char *why)
{
    if (m->num_slaves == 1u) {
        const dp_master_slave_t *sl = &m->slaves[0];
        /* as param's timeout: the last attempt's reason, whatever phase the next one is in */
        bool fault = sl->phase != DP_MASTER_PHASE_FDL_STATUS && sl->fault[0] != '\0';
        bool backoff = sl->phase == DP_MASTER_PHASE_BACKOFF;
        cli_error("master: slave %u did not complete %u Data_Exchange cycles (%s; reached %u, "
                  "phase %s%s%s)",
                  sl->cfg.address, cycles, why, sl->cycles, dp_master_phase_name(sl->phase),
                  !fault ? "" : backoff ? ": " : " again after: ", fault ? sl->fault : "");
        return;
    }
    char list[1024];
    size_t n = 0;
    unsigned missing = 0;
    for (uint8_t i = 0; i < m->num_slaves; i++) {
        const dp_master_slave_t *sl = &m->slaves[i];
        if (sl->cycles >= cycles) {
            continue;
        }
        missing++;
        if (n + 48u < sizeof list) {
            n += (size_t)snprintf(list + n, sizeof list - n, "%s%u (%u, %s)", n > 0 ? ", " : "",
                                  sl->cfg.address, sl->cycles, dp_master_phase_name(sl->phase));
        }
    }
    cli_error("master: %u of %u slaves did not complete %u Data_Exchange cycles (%s): %s",
              missing, m->num_slaves, cycles, why, list);
}

/* --reset-fault: a PLC acknowledging a drive fault at start (protocol.md §C3.1): control word
 * bit 6 "fault reset" set for a while once the slave is in data exchange, then cleared: the
 * drive resets on the rising edge. Held for RESET_CYCLES cycles and at least RESET_HOLD_NS, so
 * the drive sees it however fast the bus cycles. */
#define RESET_CYCLES 5u
#define RESET_HOLD_NS 100000000ull
#define CW_FAULT_RESET 0x0040u

typedef enum reset_phase { RESET_WAIT = 0, RESET_HOLD, RESET_DONE } reset_phase_t;

typedef struct fault_reset {
    reset_phase_t phase[DP_MASTER_MAX_SLAVES];
    uint32_t until_cycles[DP_MASTER_MAX_SLAVES];
    uint64_t until_ns[DP_MASTER_MAX_SLAVES];
} fault_reset_t;

/* The outputs as given, with bit 6 of the control word set or cleared; returns the control
 * word sent. */
static uint16_t outputs_with_reset(const master_opts_t *o, dp_master_t *m, unsigned i, bool bit6)
{
    uint8_t out[DP_MASTER_MAX_IO];
    memcpy(out, o->outputs, sizeof out);
    size_t cw_at = o->control_word;
    uint16_t cw = hal_get_be16(&out[cw_at]);
    cw = bit6 ? (uint16_t)(cw | CW_FAULT_RESET) : (uint16_t)(cw & ~CW_FAULT_RESET);
    hal_put_be16(&out[cw_at], cw);
    dp_master_set_outputs(m, i, out, o->out_given > cw_at + 2u ? o->out_given : cw_at + 2u);
    return cw;
}

/* From the loop: moves each slave's fault reset along. */
static void fault_reset_step(session_t *s, const master_opts_t *o, fault_reset_t *fr)
{
    dp_master_t *m = &s->rig.master;
    for (unsigned i = 0; i < m->num_slaves; i++) {
        const dp_master_slave_t *sl = &m->slaves[i];
        if (fr->phase[i] == RESET_WAIT && sl->phase == DP_MASTER_PHASE_DATA_EXCH) {
            uint16_t cw = outputs_with_reset(o, m, i, true);
            fr->phase[i] = RESET_HOLD;
            fr->until_cycles[i] = sl->cycles + RESET_CYCLES;
            fr->until_ns[i] = host_clock_mono_ns() + RESET_HOLD_NS;
            rig_log(&s->in.log, RIG_LOG_INFO, "master", "master",
                    "slave %u: fault reset, control word %04X (bit 6 set)", sl->cfg.address, cw);
        } else if (fr->phase[i] == RESET_HOLD && sl->cycles >= fr->until_cycles[i] &&
                   host_clock_mono_ns() >= fr->until_ns[i]) {
            uint16_t cw = outputs_with_reset(o, m, i, false);
            fr->phase[i] = RESET_DONE;
            rig_log(&s->in.log, RIG_LOG_INFO, "master", "master",
                    "slave %u: fault reset done, control word %04X", sl->cfg.address, cw);
        }
    }
}

/* A reset still under way: the run does not end in the middle of it. */
static bool fault_reset_holding(const fault_reset_t *fr, unsigned num_slaves)
{
    for (unsigned i = 0; i < num_slaves; i++) {
        if (fr->phase[i] == RESET_HOLD) {
            return true;
        }
    }
    return false;
}

/* What ends a stretch of the run, checked at every master event: the runner returns as soon as
 * it is met instead of at the end of its 20 ms slice, which added up to 20 ms of cycles nobody
 * asked for at the end of a run and again when leaving (about an eighth of a run of 2 000
 * cycles over a PTY). A signal is seen at the next event or, on a silent bus, the slice end. */
typedef struct run_goal {
    const dp_master_t *m;
    uint32_t until[DP_MASTER_MAX_SLAVES]; /* cycles each slave must reach; 0: none */
    bool active;                          /* false: only a signal ends the stretch */
    bool leaving;                         /* a slave out of data exchange is done as well */
    bool on_signal;                       /* a signal ends the stretch */
    volatile int met;                     /* the runner's stop flag */
} run_goal_t;

static bool goal_reached(const run_goal_t *g)
{
    for (unsigned i = 0; i < g->m->num_slaves; i++) {
        const dp_master_slave_t *sl = &g->m->slaves[i];
        bool gone = g->leaving && sl->phase != DP_MASTER_PHASE_DATA_EXCH;
        if (sl->cycles < g->until[i] && !gone) {
            return false;
        }
    }
    return true;
}

static void goal_event(void *ctx, const dp_master_event_t *ev)
{
    run_goal_t *g = ctx;
    (void)ev;
    if ((g->on_signal && cli_stop) || (g->active && goal_reached(g))) {
        g->met = 1;
    }
}

/* One slice of the run: 0, or -1 when the medium failed. */
static int run_slice(session_t *s, run_goal_t *g)
{
    g->met = 0;
    if (g->on_signal && cli_stop) {
        return 0;
    }
    return rig_run_until(&s->rig, tty_now_us() + 20000u, &g->met);
}

/* Leaving like a PLC going to STOP (protocol.md §A3.5): Global_Control Clear_Data and zero
 * outputs for LEAVE_CYCLES cycles, so the drive sees controller inhibit before the watchdog
 * runs out. Whether it then reports F28 is its P831 reaction. */
#define LEAVE_CYCLES 3u
#define LEAVE_TIMEOUT_US 1000000u

static void master_leave(session_t *s, run_goal_t *g)
{
    dp_master_t *m = &s->rig.master;
    static const uint8_t zeros[DP_MASTER_MAX_IO];
    /* a second signal does not cut the goodbye short */
    *g = (run_goal_t){.m = m, .active = true, .leaving = true, .on_signal = false};
    unsigned exchanging = 0;
    for (unsigned i = 0; i < m->num_slaves; i++) {
        if (m->slaves[i].phase == DP_MASTER_PHASE_DATA_EXCH) {
            exchanging++;
            g->until[i] = m->slaves[i].cycles + LEAVE_CYCLES;
        }
        dp_master_set_outputs(m, i, zeros, m->slaves[i].out_len);
    }
    if (exchanging == 0u) {
        return;
    }
    rig_log(&s->in.log, RIG_LOG_INFO, "master", "master",
            "going to STOP: Global_Control Clear_Data, outputs zero for %u cycles", LEAVE_CYCLES);
    dp_master_global_control(m, DP_GC_CLEAR_DATA, 0);
    rig_wake(&s->rig);
    hal_time_us_t end = tty_now_us() + LEAVE_TIMEOUT_US;
    bool done = false;
    while (!done && hal_time_diff(end, tty_now_us()) > 0) {
        if (run_slice(s, g) < 0) {
            return;
        }
        done = goal_reached(g);
    }
    rig_log(&s->in.log, RIG_LOG_INFO, "master", "master", "%s",
            done ? "stopped: outputs cleared, leaving the bus"
                 : "stopped: the slaves did not confirm the cleared outputs in time");
}

/* Cycles until every slave ran --cycles of them (0), --timeout or a signal (1), or a medium
 * failure (-1, *why says which). */
static int master_cycle(session_t *s, const master_opts_t *o, run_times_t *t, run_goal_t *g,
                        const char **why)
{
    const dp_master_t *m = &s->rig.master;
    *g = (run_goal_t){.m = m, .active = o->cycles != 0u, .on_signal = true};
    for (unsigned i = 0; i < m->num_slaves; i++) {
        g->until[i] = o->cycles;
    }
    uint64_t end_ns = o->timeout_given || o->cycles != 0u
                          ? t->t_start + (uint64_t)o->timeout_s * 1000000000ull
                          : UINT64_MAX;
    static fault_reset_t fr;
    memset(&fr, 0, sizeof fr);
    *why = "timeout";
    while (!cli_stop && host_clock_mono_ns() < end_ns) {
        if (run_slice(s, g) < 0) {
            *why = rig_error(&s->rig);
            return -1;
        }
        if (o->reset_fault) {
            fault_reset_step(s, o, &fr);
        }
        if (t->t_all == 0u && all_in_data_exchange(m)) {
            t->t_all = host_clock_mono_ns();
            t->cycles_at_all = total_cycles(m);
            if (o->num_slaves > 1u) {
                rig_log(&s->in.log, RIG_LOG_INFO, "master", "master", "all %zu slaves in data "
                        "exchange", o->num_slaves);
            }
        }
        if (o->cycles != 0u && all_cycled(m, o->cycles) &&
            !fault_reset_holding(&fr, m->num_slaves)) {
            return 0;
        }
    }
    return 1;
}

/* The run and its outcome: 0 when every slave ran its cycles (or, with --cycles 0, on a
 * signal), 1 when not. */
static int master_run(session_t *s, const master_opts_t *o, run_goal_t *g)
{
    run_times_t t = {.t_start = host_clock_mono_ns()};
    const char *why = NULL;
    int rc = master_cycle(s, o, &t, g, &why);
    if (o->cycles == 0u && cli_stop) {
        rig_log(&s->in.log, RIG_LOG_INFO, "master", "master", "stopping (signal)");
        rc = 0;
    } else if (rc == 0) {
        report_done(s, &t);
    } else {
        report_missing(&s->rig.master, o->cycles, cli_stop ? "interrupted" : why);
    }
    if (rc >= 0) {
        master_leave(s, g);
    }
    return rc < 0 ? 1 : rc;
}

int cmd_master(int argc, char **argv)
{
    static master_opts_t o;
    static session_t s;
    static run_goal_t goal; /* the tap below points here until the process ends */
    int rc = master_parse(&o, argc, argv);
    if (rc != 0) {
        return rc;
    }
    if (!session_open(&s, &o.med, (int16_t)o.own, o.baud, &o.capture, &o.io, o.echo)) {
        return 1;
    }
    if (master_build(&s, &o) != 0) {
        session_close(&s);
        return EXIT_USAGE;
    }
    print_start_line(&s, &o);
    rig_tap_t tap = {.ctx = &goal, .master_event = goal_event};
    if (rig_add_tap(&s.rig, &tap) != 0) {
        cli_error("master: no room for another rig tap");
        return session_end(&s, 1);
    }
    rc = instrument_start_http(&s.in, &s.rig, &o.io, "master", false);
    if (rc == 0) {
        rc = master_run(&s, &o, &goal);
    }
    return session_end(&s, rc);
}
