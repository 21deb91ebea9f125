/* Startup of the bare-metal fsw image (Cortex-M7, no OS): the vector table and what follows reset
   (crt0.c: FPU access, .data copied from flash, .bss zeroed, static constructors, no heap), then
   main; on this board main's return parks the core. */
#include <stdint.h>

#include "crt0.h"

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

void sdins_start(void) {
  sdins_runtime_init();
  (void)main();
  for (;;) {
  }
}
