// Little-endian loads and stores that are safe at any alignment: tables come
// from mmap'd files or const arrays in MCU flash with no alignment promise,
// and Cortex-M faults on some unaligned accesses (LDRD/LDM). memcpy of a
// constant size compiles to a single load where the target allows it.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace gabarit {

static_assert(std::endian::native == std::endian::little,
              "gabarit reads little-endian tables with native loads; add byte swaps for a big-endian target");

template <class T>
inline T load_le(const std::byte* p) noexcept {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

template <class T>
inline void store_le(std::byte* p, T value) noexcept {
  std::memcpy(p, &value, sizeof(T));
}

}  // namespace gabarit
