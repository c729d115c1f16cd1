#include "console.hpp"

#include "board.hpp"
#include "uart.hpp"

namespace gabarit::mcu {

void Line::put(char c) noexcept {
  if (length_ + 1 < sizeof(buffer_)) buffer_[length_++] = c;  // long lines are cut, never overrun
}

Line& Line::text(const char* s) noexcept {
  for (; *s != '\0'; ++s) put(*s);
  return *this;
}

Line& Line::dec(std::uint64_t value) noexcept {
  char digits[20];
  std::size_t n = 0;
  do {
    digits[n++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0);
  while (n > 0) put(digits[--n]);
  return *this;
}

Line& Line::dec(std::int64_t value) noexcept {
  if (value < 0) {
    put('-');
    return dec(static_cast<std::uint64_t>(-(value + 1)) + 1);
  }
  return dec(static_cast<std::uint64_t>(value));
}

Line& Line::hex(std::uint64_t value) noexcept {
  text("0x");
  bool started = false;
  for (int shift = 60; shift >= 0; shift -= 4) {
    const auto nibble = static_cast<unsigned>((value >> shift) & 0xF);
    if (nibble != 0 || started || shift == 0) {
      put("0123456789abcdef"[nibble]);
      started = true;
    }
  }
  return *this;
}

const char* Line::c_str() noexcept {
  buffer_[length_] = '\0';
  return buffer_;
}

void console_write(Line& line) noexcept {
  static Uart uart(board::kUart0Base);
  static bool enabled = false;
  if (!enabled) {
    uart.enable_tx();
    enabled = true;
  }
  uart.write(line.c_str());
  uart.write("\n");
}

}  // namespace gabarit::mcu
