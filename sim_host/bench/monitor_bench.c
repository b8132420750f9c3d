/* dfp-monitor-bench: what the bus monitor (sim_host/monitor) costs.
 *
 * 1. A saturated 12 Mbit/s line: two masters (1 and 2) passing the token, each polling its
 *    slaves (3.. ) with short Data_Exchange: half of them outputs only (SD2 with one octet,
 *    answered SC), half inputs only (SD1, answered SD2 with one octet); every slave started up
 *    first (Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag). The telegrams are built with their line
 *    times (11 bit times an octet, min TSDR 11 before an answer, TID1 37 after an answer or a
 *    token) into one buffer of whole rounds, which is then fed to mon_telegram again and again,
 *    shifted in time, for the line time asked. Only the feeding is timed (the process's CPU
 *    clock): the monitor's CPU time per second of line time, as a share of one core. The same
 *    line is then also written to a pcapng file as the monitor command does (pcapng_writer.h),
 *    and that is timed on its own.
 * 2. Offline: a capture written by dfp-sim's generator (the one dfp-replay-bench replays: 12
 *    Mbit/s, Param + 3 PD, a parameter service every 10 cycles) read through the capture reader
 *    into the monitor, telegrams per second (wall and CPU), and the reader alone for comparison.
 *
 * Usage: dfp-monitor-bench [--seconds S] [--slaves N] [--telegrams N] [--dir DIR] */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "capture/capture.h"
#include "capture/pcapng_writer.h"
#include "dp_slave/dp_wire.h"
#include "dp_slave/fdl_frame.h"
#include "dp_slave/fdl_wire.h"
#include "monitor/mon_chars.h"
#include "monitor/monitor.h"
#include "replay/generator.h"
#include "replay/replay.h"
#include "sim_hal/host_clock.h"

#define LINE_BAUD 12000000u
#define TSDR_BITS FDL_MIN_TSDR_DEFAULT_BITS
#define TID1_BITS 37u
#define MASTER_A 1u
#define MASTER_B 2u
#define FIRST_SLAVE 3u
#define MAX_SLAVES 120u
#define IDENT 0x6003u
#define MAX_TELEGRAM 16u /* the longest one the line bench builds (Set_Prm: 15 octets) */

typedef struct bench_args {
    double seconds;
    unsigned slaves;
    unsigned long telegrams;
    const char *dir;
} bench_args_t;

/* ---- 1. the line -------------------------------------------------------------------------- */

typedef struct telegram {
    uint64_t start_ns; /* from the start of the buffer */
    uint64_t end_ns;
    uint8_t len;
    uint8_t f[MAX_TELEGRAM];
} telegram_t;

/* The line being built: telegrams back to back at their bit times. */
typedef struct line {
    telegram_t *t;
    size_t n;
    size_t cap;
    uint64_t bits; /* line time so far, in bit times */
    bool fcb[MAX_SLAVES + FIRST_SLAVE]; /* the next request's FCB to each slave */
    bool fcv[MAX_SLAVES + FIRST_SLAVE]; /* FCV set once the slave had its first request */
} line_t;

static uint64_t bits_ns(uint64_t bits)
{
    return bits * 1000000000ull / LINE_BAUD;
}

/* One telegram after idle_bits of silence. */
static void put(line_t *l, const uint8_t *f, size_t len, uint32_t idle_bits)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? l->cap * 2u : 4096u;
        l->t = realloc(l->t, l->cap * sizeof *l->t);
        if (l->t == NULL) {
            fputs("dfp-monitor-bench: out of memory\n", stderr);
            exit(1);
        }
    }
    telegram_t *t = &l->t[l->n++];
    l->bits += idle_bits;
    t->start_ns = bits_ns(l->bits);
    l->bits += FDL_CHAR_BITS * len;
    t->end_ns = bits_ns(l->bits);
    t->len = (uint8_t)len;
    memcpy(t->f, f, len);
}

/* A request of master ma to slave da (FCB toggled as a master does), then its answer. */
static void request(line_t *l, uint8_t ma, uint8_t da, bool saps, uint8_t dsap,
                    const uint8_t *du, size_t du_len, const uint8_t *answer, size_t ans_len)
{
    uint8_t fc = FDL_FC_REQUEST | FDL_REQ_SRD_HIGH;
    if (!l->fcv[da]) {
        fc |= FDL_FC_FCB; /* the first request: FCB 1, FCV 0 */
        l->fcv[da] = true;
    } else {
        fc |= FDL_FC_FCV | (l->fcb[da] ? FDL_FC_FCB : 0u);
        l->fcb[da] = !l->fcb[da];
    }
    uint8_t f[FDL_FRAME_MAX];
    size_t n = fdl_encode(f, da, ma, fc, saps, dsap, DP_SAP_MASTER, du, du_len);
    put(l, f, n, TID1_BITS);
    put(l, answer, ans_len, TSDR_BITS);
}

/* The answer of slave sa to master da: SC without data, else a DL response. */
static size_t answer(uint8_t *out, uint8_t sa, uint8_t da, bool saps, const uint8_t *du,
                     size_t du_len)
{
    if (du_len == 0u && !saps) {
        out[0] = FDL_SC;
        return 1u;
    }
    return fdl_encode(out, da, sa, FDL_RSP_DL, saps, DP_SAP_MASTER, DP_SAP_SLAVE_DIAG, du,
                      du_len);
}

static void token(line_t *l, uint8_t from, uint8_t to)
{
    const uint8_t f[] = {FDL_SD4, to, from};
    put(l, f, sizeof f, TID1_BITS);
}

static bool outputs_only(unsigned i) { return i % 2u == 0u; }

static uint8_t master_of(const bench_args_t *a, unsigned i)
{
    return i < (a->slaves + 1u) / 2u ? MASTER_A : MASTER_B;
}

/* Slave_Diag, Set_Prm, Chk_Cfg, Slave_Diag: the slave ends in Data_Exchange. */
static void start_slave(line_t *l, const bench_args_t *a, unsigned i)
{
    uint8_t ans[FDL_FRAME_MAX];
    uint8_t s = (uint8_t)(FIRST_SLAVE + i);
    uint8_t ma = master_of(a, i);
    const uint8_t diag_prm[] = {0x00, 0x05, 0x00, MON_NO_MASTER, IDENT >> 8, IDENT & 0xFF};
    const uint8_t diag_ok[] = {0x00, 0x0C, 0x00, ma, IDENT >> 8, IDENT & 0xFF};
    /* Lock_Req and WD_On, watchdog 10 x 10 ms, min TSDR 11, the ident, group 0 */
    const uint8_t prm[] = {0x88, 10, 10, TSDR_BITS, IDENT >> 8, IDENT & 0xFF, 0x00};
    const uint8_t cfg[] = {outputs_only(i) ? 0x20 : 0x10}; /* 1 octet out / in */
    size_t n = answer(ans, s, ma, true, diag_prm, sizeof diag_prm);
    request(l, ma, s, true, DP_SAP_SLAVE_DIAG, NULL, 0, ans, n);
    ans[0] = FDL_SC;
    request(l, ma, s, true, DP_SAP_SET_PRM, prm, sizeof prm, ans, 1);
    request(l, ma, s, true, DP_SAP_CHK_CFG, cfg, sizeof cfg, ans, 1);
    n = answer(ans, s, ma, true, diag_ok, sizeof diag_ok);
    request(l, ma, s, true, DP_SAP_SLAVE_DIAG, NULL, 0, ans, n);
}

/* Every slave started up by its master, the token passing between them as in a round. */
static void start_up(line_t *l, const bench_args_t *a)
{
    for (unsigned i = 0; i < a->slaves; i++) {
        if (i > 0u && master_of(a, i) != master_of(a, i - 1u)) {
            token(l, MASTER_A, MASTER_B);
        }
        start_slave(l, a, i);
    }
    token(l, master_of(a, a->slaves - 1u), MASTER_A);
}

/* One round: master A polls its slaves, passes the token to B, B polls its own and passes it
 * back. */
static void round_of_data(line_t *l, const bench_args_t *a, unsigned r)
{
    uint8_t ans[FDL_FRAME_MAX];
    for (unsigned i = 0; i < a->slaves; i++) {
        uint8_t s = (uint8_t)(FIRST_SLAVE + i);
        uint8_t ma = master_of(a, i);
        if (i > 0u && ma != master_of(a, i - 1u)) {
            token(l, MASTER_A, MASTER_B);
        }
        uint8_t data = (uint8_t)(r + i);
        if (outputs_only(i)) {
            ans[0] = FDL_SC;
            request(l, ma, s, false, 0, &data, 1, ans, 1);
        } else {
            size_t n = fdl_encode(ans, ma, s, FDL_RSP_DL, false, 0, 0, &data, 1);
            request(l, ma, s, false, 0, NULL, 0, ans, n);
        }
    }
    token(l, master_of(a, a->slaves - 1u), MASTER_A);
}

/* Whole rounds covering at least `seconds` (at most one second) of line time, an even number
 * so that every slave's FCB goes on alternating when the buffer is fed again. */
static void build_rounds(line_t *l, const bench_args_t *a)
{
    uint64_t want_ns = (uint64_t)((a->seconds < 1.0 ? a->seconds : 1.0) * 1e9);
    l->n = 0;
    l->bits = 0;
    for (unsigned r = 0; r < 2u || bits_ns(l->bits) < want_ns || r % 2u != 0u; r++) {
        round_of_data(l, a, r);
    }
}

static double cpu_s(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

/* The command prints every event as it comes: the bench's callback at least looks at it. */
static void count_event(void *ctx, const mon_event_t *ev)
{
    uint64_t *levels = ctx;
    levels[ev->level]++;
}

static mon_t mon; /* large (every station's images): static storage */
static mon_chars_t chars;
static pcapng_writer_t png;

/* Where the telegrams go: the monitor whole (mon_telegram, as from the in-memory bus or a
 * capture), the monitor through its character receiver (each telegram in one read, as a tty
 * at 12 Mbit/s delivers them at best), or the pcapng record. */
typedef enum sink { TO_MONITOR, TO_CHARS, TO_PCAPNG } sink_t;

typedef struct fed {
    uint64_t telegrams;
    uint64_t line_ns;
    double cpu;
} fed_t;

/* The buffer fed reps times, each copy shifted by the buffer's line time. */
static fed_t feed(const line_t *l, uint64_t t0, unsigned reps, sink_t to)
{
    fed_t r = {0};
    uint64_t span = bits_ns(l->bits);
    double c0 = cpu_s();
    for (unsigned k = 0; k < reps; k++) {
        uint64_t base = t0 + (uint64_t)k * span;
        for (size_t i = 0; i < l->n; i++) {
            const telegram_t *t = &l->t[i];
            if (to == TO_MONITOR) {
                mon_telegram(&mon, t->f, t->len, base + t->start_ns, base + t->end_ns);
            } else if (to == TO_CHARS) {
                mon_chars_feed(&chars, t->f, NULL, t->len, base + t->end_ns);
            } else {
                (void)pcapng_writer_telegram(&png, base + t->start_ns, t->f, t->len);
            }
        }
        if (to == TO_PCAPNG) {
            (void)pcapng_writer_tick(&png, base + span);
        }
    }
    r.cpu = cpu_s() - c0;
    r.telegrams = (uint64_t)reps * l->n;
    r.line_ns = (uint64_t)reps * span;
    return r;
}

static unsigned slaves_in_data_exchange(const bench_args_t *a)
{
    unsigned n = 0;
    for (unsigned i = 0; i < a->slaves; i++) {
        n += mon.st[FIRST_SLAVE + i].dp_state == MON_DP_DATA_EXCH;
    }
    return n;
}

static void print_share(const char *what, const fed_t *f)
{
    double line_s = (double)f->line_ns / 1e9;
    double cpu = f->cpu > 1e-9 ? f->cpu : 1e-9; /* a run shorter than the clock's tick */
    printf("%s: %.3f s CPU for %.3f s of line time: %.0f ns a telegram, %.0f telegrams/s of "
           "CPU\n  -> %.2f %% of one core (%.1f ms CPU per second of line)\n", what, f->cpu,
           line_s, cpu * 1e9 / (double)f->telegrams, (double)f->telegrams / cpu,
           100.0 * cpu / line_s, 1000.0 * cpu / line_s);
}

typedef struct bench_line {
    line_t up;     /* the start-up */
    line_t rounds; /* whole rounds of data exchange, fed again and again */
    unsigned reps;
} bench_line_t;

/* A fresh monitor fed the start-up and the rounds (whole or by characters); 0 when it counted
 * every telegram as one, none garbled, and put every slave in Data_Exch without a warning. */
static int monitor_pass(const bench_line_t *bl, const bench_args_t *a, sink_t to)
{
    uint64_t levels[MON_LEVEL_ERROR + 1] = {0};
    mon_cfg_t cfg = {.baud = LINE_BAUD, .timing = true, .on_event = count_event,
                     .ctx = levels};
    mon_init(&mon, &cfg);
    mon_chars_init(&chars, &mon, LINE_BAUD);
    fed_t up = feed(&bl->up, 0, 1, to);
    fed_t f = feed(&bl->rounds, up.line_ns, bl->reps, to);
    print_share(to == TO_CHARS ? "monitor, by characters" : "monitor", &f);
    unsigned dx = slaves_in_data_exchange(a);
    uint64_t warnings = levels[MON_LEVEL_WARN] + levels[MON_LEVEL_ERROR];
    printf("  %llu telegrams, %llu garbled, %u of %u slaves in Data_Exch, %llu events "
           "(%llu warnings or errors)\n", (unsigned long long)mon.line.telegrams,
           (unsigned long long)mon.line.garbled, dx, a->slaves,
           (unsigned long long)mon.events_total, (unsigned long long)warnings);
    uint64_t want = up.telegrams + f.telegrams;
    return mon.line.telegrams == want && mon.line.garbled == 0u && dx == a->slaves &&
                   warnings == 0u
               ? 0
               : 1;
}

static int pcapng_pass(const bench_line_t *bl, const bench_args_t *a)
{
    char path[600];
    snprintf(path, sizeof path, "%s/dfp-monitor-bench-%ld.pcapng", a->dir, (long)getpid());
    char err[800];
    pcapng_writer_opt_t o = {.baud = LINE_BAUD, .if_name = "dfp-monitor-bench"};
    if (pcapng_writer_open(&png, path, &o, err, sizeof err) != 0) {
        fprintf(stderr, "dfp-monitor-bench: %s\n", err);
        return 1;
    }
    fed_t p = feed(&bl->rounds, 0, bl->reps, TO_PCAPNG);
    double c0 = cpu_s();
    int closed = pcapng_writer_close(&png);
    p.cpu += cpu_s() - c0;
    print_share("pcapng record", &p);
    (void)unlink(path);
    if (closed != 0 || png.records != p.telegrams) {
        fprintf(stderr, "dfp-monitor-bench: %s: %llu of %llu records written\n", path,
                (unsigned long long)png.records, (unsigned long long)p.telegrams);
        return 1;
    }
    return 0;
}

static int run_line(const bench_args_t *a)
{
    static bench_line_t bl;
    start_up(&bl.up, a);
    memcpy(bl.rounds.fcb, bl.up.fcb, sizeof bl.up.fcb); /* FCBs go on from the start-up */
    memcpy(bl.rounds.fcv, bl.up.fcv, sizeof bl.up.fcv);
    build_rounds(&bl.rounds, a);
    bl.reps = (unsigned)ceil(a->seconds * 1e9 / (double)bits_ns(bl.rounds.bits));
    uint64_t line_ns = (uint64_t)bl.reps * bits_ns(bl.rounds.bits);
    printf("line: 12 Mbit/s, masters %u and %u passing the token, %u slaves (Data_Exchange "
           "of one octet: SD2 -> SC, SD1 -> SD2), min TSDR %u, TID1 %u bit times\n"
           "fed: %llu telegrams in %.3f s of line time: %.0f telegrams/s of line\n",
           MASTER_A, MASTER_B, a->slaves, TSDR_BITS, TID1_BITS,
           (unsigned long long)bl.reps * bl.rounds.n, (double)line_ns / 1e9,
           (double)bl.reps * (double)bl.rounds.n * 1e9 / (double)line_ns);
    int rc = monitor_pass(&bl, a, TO_MONITOR);
    rc |= monitor_pass(&bl, a, TO_CHARS);
    rc |= pcapng_pass(&bl, a);
    free(bl.up.t);
    free(bl.rounds.t);
    return rc;
}

/* ---- 2. offline: a capture through the reader into the monitor ---------------------------- */

static cap_record_t rec;

/* Reads the whole capture, into the monitor when into_monitor; returns records, 0 on error. */
static uint64_t read_capture(const char *path, bool into_monitor, double *wall, double *cpu)
{
    cap_reader_t *r = calloc(1, sizeof *r);
    char err[1200];
    if (r == NULL || cap_reader_open(r, path, CAP_FORMAT_AUTO, err, sizeof err) != 0) {
        fprintf(stderr, "dfp-monitor-bench: %s\n", r != NULL ? err : "out of memory");
        free(r);
        return 0;
    }
    mon_cfg_t cfg = {.baud = LINE_BAUD, .timing = true};
    mon_init(&mon, &cfg);
    uint64_t w0 = host_clock_mono_ns();
    double c0 = cpu_s();
    int rc;
    while ((rc = cap_reader_next(r, &rec)) == 1) {
        if (into_monitor) {
            mon_telegram(&mon, rec.data, rec.len, rec.t_ns, rec.t_ns);
        }
    }
    *cpu = cpu_s() - c0;
    *wall = (double)(host_clock_mono_ns() - w0) / 1e9;
    uint64_t n = r->records;
    if (rc < 0) {
        fprintf(stderr, "dfp-monitor-bench: %s\n", r->error);
        n = 0;
    }
    cap_reader_close(r);
    free(r);
    return n;
}

static int run_offline(const bench_args_t *a)
{
    char path[600];
    snprintf(path, sizeof path, "%s/dfp-monitor-bench-%ld.pcap", a->dir, (long)getpid());
    gen_options_t o = {.path = path, .cycles = (uint32_t)(a->telegrams / 2u + 50u),
                       .baud = LINE_BAUD, .address = 4, .param_every = 10,
                       .inverter = CARD_INVERTER_SIM,
                       .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT};
    gen_result_t g;
    char err[512];
    if (gen_run(&o, &g, err, sizeof err) != 0) {
        fprintf(stderr, "dfp-monitor-bench: %s\n", err);
        return 1;
    }
    printf("\noffline: %s, %llu telegrams (dfp-sim record's generator, 12 Mbit/s, Param + 3 "
           "PD)\n", path, (unsigned long long)g.telegrams);
    double wall_r = 0;
    double cpu_r = 0;
    double wall_m = 0;
    double cpu_m = 0;
    uint64_t nr = read_capture(path, false, &wall_r, &cpu_r);
    uint64_t nm = read_capture(path, true, &wall_m, &cpu_m);
    (void)unlink(path);
    if (nr == 0u || nm != nr) {
        return 1;
    }
    printf("reader alone: %.3f s wall, %.3f s CPU: %.0f telegrams/s\n", wall_r, cpu_r,
           (double)nr / wall_r);
    printf("reader + monitor: %.3f s wall, %.3f s CPU: %.0f telegrams/s (the monitor %.0f ns a "
           "telegram)\n", wall_m, cpu_m, (double)nm / wall_m, (cpu_m - cpu_r) * 1e9 / (double)nm);
    printf("monitor: %llu telegrams, %llu garbled, %llu events\n",
           (unsigned long long)mon.line.telegrams, (unsigned long long)mon.line.garbled,
           (unsigned long long)mon.events_total);
    return mon.line.telegrams + mon.line.garbled == nm ? 0 : 1;
}

/* ---- options ------------------------------------------------------------------------------- */

static const char usage[] =
    "usage: dfp-monitor-bench [--seconds S] [--slaves N] [--telegrams N] [--dir DIR]\n"
    "\n"
    "What the bus monitor costs. 1: a saturated 12 Mbit/s line (two masters, N slaves with\n"
    "short Data_Exchange) fed to the monitor for S seconds of line time: CPU time per second\n"
    "of line, as a share of one core; the same line written as pcapng. 2: a capture of about\n"
    "N telegrams (dfp-sim record's generator) read into the monitor: telegrams per second.\n"
    "Exit status 1 when the monitor did not count every telegram.\n"
    "\n"
    "  --seconds S    line time fed, 0 < S <= 3600 (default 10)\n"
    "  --slaves N     2..120 (default 60)\n"
    "  --telegrams N  the offline capture, 1000..100000000 (default 1000000)\n"
    "  --dir DIR      where the files are written and removed (default /tmp)\n"
    "  --help         this text\n";

static bool parse_ulong(const char *s, unsigned long lo, unsigned long hi, unsigned long *v)
{
    char *end = NULL;
    errno = 0;
    if (s == NULL || *s == '-' || *s == '\0') {
        return false;
    }
    *v = strtoul(s, &end, 10);
    return errno == 0 && *end == '\0' && *v >= lo && *v <= hi;
}

static bool parse_seconds(const char *s, double *v)
{
    char *end = NULL;
    errno = 0;
    if (s == NULL || *s == '\0') {
        return false;
    }
    *v = strtod(s, &end);
    return errno == 0 && *end == '\0' && isfinite(*v) && *v > 0.0 && *v <= 3600.0;
}

/* One option and its value; returns false after a one-line error. */
static bool parse_option(const char *opt, const char *val, bench_args_t *a)
{
    unsigned long v = 0;
    bool ok = false;
    const char *want = "";
    if (strcmp(opt, "--seconds") == 0) {
        ok = parse_seconds(val, &a->seconds);
        want = "0 < S <= 3600";
    } else if (strcmp(opt, "--slaves") == 0) {
        ok = parse_ulong(val, 2u, MAX_SLAVES, &v);
        a->slaves = (unsigned)v;
        want = "2..120";
    } else if (strcmp(opt, "--telegrams") == 0) {
        ok = parse_ulong(val, 1000u, 100000000u, &v);
        a->telegrams = v;
        want = "1000..100000000";
    } else if (strcmp(opt, "--dir") == 0) {
        ok = val != NULL && *val != '\0';
        a->dir = val;
        want = "a directory";
    } else {
        fprintf(stderr, "dfp-monitor-bench: unknown option %s (see --help)\n", opt);
        return false;
    }
    if (!ok) {
        if (val == NULL) {
            fprintf(stderr, "dfp-monitor-bench: %s needs a value (%s)\n", opt, want);
        } else {
            fprintf(stderr, "dfp-monitor-bench: %s: bad value '%s' (%s)\n", opt, val, want);
        }
    }
    return ok;
}

int main(int argc, char **argv)
{
    bench_args_t a = {.seconds = 10.0, .slaves = 60u, .telegrams = 1000000u, .dir = "/tmp"};
    for (int i = 1; i < argc; i += 2) { /* each option takes one value */
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        }
        if (!parse_option(argv[i], i + 1 < argc ? argv[i + 1] : NULL, &a)) {
            return 2;
        }
    }
    printf("dfp-monitor-bench: sizeof(mon_t) %zu bytes\n", sizeof(mon_t));
    int rc = run_line(&a);
    int rc2 = run_offline(&a);
    return rc != 0 ? rc : rc2;
}
