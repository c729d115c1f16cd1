// The bilinear blend of gathered samples (intensity_samples.hpp).
#include "intensity_samples.hpp"

#include <cstring>

namespace gabarit::intensity {

// On x86-64 Linux GCC also builds the blend for AVX2 and the loader picks
// the clone the CPU runs (an ifunc): twice SSE2's lanes, and the 32-bit
// multiply SSE2 lacks. The integers are the same, so the sums are the same
// on any CPU and target. (Measured: docs/performance.md, "The particle
// measure's blend in vector lanes".)
#if defined(__x86_64__) && defined(__linux__) && defined(__GNUC__) && !defined(__clang__)
#define GABARIT_BLEND_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GABARIT_BLEND_CLONES
#endif

// b is FrameSample::value's integer, written as weights times pixels: each
// row's blend is at most 255 * 256, so it fits 16 bits, and the last
// blend's sum before the shift fits 32. A full array's b and model * b sums
// fit 32 bits (128 * 255 * 65280 < 2^32).
GABARIT_BLEND_CLONES void GatheredSamples::flush() noexcept {
  std::memset(top_pair + count, 0, sizeof(top_pair[0]) * kBlock);
  std::memset(bottom_pair + count, 0, sizeof(bottom_pair[0]) * kBlock);
  std::memset(wx + count, 0, kBlock);
  std::memset(wy + count, 0, kBlock);
  std::memset(model + count, 0, kBlock);
  const std::uint32_t padded = (count + kBlock - 1) / kBlock * kBlock;
  std::uint32_t chunk_b = 0, chunk_ab = 0;
  std::uint64_t chunk_bb = 0;
  for (std::uint32_t k = 0; k < padded; ++k) {
    const std::uint32_t x1 = wx[k], x0 = 256u - x1, y1 = wy[k], y0 = 256u - y1;
    const std::uint32_t p00 = top_pair[k] & 255u, p01 = top_pair[k] >> 8u;
    const std::uint32_t p10 = bottom_pair[k] & 255u, p11 = bottom_pair[k] >> 8u;
    const auto top = static_cast<std::uint16_t>(p00 * x0 + p01 * x1);
    const auto bottom = static_cast<std::uint16_t>(p10 * x0 + p11 * x1);
    const auto b = static_cast<std::uint16_t>((std::uint32_t{top} * y0 + std::uint32_t{bottom} * y1 + 128u) >> 8u);
    chunk_b += b;
    chunk_bb += std::uint32_t{b} * b;
    chunk_ab += std::uint32_t{model[k]} * b;
  }
  b_sum += chunk_b;
  bb += chunk_bb;
  ab += chunk_ab;
  count = 0;
}

}  // namespace gabarit::intensity
