/* dfp-replay-bench: how fast `dfp-sim replay --check --speed max` gets through a long capture,
 * compared with the telegram rate of a saturated 12 Mbit/s bus, and whether memory stays flat
 * as the capture grows.
 *
 * 1. The saturated bus, computed: back-to-back Data_Exchange cycles with the card's usual
 *    configuration (Param + 3 PD: 14 octets each way, SD2 request and response), min TSDR 11
 *    and TID1 37 bit times (protocol.md §A2.1).
 * 2. Two captures written by dfp-sim's generator (`dfp-sim record --baud 12M`): N/10 and N
 *    telegrams (default N = 1 000 000).
 * 3. Each replayed with the check in a child process (the replay library, as dfp-sim replay
 *    --check --address 4 --baud 12M runs it): telegrams/s, bytes/s, and the child's maximum
 *    resident set size from getrusage (wait4).
 *
 * Usage: dfp-replay-bench [--telegrams N] [--dir DIR] [--keep] */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "replay/generator.h"
#include "replay/replay.h"
#include "sim_hal/host_clock.h"

#define BENCH_BAUD 12000000u

/* ---- 1. the saturated bus ------------------------------------------------------------------ */

typedef struct saturated {
    double cycle_us;
    double telegrams_per_s;
    double bytes_per_s;
} saturated_t;

static saturated_t saturated_12m(void)
{
    const unsigned io = 14u;             /* Param + 3 PD */
    const unsigned sd2 = 9u + io;        /* 68 LE LEr 68 DA SA FC DU FCS ED */
    const unsigned bits = 11u * sd2      /* request */
                          + 11u          /* min TSDR */
                          + 11u * sd2    /* response */
                          + 37u;         /* TID1 before the next request (>= TSYN 33) */
    saturated_t s;
    s.cycle_us = (double)bits * 1e6 / BENCH_BAUD;
    s.telegrams_per_s = 2.0 * 1e6 / s.cycle_us;
    s.bytes_per_s = 2.0 * sd2 * 1e6 / s.cycle_us;
    printf("saturated 12 Mbit/s bus, Data_Exchange with Param + 3 PD (SD2 %u + %u octets):\n"
           "  %u + 11 (min TSDR) + %u + 37 (TID1) = %u bit times = %.2f us per cycle\n"
           "  -> %.0f telegrams/s, %.0f bytes/s\n\n",
           sd2, sd2, 11u * sd2, 11u * sd2, bits, s.cycle_us, s.telegrams_per_s, s.bytes_per_s);
    return s;
}

/* ---- 2. captures ----------------------------------------------------------------------------- */

static int make_capture(const char *path, uint64_t telegrams, gen_result_t *res)
{
    /* Start-up takes about 40 telegrams, every cycle 2 (parameter services ride in them). */
    gen_options_t o = {.path = path, .cycles = (uint32_t)(telegrams / 2u + 50u),
                       .baud = BENCH_BAUD, .address = 4, .param_every = 10,
                       .inverter = CARD_INVERTER_SIM,
                       .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT};
    char err[512];
    uint64_t t0 = host_clock_mono_ns();
    if (gen_run(&o, res, err, sizeof err) != 0) {
        fprintf(stderr, "dfp-replay-bench: %s\n", err);
        return -1;
    }
    double s = (double)(host_clock_mono_ns() - t0) / 1e9;
    struct stat st;
    long long size = stat(path, &st) == 0 ? (long long)st.st_size : -1;
    printf("  %s: %llu telegrams, %llu octets, %lld bytes on disk, %.1f s of bus time; "
           "written in %.2f s\n",
           path, (unsigned long long)res->telegrams, (unsigned long long)res->octets, size,
           (double)res->bus_ns / 1e9, s);
    return 0;
}

/* ---- 3. replay in a child ----------------------------------------------------------------- */

typedef struct run_result {
    uint64_t records;
    uint64_t octets;
    uint64_t requests;
    uint64_t mismatches;
    uint64_t wall_ns;
    int file_ok;
} run_result_t;

static replay_t rp;

static void child_replay(const char *path, int fd)
{
    run_result_t out = {0};
    replay_options_t o = {.address = 4, .check = true, .baud = BENCH_BAUD,
                          .inverter = CARD_INVERTER_SIM,
                          .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT,
                          .speed = REPLAY_SPEED_MAX};
    char err[256];
    if (replay_init(&rp, &o, err, sizeof err) == 0) {
        replay_file_status_t st;
        replay_input_t src = {.path = path, .format = CAP_FORMAT_AUTO};
        uint64_t t0 = host_clock_mono_ns();
        int rc = replay_run_file(&rp, &src, NULL, NULL, NULL, &st);
        out.wall_ns = host_clock_mono_ns() - t0;
        out.file_ok = rc == 0 && !st.read_error;
        out.records = rp.records;
        out.octets = rp.octets;
        out.requests = replay_total_requests(&rp);
        out.mismatches = rp.mismatches;
    }
    ssize_t w = write(fd, &out, sizeof out);
    _exit(w == (ssize_t)sizeof out ? 0 : 1);
}

static int measure(const char *path, run_result_t *res, long *maxrss_kb, double *cpu_s)
{
    int p[2];
    if (pipe(p) != 0) {
        return -1;
    }
    fflush(stdout);
    pid_t pid = fork();
    if (pid < 0) {
        return -1;
    }
    if (pid == 0) {
        close(p[0]);
        child_replay(path, p[1]);
    }
    close(p[1]);
    memset(res, 0, sizeof *res);
    ssize_t n = read(p[0], res, sizeof *res);
    close(p[0]);
    int status = 0;
    struct rusage ru;
    if (wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
        n != (ssize_t)sizeof *res) {
        return -1;
    }
    *maxrss_kb = ru.ru_maxrss;
    *cpu_s = (double)ru.ru_utime.tv_sec + (double)ru.ru_utime.tv_usec / 1e6 +
             (double)ru.ru_stime.tv_sec + (double)ru.ru_stime.tv_usec / 1e6;
    return 0;
}

int main(int argc, char **argv)
{
    uint64_t big = 1000000u;
    const char *dir = NULL;
    bool keep = false;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--telegrams") == 0 && i + 1 < argc) {
            big = strtoull(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--dir") == 0 && i + 1 < argc) {
            dir = argv[++i];
        } else if (strcmp(argv[i], "--keep") == 0) {
            keep = true;
        } else {
            fprintf(stderr, "usage: dfp-replay-bench [--telegrams N] [--dir DIR] [--keep]\n");
            return 2;
        }
    }
    if (big < 1000u) {
        fprintf(stderr, "dfp-replay-bench: --telegrams: at least 1000\n");
        return 2;
    }
    char tmpl[] = "/tmp/dfp-replay-bench.XXXXXX";
    if (dir == NULL) {
        dir = mkdtemp(tmpl);
        if (dir == NULL) {
            fprintf(stderr, "dfp-replay-bench: mkdtemp: %s\n", strerror(errno));
            return 1;
        }
    }
    saturated_t sat = saturated_12m();
    uint64_t sizes[2] = {big / 10u, big};
    char paths[2][600];
    printf("captures (dfp-sim record --baud 12M, parameter services every 10 cycles):\n");
    for (unsigned i = 0; i < 2u; i++) {
        snprintf(paths[i], sizeof paths[i], "%s/bench-%llu.pcap", dir,
                 (unsigned long long)sizes[i]);
        gen_result_t g;
        if (make_capture(paths[i], sizes[i], &g) != 0) {
            return 1;
        }
    }
    printf("\nreplay --check --speed max (address 4, 12 Mbit/s, emulated MOVIDRIVE), one child "
           "process each:\n");
    printf("  %10s %12s %9s %14s %14s %11s %10s %10s\n", "telegrams", "octets", "wall s",
           "telegrams/s", "bytes/s", "x 12M bus", "max RSS", "mismatch");
    long rss[2] = {0, 0};
    int rc = 0;
    for (unsigned i = 0; i < 2u; i++) {
        run_result_t r;
        double cpu = 0;
        if (measure(paths[i], &r, &rss[i], &cpu) != 0 || !r.file_ok) {
            fprintf(stderr, "dfp-replay-bench: replay of %s failed\n", paths[i]);
            return 1;
        }
        double s = (double)r.wall_ns / 1e9;
        double tps = (double)r.records / s;
        printf("  %10llu %12llu %9.2f %14.0f %14.0f %10.1fx %7ld kB %10llu\n",
               (unsigned long long)r.records, (unsigned long long)r.octets, s, tps,
               (double)r.octets / s, tps / sat.telegrams_per_s, rss[i],
               (unsigned long long)r.mismatches);
        if (r.mismatches != 0u || r.requests == 0u) {
            rc = 1;
        }
    }
    printf("\nmax RSS %ld kB at %llu telegrams, %ld kB at %llu: %+ld kB for 10x the capture\n",
           rss[0], (unsigned long long)sizes[0], rss[1], (unsigned long long)sizes[1],
           rss[1] - rss[0]);
    if (!keep) {
        for (unsigned i = 0; i < 2u; i++) {
            unlink(paths[i]);
        }
        if (dir == tmpl) {
            rmdir(dir);
        }
    }
    return rc;
}
