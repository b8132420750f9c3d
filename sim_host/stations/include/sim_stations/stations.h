/* The card and the master as stations on a host medium (sim_station_t). */
#ifndef SIM_STATIONS_STATIONS_H
#define SIM_STATIONS_STATIONS_H

#include "dfp21b/dfp21b.h"
#include "dp_master/dp_master.h"
#include "sim_hal/sim_board.h"
#include "sim_hal/sim_station.h"

typedef struct card_station {
    dfp21b_t card;
    sim_leds_t leds;
    sim_dip_t dip;
} card_station_t;

typedef struct card_options {
    uint8_t address;     /* DIP switches */
    uint32_t fixed_baud; /* 0 = automatic */
    bool strict_timing;
    uint32_t baud_control_ms;
    void (*event)(void *ctx, const dp_event_t *ev);
    void (*led_change)(void *ctx, hal_led_id_t led, hal_led_mode_t mode);
    void *ctx;
} card_options_t;

sim_station_t card_station(card_station_t *c);
/* Call after attaching the station to a medium (which supplies uart). */
void card_station_init(card_station_t *c, const card_options_t *opt, hal_uart_t uart,
                       hal_time_us_t now);

sim_station_t master_station(dp_master_t *m);

/* The DFP21B's 9 user-parameter octets (DP-V1 status 00 00 00, SEW block, diag alarm off). */
extern const uint8_t dfp21b_user_prm_default[9];

#endif
