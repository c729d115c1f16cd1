// Reset and exception entry for the Cortex-M boards: the vector table, the
// C++ runtime set-up a hosted program gets from crt0 (.data copied from
// flash, .bss zeroed, the FPU enabled), then the application's app_main.
// There are no static constructors to run: firmware.ld refuses to link any,
// so start-up has no indirect calls and the stack report sees every call.
// A fault reports itself on the console and ends the run with a failure.
#include <cstdint>

#include "console.hpp"
#include "semihosting.hpp"

extern "C" {
extern std::uint32_t __data_start[], __data_end[], __data_load[], __bss_start[], __bss_end[], __stack_top[];
int app_main();  // the application (ISO C++ forbids calling main)
[[noreturn]] void Reset_Handler();
[[noreturn]] void Fault_Handler();
}

namespace {

// Coprocessor Access Control: full access to CP10/CP11 (the FPU). The
// kernel is built for the hard-float ABI, so this comes before any C++ code.
void enable_fpu() {
  volatile std::uint32_t& cpacr = *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u);
  cpacr = cpacr | (0xFu << 20);
  asm volatile("dsb\n\tisb" ::: "memory");
}

using Handler = void (*)();

}  // namespace

[[noreturn]] void Fault_Handler() {
  gabarit::mcu::Line line;
  gabarit::mcu::console_write(line.text("FAULT: hard fault or unexpected exception"));
  gabarit::mcu::semihost_exit(3);
}

[[noreturn]] void Reset_Handler() {
  enable_fpu();
  for (std::uint32_t *src = __data_load, *dst = __data_start; dst < __data_end;) *dst++ = *src++;
  for (std::uint32_t* dst = __bss_start; dst < __bss_end;) *dst++ = 0;
  gabarit::mcu::semihost_exit(static_cast<std::uint32_t>(app_main()));
}

// Initial stack pointer, reset, then NMI..SysTick (15 system exceptions);
// every other exception is a fault here (the firmware uses no interrupts).
__attribute__((section(".isr_vector"), used)) const Handler kVectorTable[16] = {
    reinterpret_cast<Handler>(__stack_top), Reset_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    Fault_Handler, Fault_Handler, nullptr, nullptr, nullptr, nullptr, Fault_Handler, Fault_Handler, nullptr,
    Fault_Handler, Fault_Handler,
};
