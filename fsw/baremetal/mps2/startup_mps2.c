/* Startup of the QEMU board port (mps2-an500, Cortex-M7; docs/baremetal-qemu.md): the vector table
   at address 0, the reset handler (FPU access first: CPACR CP10/CP11 full access, then .data copied
   from its load image, .bss zeroed, static constructors, main), a fault handler that reports over
   semihosting and exits (a fault under QEMU must end the run, not spin until the time limit), and
   a heap that does not exist (_sbrk always fails: the flight software allocates nothing). */
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
/* board_mps2.cpp: writes the fault registers and exits QEMU with a failure. */
void sdins_board_fault(uint32_t ipsr) __attribute__((noreturn));
void sdins_board_exit(int code) __attribute__((noreturn));

static void Fault_Handler(void) {
  uint32_t ipsr;
  __asm volatile("mrs %0, ipsr" : "=r"(ipsr));
  sdins_board_fault(ipsr);
}

__attribute__((section(".isr_vector"), used)) void (*const g_vectors[16])(void) = {
    (void (*)(void))_estack, Reset_Handler, Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    Fault_Handler,           0,             0,             0,             0,             Fault_Handler,
    Fault_Handler,           0,             Fault_Handler, Fault_Handler};

/* CPACR (0xE000ED88) bits 20..23: CP10 and CP11 full access, before any floating-point
   instruction (the code uses the hard-float ABI). Naked, so the compiler emits nothing before it. */
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
  sdins_board_exit(main());
}

/* No heap: newlib's malloc (if anything linked it) gets ENOMEM instead of memory. */
void* _sbrk(ptrdiff_t increment) {
  (void)increment;
  errno = ENOMEM;
  return (void*)-1;
}
