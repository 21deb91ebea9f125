/* Startup of the QEMU board port (mps2-an500, Cortex-M7; docs/baremetal-qemu.md): the vector table
   at address 0, what follows reset (../crt0.c: FPU access, .data, .bss, static constructors, no
   heap), main, whose return code leaves QEMU over semihosting, and a fault handler that reports
   over semihosting and exits (a fault under QEMU must end the run, not spin until the time limit). */
#include <stdint.h>

#include "../crt0.h"

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

void sdins_start(void) {
  sdins_runtime_init();
  sdins_board_exit(main());
}
