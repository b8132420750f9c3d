/* dfp-bench: what the card costs per telegram, and how fast start-up and cycles run.
 *
 * 1. Reply path per telegram type: the time (ns, median of many runs) and the instructions
 *    (callgrind, deterministic) of the one call that receives the last octet of a request and
 *    ends with the reply handed to the UART: decode, checks, FCB, service, encode. Everything
 *    before the last octet happens while the request is still on the wire.
 * 2. Start-up + N Data_Exchange cycles of master and card on the in-memory bus (simulated bus
 *    time, and how much faster than real time the simulation runs).
 * 3. The same over a PTY pair in one process (wall clock; the PTY ignores the baud rate).
 *
 * Instruction counts need valgrind: dfp-bench runs itself under callgrind once per telegram
 * type (--instructions, default on when valgrind is installed). */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "dp_slave/dp_wire.h"
#include "dp_master/dpv1_c2.h"
#include "dp_master/dpv1_ds47.h"
#include "dp_master/param_channel.h"
#include "dp_slave/fdl_frame.h"
#include "rig/rig.h"
#include "sim_hal/host_clock.h"
#include "sim_hal/membus.h"
#include "sim_hal/tty_port.h"
#include "sim_stations/stations.h"

#define BAUD 12000000u

/* ---- 1. reply path ------------------------------------------------------------------------ */

typedef struct sink {
    size_t last_len;
    unsigned transmits;
} sink_t;

static int sink_set_baud(void *ctx, uint32_t baud)
{
    (void)ctx;
    (void)baud;
    return 0;
}

static int sink_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t nb)
{
    (void)frame;
    (void)nb;
    sink_t *s = ctx;
    s->last_len = len;
    s->transmits++;
    return 0;
}

static const hal_uart_ops_t sink_ops = {.set_baud = sink_set_baud, .transmit = sink_transmit};

static dfp21b_t card;
static sink_t sink;
static hal_time_us_t now_us;

static void feed(const uint8_t *f, size_t len)
{
    uint32_t char_ns = hal_uart_char_ns(BAUD);
    now_us += 10u; /* idle > TSYN before the request */
    uint64_t t_ns = (uint64_t)now_us * 1000u;
    for (size_t i = 0; i < len; i++) {
        t_ns += char_ns;
        dfp21b_rx_char(&card, f[i], 0, (hal_time_us_t)(t_ns / 1000u));
    }
    now_us = (hal_time_us_t)(t_ns / 1000u) + 1u;
}

static size_t request(uint8_t *out, uint8_t fc_code, bool fcb, bool saps, uint8_t dsap,
                      const uint8_t *data, size_t len)
{
    uint8_t fc = (uint8_t)(0x40u | 0x10u | (fcb ? 0x20u : 0u) | fc_code);
    if (fc_code == 0x9u || fc_code == 0x6u) {
        fc = (uint8_t)(0x40u | fc_code);
    }
    return fdl_encode(out, 4u, 2u, fc, saps, dsap, 62u, data, len);
}

static const uint8_t prm[16] = {0x88, 0x01, 0x64, 0x0B, 0x60, 0x03, 0x00, 0x00,
                                0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};

static void card_setup(const uint8_t *cfg, size_t cfg_len, dp_state_t target)
{
    static sim_dip_t dip = {.switches = 4};
    dfp21b_cfg_t cfg_ = {.uart = {.ops = &sink_ops, .ctx = &sink},
                         .dip = sim_dip_hal(&dip), .fixed_baud = BAUD, .strict_timing = true};
    now_us = 0;
    dfp21b_init(&card, &cfg_, now_us);
    uint8_t f[FDL_FRAME_MAX];
    if (target == DP_STATE_WAIT_PRM) {
        return;
    }
    feed(f, request(f, 0xD, true, true, DP_SAP_SET_PRM, prm, sizeof prm));
    if (target == DP_STATE_WAIT_CFG) {
        return;
    }
    feed(f, request(f, 0xD, false, true, DP_SAP_CHK_CFG, cfg, cfg_len));
    dfp21b_poll(&card, now_us);
}

static const uint8_t cfg_3pd[] = {0xF3, 0xF2};
static const uint8_t cfg_10pd[] = {0xF3, 0xF9};
static const uint8_t cfg_4pd[] = {0xF3};

typedef struct case_spec {
    const char *name;
    const uint8_t *cfg;
    size_t cfg_len;
    dp_state_t state;
    uint8_t code;
    bool saps;
    uint8_t dsap;
    const uint8_t *data;
    size_t len;
    bool same_fcb;
} case_spec_t;

static const uint8_t out14[14] = {0, 0, 0, 0, 0, 0, 0, 0, 0x00, 0x06, 0x05, 0xDC, 0, 0};
static const uint8_t out28[28] = {0};
static const uint8_t out8[8] = {1, 2, 3, 4, 5, 6, 7, 8};
static const uint8_t gc_sync[2] = {DP_GC_SYNC, 0};

static const case_spec_t cases[] = {
    {"FDL status -> SD1", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0x9, false, 0, NULL, 0, false},
    {"Slave_Diag -> SD2", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0xD, true, DP_SAP_SLAVE_DIAG, NULL, 0, false},
    {"Get_Cfg -> SD2", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0xD, true, DP_SAP_GET_CFG, NULL, 0, false},
    {"Set_Prm 16 B -> SC", cfg_3pd, 2, DP_STATE_WAIT_CFG, 0xD, true, DP_SAP_SET_PRM, prm, 16, false},
    {"Chk_Cfg F3F2 -> SC", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0xD, true, DP_SAP_CHK_CFG, cfg_3pd, 2, false},
    {"Data_Exch 14 B -> 14 B", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0xD, false, 0, out14, 14, false},
    {"Data_Exch 28 B -> 28 B", cfg_10pd, 2, DP_STATE_DATA_EXCH, 0xD, false, 0, out28, 28, false},
    {"Data_Exch SD3 8 B -> SD2", cfg_4pd, 1, DP_STATE_DATA_EXCH, 0xD, false, 0, out8, 8, false},
    {"Data_Exch FCB retry", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0xD, false, 0, out14, 14, true},
    {"Global_Control (no reply)", cfg_3pd, 2, DP_STATE_DATA_EXCH, 0x6, true, DP_SAP_GLOBAL_CONTROL, gc_sync, 2, false},
};
#define NUM_CASES (sizeof cases / sizeof cases[0])

/* The measured call. noinline and a stable name so callgrind can count exactly this. */
__attribute__((noinline)) void bench_last_octet(uint8_t byte, hal_time_us_t t);
__attribute__((noinline)) void bench_last_octet(uint8_t byte, hal_time_us_t t)
{
    dfp21b_rx_char(&card, byte, 0, t);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a;
    uint64_t y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Runs one case `iterations` times; returns the median ns of the last-octet call. */
static uint64_t run_case(const case_spec_t *c, unsigned iterations, bool *replied_ok)
{
    card_setup(c->cfg, c->cfg_len, c->state);
    uint8_t f[2][FDL_FRAME_MAX];
    size_t len = request(f[0], c->code, false, c->saps, c->dsap, c->data, c->len);
    request(f[1], c->code, true, c->saps, c->dsap, c->data, c->len);
    static uint64_t samples[200000];
    if (iterations > 200000u) iterations = 200000u;
    uint32_t char_ns = hal_uart_char_ns(BAUD);
    unsigned before = sink.transmits;
    for (unsigned i = 0; i < iterations; i++) {
        const uint8_t *fr = c->same_fcb ? f[1] : f[i & 1u];
        now_us += 10u;
        uint64_t t_ns = (uint64_t)now_us * 1000u;
        for (size_t k = 0; k + 1u < len; k++) {
            t_ns += char_ns;
            dfp21b_rx_char(&card, fr[k], 0, (hal_time_us_t)(t_ns / 1000u));
        }
        t_ns += char_ns;
        uint64_t a = host_clock_mono_ns();
        bench_last_octet(fr[len - 1u], (hal_time_us_t)(t_ns / 1000u));
        uint64_t b = host_clock_mono_ns();
        samples[i] = b - a;
        now_us = (hal_time_us_t)(t_ns / 1000u) + 1u;
    }
    bool expect_reply = c->code != 0x6u;
    *replied_ok = expect_reply ? sink.transmits - before == iterations
                               : sink.transmits == before;
    uint64_t overhead[1000];
    for (unsigned i = 0; i < 1000u; i++) {
        uint64_t a = host_clock_mono_ns();
        uint64_t b = host_clock_mono_ns();
        overhead[i] = b - a;
    }
    qsort(overhead, 1000, sizeof overhead[0], cmp_u64);
    qsort(samples, iterations, sizeof samples[0], cmp_u64);
    uint64_t med = samples[iterations / 2u];
    return med > overhead[500] ? med - overhead[500] : 0u;
}

/* Instructions of bench_last_octet per call, from callgrind run on this very program. */
static double instructions_for(const char *self, unsigned idx)
{
    char out[256];
    snprintf(out, sizeof out, "/tmp/dfp-bench-cg.%d.%u", (int)getpid(), idx);
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "valgrind --tool=callgrind --callgrind-out-file=%s --collect-atstart=no "
             "--toggle-collect=bench_last_octet %s --only %u --iterations 1000 >/dev/null 2>&1",
             out, self, idx);
    /* The command line is this program's own path and numbers it formatted itself. */
    if (system(cmd) != 0) { // NOLINT(cert-env33-c)
        return -1.0;
    }
    FILE *f = fopen(out, "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[512];
    double total = -1.0;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, "totals:", 7) == 0 || strncmp(line, "summary:", 8) == 0) {
            total = strtod(line + (line[0] == 't' ? 7 : 8), NULL);
        }
    }
    (void)fclose(f); /* read only: nothing to lose */
    unlink(out);
    return total < 0 ? -1.0 : total / 1000.0;
}

/* ---- 2. in-memory bus --------------------------------------------------------------------- */

/* Large (a bus with its event queue, room for a whole segment of cards): static storage, as
 * rig.h asks. */
static rig_t brig;
static dp_master_t *bmaster;

/* Master (2) and card (4) on a fresh in-memory bus, "Param + 3 PD", watchdog wd_ms. The card
 * attaches first, as the simulated figures in docs/performance.md were taken that way. */
static void bench_rig(uint32_t baud, card_inverter_t inverter, uint32_t inverter_us,
                      uint32_t wd_ms)
{
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS};
    rig_init(&brig, &rc);
    char err[256];
    (void)rig_open(&brig, err, sizeof err); /* an in-memory bus always opens */
    card_options_t co = {.address = 4, .fixed_baud = baud, .strict_timing = true,
                         .inverter = inverter, .inverter_delay_us = inverter_us};
    (void)rig_add_card(&brig, &co, 0);
    dp_master_cfg_t mc = {.address = 2, .baud = baud, .strict_timing = true};
    bmaster = rig_add_master(&brig, &mc, 0);
    dp_master_slave_cfg_t sc = {.address = 4};
    sc.prm_len =
        (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, wd_ms, dfp21b_user_prm_default, 9);
    memcpy(sc.cfg, cfg_3pd, 2);
    sc.cfg_len = 2;
    dp_master_add_slave(bmaster, &sc);
}

/* The rate as the tables in docs/performance.md name it (any other in bit/s). */
static const char *rate_name(uint32_t baud, char buf[24])
{
    switch (baud) {
    case 12000000u: return "12 Mbit/s";
    case 1500000u: return "1.5 Mbit/s";
    case 19200u: return "19.2 kbit/s";
    default: snprintf(buf, 24, "%u bit/s", (unsigned)baud); return buf;
    }
}

static void bench_membus(unsigned cycles, uint32_t baud)
{
    char name[24];
    uint64_t w0 = host_clock_mono_ns(); /* building the rig is part of the start-up */
    bench_rig(baud, CARD_INVERTER_NONE, 0, 100);
    uint64_t startup_ns = 0;
    while (bmaster->slaves[0].cycles < cycles && brig.bus.now_ns < 600000000000ull) {
        membus_run_for_us(&brig.bus, startup_ns == 0u ? 50u : 1000u);
        if (startup_ns == 0u && bmaster->slaves[0].phase == DP_MASTER_PHASE_DATA_EXCH) {
            startup_ns = brig.bus.now_ns;
        }
    }
    uint64_t wall = host_clock_mono_ns() - w0;
    double sim_ms = (double)brig.bus.now_ns / 1e6;
    printf("  %-12s start-up %8.3f ms, %u cycles in %9.1f ms bus time = %7.0f cycles/s on "
           "the bus; simulated in %6.1f ms wall (%.0fx real time)\n",
           rate_name(baud, name), (double)startup_ns / 1e6, bmaster->slaves[0].cycles, sim_ms,
           bmaster->slaves[0].cycles / (sim_ms / 1000.0), (double)wall / 1e6,
           sim_ms / ((double)wall / 1e6));
    printf("  %-12s bus: %llu telegrams delivered whole, %llu split into characters\n", "",
           (unsigned long long)brig.bus.telegrams_whole,
           (unsigned long long)brig.bus.telegrams_split);
}

/* ---- 2b. parameter service latency through the cyclic channel ---------------------------- */

/* Master, card and emulated inverter on the in-memory bus: the time from the master putting a
 * new request into its outputs to the master seeing the matching reply, for `n` reads of 8300.
 * inverter_us is how long the inverter takes per service (0: answers within the card's poll). */
static void bench_param_latency(uint32_t baud, uint32_t inverter_us, unsigned n)
{
    char name[24];
    bench_rig(baud, CARD_INVERTER_SIM, inverter_us, 1000);
    membus_run_for_us(&brig.bus, 200000);
    dp_master_param_t p = {0};
    uint8_t out[14] = {0};
    uint64_t sum_ns = 0;
    uint64_t max_ns = 0;
    uint32_t sum_cycles = 0;
    uint32_t max_cycles = 0;
    unsigned done = 0;
    for (unsigned i = 0; i < n; i++) {
        dp_master_param_start(&p, ML_SVC_READ, 8300, 0, out);
        dp_master_set_outputs(bmaster, 0, out, sizeof out);
        uint64_t t0 = brig.bus.now_ns;
        uint32_t c0 = bmaster->slaves[0].cycles;
        while (!dp_master_param_done(&p, bmaster->slaves[0].inputs) &&
               brig.bus.now_ns - t0 < 1000000000ull) {
            membus_run_for_us(&brig.bus, 10);
        }
        uint64_t dt = brig.bus.now_ns - t0;
        uint32_t dc = bmaster->slaves[0].cycles - c0;
        if (ml_data(bmaster->slaves[0].inputs) == 0x311C7289u) {
            done++;
        }
        sum_ns += dt;
        sum_cycles += dc;
        if (dt > max_ns) max_ns = dt;
        if (dc > max_cycles) max_cycles = dc;
    }
    printf("  %-12s inverter %5u us: %u/%u reads of 8300 correct, %5.2f cycles (max %u), "
           "%7.1f us (max %7.1f us) bus time each\n",
           rate_name(baud, name), inverter_us, done, n, (double)sum_cycles / n, max_cycles,
           (double)sum_ns / n / 1e3, (double)max_ns / 1e3);
}

/* ---- 2c. DP-V1 data set 47 through class 1 and class 2 ------------------------------------- */

/* One data set 47 access (Write.req, polls, Read.req repeated while B5, polls) on port, in bus
 * time; returns false when it did not end positively. */
static bool dpv1_access(dp_master_acyc_port_t port, const dp_master_ds47_req_t *req,
                        uint32_t step_us, uint32_t *us, uint32_t *cycles, uint32_t *telegrams,
                        uint32_t *busy)
{
    dp_master_call_t call;
    memset(&call, 0, sizeof call);
    uint32_t c0 = bmaster->slaves[0].cycles;
    if (dp_master_ds47_start(&call, port, req, NULL, NULL, membus_now_us(&brig.bus)) != 0) {
        return false;
    }
    uint64_t t0 = brig.bus.now_ns;
    while (!dp_master_call_done(&call) && brig.bus.now_ns - t0 < 5000000000ull) {
        membus_run_for_us(&brig.bus, step_us);
    }
    *us = call.t_end - call.t_start;
    *cycles = bmaster->slaves[0].cycles - c0;
    *telegrams = call.telegrams;
    *busy = call.busy;
    dp_master_ds47_rsp_t rsp;
    return dp_master_call_done(&call) && call.ok &&
           dp_master_ds47_parse(req, call.data, call.len, &rsp, NULL, 0) && !rsp.negative &&
           rsp.p[0].value == 0x311C7289u;
}

/* Master 2 with the card in cyclic exchange (Param + 3 PD, DP-V1 parameters) and, for class 2,
 * a connection from address 1 on the same station: n reads of 8300 with 1 parameter and with
 * 19 parameters per request, time and Data_Exchange cycles per access. */
static void bench_dpv1(uint32_t baud, uint32_t inverter_us, unsigned n)
{
    static dp_master_c2_t c2;
    uint32_t step_us = baud >= 1500000u ? 5u : 200u;
    char name[24];
    const char *rate = rate_name(baud, name);
    for (int cls = 1; cls <= 2; cls++) {
        bench_rig(baud, CARD_INVERTER_SIM, inverter_us, 1000);
        dp_master_slave_cfg_t sc = bmaster->slaves[0].cfg;
        sc.prm_len = (uint8_t)dp_master_build_prm_dpv1(sc.prm, DFP21B_IDENT, 1000,
                                                 dfp21b_user_prm_default, 9);
        dp_master_reconfigure(bmaster, 0, &sc, 0);
        membus_run_for_us(&brig.bus, 200000);
        dp_master_acyc_port_t port = dp_master_c1_port(bmaster, 0);
        uint32_t open_us = 0;
        if (cls == 2) {
            dp_master_c2_cfg_t cc = {.slave = 4, .address = 1};
            dp_master_c2_init(&c2, &cc);
            dp_master_add_c2(bmaster, &c2);
            hal_time_us_t t0 = membus_now_us(&brig.bus);
            dp_master_c2_open(&c2, NULL, NULL, t0);
            while (dp_master_c2_state(&c2) != DP_MASTER_C2_OPEN &&
                   dp_master_c2_state(&c2) != DP_MASTER_C2_CLOSED) {
                membus_run_for_us(&brig.bus, step_us);
            }
            open_us = membus_now_us(&brig.bus) - t0;
            port = dp_master_c2_port(&c2);
        }
        for (unsigned params = 1; params <= DS47_MAX_PARAMS; params += 18u) {
            dp_master_ds47_req_t req = {.ref = 1, .id = DS47_ID_MOVILINK, .n = (uint8_t)params};
            for (unsigned i = 0; i < params; i++) {
                req.p[i] = (dp_master_ds47_param_t){.attribute = DS47_ATTR_ML_READ, .number = 8300};
            }
            uint64_t sum_us = 0;
            uint32_t max_us = 0;
            uint64_t sum_cycles = 0;
            uint64_t sum_tel = 0;
            uint64_t sum_busy = 0;
            unsigned good = 0;
            for (unsigned i = 0; i < n; i++) {
                uint32_t us = 0;
                uint32_t cycles = 0;
                uint32_t tel = 0;
                uint32_t busy = 0;
                good += dpv1_access(port, &req, step_us, &us, &cycles, &tel, &busy) ? 1u : 0u;
                req.ref = (uint8_t)(req.ref % 255u + 1u); /* 1..255: 0 is not a reference */
                sum_us += us;
                sum_cycles += cycles;
                sum_tel += tel;
                sum_busy += busy;
                if (us > max_us) max_us = us;
            }
            double mean_us = (double)sum_us / n;
            printf("  %-11s  C%d %5u %3u %5u/%-4u %10.1f %10.1f %6.1f %6.1f %5.1f %8.0f", rate,
                   cls, inverter_us, params, good, n, mean_us, (double)max_us,
                   (double)sum_cycles / n, (double)sum_tel / n, (double)sum_busy / n,
                   params * 1e6 / mean_us);
            if (cls == 2 && params == 1u) {
                printf("   Initiate %.1f us", (double)open_us);
            }
            printf("\n");
        }
    }
}

/* ---- 3. PTY ------------------------------------------------------------------------------- */

/* One rig per end of the PTY pair, both driven by one runner so card and master share a loop. */
static rig_t prig[2];
static tty_runner_t runner;

/* Opens both ends: the card's (index 0) by the slave side's path, the master's on the master
 * side, which has no path. Returns 0, or -1 after printing why (nothing left open). */
static int open_pty_rigs(int m)
{
    char err[256];
    tty_runner_init(&runner);
    for (int i = 0; i < 2; i++) {
        rig_cfg_t rc = {.medium = RIG_MEDIUM_TTY, .device = ptsname(m), .use_fd = i == 1,
                        .fd = m, .baud = BAUD, .shared_runner = &runner};
        rig_init(&prig[i], &rc);
        if (rig_open(&prig[i], err, sizeof err) != 0) {
            printf("  PTY: %s\n", err);
            if (i == 1) {
                rig_close(&prig[0]);
            }
            (void)close(m); /* a failed open leaves m with us */
            return -1;
        }
    }
    return 0;
}

static int bench_pty(unsigned cycles)
{
    int m = posix_openpt(O_RDWR | O_NOCTTY);
    if (m < 0 || grantpt(m) != 0 || unlockpt(m) != 0) {
        printf("  PTY: cannot create a PTY pair: %s\n", strerror(errno));
        return -1;
    }
    if (open_pty_rigs(m) != 0) {
        return -1;
    }
    card_options_t co = {.address = 4, .fixed_baud = BAUD, .strict_timing = false};
    (void)rig_add_card(&prig[0], &co, tty_now_us());
    dp_master_cfg_t mc = {.address = 2, .baud = BAUD, .strict_timing = false,
                          .slot_time_us = 100000};
    dp_master_t *pm = rig_add_master(&prig[1], &mc, tty_now_us());
    dp_master_slave_cfg_t sc = {.address = 4};
    sc.prm_len =
        (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, 1000, dfp21b_user_prm_default, 9);
    memcpy(sc.cfg, cfg_3pd, 2);
    sc.cfg_len = 2;
    dp_master_add_slave(pm, &sc);
    uint64_t t0 = host_clock_mono_ns();
    uint64_t startup = 0;
    uint64_t dx0 = 0;
    while (pm->slaves[0].cycles < cycles && host_clock_mono_ns() - t0 < 30000000000ull) {
        if (rig_run_until(&prig[1], tty_now_us() + 10000u, NULL) < 0) {
            printf("  PTY: %s\n", rig_error(&prig[1]));
            break;
        }
        if (startup == 0u && pm->slaves[0].phase == DP_MASTER_PHASE_DATA_EXCH) {
            startup = host_clock_mono_ns() - t0;
            dx0 = host_clock_mono_ns();
        }
    }
    double dx_s = (double)(host_clock_mono_ns() - dx0) / 1e9;
    printf("  PTY pair    start-up %8.3f ms, %u cycles in %9.1f ms wall = %7.0f cycles/s "
           "(card and master in one process)\n",
           (double)startup / 1e6, pm->slaves[0].cycles, dx_s * 1000.0,
           pm->slaves[0].cycles / dx_s);
    rig_close(&prig[0]);
    rig_close(&prig[1]);
    return 0;
}

/* A whole decimal number in 0..max, or -1. */
static long parse_count(const char *s, long max)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < 0 || v > max) {
        return -1;
    }
    return v;
}

typedef struct bench_args {
    unsigned iterations;
    int only;
    bool instructions;
    unsigned cycles; /* --cycles: only start-up + this many cycles on the in-memory bus */
    uint32_t baud;
} bench_args_t;

static bool is_profibus_baud(long v)
{
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        if (hal_uart_bauds[i] == (uint32_t)v) {
            return true;
        }
    }
    return false;
}

/* One option with its value at argv[*i]; returns 0, or 2 after an error message. */
static int parse_option(int argc, char **argv, int *i, bench_args_t *a)
{
    const char *opt = argv[*i];
    if (strcmp(opt, "--no-instructions") == 0) {
        a->instructions = false;
        return 0;
    }
    long v = *i + 1 < argc ? parse_count(argv[*i + 1], 100000000) : -1;
    (*i)++;
    if (strcmp(opt, "--only") == 0 && v >= 0 && v <= 1000) {
        a->only = (int)v;
    } else if (strcmp(opt, "--iterations") == 0 && v >= 1) {
        a->iterations = (unsigned)v;
    } else if (strcmp(opt, "--cycles") == 0 && v >= 1) {
        a->cycles = (unsigned)v;
    } else if (strcmp(opt, "--baud") == 0 && is_profibus_baud(v)) {
        a->baud = (uint32_t)v;
    } else {
        fprintf(stderr, "dfp-bench: %s: %s\n"
                        "usage: dfp-bench [--iterations N] [--no-instructions] | --only CASE | "
                        "--cycles N [--baud RATE]\n",
                opt, *i < argc ? "bad value" : "needs a value");
        return 2;
    }
    return 0;
}

int main(int argc, char **argv)
{
    bench_args_t a = {.iterations = 100000, .only = -1, .baud = 12000000u,
                      .instructions = access("/usr/bin/valgrind", X_OK) == 0};
    for (int i = 1; i < argc; i++) {
        int rc = parse_option(argc, argv, &i, &a);
        if (rc != 0) {
            return rc;
        }
    }
    unsigned iterations = a.iterations;
    bool instructions = a.instructions;
    if (a.cycles > 0u) {
        /* what tools/bench/ratio_bench.py compares with pyprofibus */
        bench_membus(a.cycles, a.baud);
        return 0;
    }
    if (a.only >= 0) {
        bool ok;
        if ((unsigned)a.only < NUM_CASES) {
            run_case(&cases[a.only], iterations, &ok);
        }
        return 0;
    }
    printf("dfp-bench: DFP21B card, reply path = the call that takes the last octet of a request\n"
           "and hands the reply to the UART (x86-64 host, %u runs each, median)\n\n", iterations);
    printf("  %-28s %10s %14s\n", "telegram", "ns", "instructions");
    int rc = 0;
    for (unsigned i = 0; i < NUM_CASES; i++) {
        bool ok = false;
        uint64_t ns = run_case(&cases[i], iterations, &ok);
        double ins = instructions ? instructions_for(argv[0], i) : -1.0;
        if (ins >= 0) {
            printf("  %-28s %10llu %14.0f%s\n", cases[i].name, (unsigned long long)ns, ins,
                   ok ? "" : "  (UNEXPECTED reply count)");
        } else {
            printf("  %-28s %10llu %14s%s\n", cases[i].name, (unsigned long long)ns, "n/a",
                   ok ? "" : "  (UNEXPECTED reply count)");
        }
        if (!ok) rc = 1;
    }
    printf("\nRAM of one card: dp_slave_t %zu bytes (fdl_rx_t %zu, FCB reply caches %zu), "
           "dfp21b_t %zu bytes in all\n",
           sizeof(dp_slave_t), sizeof(fdl_rx_t), sizeof(((dp_slave_t *)0)->fcb),
           sizeof(dfp21b_t));
    printf("\nStart-up (FDL status .. Data_Exch) and 10000 Data_Exchange cycles, Param + 3 PD:\n");
    bench_membus(10000, 12000000u);
    bench_membus(10000, 1500000u);
    bench_membus(1000, 19200u);
    bench_pty(5000);
    printf("\nParameter service through the cyclic channel (master output -> matching reply), "
           "emulated inverter in-process:\n");
    bench_param_latency(12000000u, 0, 200);
    bench_param_latency(1500000u, 0, 200);
    bench_param_latency(1500000u, 1000, 200);
    bench_param_latency(19200u, 0, 50);
    printf("\nDP-V1 data set 47 (Write.req + Read.req until not B5, each with its polls), reads of "
           "8300, cyclic exchange going on, emulated inverter in-process; per access, bus time:\n"
           "  %-11s  %-2s %5s %3s %10s %10s %10s %6s %6s %5s %8s\n", "rate", "", "inv.us",
           "par", "ok", "us mean", "us max", "DX", "acyc", "B5", "params/s");
    bench_dpv1(12000000u, 0, 100);
    bench_dpv1(1500000u, 0, 100);
    bench_dpv1(1500000u, 1000, 100);
    bench_dpv1(19200u, 0, 10);
    return rc;
}
