/* The card's two LEDs. Blinking is the backend's job (a timer on the MCU, a state on the host),
 * so the protocol core only says what an LED should show when something changes. */
#ifndef HAL_LED_H
#define HAL_LED_H

typedef enum hal_led_id { HAL_LED_RUN = 0, HAL_LED_BUS_FAULT = 1, HAL_LED_COUNT = 2 } hal_led_id_t;
typedef enum hal_led_mode { HAL_LED_OFF = 0, HAL_LED_ON = 1, HAL_LED_BLINK = 2 } hal_led_mode_t;

typedef struct hal_led_ops {
    void (*set)(void *ctx, hal_led_id_t led, hal_led_mode_t mode);
} hal_led_ops_t;

typedef struct hal_led {
    const hal_led_ops_t *ops;
    void *ctx;
} hal_led_t;

const char *hal_led_mode_name(hal_led_mode_t mode);

#endif
