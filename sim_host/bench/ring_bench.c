/* dfp-ring-bench: a token ring of masters with their cards on the in-memory bus, run to steady
 * state (every card in Data_Exchange), then for a given simulated time. Prints how much faster
 * than real time it runs, the token rotation time each master measured against the rotation the
 * bus rules give for the same telegrams, telegrams per second, collisions and late tokens.
 *
 * The rule side of a rotation is built from the frame tap, telegram by telegram: its octets at
 * 11 bit times each, and the idle before it as the rules set it: TID1 before a request or token
 * that follows a reply or a token, TID2 after a request no one answers by design (SDN), TSL
 * after a request whose reply never came, and the responder's TSDR before a reply (the card's
 * own time, measured on the line: request end to reply start). A rotation of master A is the
 * time between the ends of two tokens to A; its rule time is the sum over the telegrams that
 * ended in between. The difference is what the stations add beyond the rules (timers that run
 * in whole microseconds, poll latency). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dp_master/dp_master.h"
#include "dp_slave/fdl_wire.h"
#include "rig/rig.h"
#include "sim_stations/stations.h"

#define MAX_MASTERS 8u
#define PD_OCTETS 14u /* Param + 3 PD: 8 octets parameter channel, 3 words process data */
#define DX_LEN (FDL_SD2_OVERHEAD + FDL_ADDR_FC_LEN + PD_OCTETS) /* one Data_Exchange telegram */
#define STATUS_LEN FDL_SD1_LEN

typedef struct minmax {
    uint64_t n;
    double sum;
    double min;
    double max;
} minmax_t;

static void mm_add(minmax_t *m, double v)
{
    if (m->n == 0u || v < m->min) m->min = v;
    if (m->n == 0u || v > m->max) m->max = v;
    m->sum += v;
    m->n++;
}

static double mm_mean(const minmax_t *m) { return m->n ? m->sum / (double)m->n : 0.0; }

/* What the tap keeps of the telegram before, to place the next one. */
typedef enum kind { K_NONE = 0, K_TOKEN, K_REQ_REPLY, K_REQ_NOREPLY, K_REPLY } kind_t;

typedef struct ring_bench {
    rig_t rig;
    dp_master_t m[MAX_MASTERS];
    unsigned num_masters;
    fdl_bus_params_t bus;
    double bit_ns;
    /* The tap. */
    bool measuring;
    kind_t prev_kind;
    uint64_t prev_end_ns;
    double rule_ns;                   /* the rules' time of everything since measuring began */
    uint64_t tok_end_ns[MAX_MASTERS]; /* the last token to each master (0: none yet) */
    double tok_rule_ns[MAX_MASTERS];
    minmax_t trr[MAX_MASTERS];  /* measured rotations, ns */
    minmax_t rule[MAX_MASTERS]; /* the rules' rotations, ns */
    minmax_t diff_pct;          /* per rotation: (measured - rule) / rule */
    minmax_t tsdr_bits;
    minmax_t tid1_bits; /* the idle measured where the rules put TID1 */
    uint64_t unanswered;
    uint64_t gap_requests;
    uint64_t tokens;
    unsigned ring_events[16];
} ring_bench_t;

static ring_bench_t B; /* large (the rig): static storage, as rig.h asks */

/* ---- the tap: the rules' time of each telegram --------------------------------------------- */

static kind_t kind_of(const uint8_t *f, size_t len, uint8_t *da, uint8_t *fc)
{
    *da = 0xFFu;
    *fc = 0;
    if (len == FDL_SD4_LEN && f[0] == FDL_SD4) {
        *da = f[1];
        return K_TOKEN;
    }
    if (len == FDL_SC_LEN) {
        return K_REPLY;
    }
    size_t at = f[0] == FDL_SD2 ? FDL_SD2_HEADER_LEN : FDL_SD1_SD3_HEADER_LEN;
    if (len < at + FDL_ADDR_FC_LEN) {
        return K_REPLY;
    }
    *da = f[at] & FDL_ADDR_MASK;
    *fc = f[at + FDL_FC_FROM_DA];
    if ((*fc & FDL_FC_REQUEST) == 0u) {
        return K_REPLY;
    }
    uint8_t code = *fc & 0x0Fu;
    bool sdn = code == 0x4u || code == 0x6u || *da == FDL_ADDR_BROADCAST;
    return sdn ? K_REQ_NOREPLY : K_REQ_REPLY;
}

/* The idle the rules put before a telegram of kind k after one of kind prev; a reply's TSDR is
 * the responder's, taken as measured (gap_ns). */
static double rule_idle_ns(ring_bench_t *b, kind_t prev, kind_t k, uint64_t gap_ns)
{
    if (prev == K_NONE) {
        return (double)gap_ns;
    }
    if (k == K_REPLY && prev == K_REQ_REPLY) {
        mm_add(&b->tsdr_bits, (double)gap_ns / b->bit_ns);
        return (double)gap_ns;
    }
    if (prev == K_REQ_NOREPLY) {
        return fdl_bus_tid2_bits(&b->bus) * b->bit_ns;
    }
    if (prev == K_REQ_REPLY) {
        b->unanswered++;
        return b->bus.tsl_bits * b->bit_ns;
    }
    mm_add(&b->tid1_bits, (double)gap_ns / b->bit_ns);
    return fdl_bus_tid1_bits(&b->bus) * b->bit_ns;
}

static void rotation_done(ring_bench_t *b, unsigned i, uint64_t end_ns)
{
    if (b->tok_end_ns[i] != 0u) {
        double measured = (double)(end_ns - b->tok_end_ns[i]);
        double rule = b->rule_ns - b->tok_rule_ns[i];
        mm_add(&b->trr[i], measured);
        mm_add(&b->rule[i], rule);
        mm_add(&b->diff_pct, 100.0 * (measured - rule) / rule);
    }
    b->tok_end_ns[i] = end_ns;
    b->tok_rule_ns[i] = b->rule_ns;
}

static void tap(void *ctx, uint64_t t_ns, const uint8_t *f, size_t len, bool local, uint32_t baud)
{
    (void)local;
    (void)baud;
    ring_bench_t *b = ctx;
    if (!b->measuring) {
        return;
    }
    uint8_t da = 0;
    uint8_t fc = 0;
    kind_t k = kind_of(f, len, &da, &fc);
    uint64_t end_ns = t_ns + (uint64_t)hal_uart_char_ns(b->bus.baud) * len;
    bool after = b->prev_kind != K_NONE && t_ns >= b->prev_end_ns;
    uint64_t gap_ns = after ? t_ns - b->prev_end_ns : 0u;
    b->rule_ns += rule_idle_ns(b, b->prev_kind, k, gap_ns) + (double)len * 11.0 * b->bit_ns;
    b->prev_kind = k;
    b->prev_end_ns = end_ns;
    if (k == K_REQ_REPLY && (fc & 0x0Fu) == 0x9u && len == STATUS_LEN) {
        b->gap_requests++;
    }
    if (k != K_TOKEN) {
        return;
    }
    b->tokens++;
    for (unsigned i = 0; i < b->num_masters; i++) {
        if (b->m[i].cfg.address == da) {
            rotation_done(b, i, end_ns);
        }
    }
}

static void ring_event(void *ctx, const fdl_active_event_t *ev)
{
    ring_bench_t *b = ctx;
    if (b->measuring && (unsigned)ev->type < sizeof b->ring_events / sizeof b->ring_events[0]) {
        b->ring_events[ev->type]++;
    }
}

/* ---- the ring ------------------------------------------------------------------------------ */

static dp_master_whole_t whole_of(const membus_telegram_t *tg)
{
    return (dp_master_whole_t){.data = tg->data, .len = (uint16_t)tg->len,
                               .char_ns = tg->char_ns, .first_t = membus_char_us(tg, 1u),
                               .before_last_t = membus_char_us(tg, tg->len > 1u ? tg->len - 1u
                                                                                : 1u),
                               .end_t = membus_char_us(tg, tg->len)};
}

static bool master_takes(void *ctx, const membus_telegram_t *tg)
{
    dp_master_t *m = ctx;
    dp_master_whole_t w = whole_of(tg);
    return dp_master_whole_clean(&m->rx, &w);
}

static bool master_rx(void *ctx, const membus_telegram_t *tg)
{
    dp_master_whole_t w = whole_of(tg);
    dp_master_rx_telegram(ctx, &w);
    return true;
}

typedef struct bench_args {
    uint32_t baud;
    unsigned masters;
    unsigned cards;
    double seconds;
    uint32_t ttr_bits; /* 0: from the estimate */
} bench_args_t;

/* The rotation the rules give when every card has one Data_Exchange per rotation and one GAP
 * request goes out, with the longest TSDR: the base of the default TTR and the watchdog. */
static uint64_t estimate_bits(const fdl_bus_params_t *p, unsigned masters, unsigned cards)
{
    uint64_t tid1 = fdl_bus_tid1_bits(p);
    uint64_t cycle = 2u * (uint64_t)DX_LEN * 11u + tid1 + p->max_tsdr_bits;
    uint64_t token = (uint64_t)FDL_SD4_LEN * 11u + tid1;
    uint64_t gap = 2u * (uint64_t)STATUS_LEN * 11u + tid1 + p->max_tsdr_bits;
    return cards * cycle + masters * token + gap;
}

/* Masters at 0..masters-1, cards after them, HSA the highest card: every address GAP
 * maintenance asks answers, so no rotation waits out a slot time. Cards are shared out in
 * turn. Returns 0, or 1 after saying what could not be built. */
static int build_ring(ring_bench_t *b, const bench_args_t *a)
{
    memset(b, 0, sizeof *b);
    fdl_bus_params_default(&b->bus, a->baud, FDL_BUS_PROFILE_DP);
    b->bus.hsa = (uint8_t)(a->masters + a->cards - 1u);
    uint64_t est = estimate_bits(&b->bus, a->masters, a->cards);
    b->bus.ttr_bits = a->ttr_bits ? a->ttr_bits : (uint32_t)(2u * est);
    b->bit_ns = 1e9 / (double)a->baud;
    uint32_t wd_ms = (uint32_t)(10u * est * 1000u / a->baud);
    wd_ms = wd_ms < 100u ? 100u : wd_ms;
    char why[160];
    if (!fdl_bus_params_check(&b->bus, why, sizeof why)) {
        fprintf(stderr, "dfp-ring-bench: bus parameters: %s\n", why);
        return 1;
    }
    rig_cfg_t rc = {.medium = RIG_MEDIUM_MEMBUS, .start_ns = 1000000u, .baud = a->baud};
    rig_init(&b->rig, &rc);
    rig_tap_t t = {.ctx = b, .frame = tap};
    (void)rig_add_tap(&b->rig, &t);
    char err[256] = "";
    if (rig_open(&b->rig, err, sizeof err) != 0) {
        fprintf(stderr, "dfp-ring-bench: %s\n", err);
        return 1;
    }
    for (unsigned i = 0; i < a->cards; i++) {
        card_options_t co = {.address = (uint8_t)(a->masters + i), .fixed_baud = a->baud,
                             .strict_timing = true};
        if (rig_add_card(&b->rig, &co, rig_now_us(&b->rig)) == NULL) {
            fprintf(stderr, "dfp-ring-bench: no room for card %u\n", i);
            return 1;
        }
    }
    for (unsigned i = 0; i < a->masters; i++) {
        dp_master_cfg_t mc = {.address = (uint8_t)i, .baud = a->baud, .strict_timing = true,
                              .token_ring = true, .bus = b->bus, .ring_event = ring_event,
                              .event_ctx = b};
        dp_master_t *m = &b->m[i];
        sim_station_t st = master_station(m);
        membus_port_t *p = membus_attach(&b->rig.bus, &st, &mc.uart);
        if (p == NULL) {
            fprintf(stderr, "dfp-ring-bench: no room on the bus for master %u\n", i);
            return 1;
        }
        membus_whole_rx_t whole = {.ctx = m, .takes = master_takes, .rx = master_rx};
        membus_set_whole_rx(p, &whole);
        dp_master_init(m, &mc, rig_now_us(&b->rig));
        for (unsigned c = i; c < a->cards; c += a->masters) {
            dp_master_slave_cfg_t sc = {.address = (uint8_t)(a->masters + c)};
            sc.prm_len = (uint8_t)dp_master_build_prm(sc.prm, DFP21B_IDENT, wd_ms,
                                                      dfp21b_user_prm_default,
                                                      sizeof dfp21b_user_prm_default);
            sc.cfg[0] = 0xF3; /* Param + 3 PD */
            sc.cfg[1] = 0xF2;
            sc.cfg_len = 2;
            if (dp_master_add_slave(m, &sc) < 0) {
                fprintf(stderr, "dfp-ring-bench: master %u takes no more slaves\n", i);
                return 1;
            }
        }
    }
    b->num_masters = a->masters;
    return 0;
}

static bool all_exchanging(const ring_bench_t *b)
{
    for (unsigned i = 0; i < b->rig.num_cards; i++) {
        if (dp_slave_state(&b->rig.cards[i].cs.card.dp) != DP_STATE_DATA_EXCH) {
            return false;
        }
    }
    for (unsigned i = 0; i < b->num_masters; i++) {
        for (unsigned s = 0; s < b->m[i].num_slaves; s++) {
            if (b->m[i].slaves[s].phase != DP_MASTER_PHASE_DATA_EXCH) {
                return false;
            }
        }
    }
    return true;
}

/* ---- running and the figures --------------------------------------------------------------- */

static double clock_s(clockid_t id)
{
    struct timespec ts;
    (void)clock_gettime(id, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static uint64_t sum_late_tokens(const ring_bench_t *b)
{
    uint64_t n = 0;
    for (unsigned i = 0; i < b->num_masters; i++) {
        n += dp_master_ring(&b->m[i])->stats.late_tokens;
    }
    return n;
}

/* Start-up until every card exchanges data, in slices of a hundredth of the estimated rotation;
 * bounded by 1000 rotations and 10 s of bus time. False when it never got there. */
static bool run_to_steady_state(ring_bench_t *b, const bench_args_t *a)
{
    uint64_t est = estimate_bits(&b->bus, a->masters, a->cards);
    uint64_t slice_ns = (uint64_t)((double)est * b->bit_ns / 100.0) + 1000u;
    uint64_t limit_ns = b->rig.bus.now_ns + 10000000000ull + slice_ns * 100000u;
    double w0 = clock_s(CLOCK_MONOTONIC);
    uint64_t t0 = b->rig.bus.now_ns;
    while (!all_exchanging(b)) {
        if (b->rig.bus.now_ns >= limit_ns) {
            fprintf(stderr, "dfp-ring-bench: not every card in Data_Exchange after %.3f s of "
                            "bus time\n", (double)(b->rig.bus.now_ns - t0) / 1e9);
            return false;
        }
        membus_run_until_ns(&b->rig.bus, b->rig.bus.now_ns + slice_ns);
    }
    printf("start-up: every card in Data_Exchange after %.3f ms of bus time (%.1f ms wall)\n",
           (double)(b->rig.bus.now_ns - t0) / 1e6, (clock_s(CLOCK_MONOTONIC) - w0) * 1e3);
    return true;
}

static void print_rotations(const ring_bench_t *b)
{
    printf("\ntoken rotation (TRR: token end to token end at each master; rules: the sum of "
           "telegram and idle times of the same rotation), us:\n"
           "  %-7s %9s %10s %10s %10s %10s %10s %10s %8s %10s\n", "master", "rotations",
           "TRR mean", "min", "max", "rules mean", "min", "max", "diff", "fdl TRR");
    minmax_t all_trr = {0};
    minmax_t all_rule = {0};
    for (unsigned i = 0; i < b->num_masters; i++) {
        const minmax_t *t = &b->trr[i];
        const minmax_t *r = &b->rule[i];
        if (t->n == 0u) {
            printf("  %-7u %9s\n", b->m[i].cfg.address, "none");
            continue;
        }
        printf("  %-7u %9llu %10.2f %10.2f %10.2f %10.2f %10.2f %10.2f %+7.2f%% %10u\n",
               b->m[i].cfg.address, (unsigned long long)t->n, mm_mean(t) / 1e3, t->min / 1e3,
               t->max / 1e3, mm_mean(r) / 1e3, r->min / 1e3, r->max / 1e3,
               100.0 * (mm_mean(t) - mm_mean(r)) / mm_mean(r),
               (unsigned)dp_master_ring(&b->m[i])->stats.trr_us);
        all_trr.sum += t->sum;
        all_trr.n += t->n;
        all_rule.sum += r->sum;
        all_rule.n += r->n;
    }
    if (all_trr.n > 0u) {
        printf("  %-7s %9llu %10.2f %32.2f %29s%+7.2f%%\n", "all", (unsigned long long)all_trr.n,
               mm_mean(&all_trr) / 1e3, mm_mean(&all_rule) / 1e3, "",
               100.0 * (mm_mean(&all_trr) - mm_mean(&all_rule)) / mm_mean(&all_rule));
        printf("  per rotation, measured against rules: mean %+.2f %%, min %+.2f %%, "
               "max %+.2f %% (goal: within 1 %%)\n", mm_mean(&b->diff_pct), b->diff_pct.min,
               b->diff_pct.max);
    }
    if (b->tsdr_bits.n > 0u) {
        printf("  TSDR (request end to reply start, on the line): mean %.1f, min %.1f, max %.1f "
               "bit times; TID1 %u, TID2 %u, TSL %u bit times\n", mm_mean(&b->tsdr_bits),
               b->tsdr_bits.min, b->tsdr_bits.max, (unsigned)fdl_bus_tid1_bits(&b->bus),
               (unsigned)fdl_bus_tid2_bits(&b->bus), (unsigned)b->bus.tsl_bits);
    }
    if (b->tid1_bits.n > 0u) {
        printf("  idle where the rules put TID1 (%u bit times), on the line: mean %.1f, "
               "min %.1f, max %.1f bit times\n", (unsigned)fdl_bus_tid1_bits(&b->bus),
               mm_mean(&b->tid1_bits), b->tid1_bits.min, b->tid1_bits.max);
    }
}

/* The measured run. Returns 0, or 1 when a collision or a lost token showed something wrong.
 * noinline: callgrind --toggle-collect=measure profiles the steady state alone. */
__attribute__((noinline)) static int measure(ring_bench_t *b, const bench_args_t *a)
{
    uint64_t frames0 = b->rig.bus.frames_sent;
    uint64_t coll0 = b->rig.bus.collisions;
    uint64_t late0 = sum_late_tokens(b);
    uint64_t whole0 = b->rig.bus.telegrams_whole;
    uint64_t split0 = b->rig.bus.telegrams_split;
    uint64_t t0 = b->rig.bus.now_ns;
    uint64_t t_end = t0 + (uint64_t)llround(a->seconds * 1e9);
    b->measuring = true;
    double w0 = clock_s(CLOCK_MONOTONIC);
    double c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    membus_run_until_ns(&b->rig.bus, t_end);
    double wall = clock_s(CLOCK_MONOTONIC) - w0;
    double cpu = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
    b->measuring = false;
    double sim = (double)(b->rig.bus.now_ns - t0) / 1e9;
    uint64_t frames = b->rig.bus.frames_sent - frames0;
    uint64_t coll = b->rig.bus.collisions - coll0;
    uint64_t late = sum_late_tokens(b) - late0;
    printf("run: %.3f s of bus time in %.3f s wall, %.3f s CPU: %.2fx real time "
           "(goal: at least 20x)\n", sim, wall, cpu, wall > 0 ? sim / wall : 0.0);
    print_rotations(b);
    printf("\ntelegrams: %.0f per s of bus time (%llu in all; %llu tokens, %llu GAP requests, "
           "%llu requests unanswered)\n", (double)frames / sim, (unsigned long long)frames,
           (unsigned long long)b->tokens, (unsigned long long)b->gap_requests,
           (unsigned long long)b->unanswered);
    printf("bus: %llu telegrams delivered whole, %llu split into characters\n",
           (unsigned long long)(b->rig.bus.telegrams_whole - whole0),
           (unsigned long long)(b->rig.bus.telegrams_split - split0));
    printf("collisions: %llu\nlate tokens: %llu\n", (unsigned long long)coll,
           (unsigned long long)late);
    printf("ring events: %u claims, %u stations skipped, %u double tokens\n",
           b->ring_events[FDL_EV_CLAIM], b->ring_events[FDL_EV_PASS_FAILED],
           b->ring_events[FDL_EV_DOUBLE_TOKEN]);
    return coll == 0u && b->ring_events[FDL_EV_CLAIM] == 0u ? 0 : 1;
}

/* ---- options ------------------------------------------------------------------------------- */

static const char usage[] =
    "usage: dfp-ring-bench [--rate BAUD] [--masters N] [--cards N] [--seconds S] [--ttr BITS]\n"
    "\n"
    "A token ring of N masters (addresses 0..N-1) sharing the cards (DFP21B, Param + 3 PD, the\n"
    "addresses after the masters) on the in-memory bus: runs it until every card is in\n"
    "Data_Exchange, then for S seconds of bus time, and prints the speed against real time, the\n"
    "token rotation times against the bus rules, telegrams per second, collisions and late\n"
    "tokens. Exit status 1 when start-up did not finish or a collision or lost token occurred.\n"
    "\n"
    "  --rate BAUD    a PROFIBUS rate in bit/s (9600 .. 12000000; default 12000000)\n"
    "  --masters N    1..8 (default 5)\n"
    "  --cards N      1..126 - masters, at most 32 per master (default 100)\n"
    "  --seconds S    bus time measured, 0 < S <= 3600 (default 2)\n"
    "  --ttr BITS     target rotation time in bit times, 256..16777215 (default: twice the\n"
    "                 rotation the rules give for the configuration)\n"
    "  --help         this text\n";

static bool is_rate(unsigned long v)
{
    for (unsigned i = 0; i < HAL_UART_NUM_BAUDS; i++) {
        if (hal_uart_bauds[i] == v) {
            return true;
        }
    }
    return false;
}

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
    if (strcmp(opt, "--rate") == 0) {
        ok = parse_ulong(val, 9600u, 12000000u, &v) && is_rate(v);
        a->baud = (uint32_t)v;
        want = "a PROFIBUS rate in bit/s";
    } else if (strcmp(opt, "--masters") == 0) {
        ok = parse_ulong(val, 1u, MAX_MASTERS, &v);
        a->masters = (unsigned)v;
        want = "1..8";
    } else if (strcmp(opt, "--cards") == 0) {
        ok = parse_ulong(val, 1u, RIG_MAX_CARDS, &v);
        a->cards = (unsigned)v;
        want = "1..126";
    } else if (strcmp(opt, "--seconds") == 0) {
        ok = parse_seconds(val, &a->seconds);
        want = "0 < S <= 3600";
    } else if (strcmp(opt, "--ttr") == 0) {
        ok = parse_ulong(val, 256u, 16777215u, &v);
        a->ttr_bits = (uint32_t)v;
        want = "256..16777215 bit times";
    } else {
        fprintf(stderr, "dfp-ring-bench: unknown option %s (see --help)\n", opt);
        return false;
    }
    if (!ok) {
        if (val == NULL) {
            fprintf(stderr, "dfp-ring-bench: %s needs a value (%s)\n", opt, want);
        } else {
            fprintf(stderr, "dfp-ring-bench: %s: bad value '%s' (%s)\n", opt, val, want);
        }
    }
    return ok;
}

/* Returns -1 to go on, else the exit status. */
static int parse_args(int argc, char **argv, bench_args_t *a)
{
    for (int i = 1; i < argc; i += 2) { /* each option takes one value */
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        }
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!parse_option(argv[i], val, a)) {
            return 2;
        }
    }
    if (a->masters + a->cards > RIG_MAX_CARDS) {
        fprintf(stderr, "dfp-ring-bench: %u masters and %u cards need more than the %u "
                        "addresses 0..125\n", a->masters, a->cards, (unsigned)RIG_MAX_CARDS);
        return 2;
    }
    if (a->cards > a->masters * DP_MASTER_MAX_SLAVES) {
        fprintf(stderr, "dfp-ring-bench: %u cards are more than %u masters can hold (%u each)\n",
                a->cards, a->masters, (unsigned)DP_MASTER_MAX_SLAVES);
        return 2;
    }
    return -1;
}

int main(int argc, char **argv)
{
    bench_args_t a = {.baud = 12000000u, .masters = 5u, .cards = 100u, .seconds = 2.0};
    int rc = parse_args(argc, argv, &a);
    if (rc >= 0) {
        return rc;
    }
    if (build_ring(&B, &a) != 0) {
        return 1;
    }
    printf("dfp-ring-bench: %u masters, %u cards (DFP21B, Param + 3 PD), %u bit/s, in-memory "
           "bus\nbus parameters: TSL %u, max TSDR %u, TID1 %u, TTR %u bit times (%.3f ms), "
           "G %u, HSA %u\n", a.masters, a.cards, (unsigned)a.baud, (unsigned)B.bus.tsl_bits,
           (unsigned)B.bus.max_tsdr_bits, (unsigned)fdl_bus_tid1_bits(&B.bus),
           (unsigned)B.bus.ttr_bits, B.bus.ttr_bits * B.bit_ns / 1e6, B.bus.gap_factor,
           B.bus.hsa);
    if (!run_to_steady_state(&B, &a)) {
        return 1;
    }
    return measure(&B, &a);
}
