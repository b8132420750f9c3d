#include "sim_stations/stations.h"

#include <string.h>

const uint8_t dfp21b_user_prm_default[9] = {0x00, 0x00, 0x00, 0x06, 0x81, 0x00, 0x00, 0x01, 0x01};

static void card_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    card_station_t *c = ctx;
    dfp21b_rx_char(&c->card, byte, flags, t);
}

static hal_time_us_t card_poll(void *ctx, hal_time_us_t now)
{
    card_station_t *c = ctx;
    return dfp21b_poll(&c->card, now);
}

sim_station_t card_station(card_station_t *c)
{
    return (sim_station_t){.ctx = c, .rx_char = card_rx, .poll = card_poll};
}

void card_station_init(card_station_t *c, const card_options_t *opt, hal_uart_t uart,
                       hal_time_us_t now)
{
    memset(&c->leds, 0, sizeof c->leds);
    c->leds.on_change = opt->led_change;
    c->leds.ctx = opt->ctx;
    c->dip.switches = opt->address;
    dfp21b_cfg_t cfg = {
        .uart = uart,
        .led = sim_leds_hal(&c->leds),
        .dip = sim_dip_hal(&c->dip),
        .fixed_baud = opt->fixed_baud,
        .strict_timing = opt->strict_timing,
        .baud_control_ms = opt->baud_control_ms,
        .event = opt->event,
        .event_ctx = opt->ctx,
    };
    dfp21b_init(&c->card, &cfg, now);
}

static void master_rx(void *ctx, uint8_t byte, uint8_t flags, hal_time_us_t t)
{
    dp_master_rx_char(ctx, byte, flags, t);
}

static hal_time_us_t master_poll(void *ctx, hal_time_us_t now)
{
    return dp_master_poll(ctx, now);
}

sim_station_t master_station(dp_master_t *m)
{
    return (sim_station_t){.ctx = m, .rx_char = master_rx, .poll = master_poll};
}
