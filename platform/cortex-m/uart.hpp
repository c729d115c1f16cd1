// Arm CMSDK APB UART (the console of the MPS2/MPS3 FPGA images), polled.
// The base address comes from the board header.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gabarit::mcu {

class Uart {
 public:
  explicit Uart(std::uintptr_t base) noexcept : base_(base) {}
  void enable_tx() noexcept;
  void enable_tx_rx() noexcept;
  void write(const char* text) noexcept;
  void write(const std::uint8_t* bytes, std::size_t count) noexcept;
  // The received byte, or -1 when none is waiting.
  int read() noexcept;

 private:
  std::uintptr_t base_;
};

}  // namespace gabarit::mcu
