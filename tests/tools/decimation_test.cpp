#include "gabarit/host/decimation.hpp"

#include <gtest/gtest.h>

#include "gabarit/app/error.hpp"
#include "gabarit/host/rng.hpp"

namespace gabarit::host {
namespace {

std::vector<std::uint32_t> mixed_overlap() {
  // Half the references sit on pixels covered by 2 stencils, half on pixels covered by 20.
  std::vector<std::uint32_t> o(20000, 2);
  for (std::size_t i = 0; i < o.size(); i += 2) o[i] = 20;
  return o;
}

TEST(Decimation, KeepsTheRequestedFractionOnAverage) {
  const auto overlap = mixed_overlap();
  for (double keep : {0.9, 0.5, 0.1, 0.01}) {
    const auto kept = decimate(overlap, keep, 3);
    const double fraction = static_cast<double>(std::count(kept.begin(), kept.end(), true)) / static_cast<double>(kept.size());
    EXPECT_NEAR(fraction, keep, 0.02) << keep;
  }
}

TEST(Decimation, RemovesMoreOverlappedReferencesMoreOften) {
  const auto overlap = mixed_overlap();
  const auto kept = decimate(overlap, 0.7, 5);
  double removed_high = 0, removed_low = 0;
  for (std::size_t i = 0; i < kept.size(); ++i) (overlap[i] == 20 ? removed_high : removed_low) += !kept[i];
  // Removal probability is proportional to n(p): about 10x more often at n = 20 than at n = 2.
  EXPECT_NEAR(removed_high / removed_low, 10.0, 1.5);
}

TEST(Decimation, IsDeterministicPerSeedAndKeepsAllAtOne) {
  const auto overlap = mixed_overlap();
  EXPECT_EQ(decimate(overlap, 0.3, 11), decimate(overlap, 0.3, 11));
  EXPECT_NE(decimate(overlap, 0.3, 11), decimate(overlap, 0.3, 12));
  const auto all = decimate(overlap, 1.0, 11);
  EXPECT_EQ(std::count(all.begin(), all.end(), true), static_cast<long>(overlap.size()));
  EXPECT_THROW(decimate(overlap, 0.0, 1), app::Error);
  EXPECT_THROW(decimate(overlap, 1.5, 1), app::Error);
}

}  // namespace
}  // namespace gabarit::host
