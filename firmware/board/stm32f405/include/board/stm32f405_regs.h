/* STM32F405 and Cortex-M4 registers the board support uses, as plain structs (RM0090, PM0214).
 *
 * Drivers never name an address: they get a pointer to a register block at init, so the host
 * unit tests (tests/firmware/) hand them a struct in RAM (a register fake) and check what the
 * driver wrote. Only board.c and main.c bind the real addresses below. */
#ifndef BOARD_STM32F405_REGS_H
#define BOARD_STM32F405_REGS_H

#include <stdint.h>

#define REG volatile uint32_t

/* ---- USART (RM0090 §30.6) ------------------------------------------------------------------ */
typedef struct usart_regs {
    REG SR;   /* 0x00 */
    REG DR;   /* 0x04 */
    REG BRR;  /* 0x08 */
    REG CR1;  /* 0x0C */
    REG CR2;  /* 0x10 */
    REG CR3;  /* 0x14 */
    REG GTPR; /* 0x18 */
} usart_regs_t;

#define USART_SR_PE (1u << 0)
#define USART_SR_FE (1u << 1)
#define USART_SR_NF (1u << 2)
#define USART_SR_ORE (1u << 3)
#define USART_SR_IDLE (1u << 4)
#define USART_SR_RXNE (1u << 5)
#define USART_SR_TC (1u << 6)
#define USART_SR_TXE (1u << 7)

#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_IDLEIE (1u << 4)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TCIE (1u << 6)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR1_PEIE (1u << 8)
#define USART_CR1_PS (1u << 9)
#define USART_CR1_PCE (1u << 10)
#define USART_CR1_M (1u << 12)
#define USART_CR1_UE (1u << 13)
#define USART_CR1_OVER8 (1u << 15)

#define USART_CR3_EIE (1u << 0)
#define USART_CR3_ONEBIT (1u << 11)

/* ---- GPIO (RM0090 §8.4) -------------------------------------------------------------------- */
typedef struct gpio_regs {
    REG MODER;   /* 0x00 */
    REG OTYPER;  /* 0x04 */
    REG OSPEEDR; /* 0x08 */
    REG PUPDR;   /* 0x0C */
    REG IDR;     /* 0x10 */
    REG ODR;     /* 0x14 */
    REG BSRR;    /* 0x18 */
    REG LCKR;    /* 0x1C */
    REG AFR[2];  /* 0x20 */
} gpio_regs_t;

#define GPIO_MODE_INPUT 0u
#define GPIO_MODE_OUTPUT 1u
#define GPIO_MODE_AF 2u
#define GPIO_PULL_NONE 0u
#define GPIO_PULL_UP 1u
#define GPIO_PULL_DOWN 2u

/* ---- RCC (RM0090 §7.3) --------------------------------------------------------------------- */
typedef struct rcc_regs {
    REG CR;         /* 0x00 */
    REG PLLCFGR;    /* 0x04 */
    REG CFGR;       /* 0x08 */
    REG CIR;        /* 0x0C */
    REG AHB1RSTR;   /* 0x10 */
    REG AHB2RSTR;   /* 0x14 */
    REG AHB3RSTR;   /* 0x18 */
    REG RSV0;       /* 0x1C */
    REG APB1RSTR;   /* 0x20 */
    REG APB2RSTR;   /* 0x24 */
    REG RSV1[2];    /* 0x28 */
    REG AHB1ENR;    /* 0x30 */
    REG AHB2ENR;    /* 0x34 */
    REG AHB3ENR;    /* 0x38 */
    REG RSV2;       /* 0x3C */
    REG APB1ENR;    /* 0x40 */
    REG APB2ENR;    /* 0x44 */
    REG RSV3[2];    /* 0x48 */
    REG AHB1LPENR;  /* 0x50 */
    REG AHB2LPENR;  /* 0x54 */
    REG AHB3LPENR;  /* 0x58 */
    REG RSV4;       /* 0x5C */
    REG APB1LPENR;  /* 0x60 */
    REG APB2LPENR;  /* 0x64 */
    REG RSV5[2];    /* 0x68 */
    REG BDCR;       /* 0x70 */
    REG CSR;        /* 0x74 */
} rcc_regs_t;

#define RCC_CR_HSION (1u << 0)
#define RCC_CR_HSIRDY (1u << 1)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_PLLCFGR_SRC_HSE (1u << 22)
#define RCC_CFGR_SW_MASK 3u
#define RCC_CFGR_SW_PLL 2u
#define RCC_CFGR_SWS_MASK (3u << 2)
#define RCC_CFGR_SWS_PLL (2u << 2)
#define RCC_CFGR_HPRE_MASK (0xFu << 4)
#define RCC_CFGR_PPRE1_SHIFT 10u /* APB1: 0xx /1, 100 /2, 101 /4, 110 /8, 111 /16 */
#define RCC_CFGR_PPRE2_SHIFT 13u /* APB2: the same code */
#define RCC_CFGR_PPRE1_MASK (7u << RCC_CFGR_PPRE1_SHIFT)
#define RCC_CFGR_PPRE2_MASK (7u << RCC_CFGR_PPRE2_SHIFT)
#define RCC_CFGR_PPRE_DIV2 4u
#define RCC_CFGR_PPRE_DIV4 5u
#define RCC_AHB1ENR_GPIOA (1u << 0)
#define RCC_AHB1ENR_GPIOB (1u << 1)
#define RCC_AHB1ENR_GPIOC (1u << 2)
#define RCC_APB1ENR_CAN1 (1u << 25)
#define RCC_APB2ENR_USART1 (1u << 4)
#define RCC_CSR_RMVF (1u << 24)    /* write 1: clear the reset flags */
#define RCC_CSR_IWDGRSTF (1u << 29) /* the last reset came from the independent watchdog */

/* ---- IWDG, the independent watchdog (RM0090 §21; at /32 a count is 1 ms at 32 kHz) --------- */
typedef struct iwdg_regs {
    REG KR;  /* 0x00 key */
    REG PR;  /* 0x04 prescaler: 0 /4, 1 /8, 2 /16, 3 /32, 4 /64, 5 /128, 6 /256 */
    REG RLR; /* 0x08 reload, 12 bits */
    REG SR;  /* 0x0C PVU, RVU: an update of PR or RLR still on its way to the LSI domain */
} iwdg_regs_t;
#define IWDG_KEY_START 0xCCCCu  /* starts the counter (and forces the LSI on); nothing stops it */
#define IWDG_KEY_ACCESS 0x5555u /* opens PR and RLR for writing */
#define IWDG_KEY_RELOAD 0xAAAAu /* counter back to RLR */
#define IWDG_PR_DIV32 3u
#define IWDG_RLR_MAX 0xFFFu

typedef struct flash_regs {
    REG ACR; /* 0x00 */
} flash_regs_t;
#define FLASH_ACR_LATENCY_5WS 5u
#define FLASH_ACR_PRFTEN (1u << 8)
#define FLASH_ACR_ICEN (1u << 9)
#define FLASH_ACR_DCEN (1u << 10)

/* ---- bxCAN (RM0090 §32.9) ------------------------------------------------------------------ */
typedef struct can_txmb {
    REG TIR, TDTR, TDLR, TDHR;
} can_txmb_t;
typedef struct can_rxfifo {
    REG RIR, RDTR, RDLR, RDHR;
} can_rxfifo_t;
typedef struct can_filter {
    REG FR1, FR2;
} can_filter_t;
typedef struct can_regs {
    REG MCR;              /* 0x000 */
    REG MSR;              /* 0x004 */
    REG TSR;              /* 0x008 */
    REG RF0R;             /* 0x00C */
    REG RF1R;             /* 0x010 */
    REG IER;              /* 0x014 */
    REG ESR;              /* 0x018 */
    REG BTR;              /* 0x01C */
    REG RSV0[88];         /* 0x020 */
    can_txmb_t TX[3];     /* 0x180 */
    can_rxfifo_t RX[2];   /* 0x1B0 */
    REG RSV1[12];         /* 0x1D0 */
    REG FMR;              /* 0x200 */
    REG FM1R;             /* 0x204 */
    REG RSV2;             /* 0x208 */
    REG FS1R;             /* 0x20C */
    REG RSV3;             /* 0x210 */
    REG FFA1R;            /* 0x214 */
    REG RSV4;             /* 0x218 */
    REG FA1R;             /* 0x21C */
    REG RSV5[8];          /* 0x220 */
    can_filter_t FILTER[28]; /* 0x240 */
} can_regs_t;

#define CAN_MCR_INRQ (1u << 0)
#define CAN_MCR_SLEEP (1u << 1)
#define CAN_MCR_TXFP (1u << 2)
#define CAN_MCR_ABOM (1u << 6)
#define CAN_MSR_INAK (1u << 0)
#define CAN_MSR_SLAK (1u << 1)
#define CAN_TSR_TME0 (1u << 26)
#define CAN_RF0R_FMP_MASK 3u
#define CAN_RF0R_FOVR (1u << 4)
#define CAN_RF0R_RFOM (1u << 5)
#define CAN_IER_FMPIE0 (1u << 1)
#define CAN_ESR_BOFF (1u << 2)
#define CAN_TIR_TXRQ (1u << 0)
#define CAN_RIR_IDE (1u << 2)
#define CAN_RIR_RTR (1u << 1)
#define CAN_FMR_FINIT (1u << 0)

/* ---- TIM2, a 32-bit general-purpose timer (RM0090 §18.4) ------------------------------------ */
typedef struct tim_regs {
    REG CR1, CR2, SMCR, DIER, SR, EGR, CCMR1, CCMR2, CCER, CNT, PSC, ARR;
} tim_regs_t;
#define TIM_CR1_CEN (1u << 0)
#define TIM_EGR_UG (1u << 0)
#define RCC_APB1ENR_TIM2 (1u << 0)

/* ---- Cortex-M4 system control (PM0214 §4) -------------------------------------------------- */
typedef struct systick_regs {
    REG CTRL, LOAD, VAL, CALIB;
} systick_regs_t;
#define SYSTICK_CTRL_ENABLE (1u << 0)
#define SYSTICK_CTRL_TICKINT (1u << 1)
#define SYSTICK_CTRL_CLKSOURCE (1u << 2)

#define SCB_ICSR_PENDSTSET (1u << 26)
#define SCB_ICSR_PENDSVSET (1u << 28)

#ifndef BOARD_HOST_TEST
/* Real addresses (STM32F405, RM0090 Table 1). */
#define USART1 ((usart_regs_t *)0x40011000u)
#define GPIOA ((gpio_regs_t *)0x40020000u)
#define GPIOB ((gpio_regs_t *)0x40020400u)
#define GPIOC ((gpio_regs_t *)0x40020800u)
#define RCC ((rcc_regs_t *)0x40023800u)
#define FLASH_IF ((flash_regs_t *)0x40023C00u)
#define CAN1 ((can_regs_t *)0x40006400u)
#define TIM2 ((tim_regs_t *)0x40000000u)
#define IWDG ((iwdg_regs_t *)0x40003000u)
/* DBGMCU_APB1_FZ (RM0090 §38.16.2): DBG_IWDG_STOP holds the watchdog while a debugger halts. */
#define DBGMCU_APB1_FZ (*(volatile uint32_t *)0xE0042008u)
#define DBGMCU_APB1_FZ_IWDG_STOP (1u << 12)
#define SYSTICK ((systick_regs_t *)0xE000E010u)
#define SCB_ICSR (*(volatile uint32_t *)0xE000ED04u)
#define SCB_VTOR (*(volatile uint32_t *)0xE000ED08u)
#define SCB_AIRCR (*(volatile uint32_t *)0xE000ED0Cu)
#define SCB_SHPR3 (*(volatile uint32_t *)0xE000ED20u)
#define SCB_SHCSR (*(volatile uint32_t *)0xE000ED24u)
#define SCB_CFSR (*(volatile uint32_t *)0xE000ED28u)
#define SCB_HFSR (*(volatile uint32_t *)0xE000ED2Cu)
#define SCB_MMFAR (*(volatile uint32_t *)0xE000ED34u)
#define SCB_BFAR (*(volatile uint32_t *)0xE000ED38u)
#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)
#define NVIC_ISER ((volatile uint32_t *)0xE000E100u)
#define NVIC_ICER ((volatile uint32_t *)0xE000E180u)
#define NVIC_ICPR ((volatile uint32_t *)0xE000E280u)
#define NVIC_IPR ((volatile uint8_t *)0xE000E400u)
#endif

#define IRQ_CAN1_RX0 20u
#define IRQ_USART1 37u

#undef REG
#endif
