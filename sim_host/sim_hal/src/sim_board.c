#include "sim_hal/sim_board.h"

#include <stddef.h>

static void leds_set(void *ctx, hal_led_id_t led, hal_led_mode_t mode)
{
    sim_leds_t *l = ctx;
    if ((unsigned)led >= HAL_LED_COUNT) {
        return;
    }
    l->mode[led] = mode;
    l->changes++;
    if (l->on_change != NULL) {
        l->on_change(l->ctx, led, mode);
    }
}

static const hal_led_ops_t sim_led_ops = {.set = leds_set};

hal_led_t sim_leds_hal(sim_leds_t *leds)
{
    return (hal_led_t){.ops = &sim_led_ops, .ctx = leds};
}

static uint8_t dip_read(void *ctx)
{
    const sim_dip_t *d = ctx;
    return (uint8_t)(d->switches & 0x7Fu);
}

static const hal_dip_ops_t sim_dip_ops = {.read = dip_read};

hal_dip_t sim_dip_hal(sim_dip_t *dip)
{
    return (hal_dip_t){.ops = &sim_dip_ops, .ctx = dip};
}

const char *sim_led_name(hal_led_id_t led)
{
    return led == HAL_LED_RUN ? "RUN" : led == HAL_LED_BUS_FAULT ? "BUS FAULT" : "?";
}
