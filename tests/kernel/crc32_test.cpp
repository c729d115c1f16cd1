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

TEST(Crc32c, MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32c(bytes_of("123456789")), 0xE3069283u);  // the CRC-32/ISCSI check value
  EXPECT_EQ(crc32c({}), 0u);
  // RFC 3720 B.4: 32 bytes of zeros.
  const std::vector<std::byte> zeros(32, std::byte{0});
  EXPECT_EQ(crc32c(zeros), 0x8A9136AAu);
}

TEST(Crc32c, UpdatesIncrementallyAndDiffersFromCrc32) {
  const auto all = bytes_of("The quick brown fox jumps over the lazy dog");
  const std::span<const std::byte> s(all);
  EXPECT_NE(crc32c(s), crc32(s));
  for (std::size_t cut = 0; cut <= all.size(); ++cut) {
    EXPECT_EQ(crc32c_update(crc32c(s.first(cut)), s.subspan(cut)), crc32c(s)) << "cut at " << cut;
  }
}

}  // namespace
}  // namespace gabarit
