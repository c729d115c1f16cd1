// The gathered samples' blend (kernel/src/intensity_samples.hpp, internal
// to the kernel: the one white-box test of it), which the compiler
// vectorises and on x86-64 Linux also builds for AVX2, against the scalar
// reference it replaces in the hot loops: FrameSample::value and
// add_sample, sample by sample. Every count up to two arrays' worth (the
// padded last block, a full array, a flush in between), pixels and weights
// at their extremes and at random.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "../../kernel/src/intensity_samples.hpp"

namespace gabarit::intensity {
namespace {

struct Reference {
  FrameSums frame;
  ImageSums model;
};

// One sample's pixels, weights and model pixel, as the gathering loop
// stores them, and as the reference reads them.
struct Drawn {
  std::uint8_t p[4];  // row0[0], row0[1], row1[0], row1[1]
  std::uint8_t wx, wy, model;
};

void gather(GatheredSamples& g, const Drawn& d) {
  const std::uint8_t top[2] = {d.p[0], d.p[1]}, bottom[2] = {d.p[2], d.p[3]};
  const std::uint32_t k = g.count++;
  g.top_pair[k] = GatheredSamples::pair(top);
  g.bottom_pair[k] = GatheredSamples::pair(bottom);
  g.wx[k] = d.wx;
  g.wy[k] = d.wy;
  g.model[k] = d.model;
  if (g.count == GatheredSamples::kCapacity) g.flush();
}

void add_reference(Reference& r, const Drawn& d) {
  FrameSample at{};
  at.row0 = d.p;
  at.row1 = d.p + 2;
  at.wx = d.wx;
  at.wy = d.wy;
  add_sample(r.frame, r.model, d.model, at.value());
}

TEST(GatheredSamples, BlendsAndSumsAsTheSampleBySampleLoopDoes) {
  std::mt19937 rng(31u);
  const auto byte = [&](int extremes) -> std::uint8_t {
    // One draw in `extremes` is 0 or 255 (the blend's and the sums' bounds).
    if (extremes > 0 && rng() % static_cast<std::uint32_t>(extremes) == 0) return rng() % 2 ? 255 : 0;
    return static_cast<std::uint8_t>(rng());
  };
  for (std::uint32_t count = 0; count <= 2 * GatheredSamples::kCapacity + 3; ++count) {
    for (const int extremes : {0, 2, 1}) {
      GatheredSamples g;
      Reference r;
      for (std::uint32_t i = 0; i < count; ++i) {
        const Drawn d{{byte(extremes), byte(extremes), byte(extremes), byte(extremes)}, byte(extremes), byte(extremes), byte(extremes)};
        gather(g, d);
        add_reference(r, d);
      }
      g.flush();
      EXPECT_EQ(g.count, 0u);
      ASSERT_EQ(g.b_sum, r.frame.b) << count << " samples, extremes " << extremes;
      ASSERT_EQ(g.bb, r.frame.bb) << count << " samples, extremes " << extremes;
      ASSERT_EQ(g.ab, r.model.ab) << count << " samples, extremes " << extremes;
    }
  }
}

// Every sample at 255 with the weights that keep it there: the largest b,
// b^2 and model * b sums a full array can hold, still exact.
TEST(GatheredSamples, AFullArrayOfWhiteSumsExactly) {
  GatheredSamples g;
  for (std::uint32_t i = 0; i + 1 < GatheredSamples::kCapacity; ++i) gather(g, Drawn{{255, 255, 255, 255}, 0, 255, 255});
  gather(g, Drawn{{255, 255, 255, 255}, 128, 128, 255});  // the array fills and flushes itself
  EXPECT_EQ(g.count, 0u);
  const std::uint64_t n = GatheredSamples::kCapacity, b = 255u * 256u;
  EXPECT_EQ(g.b_sum, n * b);
  EXPECT_EQ(g.bb, n * b * b);
  EXPECT_EQ(g.ab, n * 255u * b);
}

}  // namespace
}  // namespace gabarit::intensity
