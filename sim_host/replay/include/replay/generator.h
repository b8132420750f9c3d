/* Captures made on the in-memory bus: the built-in class-1 master and the emulated card (and,
 * on request, more stations) run N Data_Exchange cycles in simulated time while every telegram
 * goes into a capture file. `dfp-sim record` is the command line; the golden captures in
 * tests/replay/golden and the replay benchmark come from here.
 *
 * The run is deterministic: the same options give the same telegrams at the same bus times, and
 * the file's timestamps count from a fixed instant (GEN_EPOCH_S), so a capture made again is
 * byte-identical as long as the card and the master behave the same. */
#ifndef REPLAY_GENERATOR_H
#define REPLAY_GENERATOR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/capture.h"
#include "sim_stations/stations.h"

/* 2024-01-01 00:00:00 UTC: the first telegram's timestamp. */
#define GEN_EPOCH_S 1704067200u
#define GEN_MASTER_ADDRESS 2u
#define GEN_FOREIGN_MASTER_ADDRESS 3u

typedef struct gen_options {
    const char *path;
    cap_writer_options_t writer; /* format AUTO: by the file's extension; baud: set by the run */
    uint32_t cycles;         /* Data_Exchange cycles of the card */
    uint32_t baud;           /* 0: 1.5 Mbit/s */
    uint8_t address;         /* the card; 0 is a valid address, so always give it */
    uint32_t param_every;    /* a parameter-channel service every N cycles; 0: none */
    bool dpv1;               /* DP-V1 parameterisation, class-1 data set 47 requests, I&M0 and a
                                class-2 connection (Initiate, data set 47, Abort) */
    bool faults;             /* a master that stops (watchdog expiry), a wrong configuration,
                                Global_Control Clear_Data / Operate */
    bool foreign;            /* a second DFP21B at address + 1 served by the same master, and a
                                second master (address 3) passing the token, probing a free
                                address and reading the card's diagnosis */
    card_inverter_t inverter; /* CARD_INVERTER_SIM or _NONE */
    uint32_t inverter_delay_us;
    /* Called now and then with the cycles done so far. Optional. */
    void (*progress)(void *ctx, uint32_t cycles, uint64_t telegrams);
    void *ctx;
} gen_options_t;

typedef struct gen_result {
    uint64_t telegrams;
    uint64_t octets;
    uint32_t cycles;
    uint64_t bus_ns;        /* simulated time of the run */
    uint32_t param_services;
    uint32_t param_errors;  /* services answered with a MOVILINK error (some are on purpose) */
    uint32_t ds47_calls;
    uint32_t c2_connections;
    uint32_t foreign_bursts;
    uint32_t watchdog_expiries;
    uint32_t restarts;      /* master start-ups of the card after the first */
} gen_result_t;

/* Returns 0, or -1 with the reason in err (file not writable, the card never reached data
 * exchange). The run is assembled on a rig (rig/rig.h) that lives on the heap for the call:
 * runs in several threads do not share anything. */
int gen_run(const gen_options_t *opt, gen_result_t *res, char *err, size_t errlen);

#endif
