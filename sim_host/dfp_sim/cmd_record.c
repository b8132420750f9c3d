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

/* The command line as given. */
typedef struct record_opts {
    gen_options_t gen;
    capture_opts_t capture;
    uint32_t address;
    bool have_cycles;
} record_opts_t;

static const cli_choice_t record_inverters[] = {
    {"sim", CARD_INVERTER_SIM, false},
    {"none", CARD_INVERTER_NONE, false},
    {NULL, 0, false},
};

#define RECORD(field) offsetof(record_opts_t, field)

static const cli_opt_t record_options[] = {
    {CLI_OPT("--cycles", "N", CLI_U32, RECORD(gen.cycles)), .min = 1, .max = 100000000u,
     .seen = CLI_SEEN(record_opts_t, have_cycles)},
    {CLI_OPT("--baud", "RATE", CLI_BAUD, RECORD(gen.baud))},
    {CLI_OPT("--address", "N", CLI_U32, RECORD(address)), .min = 0, .max = 125},
    {CLI_OPT("--dpv1", NULL, CLI_FLAG, RECORD(gen.dpv1))},
    {CLI_OPT("--faults", NULL, CLI_FLAG, RECORD(gen.faults))},
    {CLI_OPT("--foreign", NULL, CLI_FLAG, RECORD(gen.foreign))},
    {CLI_OPT("--param-every", "N", CLI_U32, RECORD(gen.param_every)),
     .min = 0, .max = 100000000u},
    {CLI_OPT("--inverter", "sim|none", CLI_CHOICE, RECORD(gen.inverter)),
     .choices = record_inverters,
     .bad = "record: --inverter '%s': use sim or none"},
};

static const cli_group_t record_groups[] = {
    {capture_options, CLI_COUNT(capture_options), RECORD(capture)},
    {record_options, CLI_COUNT(record_options), 0},
};

const cli_command_t cli_record = {.name = "record", .groups = record_groups,
                                  .n_groups = CLI_COUNT(record_groups)};

static int parse_record_args(int argc, char **argv, record_opts_t *r)
{
    gen_options_t *o = &r->gen;
    if (cli_parse(&cli_record, argc, argv, r) != 0) {
        return EXIT_USAGE;
    }
    o->path = r->capture.path;
    o->writer = r->capture.w;
    if (o->path == NULL || !r->have_cycles) {
        cli_error("record: --capture FILE and --cycles N are required");
        return EXIT_USAGE;
    }
    if (o->foreign && r->address > 114u) {
        cli_error("record: --foreign puts stations at --address + 1 and + 10: the address must "
                  "be 114 or lower");
        return EXIT_USAGE;
    }
    const cli_file_t out = {"--capture", o->path, false};
    return cli_no_links("record", &out, 1u) ? 0 : EXIT_USAGE;
}

int cmd_record(int argc, char **argv)
{
    record_opts_t r = {.gen = {.address = 4, .param_every = 10, .inverter = CARD_INVERTER_SIM,
                               .inverter_delay_us = REPLAY_INVERTER_DELAY_US_DEFAULT},
                       .address = 4};
    int rc = parse_record_args(argc, argv, &r);
    if (rc != 0) {
        return rc;
    }
    gen_options_t o = r.gen;
    uint32_t address = r.address;
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
