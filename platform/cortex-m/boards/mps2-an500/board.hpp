// Arm MPS2 FPGA image AN500: Cortex-M7 (QEMU `-M mps2-an500`).
#pragma once

#include <cstdint>

namespace gabarit::mcu::board {
inline constexpr const char* kName = "mps2-an500 (Cortex-M7)";
inline constexpr std::uintptr_t kUart0Base = 0x40004000;  // CMSDK APB UART0
inline constexpr std::uintptr_t kUart1Base = 0x40005000;  // CMSDK APB UART1: the HIL firmware's console
// The core clock SysTick counts (QEMU's SYSCLK for the board).
inline constexpr std::uint32_t kCoreClockHz = 25000000;
}  // namespace gabarit::mcu::board
