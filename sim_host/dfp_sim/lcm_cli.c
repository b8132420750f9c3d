#include "lcm_cli.h"

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "cli.h"

int64_t lcm_cli_wall_of_mono(uint64_t mono_ns)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t now_mono = (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
    return dfp_lcm_wall_us() - (int64_t)((now_mono - mono_ns) / 1000u);
}

static int64_t clock_utime(void *ctx)
{
    lcm_cli_t *l = ctx;
    uint64_t ns = l->rep->now_ns != NULL ? l->rep->now_ns(l->rep->now_ctx) : 0u;
    return l->clock_wall_us + (int64_t)(ns / 1000u);
}

static void report_failure(lcm_cli_t *l)
{
    if (l->bridge.failures > 0u && !l->failure_reported) {
        l->failure_reported = true;
        report_line(l->rep, "lcm", "%s (the card goes on; further failures are only counted)",
                    l->bridge.error);
    }
}

int lcm_cli_open(lcm_cli_t *l, const char *url, const dfp21b_t *card, uint8_t address,
                 report_t *rep, int64_t tap_wall_us, int64_t clock_wall_us)
{
    memset(l, 0, sizeof *l);
    char err[320];
    if (dfp_lcm_bridge_open(&l->bridge, url, (int16_t)address, err, sizeof err) != 0) {
        cli_error("%s", err);
        return 1;
    }
    l->open = true;
    l->rep = rep;
    l->card = card;
    l->tap_wall_us = tap_wall_us;
    l->clock_wall_us = clock_wall_us;
    l->bridge.clock = clock_utime;
    l->bridge.clock_ctx = l;
    return 0;
}

void lcm_cli_tap(void *ctx, uint64_t t_start_ns, const uint8_t *frame, size_t len, bool local,
                 uint32_t baud)
{
    lcm_cli_t *l = ctx;
    report_tap(l->rep, t_start_ns, frame, len, local, baud);
    if (!l->open) {
        return;
    }
    bool from_card = l->mark_direction ? l->card_sending : local;
    (void)dfp_lcm_bridge_telegram(&l->bridge, l->tap_wall_us + (int64_t)(t_start_ns / 1000u),
                                  frame, len, from_card, baud, 0);
    report_failure(l);
}

static int marked_set_baud(void *ctx, uint32_t baud)
{
    lcm_cli_t *l = ctx;
    return l->card_uart.ops->set_baud(l->card_uart.ctx, baud);
}

static int marked_transmit(void *ctx, const uint8_t *frame, size_t len, hal_time_us_t not_before)
{
    lcm_cli_t *l = ctx;
    l->card_sending = true;
    int rc = l->card_uart.ops->transmit(l->card_uart.ctx, frame, len, not_before);
    l->card_sending = false;
    return rc;
}

static const hal_uart_ops_t marked_uart_ops = {.set_baud = marked_set_baud,
                                               .transmit = marked_transmit};

hal_uart_t lcm_cli_card_uart(lcm_cli_t *l, hal_uart_t inner)
{
    l->card_uart = inner;
    l->mark_direction = true;
    return (hal_uart_t){.ops = &marked_uart_ops, .ctx = l};
}

void lcm_cli_poll_state(lcm_cli_t *l)
{
    if (!l->open || l->card == NULL) {
        return;
    }
    (void)dfp_lcm_bridge_card_state(&l->bridge, clock_utime(l), l->card);
    report_failure(l);
}

void lcm_cli_pace(lcm_cli_t *l, uint64_t sim_ns)
{
    if (!l->open) {
        return;
    }
    int64_t ahead = l->clock_wall_us + (int64_t)(sim_ns / 1000u) - dfp_lcm_wall_us();
    if (ahead > 0) {
        struct timespec ts = {.tv_sec = (time_t)(ahead / 1000000),
                              .tv_nsec = (long)(ahead % 1000000) * 1000L};
        (void)nanosleep(&ts, NULL);
    }
}

hal_time_us_t lcm_cli_timer(void *ctx, hal_time_us_t now)
{
    lcm_cli_poll_state(ctx);
    return now + LCM_CLI_STATE_CHECK_US;
}

void lcm_cli_observe_params(lcm_cli_t *l, card_options_t *co)
{
    co->param_observer = dfp_lcm_bridge_param_observer;
    co->param_observer_ctx = &l->bridge;
}

void lcm_cli_close(lcm_cli_t *l)
{
    if (!l->open) {
        return;
    }
    if (l->card != NULL) {
        l->bridge.state_interval_ms = 0; /* the last state goes out whatever the interval */
        lcm_cli_poll_state(l);
    }
    report_failure(l);
    report_line(l->rep, "lcm", "%llu messages published to %s%s",
                (unsigned long long)l->bridge.messages, l->bridge.url,
                l->bridge.failures > 0u ? " (some failed, see above)" : "");
    dfp_lcm_bridge_close(&l->bridge);
    l->open = false;
}

void lcm_cli_api_event(void *ctx, const rig_ctl_event_t *e)
{
    lcm_cli_t *l = ctx;
    if (l->open && dfp_lcm_bridge_api_event(&l->bridge, dfp_lcm_wall_us(), (int64_t)e->t_us,
                                            (int64_t)e->seq, rig_log_level_name(e->level),
                                            e->kind, e->text) != 0) {
        report_failure(l);
    }
}
