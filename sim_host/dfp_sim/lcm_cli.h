/* dfp-sim --lcm URL: the card's telegrams, state and parameter services published to LCM
 * (sim_host/lcm_bridge/README.md), on top of the report's timeline and --capture. */
#ifndef DFP_SIM_LCM_CLI_H
#define DFP_SIM_LCM_CLI_H

#include <stdbool.h>
#include <stdint.h>

#include "lcm_bridge/lcm_bridge.h"
#include "rig/rig_ctl.h"
#include "rig/rig_log.h"
#include "report.h"
#include "sim_stations/stations.h"

/* How often a tty card's state is looked at; the bridge publishes at most every 100 ms. */
#define LCM_CLI_STATE_CHECK_US 10000u

typedef struct lcm_cli {
    dfp_lcm_bridge_t bridge;
    bool open;
    report_t *rep;         /* its tap is called first; failures are reported there */
    int64_t tap_wall_us;   /* utime of the tap's time origin (t_start_ns = 0) */
    int64_t clock_wall_us; /* utime of the report clock's origin (rep->now_ns = 0) */
    const dfp21b_t *card;
    hal_uart_t card_uart;  /* the card's real UART (lcm_cli_card_uart) */
    bool card_sending;     /* inside the card's transmit: the tapped frame is the card's */
    bool mark_direction;   /* the medium's tap cannot tell who sent a frame (in-memory bus) */
    bool failure_reported;
} lcm_cli_t;

/* Opens url for the card with this address. tap_wall_us / clock_wall_us: see above. Returns 0,
 * or 1 after printing the reason (cli_error). */
int lcm_cli_open(lcm_cli_t *l, const char *url, const dfp21b_t *card, uint8_t address,
                 report_t *rep, int64_t tap_wall_us, int64_t clock_wall_us);
/* utime of a CLOCK_MONOTONIC instant (ns), for media whose clock is the monotonic one. */
int64_t lcm_cli_wall_of_mono(uint64_t mono_ns);
/* sim_frame_tap_t (ctx = the lcm_cli_t): report_tap, then the telegram to LCM. */
void lcm_cli_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len, bool local,
                 uint32_t baud);
/* On a medium whose tap marks every frame local (the in-memory bus): wrap the card's UART so
 * the card's own frames go out as TX and everybody else's as RX. */
hal_uart_t lcm_cli_card_uart(lcm_cli_t *l, hal_uart_t inner);
/* Publishes the card state when it changed (and the bridge's interval allows). */
void lcm_cli_poll_state(lcm_cli_t *l);
/* For simulated time (the demo): waits until the wall clock reaches the utime of simulated
 * instant sim_ns, so the telemetry flows at the pace it describes. Without it the demo would
 * publish 1300 messages within milliseconds and a udpm subscriber (lcm-logger, lcm-spy) would
 * lose most of them in its socket buffer. */
void lcm_cli_pace(lcm_cli_t *l, uint64_t sim_ns);
/* tty_timer_fn doing lcm_cli_poll_state every LCM_CLI_STATE_CHECK_US. */
hal_time_us_t lcm_cli_timer(void *ctx, hal_time_us_t now);
/* The card options' param_observer / ctx for this context. */
void lcm_cli_observe_params(lcm_cli_t *l, card_options_t *co);
/* instrument_api_event_fn (ctx = the lcm_cli_t): an event of the control API to DFP_API. */
void lcm_cli_api_event(void *ctx, const rig_ctl_event_t *e);
/* Publishes the last state, prints "lcm: N messages published to URL" (and the failures: they
 * never change the exit status, telemetry is not the card's job) and closes. */
void lcm_cli_close(lcm_cli_t *l);

#endif
