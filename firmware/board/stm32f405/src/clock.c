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

board_clocks_t board_clock_init(rcc_regs_t *rcc, flash_regs_t *flash)
{
    board_clocks_t c = {.source = BOARD_CLOCK_HSI_ONLY, .hclk_hz = BOARD_HSI_HZ,
                        .pclk1_hz = BOARD_HSI_HZ, .pclk2_hz = BOARD_HSI_HZ};
    if (rcc->CR == 0u) {
        /* HSION/HSIRDY are 1 out of reset on silicon; all-zero means no RCC model (QEMU's
         * netduinoplus2 runs the core at a fixed 168 MHz). */
        c.source = BOARD_CLOCK_NOT_MODELLED;
        c.hclk_hz = BOARD_HCLK_HZ;
        c.pclk1_hz = BOARD_PCLK1_HZ;
        c.pclk2_hz = BOARD_PCLK2_HZ;
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
    /* 5 wait states at 168 MHz / 3.3 V, prefetch and caches on. */
    flash->ACR = FLASH_ACR_LATENCY_5WS | FLASH_ACR_PRFTEN | FLASH_ACR_ICEN | FLASH_ACR_DCEN;
    /* AHB /1, APB1 /4 = 42 MHz, APB2 /2 = 84 MHz. */
    rcc->CFGR = (rcc->CFGR & ~0xFCF0u) | (5u << 10) | (4u << 13);
    rcc->CR |= RCC_CR_PLLON;
    if (!wait_set(&rcc->CR, RCC_CR_PLLRDY, RCC_CR_PLLRDY)) {
        return c;
    }
    rcc->CFGR = (rcc->CFGR & ~3u) | RCC_CFGR_SW_PLL;
    if (!wait_set(&rcc->CFGR, RCC_CFGR_SWS_MASK, RCC_CFGR_SWS_PLL)) {
        return c;
    }
    c.source = hse ? BOARD_CLOCK_PLL_HSE : BOARD_CLOCK_PLL_HSI;
    c.hclk_hz = BOARD_HCLK_HZ;
    c.pclk1_hz = BOARD_PCLK1_HZ;
    c.pclk2_hz = BOARD_PCLK2_HZ;
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
