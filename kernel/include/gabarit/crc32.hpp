// CRC-32 (IEEE 802.3: reflected polynomial 0xEDB88320, init and final XOR
// 0xFFFFFFFF) — the same CRC as zlib, gzip and PNG, so `crc32` tools agree;
// tables carry it. CRC-32C (Castagnoli: reflected 0x82F63B78, the same init
// and final XOR; iSCSI, ext4, SCTP), whose Hamming distance is better at
// message lengths, guards the HIL link's messages (docs/hil-protocol.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace gabarit {

// Continue a running CRC: crc32_update(crc32_update(0, a), b) == crc32 of a||b.
std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept;

inline std::uint32_t crc32(std::span<const std::byte> bytes) noexcept {
  return crc32_update(0, bytes);
}

std::uint32_t crc32c_update(std::uint32_t crc, std::span<const std::byte> bytes) noexcept;

inline std::uint32_t crc32c(std::span<const std::byte> bytes) noexcept {
  return crc32c_update(0, bytes);
}

}  // namespace gabarit
