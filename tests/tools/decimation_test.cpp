#include "gabarit/host/tables/decimation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "gabarit/app/error.hpp"

namespace gabarit::host {
namespace {

constexpr std::uint32_t kCells = 20;
constexpr std::uint32_t kCrowded = 500;  // pixels 0..499 lie in every stencil
constexpr std::uint32_t kSparse = 5000;  // then each pixel lies in two consecutive stencils

// Half the references sit on pixels covered by 20 stencils, half on pixels
// covered by 2; every stencil holds 500 of each.
StencilPixels mixed_stencils() {
  StencilPixels s;
  s.roi_width = 100;
  s.roi_height = (kCrowded + kSparse) / 100;
  s.cells.resize(kCells);
  for (std::uint32_t c = 0; c < kCells; ++c)
    for (std::uint32_t p = 0; p < kCrowded; ++p) s.cells[c].push_back(p);
  for (std::uint32_t k = 0; k < kSparse; ++k) {
    s.cells[k % kCells].push_back(kCrowded + k);
    s.cells[(k + 1) % kCells].push_back(kCrowded + k);
  }
  for (auto& c : s.cells) std::sort(c.begin(), c.end());
  return s;
}

bool crowded(std::uint32_t pixel) { return pixel < kCrowded; }

// Kept references per cell, and removals on crowded / sparse pixels.
struct Tally {
  std::vector<std::size_t> kept_per_cell;
  double removed_crowded = 0, removed_sparse = 0;
};
Tally tally(const StencilPixels& s, const std::vector<bool>& kept) {
  Tally t;
  std::size_t i = 0;
  for (const auto& cell : s.cells) {
    std::size_t k = 0;
    for (std::uint32_t p : cell) {
      if (kept[i]) ++k;
      else (crowded(p) ? t.removed_crowded : t.removed_sparse) += 1;
      ++i;
    }
    t.kept_per_cell.push_back(k);
  }
  return t;
}

DecimationPolicy global_pass() {
  DecimationPolicy p;
  p.method = Decimation::kGlobal;
  return p;
}

TEST(Decimation, TheGlobalPassKeepsTheFractionOnAverageAndRemovesByOverlap) {
  const StencilPixels s = mixed_stencils();
  for (double keep : {0.9, 0.5, 0.1}) {
    const auto kept = decimate(s, keep, 3, global_pass());
    EXPECT_NEAR(static_cast<double>(std::count(kept.begin(), kept.end(), true)) / kept.size(), keep, 0.02) << keep;
  }
  const Tally t = tally(s, decimate(s, 0.7, 5, global_pass()));
  // Removal probability is proportional to n(p): 10x more often at n = 20 than at n = 2.
  EXPECT_NEAR(t.removed_crowded / t.removed_sparse, 10.0, 1.5);
}

TEST(Decimation, AlgorithmTwoKeepsEveryStencilAtItsTargetSize) {
  const StencilPixels s = mixed_stencils();
  for (double keep : {0.5, 0.1, 0.01}) {
    for (bool spread : {false, true}) {
      DecimationPolicy p;
      p.spread = spread;
      const Tally t = tally(s, decimate(s, keep, 7, p));
      for (std::size_t c = 0; c < kCells; ++c) {
        EXPECT_EQ(t.kept_per_cell[c], static_cast<std::size_t>(std::llround(keep * 1000))) << keep << " cell " << c;
      }
    }
  }
  DecimationPolicy floor;
  floor.min_area = 25;
  for (std::size_t k : tally(s, decimate(s, 0.01, 7, floor)).kept_per_cell) EXPECT_EQ(k, 25u);
  // However small keep is, no stencil is emptied.
  for (std::size_t k : tally(s, decimate(s, 1e-9, 7, DecimationPolicy{})).kept_per_cell) EXPECT_EQ(k, 1u);
}

TEST(Decimation, AlgorithmTwoRemovesTheCrowdedPixelsFirstAndMoreSoWithSharperWeights) {
  const StencilPixels s = mixed_stencils();
  DecimationPolicy identity, power, greedy;
  identity.spread = power.spread = greedy.spread = false;  // the weights alone
  power.weight = RemovalWeight::kPower;
  power.power = 2;
  greedy.weight = RemovalWeight::kGreedy;
  const Tally ti = tally(s, decimate(s, 0.6, 9, identity));
  const Tally tp = tally(s, decimate(s, 0.6, 9, power));
  const Tally tg = tally(s, decimate(s, 0.6, 9, greedy));
  EXPECT_GT(ti.removed_crowded, 2 * ti.removed_sparse);
  EXPECT_GT(tp.removed_crowded, ti.removed_crowded);
  EXPECT_GE(tg.removed_crowded, tp.removed_crowded);
  // Greedy removes 400 of the first stencil's references, all from the
  // crowded pixels (|array(p)| = 20 there against 2).
  const auto kept = decimate(s, 0.6, 9, greedy);
  std::size_t first_cell_crowded_removed = 0;
  for (std::size_t i = 0; i < s.cells[0].size(); ++i) first_cell_crowded_removed += !kept[i] && crowded(s.cells[0][i]);
  EXPECT_EQ(first_cell_crowded_removed, 400u);
}

TEST(Decimation, MostOverlappingFirstKeepsWhatTellsAStencilFromItsRival) {
  // Cell 0 is a row of 40 pixels; cell 1 its first 30 (the rival); cell 2
  // shares 10 pixels of it. Removing 30 of cell 0's references takes exactly
  // the 30 shared with cell 1: the 10 that tell cell 0 from cell 1 stay.
  StencilPixels s;
  s.roi_width = 40;
  s.roi_height = 1;
  s.cells.resize(3);
  for (std::uint32_t p = 0; p < 40; ++p) s.cells[0].push_back(p);
  for (std::uint32_t p = 0; p < 30; ++p) s.cells[1].push_back(p);
  for (std::uint32_t p = 25; p < 35; ++p) s.cells[2].push_back(p);
  DecimationPolicy p;
  p.most_overlapping = true;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto kept = decimate(s, 0.25, seed, p);
    for (std::uint32_t px = 0; px < 40; ++px) EXPECT_EQ(kept[px], px >= 30) << "seed " << seed << " pixel " << px;
  }
}

// The longest run of consecutive removed references along a one-row stencil.
std::size_t longest_hole(const std::vector<bool>& kept, std::size_t n) {
  std::size_t best = 0, run = 0;
  for (std::size_t i = 0; i < n; ++i) {
    run = kept[i] ? 0 : run + 1;
    best = std::max(best, run);
  }
  return best;
}

TEST(Decimation, SpreadLeavesNoLargeHoles) {
  StencilPixels s;
  s.roi_width = 2000;
  s.roi_height = 1;
  s.cells.resize(1);
  for (std::uint32_t p = 0; p < 2000; ++p) s.cells[0].push_back(p);
  DecimationPolicy plain, spread;
  plain.spread = false;
  spread.spread = true;
  std::size_t plain_worst = 0, spread_worst = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    plain_worst = std::max(plain_worst, longest_hole(decimate(s, 0.3, seed, plain), 2000));
    spread_worst = std::max(spread_worst, longest_hole(decimate(s, 0.3, seed, spread), 2000));
  }
  EXPECT_LT(spread_worst, plain_worst) << plain_worst;
  EXPECT_LE(3 * spread_worst, 2 * plain_worst) << spread_worst << " against " << plain_worst;
}

TEST(Decimation, IsDeterministicPerSeedAndKeepsAllAtOne) {
  const StencilPixels s = mixed_stencils();
  for (const DecimationPolicy& p : {DecimationPolicy{}, global_pass()}) {
    EXPECT_EQ(decimate(s, 0.3, 11, p), decimate(s, 0.3, 11, p));
    EXPECT_NE(decimate(s, 0.3, 11, p), decimate(s, 0.3, 12, p));
    const auto all = decimate(s, 1.0, 11, p);
    EXPECT_EQ(std::count(all.begin(), all.end(), true), static_cast<long>(all.size()));
    EXPECT_THROW((void)decimate(s, 0.0, 1, p), app::Error);
    EXPECT_THROW((void)decimate(s, 1.5, 1, p), app::Error);
  }
}

TEST(Decimation, NamesParse) {
  EXPECT_EQ(parse_decimation("stencil"), Decimation::kStencil);
  EXPECT_EQ(parse_decimation("overlap"), Decimation::kGlobal);
  EXPECT_THROW(parse_decimation("random"), app::Error);
  DecimationPolicy p;
  parse_removal_weight("power:3", p);
  EXPECT_EQ(p.weight, RemovalWeight::kPower);
  EXPECT_EQ(p.power, 3u);
  EXPECT_THROW(parse_removal_weight("power:4", p), app::Error);
  p.most_overlapping = true;
  EXPECT_EQ(describe(p), "stencil, power:3, most-overlapping");
  p.spread = true;
  EXPECT_EQ(describe(p), "stencil, power:3, most-overlapping, spread");
}

}  // namespace
}  // namespace gabarit::host
