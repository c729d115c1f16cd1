// Internal to the kernel: the loops of extract_canny's rows path that touch
// every pixel of the ROI, with scalar bodies and, where the build has Google
// Highway (libhwy-dev) and the target a SIMD unit, vector bodies. Not
// installed.
//
// Both are integer arithmetic with the scalar path's very comparisons, so
// the vector bodies give its features bit for bit on every target (the test
// Canny.RowsOfMagnitudesGiveTheReferenceFeaturesBitForBit compares the rows
// path, vector or not, with the per-pixel reference path on awkward sizes).
#pragma once

#include <cstddef>
#include <cstdint>

namespace gabarit::canny_rows {

// out[i] = |gx| + |gy| of the 3x3 Sobel operator centred on column i of the
// row `mid`, for i in [0, count); `up` and `down` are the rows above and
// below, at the same column. Reads columns -1 .. count of the three rows.
void sobel_magnitudes(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down, std::size_t count,
                      std::uint16_t* out) noexcept;
void sobel_magnitudes_scalar(const std::uint8_t* up, const std::uint8_t* mid, const std::uint8_t* down,
                             std::size_t count, std::uint16_t* out) noexcept;

// Canny's direction test (features.cpp, canny_keeps) compares ay * 100000
// with ax * 41421, products up to 1.02e8, for |gx| = ax and |gy| = ay of at
// most 1020. For whole integers it is ay <= floor(ax * 41421 / 100000)
// (mostly horizontal) and ay >= ceil(ax * 100000 / 41421) (mostly vertical),
// and these two limits come exactly from 16-bit lanes: ax plus the high half
// of a 16-bit product, shifted (checked for every ax below).
inline constexpr std::uint16_t kHorizontalMultiplier = 43047, kVerticalMultiplier = 43053;
inline constexpr std::int32_t kMaxSobelComponent = 4 * 255;
constexpr std::int32_t horizontal_limit(std::int32_t ax) noexcept {
  return (ax + ((ax * kHorizontalMultiplier) >> 16)) >> 2;
}
constexpr std::int32_t vertical_limit(std::int32_t ax) noexcept {
  return 2 * ax + ((ax + ((ax * kVerticalMultiplier) >> 16)) >> 2) + (ax > 0 ? 1 : 0);
}
constexpr bool direction_limits_exact() noexcept {
  for (std::int32_t ax = 0; ax <= kMaxSobelComponent; ++ax) {
    if (horizontal_limit(ax) != ax * 41421 / 100000) return false;
    if (vertical_limit(ax) != (ax * 100000 + 41420) / 41421) return false;
  }
  return true;
}
static_assert(direction_limits_exact());

// One row of Canny's decision, every pointer indexed by the same column c:
// the magnitudes of the rows above, at and below (sobel_magnitudes), the
// image rows they come from, and the two thresholds (low >= 1).
struct DecisionRow {
  const std::uint16_t* above;
  const std::uint16_t* at;
  const std::uint16_t* below;
  const std::uint8_t* up;
  const std::uint8_t* mid;
  const std::uint8_t* down;
  std::uint16_t low, high;
};

// Canny's decision (features.cpp, canny_keeps: above the low threshold, a
// maximum across the edge, strong or next to a strong pixel) for the columns
// [begin, begin + done), done the largest whole number of vectors within
// end - begin and 64 columns: bit k of the result is column begin + k. Reads
// columns begin - 1 .. begin + done of every row. done = 0 (nothing decided)
// where there is no vector body or too few columns left.
[[nodiscard]] std::uint64_t decide(const DecisionRow& row, std::size_t begin, std::size_t end,
                                   std::size_t& done) noexcept;

// Which body the functions above run on this machine: "AVX2", "SSE4",
// "NEON" or "scalar".
[[nodiscard]] const char* vector_target() noexcept;

}  // namespace gabarit::canny_rows
