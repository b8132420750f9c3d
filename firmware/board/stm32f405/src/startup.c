/* Reset, vector table, fault handlers, semihosting, stack painting. Cortex-M4F (STM32F405). */
#include <stdint.h>
#include <string.h>

#include "board/board.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack, _sstack;
extern void __libc_init_array(void);
int main(void);

#define STACK_PAINT 0xA5A5A5A5u

board_fault_record_t board_fault __attribute__((section(".noinit")));

void Reset_Handler(void);
void Default_Handler(void);
void HardFault_Handler(void);
void SysTick_Handler(void);
void USART1_IRQHandler(void);
void PendSV_Handler(void);
void CAN1_RX0_IRQHandler(void);
void board_fault_entry(uint32_t *frame, uint32_t exc_return, uint32_t exception);

/* Newlib's __libc_init_array calls these; there are no constructors to run. */
void _init(void);
void _fini(void);
void _init(void) {}
void _fini(void) {}

__attribute__((noreturn, naked)) void Reset_Handler(void)
{
    __asm volatile(
        "ldr r0, =_estack   \n"
        "mov sp, r0         \n"
        "b board_reset_c    \n");
}

__attribute__((noreturn, used)) void board_reset_c(void);
__attribute__((noreturn, used)) void board_reset_c(void)
{
    /* The FPU stays off (CPACR CP10/CP11 "access denied"): the image has no floating-point
     * instruction (tools/stack_report.py fails the build if one appears), so every exception
     * frame is the basic 8 words instead of 26 with the FP context, which the stack reservation
     * counts on. An FP instruction would raise a UsageFault (NOCP) at once, not grow the stack. */
    SCB_VTOR = 0x08000000u;
    uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = &_sbss; dst < &_ebss;) {
        *dst++ = 0u;
    }
    /* Paint the stack below the current frame, for board_stack_used(). */
    uint32_t sp;
    __asm volatile("mov %0, sp" : "=r"(sp));
    for (uint32_t *p = &_sstack; (uint32_t)p < sp - 64u; p++) {
        *p = STACK_PAINT;
    }
    __libc_init_array();
    (void)main();
    for (;;) {
        __asm volatile("wfi");
    }
}

uint32_t board_stack_size(void)
{
    return (uint32_t)((uintptr_t)&_estack - (uintptr_t)&_sstack);
}

uint32_t board_stack_used(void)
{
    const uint32_t *p = &_sstack;
    while (p < &_estack && *p == STACK_PAINT) {
        p++;
    }
    return (uint32_t)((uintptr_t)&_estack - (uintptr_t)p);
}

/* ---- faults ---------------------------------------------------------------------------------
 * Every fault and every unexpected interrupt lands here with the frame the CPU stacked. The
 * record goes to .noinit RAM; then a test image (semihosting) prints it and exits with 3, the
 * card image and the fault test image reset (the record is there at the next start, main.c). */
__attribute__((naked)) void HardFault_Handler(void)
{
    __asm volatile(
        "tst lr, #4              \n"
        "ite eq                  \n"
        "mrseq r0, msp           \n"
        "mrsne r0, psp           \n"
        "mov r1, lr              \n"
        "mrs r2, ipsr            \n"
        "b board_fault_entry     \n");
}

__attribute__((naked)) void Default_Handler(void)
{
    __asm volatile("b HardFault_Handler\n");
}

__attribute__((noreturn, used)) void board_fault_entry(uint32_t *frame, uint32_t exc_return,
                                                       uint32_t exception)
{
    board_fault_record_t *r = &board_fault;
    uint32_t count = r->magic == BOARD_FAULT_MAGIC ? r->count : 0u;
    r->magic = BOARD_FAULT_MAGIC;
    r->count = count + 1u;
    r->exception = exception & 0x1FFu;
    r->r0 = frame[0];
    r->r1 = frame[1];
    r->r2 = frame[2];
    r->r3 = frame[3];
    r->r12 = frame[4];
    r->lr = frame[5];
    r->pc = frame[6];
    r->xpsr = frame[7];
    /* Frame size: 8 words, 26 with the FP context (EXC_RETURN bit 4 clear), +1 if aligned. */
    uint32_t words = (exc_return & 0x10u) != 0u ? 8u : 26u;
    if ((frame[7] & (1u << 9)) != 0u) {
        words++;
    }
    r->sp = (uint32_t)(uintptr_t)(frame + words);
    r->exc_return = exc_return;
    r->cfsr = SCB_CFSR;
    r->hfsr = SCB_HFSR;
    r->mmfar = SCB_MMFAR;
    r->bfar = SCB_BFAR;
#ifdef BOARD_SEMIHOSTING
    char line[320];
    board_fault_format(r, line, sizeof line);
    semihost_write0(line);
    semihost_write0("\n");
#endif
#if defined(BOARD_SEMIHOSTING) && !defined(DFP_BOARD_FAULT_TEST)
    semihost_exit(3);
#else
    /* The card, and the fault test image so that it sees the record over a reset as the card
     * does (main.c). */
    __asm volatile("dsb" ::: "memory");
    SCB_AIRCR = 0x05FA0004u; /* SYSRESETREQ */
    for (;;) {
    }
#endif
}

/* ---- semihosting (ARM DUI 0471) ------------------------------------------------------------ */
static uint32_t semihost_call(uint32_t op, const void *arg)
{
#ifdef BOARD_SEMIHOSTING
    register uint32_t r0 __asm("r0") = op;
    register const void *r1 __asm("r1") = arg;
    __asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
#else
    (void)op;
    (void)arg;
    return 0; /* without a debugger bkpt would fault: the card image never calls out */
#endif
}

void semihost_write0(const char *s)
{
    (void)semihost_call(0x04u, s); /* SYS_WRITE0 */
}

void semihost_exit(uint32_t code)
{
    const uint32_t block[2] = {0x20026u, code}; /* ADP_Stopped_ApplicationExit, status */
    (void)semihost_call(0x20u, block);          /* SYS_EXIT_EXTENDED */
    for (;;) {
        SCB_AIRCR = 0x05FA0004u;
    }
}

/* ---- vector table -------------------------------------------------------------------------- */
#define NUM_IRQ 82u
typedef void (*vector_t)(void);

__attribute__((section(".isr_vector"), used)) const vector_t board_vectors[16u + NUM_IRQ] = {
    (vector_t)(uintptr_t)&_estack,
    Reset_Handler,
    HardFault_Handler, /* NMI */
    HardFault_Handler,
    HardFault_Handler, /* MemManage */
    HardFault_Handler, /* BusFault */
    HardFault_Handler, /* UsageFault */
    0, 0, 0, 0,
    Default_Handler,   /* SVCall */
    Default_Handler,   /* DebugMon */
    0,
    PendSV_Handler,
    SysTick_Handler,
    /* IRQ  0 */ Default_Handler,
    /* IRQ  1 */ Default_Handler,
    /* IRQ  2 */ Default_Handler,
    /* IRQ  3 */ Default_Handler,
    /* IRQ  4 */ Default_Handler,
    /* IRQ  5 */ Default_Handler,
    /* IRQ  6 */ Default_Handler,
    /* IRQ  7 */ Default_Handler,
    /* IRQ  8 */ Default_Handler,
    /* IRQ  9 */ Default_Handler,
    /* IRQ 10 */ Default_Handler,
    /* IRQ 11 */ Default_Handler,
    /* IRQ 12 */ Default_Handler,
    /* IRQ 13 */ Default_Handler,
    /* IRQ 14 */ Default_Handler,
    /* IRQ 15 */ Default_Handler,
    /* IRQ 16 */ Default_Handler,
    /* IRQ 17 */ Default_Handler,
    /* IRQ 18 */ Default_Handler,
    /* IRQ 19 */ Default_Handler,
    /* IRQ 20 */ CAN1_RX0_IRQHandler,
    /* IRQ 21 */ Default_Handler,
    /* IRQ 22 */ Default_Handler,
    /* IRQ 23 */ Default_Handler,
    /* IRQ 24 */ Default_Handler,
    /* IRQ 25 */ Default_Handler,
    /* IRQ 26 */ Default_Handler,
    /* IRQ 27 */ Default_Handler,
    /* IRQ 28 */ Default_Handler,
    /* IRQ 29 */ Default_Handler,
    /* IRQ 30 */ Default_Handler,
    /* IRQ 31 */ Default_Handler,
    /* IRQ 32 */ Default_Handler,
    /* IRQ 33 */ Default_Handler,
    /* IRQ 34 */ Default_Handler,
    /* IRQ 35 */ Default_Handler,
    /* IRQ 36 */ Default_Handler,
    /* IRQ 37 */ USART1_IRQHandler,
    /* IRQ 38 */ Default_Handler,
    /* IRQ 39 */ Default_Handler,
    /* IRQ 40 */ Default_Handler,
    /* IRQ 41 */ Default_Handler,
    /* IRQ 42 */ Default_Handler,
    /* IRQ 43 */ Default_Handler,
    /* IRQ 44 */ Default_Handler,
    /* IRQ 45 */ Default_Handler,
    /* IRQ 46 */ Default_Handler,
    /* IRQ 47 */ Default_Handler,
    /* IRQ 48 */ Default_Handler,
    /* IRQ 49 */ Default_Handler,
    /* IRQ 50 */ Default_Handler,
    /* IRQ 51 */ Default_Handler,
    /* IRQ 52 */ Default_Handler,
    /* IRQ 53 */ Default_Handler,
    /* IRQ 54 */ Default_Handler,
    /* IRQ 55 */ Default_Handler,
    /* IRQ 56 */ Default_Handler,
    /* IRQ 57 */ Default_Handler,
    /* IRQ 58 */ Default_Handler,
    /* IRQ 59 */ Default_Handler,
    /* IRQ 60 */ Default_Handler,
    /* IRQ 61 */ Default_Handler,
    /* IRQ 62 */ Default_Handler,
    /* IRQ 63 */ Default_Handler,
    /* IRQ 64 */ Default_Handler,
    /* IRQ 65 */ Default_Handler,
    /* IRQ 66 */ Default_Handler,
    /* IRQ 67 */ Default_Handler,
    /* IRQ 68 */ Default_Handler,
    /* IRQ 69 */ Default_Handler,
    /* IRQ 70 */ Default_Handler,
    /* IRQ 71 */ Default_Handler,
    /* IRQ 72 */ Default_Handler,
    /* IRQ 73 */ Default_Handler,
    /* IRQ 74 */ Default_Handler,
    /* IRQ 75 */ Default_Handler,
    /* IRQ 76 */ Default_Handler,
    /* IRQ 77 */ Default_Handler,
    /* IRQ 78 */ Default_Handler,
    /* IRQ 79 */ Default_Handler,
    /* IRQ 80 */ Default_Handler,
    /* IRQ 81 */ Default_Handler,
};
