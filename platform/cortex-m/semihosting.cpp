#include "semihosting.hpp"

namespace gabarit::mcu {
namespace {

// Operation numbers from Arm's "Semihosting for AArch32 and AArch64".
constexpr std::uint32_t kSysWrite0 = 0x04;
constexpr std::uint32_t kSysExitExtended = 0x20;
constexpr std::uint32_t kAdpStoppedApplicationExit = 0x20026;

std::uint32_t semihost_call(std::uint32_t op, const void* arg) noexcept {
  register std::uint32_t r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace

void semihost_write(const char* text) noexcept { (void)semihost_call(kSysWrite0, text); }

void semihost_exit(std::uint32_t code) noexcept {
  const std::uint32_t block[2] = {kAdpStoppedApplicationExit, code};
  (void)semihost_call(kSysExitExtended, block);
  for (;;) asm volatile("wfi");
}

}  // namespace gabarit::mcu
