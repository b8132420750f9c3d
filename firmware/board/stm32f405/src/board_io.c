#include "board/board_io.h"

void gpio_config(gpio_regs_t *g, uint8_t pin, uint8_t mode, uint8_t pull, uint8_t af)
{
    uint32_t sh2 = 2u * pin;
    g->MODER = (g->MODER & ~(3u << sh2)) | ((uint32_t)mode << sh2);
    g->PUPDR = (g->PUPDR & ~(3u << sh2)) | ((uint32_t)pull << sh2);
    g->OSPEEDR |= 3u << sh2; /* very high speed: the USART at 6 Mbit/s */
    g->OTYPER &= ~(1u << pin);
    if (mode == GPIO_MODE_AF) {
        uint32_t sh4 = 4u * (pin & 7u);
        g->AFR[pin >> 3] = (g->AFR[pin >> 3] & ~(0xFu << sh4)) | ((uint32_t)af << sh4);
    }
}

static void led_write(board_leds_t *l, unsigned i, bool on)
{
    if (l->port[i] != NULL && l->lit[i] != on) {
        l->port[i]->BSRR = on ? (1u << l->pin[i]) : (1u << (l->pin[i] + 16u));
    }
    l->lit[i] = on;
}

void board_leds_init(board_leds_t *l)
{
    for (unsigned i = 0; i < HAL_LED_COUNT; i++) {
        if (l->port[i] != NULL) {
            gpio_config(l->port[i], l->pin[i], GPIO_MODE_OUTPUT, GPIO_PULL_NONE, 0);
        }
        l->lit[i] = true; /* force the first write */
        led_write(l, i, false);
    }
}

void board_leds_tick(board_leds_t *l)
{
    l->ms++;
    bool blink_on = (l->ms / BOARD_BLINK_HALF_MS) % 2u == 0u;
    bool fast_on = (l->ms / BOARD_FAULT_HALF_MS) % 2u == 0u;
    for (unsigned i = 0; i < HAL_LED_COUNT; i++) {
        bool on;
        /* The crash indication is BUS FAULT alone: RUN blinking means an address above 125
         * (protocol.md §B2), and a card that restarted after a fault is not that. */
        if (l->fault_pattern && i == HAL_LED_BUS_FAULT) {
            on = fast_on;
        } else if (l->mode[i] == HAL_LED_BLINK) {
            on = blink_on;
        } else {
            on = l->mode[i] == HAL_LED_ON;
        }
        led_write(l, i, on);
    }
}

static void op_led_set(void *ctx, hal_led_id_t led, hal_led_mode_t mode)
{
    board_leds_t *l = ctx;
    if ((unsigned)led < HAL_LED_COUNT) {
        l->mode[led] = (uint8_t)mode;
    }
}

static const hal_led_ops_t led_ops = {.set = op_led_set};

hal_led_t board_leds_hal(board_leds_t *l)
{
    return (hal_led_t){.ops = &led_ops, .ctx = l};
}

uint8_t board_dip_read(board_dip_t *d)
{
    uint8_t v;
    if (d->override >= 0) {
        v = (uint8_t)d->override;
    } else {
        uint32_t idr = d->port->IDR >> d->first_pin;
        v = (uint8_t)((d->active_low ? ~idr : idr) & 0x7Fu);
    }
    d->value = v;
    return v;
}

static uint8_t op_dip_read(void *ctx)
{
    return board_dip_read(ctx);
}

static const hal_dip_ops_t dip_ops = {.read = op_dip_read};

hal_dip_t board_dip_hal(board_dip_t *d)
{
    return (hal_dip_t){.ops = &dip_ops, .ctx = d};
}
