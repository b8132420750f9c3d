#include "board/board.h"

#define CLOCK_SPINS 200000u

static bool wait_set(volatile uint32_t *reg, uint32_t mask, uint32_t want)
{
    for (uint32_t i = 0; i < CLOCK_SPINS; i++) {
        if ((*reg & mask) == want) {
            return true;
        }
    }
    return false;
}

#define CFGR_PRESCALERS (RCC_CFGR_HPRE_MASK | RCC_CFGR_PPRE1_MASK | RCC_CFGR_PPRE2_MASK)

/* The PLL never came up: SYSCLK stays HSI, and AHB and both APBs run undivided, so the 16 MHz
 * reported for each is what the UART, TIM2 and bxCAN really get. */
static board_clocks_t hsi_only(rcc_regs_t *rcc)
{
    rcc->CFGR &= ~(RCC_CFGR_SW_MASK | CFGR_PRESCALERS); /* SW = HSI, AHB/APB1/APB2 /1 */
    board_clocks_t c = {.source = BOARD_CLOCK_HSI_ONLY, .hclk_hz = BOARD_HSI_HZ,
                        .pclk1_hz = BOARD_HSI_HZ, .pclk2_hz = BOARD_HSI_HZ};
    return c;
}

board_clocks_t board_clock_init(rcc_regs_t *rcc, flash_regs_t *flash)
{
    if (rcc->CR == 0u) {
        /* HSION/HSIRDY are 1 out of reset on silicon; all-zero means no RCC model (QEMU's
         * netduinoplus2 runs the core at a fixed 168 MHz). */
        board_clocks_t c = {.source = BOARD_CLOCK_NOT_MODELLED, .hclk_hz = BOARD_HCLK_HZ,
                            .pclk1_hz = BOARD_PCLK1_HZ, .pclk2_hz = BOARD_PCLK2_HZ};
        return c;
    }
    rcc->CR |= RCC_CR_HSEON;
    bool hse = wait_set(&rcc->CR, RCC_CR_HSERDY, RCC_CR_HSERDY);
    uint32_t m = hse ? BOARD_HSE_HZ / 1000000u : BOARD_HSI_HZ / 1000000u;
    if (!hse) {
        rcc->CR &= ~RCC_CR_HSEON;
    }
    /* VCO in = 1 MHz, VCO = 336 MHz, SYSCLK = /2 = 168 MHz, 48 MHz domain = /7. */
    rcc->PLLCFGR = m | (336u << 6) | (0u << 16) | (hse ? RCC_PLLCFGR_SRC_HSE : 0u) | (7u << 24);
    /* 5 wait states at 168 MHz / 3.3 V, prefetch and caches on (slower but correct on HSI). */
    flash->ACR = FLASH_ACR_LATENCY_5WS | FLASH_ACR_PRFTEN | FLASH_ACR_ICEN | FLASH_ACR_DCEN;
    rcc->CR |= RCC_CR_PLLON;
    if (!wait_set(&rcc->CR, RCC_CR_PLLRDY, RCC_CR_PLLRDY)) {
        return hsi_only(rcc);
    }
    /* AHB /1, APB1 /4 = 42 MHz, APB2 /2 = 84 MHz: the APB limits (42 and 84 MHz, RM0090 §7.2)
     * hold from the moment SYSCLK becomes 168 MHz, so the dividers go in before the switch. */
    rcc->CFGR = (rcc->CFGR & ~CFGR_PRESCALERS) |
                (RCC_CFGR_PPRE_DIV4 << RCC_CFGR_PPRE1_SHIFT) |
                (RCC_CFGR_PPRE_DIV2 << RCC_CFGR_PPRE2_SHIFT);
    rcc->CFGR = (rcc->CFGR & ~RCC_CFGR_SW_MASK) | RCC_CFGR_SW_PLL;
    if (!wait_set(&rcc->CFGR, RCC_CFGR_SWS_MASK, RCC_CFGR_SWS_PLL)) {
        return hsi_only(rcc);
    }
    board_clocks_t c = {.source = hse ? BOARD_CLOCK_PLL_HSE : BOARD_CLOCK_PLL_HSI,
                        .hclk_hz = BOARD_HCLK_HZ, .pclk1_hz = BOARD_PCLK1_HZ,
                        .pclk2_hz = BOARD_PCLK2_HZ};
    return c;
}

const char *board_clock_source_name(board_clock_source_t s)
{
    switch (s) {
    case BOARD_CLOCK_PLL_HSE: return "PLL from HSE";
    case BOARD_CLOCK_PLL_HSI: return "PLL from HSI";
    case BOARD_CLOCK_HSI_ONLY: return "HSI only";
    case BOARD_CLOCK_NOT_MODELLED: return "RCC not modelled (QEMU), 168 MHz";
    }
    return "?";
}
