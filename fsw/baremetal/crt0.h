/* The shared C runtime start of the bare-metal boards (crt0.c). */
#pragma once

#include <stdint.h>

extern uint32_t _estack[];
int main(void);
/* The reset vector: FPU access, then the board's sdins_start. */
void Reset_Handler(void);
/* Defined by each board: sdins_runtime_init(), main, and what main's return means there. */
void sdins_start(void) __attribute__((noreturn, used));
/* .data, .bss and the static constructors. */
void sdins_runtime_init(void);
