/* LEDs (RUN, BUS FAULT) with blink patterns, the seven address DIP switches, and GPIO set-up.
 *
 * Blinking is the backend's job (hal_led.h): the LED state is kept here and the SysTick calls
 * board_leds_tick() every millisecond. Patterns: ON, OFF, BLINK (1 Hz, 50 %: "flashing" in the
 * DFP21B manual §3.7) and, board-only, FAULT (BUS FAULT alone at 4 Hz, RUN as set) in the
 * start right after a fault (a fresh fault record), until Data_Exch. The DIP switches are read once
 * (dfp21b_init calls read()). */
#ifndef BOARD_BOARD_IO_H
#define BOARD_BOARD_IO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "board/stm32f405_regs.h"
#include "hal/hal_dip.h"
#include "hal/hal_led.h"

#define BOARD_BLINK_HALF_MS 500u
#define BOARD_FAULT_HALF_MS 125u

void gpio_config(gpio_regs_t *g, uint8_t pin, uint8_t mode, uint8_t pull, uint8_t af);

typedef struct board_leds {
    gpio_regs_t *port[HAL_LED_COUNT];
    uint8_t pin[HAL_LED_COUNT];
    volatile uint8_t mode[HAL_LED_COUNT]; /* hal_led_mode_t */
    volatile bool fault_pattern;
    uint32_t ms;
    bool lit[HAL_LED_COUNT];
} board_leds_t;

void board_leds_init(board_leds_t *l);
hal_led_t board_leds_hal(board_leds_t *l);
void board_leds_tick(board_leds_t *l);

typedef struct board_dip {
    gpio_regs_t *port;
    uint8_t first_pin;  /* switches 2^0..2^6 on first_pin..first_pin+6 */
    bool active_low;    /* switch ON pulls the pin to ground (pull-ups) */
    int16_t override;   /* >= 0: this value instead of the pins (QEMU test image) */
    uint8_t value;      /* what was read at power-up */
} board_dip_t;

hal_dip_t board_dip_hal(board_dip_t *d);
uint8_t board_dip_read(board_dip_t *d);

#endif
