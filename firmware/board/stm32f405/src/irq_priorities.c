/* Interrupt priorities of the board (the table in board/board.h). Separate from main.c so the
 * host tests can run it against register fakes. */
#include "board/board.h"

static uint8_t prio_byte(uint32_t prio)
{
    return (uint8_t)(prio << BOARD_PRIO_SHIFT);
}

void board_irq_priorities(volatile uint8_t *nvic_ipr, volatile uint32_t *scb_shpr3)
{
    nvic_ipr[IRQ_USART1] = prio_byte(BOARD_PRIO_USART);
    nvic_ipr[IRQ_CAN1_RX0] = prio_byte(BOARD_PRIO_CAN);
    /* SHPR3: SysTick in bits 31..24, PendSV in 23..16 (PM0214 §4.4.8). */
    *scb_shpr3 = (*scb_shpr3 & 0x0000FFFFu) | ((uint32_t)prio_byte(BOARD_PRIO_SYSTICK) << 24) |
                 ((uint32_t)prio_byte(BOARD_PRIO_CORE) << 16);
}
