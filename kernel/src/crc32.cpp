#include "gabarit/crc32.hpp"

#include <array>

namespace gabarit {
namespace {

// 1 KiB table computed at compile time; it lands in flash on an MCU.
constexpr std::array<std::uint32_t, 256> make_crc_table(std::uint32_t reflected_polynomial) {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int bit = 0; bit < 8; ++bit) c = (c & 1u) ? (reflected_polynomial ^ (c >> 1)) : (c >> 1);
    table[i] = c;
  }
  return table;
}

constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table(0xEDB88320u);
constexpr std::array<std::uint32_t, 256> kCrcCastagnoliTable = make_crc_table(0x82F63B78u);

std::uint32_t update(const std::array<std::uint32_t, 256>& table, std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  std::uint32_t c = ~crc;
  for (const std::byte b : bytes) {
    c = table[(c ^ static_cast<std::uint32_t>(b)) & 0xFFu] ^ (c >> 8);
  }
  return ~c;
}

}  // namespace

std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  return update(kCrcTable, crc, bytes);
}

std::uint32_t crc32c_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept {
  return update(kCrcCastagnoliTable, crc, bytes);
}

}  // namespace gabarit
