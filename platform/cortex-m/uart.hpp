// Arm CMSDK APB UART (the console of the MPS2/MPS3 FPGA images): transmit
// only, polled. The base address comes from the board header.
#pragma once

#include <cstdint>

namespace gabarit::mcu {

class Uart {
 public:
  explicit Uart(std::uintptr_t base) noexcept : base_(base) {}
  void enable_tx() noexcept;
  void write(const char* text) noexcept;

 private:
  std::uintptr_t base_;
};

}  // namespace gabarit::mcu
