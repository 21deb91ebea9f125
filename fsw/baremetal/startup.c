/* Startup of the bare-metal fsw image (Cortex-M7, no OS): the vector table, the reset handler
   (FPU access first, then .data copied from flash, .bss zeroed, static constructors, main) and a
   heap that does not exist (_sbrk always fails: the flight software allocates nothing). */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>

extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[], _estack[];
extern void (*__preinit_array_start[])(void);
extern void (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void);
extern void (*__init_array_end[])(void);

int main(void);
void Reset_Handler(void);
void sdins_start(void) __attribute__((noreturn, used));

static void Default_Handler(void) {
  for (;;) {
  }
}
void NMI_Handler(void) __attribute__((weak, alias("Default_Handler")));
void HardFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler(void) __attribute__((weak, alias("Default_Handler")));
void BusFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void UsageFault_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SVC_Handler(void) __attribute__((weak, alias("Default_Handler")));
void DebugMon_Handler(void) __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));

/* The Cortex-M system exception vectors (device interrupts are not used by this image). */
__attribute__((section(".isr_vector"), used)) void (*const g_vectors[16])(void) = {
    (void (*)(void))_estack, Reset_Handler,    NMI_Handler, HardFault_Handler, MemManage_Handler,
    BusFault_Handler,        UsageFault_Handler, 0,         0,                 0,
    0,                       SVC_Handler,      DebugMon_Handler, 0,             PendSV_Handler,
    SysTick_Handler};

/* Coprocessor access (CPACR, CP10/CP11 full access) before any floating-point instruction: the
   code is compiled for the hard-float ABI. Naked, so the compiler emits nothing before it. */
__attribute__((naked, noreturn)) void Reset_Handler(void) {
  __asm volatile(
      "ldr r0, =0xE000ED88\n"
      "ldr r1, [r0]\n"
      "orr r1, r1, #(0xF << 20)\n"
      "str r1, [r0]\n"
      "dsb\n"
      "isb\n"
      "b sdins_start\n");
}

void sdins_start(void) {
  for (uint32_t *s = _sidata, *d = _sdata; d < _edata;) *d++ = *s++;
  for (uint32_t* d = _sbss; d < _ebss;) *d++ = 0u;
  for (void (**f)(void) = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)(void) = __init_array_start; f < __init_array_end; ++f) (*f)();
  (void)main();
  for (;;) {
  }
}

/* No heap: newlib's malloc (if anything linked it) gets ENOMEM instead of memory. */
void* _sbrk(ptrdiff_t increment) {
  (void)increment;
  errno = ENOMEM;
  return (void*)-1;
}
