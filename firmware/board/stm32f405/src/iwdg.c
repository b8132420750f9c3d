/* The independent watchdog (RM0090 §21). Separate from main.c so the host tests can run it
 * against register fakes. */
#include "board/board.h"

uint32_t board_iwdg_reload(uint32_t timeout_ms)
{
    uint32_t counts = (uint32_t)(((uint64_t)timeout_ms * (BOARD_IWDG_LSI_HZ / 32u)) / 1000u);
    if (counts == 0u) {
        return 1u;
    }
    return counts > IWDG_RLR_MAX ? IWDG_RLR_MAX : counts;
}

void board_iwdg_start(iwdg_regs_t *iwdg, uint32_t timeout_ms)
{
    /* Started first, so that even a start-up that hangs before the first reload is caught; PR
     * and RLR are written once, so their update flags (SR) need no wait. */
    iwdg->KR = IWDG_KEY_START;
    iwdg->KR = IWDG_KEY_ACCESS;
    iwdg->PR = IWDG_PR_DIV32;
    iwdg->RLR = board_iwdg_reload(timeout_ms);
    iwdg->KR = IWDG_KEY_RELOAD;
}

bool board_reset_by_iwdg(rcc_regs_t *rcc)
{
    bool by_iwdg = (rcc->CSR & RCC_CSR_IWDGRSTF) != 0u;
    rcc->CSR |= RCC_CSR_RMVF;
    return by_iwdg;
}
