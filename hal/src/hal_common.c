#include "hal/hal_led.h"
#include "hal/hal_uart.h"

const uint32_t hal_uart_bauds[HAL_UART_NUM_BAUDS] = {
    12000000u, 6000000u, 3000000u, 1500000u, 500000u, 187500u, 93750u, 45450u, 19200u, 9600u,
};

const char *hal_led_mode_name(hal_led_mode_t mode)
{
    switch (mode) {
    case HAL_LED_OFF: return "off";
    case HAL_LED_ON: return "on";
    case HAL_LED_BLINK: return "blink";
    }
    return "?";
}
