/* Host stand-ins for the card's LEDs and DIP switches. The LEDs remember their state and report
 * each change, so programs can print it and tests can assert it. */
#ifndef SIM_HAL_SIM_BOARD_H
#define SIM_HAL_SIM_BOARD_H

#include <stdint.h>

#include "hal/hal_dip.h"
#include "hal/hal_led.h"
#include "hal/hal_time.h"

typedef struct sim_leds {
    hal_led_mode_t mode[HAL_LED_COUNT];
    unsigned changes;
    void (*on_change)(void *ctx, hal_led_id_t led, hal_led_mode_t mode);
    void *ctx;
} sim_leds_t;

typedef struct sim_dip {
    uint8_t switches; /* bit n = switch 2^n */
} sim_dip_t;

hal_led_t sim_leds_hal(sim_leds_t *leds);
hal_dip_t sim_dip_hal(sim_dip_t *dip);
const char *sim_led_name(hal_led_id_t led);

#endif
