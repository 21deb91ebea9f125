/* The C runtime start shared by every board of the bare-metal image (startup.c: STM32H7-like;
   mps2/startup_mps2.c: QEMU's mps2-an500). Reset_Handler gives the FPU access first (CPACR CP10 and
   CP11 full access, before any floating-point instruction: the code uses the hard-float ABI), then
   branches to the board's sdins_start, which calls sdins_runtime_init() (.data copied from its load
   image, .bss zeroed, static constructors) and main. _sbrk: a heap that does not exist (the flight
   software allocates nothing). Each board file keeps its vector table and what main's return means. */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>

#include "crt0.h"

extern uint32_t _sidata[], _sdata[], _edata[], _sbss[], _ebss[];
extern void (*__preinit_array_start[])(void);
extern void (*__preinit_array_end[])(void);
extern void (*__init_array_start[])(void);
extern void (*__init_array_end[])(void);

/* Naked, so the compiler emits nothing before the CPACR write. */
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

void sdins_runtime_init(void) {
  for (uint32_t *s = _sidata, *d = _sdata; d < _edata;) *d++ = *s++;
  for (uint32_t* d = _sbss; d < _ebss;) *d++ = 0u;
  for (void (**f)(void) = __preinit_array_start; f < __preinit_array_end; ++f) (*f)();
  for (void (**f)(void) = __init_array_start; f < __init_array_end; ++f) (*f)();
}

/* No heap: newlib's malloc (if anything linked it) gets ENOMEM instead of memory. */
void* _sbrk(ptrdiff_t increment) {
  (void)increment;
  errno = ENOMEM;
  return (void*)-1;
}
