// Arm MPS3 FPGA image AN547: Cortex-M55 on Corstone-300 (QEMU `-M mps3-an547`).
// The core resets in the Secure state, so the firmware uses the Secure
// aliases of memory and peripherals (bit 28 set).
#pragma once

#include <cstdint>

namespace gabarit::mcu::board {
inline constexpr const char* kName = "mps3-an547 (Cortex-M55)";
inline constexpr std::uintptr_t kUart0Base = 0x59303000;  // CMSDK APB UART0, Secure alias
inline constexpr std::uintptr_t kUart1Base = 0x59304000;  // CMSDK APB UART1, Secure alias: the HIL firmware's console
// The core clock SysTick counts (QEMU's SYSCLK for the board).
inline constexpr std::uint32_t kCoreClockHz = 32000000;
}  // namespace gabarit::mcu::board
