/* startup.c -- minimal bare-metal start for QEMU's MPS2 boards (mps2-an500 Cortex-M7,
 * mps2-an386 Cortex-M4F): vector table, reset handler, semihosting argc/argv and exit.
 *
 * Reset_Handler: enable the FPU (CPACR), copy .data from its load address, zero .bss,
 * open the semihosting stdio handles (newlib's librdimon), fetch the command line with
 * SYS_GET_CMDLINE, split it into argv, run constructors, call main and exit(status).
 * exit() flushes stdio and ends in librdimon's _exit, which uses SYS_EXIT_EXTENDED so
 * that QEMU exits with main's status. Every fault handler prints one line on the
 * semihosting console and exits with status 70 + exception number (never spins), so an
 * emulated run cannot hang on a fault.
 *
 * Link with -nostartfiles --specs=rdimon.specs and one of the mps2-*.ld scripts.
 * -DSTACK_REPORT: print the stack used by main (painted stack) before exiting.
 * -DSTARTUP_MINIMAL: no stdio/argv/constructors (footprint of the planner alone).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Symbols of the linker script. */
extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[], _estack[];

extern int main(int argc, char **argv);
extern void initialise_monitor_handles(void);   /* newlib librdimon */
extern void __libc_init_array(void);

/* ARM semihosting operations used here (ARM DUI 0471 / semihosting v2). */
#define SYS_WRITE0 0x04
#define SYS_GET_CMDLINE 0x15
#define SYS_EXIT_EXTENDED 0x20
#define ADP_STOPPED_APPLICATION_EXIT 0x20026

static inline uintptr_t semihost(uintptr_t op, const void *arg) {
    register uintptr_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

/* Exit QEMU with `status` without going through stdio (used by fault handlers). */
static void __attribute__((noreturn)) semihost_exit(int status) {
    uintptr_t block[2];
    block[0] = ADP_STOPPED_APPLICATION_EXIT;
    block[1] = (uintptr_t)status;
    for (;;) semihost(SYS_EXIT_EXTENDED, block);
}

#define MAX_CMDLINE 256
#define MAX_ARGS 16

/* argv from SYS_GET_CMDLINE (QEMU: the -semihosting-config arg=... words, or -kernel
 * and -append). Words are split at spaces; no quoting. */
static int command_line(char **argv) {
    static char buf[MAX_CMDLINE];
    uintptr_t block[2];
    int argc = 0;
    char *p;
    block[0] = (uintptr_t)buf;
    block[1] = sizeof buf - 1;
    if (semihost(SYS_GET_CMDLINE, block) != 0) {
        argv[0] = "plan_demo";
        argv[1] = 0;
        return 1;
    }
    buf[block[1] < sizeof buf ? block[1] : sizeof buf - 1] = '\0';
    for (p = buf; *p && argc < MAX_ARGS;) {
        while (*p == ' ') *p++ = '\0';
        if (!*p) break;
        argv[argc++] = p;
        while (*p && *p != ' ') ++p;
    }
    argv[argc] = 0;
    return argc;
}

#if defined(STACK_REPORT)
/* Measured stack use (a check of the static bound, not a bound): the free stack is filled
 * with a pattern before main, and the lowest overwritten word is found after main. */
#define PAINT 0xA5C3E10Fu
extern uint32_t _sstack[];
static void paint_stack(void) {
    uint32_t *p, *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (p = _sstack; p < sp - 16; ++p) *p = PAINT;
}
static void report_stack(void) {
    static char msg[] = "startup: stack used by main: 0000000 bytes\n";
    uint32_t *p = _sstack;
    uint32_t used;
    int i;
    while (p < _estack && *p == PAINT) ++p;
    used = (uint32_t)((uintptr_t)_estack - (uintptr_t)p);
    for (i = 35; i >= 29; --i, used /= 10) msg[i] = (char)('0' + used % 10);
    semihost(SYS_WRITE0, msg);
}
#endif

void __attribute__((noreturn)) Reset_Handler(void) {
    static char *argv[MAX_ARGS + 1];
    uint32_t *src, *dst;
    int argc;
#if defined(__ARM_FP)
    /* CP10 and CP11 full access, then wait for the write to take effect. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
    for (src = _sidata, dst = _sdata; dst < _edata;) *dst++ = *src++;
    for (dst = _sbss; dst < _ebss;) *dst++ = 0;
#if defined(STARTUP_MINIMAL)
    /* No stdio, no argv, no constructors: main's status straight to SYS_EXIT_EXTENDED. Used to
     * measure the footprint of the planner alone (`make size`). */
    (void)argv;
    (void)argc;
    semihost_exit(main(0, 0));
#endif
    initialise_monitor_handles();
    argc = command_line(argv);
    __libc_init_array();
#if defined(STACK_REPORT)
    paint_stack();
    argc = main(argc, argv);
    report_stack();
    exit(argc);
#else
    exit(main(argc, argv));
#endif
}

/* Any exception we do not expect: report it and exit with 70 + its number. */
void Default_Handler(void) {
    uint32_t ipsr;
    static char msg[] = "startup: unexpected exception NN\n";
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    ipsr &= 0x1ffu;
    msg[30] = (char)('0' + (ipsr / 10) % 10);
    msg[31] = (char)('0' + ipsr % 10);
    semihost(SYS_WRITE0, msg);
    semihost_exit(70 + (int)(ipsr > 29 ? 29 : ipsr));
}

/* _init/_fini are called by __libc_init_array / __libc_fini_array; nothing to do here. */
void _init(void) {}
void _fini(void) {}

#define ALIAS __attribute__((weak, alias("Default_Handler")))
void NMI_Handler(void) ALIAS;
void HardFault_Handler(void) ALIAS;
void MemManage_Handler(void) ALIAS;
void BusFault_Handler(void) ALIAS;
void UsageFault_Handler(void) ALIAS;
void SVC_Handler(void) ALIAS;
void DebugMon_Handler(void) ALIAS;
void PendSV_Handler(void) ALIAS;
void SysTick_Handler(void) ALIAS;

/* Vector table: initial SP, 15 system exceptions, 32 external interrupts (the MPS2
 * boards' NVIC has 32). Placed at address 0 (VTOR's reset value) by the linker script. */
typedef void (*vector_t)(void);
#define IRQ8 Default_Handler, Default_Handler, Default_Handler, Default_Handler, \
             Default_Handler, Default_Handler, Default_Handler, Default_Handler
__attribute__((section(".isr_vector"), used)) const vector_t vector_table[16 + 32] = {
    (vector_t)(uintptr_t)_estack,
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    0, 0, 0, 0,
    SVC_Handler,
    DebugMon_Handler,
    0,
    PendSV_Handler,
    SysTick_Handler,
    IRQ8, IRQ8, IRQ8, IRQ8,
};
