/* dfp-sim record: a capture made on the simulated bus by the replay library's generator
 * (docs/replay.md "dfp-sim record"). */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "progress.h"
#include "replay/generator.h"
#include "replay/replay.h"
#include "report.h"
#include "sim_hal/host_clock.h"

static void record_progress(void *ctx, uint32_t cycles, uint64_t telegrams)
{
    progress_t *p = ctx;
    if (!p->on) {
        return;
    }
    uint64_t now = host_clock_mono_ns();
    if (now - p->last < 200000000u) {
        return;
    }
    p->last = now;
    fprintf(stderr, "\rrecord: %u cycles, %llu telegrams\033[K", cycles,
            (unsigned long long)telegrams);
    p->shown = true;
}

/* One option of dfp-sim record that is not a capture option. 1: consumed, 0: unknown, -1:
 * reported. */
static int record_option(int argc, char **argv, int *i, gen_options_t *o, uint32_t *address,
                         bool *have_cycles)
{
    const char *opt = argv[*i];
    const char *v;
    if (strcmp(opt, "--dpv1") == 0 || strcmp(opt, "--faults") == 0 ||
        strcmp(opt, "--foreign") == 0) {
        o->dpv1 = o->dpv1 || strcmp(opt, "--dpv1") == 0;
        o->faults = o->faults || strcmp(opt, "--faults") == 0;
        o->foreign = o->foreign || strcmp(opt, "--foreign") == 0;
        return 1;
    }
    if (strcmp(opt, "--cycles") == 0) {
        *have_cycles = true;
        return (v = cli_value(argc, argv, i)) != NULL &&
               cli_u32(opt, v, 1, 100000000u, &o->cycles) ? 1 : -1;
    }
    if (strcmp(opt, "--baud") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL && cli_baud(opt, v, false, &o->baud) ? 1
                                                                                           : -1;
    }
    if (strcmp(opt, "--address") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL && cli_u32(opt, v, 0, 125, address) ? 1
                                                                                           : -1;
    }
    if (strcmp(opt, "--param-every") == 0) {
        return (v = cli_value(argc, argv, i)) != NULL &&
               cli_u32(opt, v, 0, 100000000u, &o->param_every) ? 1 : -1;
    }
    if (strcmp(opt, "--inverter") != 0) {
        return 0;
    }
    if ((v = cli_value(argc, argv, i)) == NULL) return -1;
    if (strcmp(v, "sim") == 0 || strcmp(v, "none") == 0) {
        o->inverter = strcmp(v, "sim") == 0 ? CARD_INVERTER_SIM : CARD_INVERTER_NONE;
        return 1;
    }
    cli_error("record: --inverter '%s': use sim or none", v);
    return -1;
}

static int parse_record_args(int argc, char **argv, gen_options_t *o, uint32_t *address)
{
    bool have_cycles = false;
    for (int i = 2; i < argc; i++) {
        capture_opts_t co = {.path = o->path, .w = o->writer};
        int c = capture_option(argc, argv, &i, &co);
        if (c > 0) {
            o->path = co.path;
            o->writer = co.w;
            continue;
        }
        if (c == 0) {
            c = record_option(argc, argv, &i, o, address, &have_cycles);
        }
        if (c < 0) {
            return EXIT_USAGE;
        }
        if (c == 0) {
            cli_error("record: unknown option '%s' (see dfp-sim --help)", argv[i]);
            return EXIT_USAGE;
        }
    }
    if (o->path == NULL || !have_cycles) {
        cli_error("record: --capture FILE and --cycles N are required");
        return EXIT_USAGE;
    }
    if (o->foreign && *address > 114u) {
        cli_error("record: --foreign puts stations at --address + 1 and + 10: the address must "
                  "be 114 or lower");
        return EXIT_USAGE;
    }
    const cli_file_t out = {"--capture", o->path, false};
    return cli_no_links("record", &out, 1u) ? 0 : EXIT_USAGE;
}

int cmd_record(int argc, char **argv)
{
    gen_options_t o = {.address = 4, .param_every = 10, .inverter = CARD_INVERTER_SIM,
                       .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT};
    uint32_t address = 4;
    int rc = parse_record_args(argc, argv, &o, &address);
    if (rc != 0) {
        return rc;
    }
    o.address = (uint8_t)address;
    progress_t prog;
    progress_begin(&prog, "record");
    o.progress = record_progress;
    o.ctx = &prog;
    gen_result_t res;
    char err[256];
    rc = gen_run(&o, &res, err, sizeof err);
    progress_end(&prog);
    if (rc != 0) {
        cli_error("record: %s", err);
        return 1;
    }
    printf("record: %llu telegrams (%llu octets) in %.3f s of bus time at %s -> %s\n"
           "  %u Data_Exchange cycles of the card at address %u, %u parameter-channel services "
           "(%u answered with an error), %u data set 47 calls, %u class-2 connections, "
           "%u turns of master %u, %u watchdog expiries\n",
           (unsigned long long)res.telegrams, (unsigned long long)res.octets,
           (double)res.bus_ns / 1e9, report_baud_text(o.baud != 0u ? o.baud : 1500000u), o.path,
           res.cycles, address, res.param_services, res.param_errors, res.ds47_calls,
           res.c2_connections, res.foreign_bursts, GEN_FOREIGN_MASTER_ADDRESS,
           res.watchdog_expiries);
    return 0;
}
