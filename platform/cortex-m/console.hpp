// The firmware's text output: whole lines built in a fixed buffer (no printf,
// which would pull newlib's allocator in) and sent to the board's UART.
#pragma once

#include <cstddef>
#include <cstdint>

namespace gabarit::mcu {

class Line {
 public:
  Line& text(const char* s) noexcept;
  Line& dec(std::uint64_t value) noexcept;
  Line& dec(std::int64_t value) noexcept;
  Line& hex(std::uint64_t value) noexcept;  // 0x-prefixed
  const char* c_str() noexcept;

 private:
  void put(char c) noexcept;
  char buffer_[160] = {};
  std::size_t length_ = 0;
};

// Writes one line (a newline is appended) to the console.
void console_write(Line& line) noexcept;

}  // namespace gabarit::mcu
