#include "gabarit/crc32.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace gabarit {
namespace {

std::vector<std::byte> bytes_of(const char* s) {
  std::vector<std::byte> b(std::strlen(s));
  std::memcpy(b.data(), s, b.size());
  return b;
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32(bytes_of("123456789")), 0xCBF43926u);  // the CRC-32/ISO-HDLC check value
  EXPECT_EQ(crc32({}), 0u);
}

TEST(Crc32, UpdatesIncrementally) {
  const auto all = bytes_of("The quick brown fox jumps over the lazy dog");
  const std::span<const std::byte> s(all);
  EXPECT_EQ(crc32(s), 0x414FA339u);
  for (std::size_t cut = 0; cut <= all.size(); ++cut) {
    EXPECT_EQ(crc32_update(crc32(s.first(cut)), s.subspan(cut)), crc32(s)) << "cut at " << cut;
  }
}

}  // namespace
}  // namespace gabarit
