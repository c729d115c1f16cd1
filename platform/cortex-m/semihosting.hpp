// Arm semihosting (the debugger/QEMU call interface): text to the host's
// console and the program's exit status. Under QEMU this needs
// `-semihosting-config enable=on,target=native`; on a board without a
// debugger attached a BKPT would halt, so the firmware uses it only to end a
// test run.
#pragma once

#include <cstdint>

namespace gabarit::mcu {

void semihost_write(const char* text) noexcept;
// Ends the program; QEMU exits with `code` as its own status.
[[noreturn]] void semihost_exit(std::uint32_t code) noexcept;

}  // namespace gabarit::mcu
