#include "uart.hpp"

namespace gabarit::mcu {
namespace {

// CMSDK APB UART registers (Arm DDI 0479).
constexpr std::uintptr_t kData = 0x00;
constexpr std::uintptr_t kState = 0x04;     // bit 0: TX buffer full
constexpr std::uintptr_t kCtrl = 0x08;      // bit 0: TX enable
constexpr std::uintptr_t kBaudDiv = 0x10;   // >= 16; QEMU ignores the rate
constexpr std::uint32_t kTxFull = 1u << 0;
constexpr std::uint32_t kRxFull = 1u << 1;
constexpr std::uint32_t kTxEnable = 1u << 0;
constexpr std::uint32_t kRxEnable = 1u << 1;

volatile std::uint32_t& reg(std::uintptr_t base, std::uintptr_t offset) noexcept {
  return *reinterpret_cast<volatile std::uint32_t*>(base + offset);
}

}  // namespace

void Uart::enable_tx() noexcept {
  reg(base_, kBaudDiv) = 16;
  reg(base_, kCtrl) = kTxEnable;
}

void Uart::enable_tx_rx() noexcept {
  reg(base_, kBaudDiv) = 16;
  reg(base_, kCtrl) = kTxEnable | kRxEnable;
}

void Uart::write(const std::uint8_t* bytes, std::size_t count) noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    while ((reg(base_, kState) & kTxFull) != 0) {
    }
    reg(base_, kData) = bytes[i];
  }
}

int Uart::read() noexcept {
  if ((reg(base_, kState) & kRxFull) == 0) return -1;
  return static_cast<int>(reg(base_, kData) & 0xFFu);
}

void Uart::write(const char* text) noexcept {
  for (; *text != '\0'; ++text) {
    while ((reg(base_, kState) & kTxFull) != 0) {
    }
    reg(base_, kData) = static_cast<std::uint8_t>(*text);
  }
}

}  // namespace gabarit::mcu
