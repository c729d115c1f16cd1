#include "gabarit/host/tables/stencil.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "gabarit/app/rng.hpp"

#include <cmath>
#include <set>

#include "gabarit/voter.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using host::Point;

TEST(Stencil, IntegerTranslationsAreTheIntegersInsideOrTheClosest) {
  EXPECT_EQ(host::integer_translations(-0.5f, 0.5f).first, 0);
  EXPECT_EQ(host::integer_translations(-0.5f, 0.5f).last, 0);
  EXPECT_EQ(host::integer_translations(-1.0f, 1.0f).first, -1);
  EXPECT_EQ(host::integer_translations(-1.0f, 1.0f).last, 1);
  EXPECT_EQ(host::integer_translations(2.2f, 2.8f).first, 3);  // no integer inside: closest to 2.5 (half away)
  EXPECT_EQ(host::integer_translations(2.2f, 2.4f).first, 2);
  // The other policy: the smallest enclosing integer range.
  using host::TranslationPolicy;
  EXPECT_EQ(host::integer_translations(2.2f, 2.8f, TranslationPolicy::kEnclosing).first, 2);
  EXPECT_EQ(host::integer_translations(2.2f, 2.8f, TranslationPolicy::kEnclosing).last, 3);
  EXPECT_EQ(host::integer_translations(-0.5f, 0.5f, TranslationPolicy::kEnclosing).first, -1);
  EXPECT_EQ(host::integer_translations(-0.5f, 0.5f, TranslationPolicy::kEnclosing).last, 1);
  EXPECT_EQ(host::integer_translations(-1.0f, 1.0f, TranslationPolicy::kEnclosing).first, -1);
  EXPECT_EQ(host::integer_translations(-1.0f, 1.0f, TranslationPolicy::kEnclosing).last, 1);
  EXPECT_EQ(host::integer_translations(-1.75f, 1.75f).first, -1);
  EXPECT_EQ(host::integer_translations(-1.75f, 1.75f).last, 1);
}

TEST(Stencil, SweptArcsCoverTheWholeArc) {
  const std::vector<Point> pts = {{20, 0}, {0, -13}, {7, 9}};
  const auto arcs = host::swept_arcs(pts, -8.0f, 12.0f);
  const std::set<Point> arc_set(arcs.begin(), arcs.end());
  for (const Point& p : pts) {
    for (double deg = -8; deg <= 12; deg += 0.01) {
      const double a = deg * M_PI / 180;
      const double x = std::cos(a) * p.x - std::sin(a) * p.y, y = std::sin(a) * p.x + std::cos(a) * p.y;
      double best = 1e9;
      for (const Point& q : arcs) best = std::min(best, std::hypot(q.x - x, q.y - y));
      // Half the sample spacing plus the rounding to a pixel.
      EXPECT_LE(best, 0.25 + std::sqrt(0.5)) << "point (" << p.x << "," << p.y << ") at " << deg << " deg";
    }
  }
  // The start of the arc is sampled exactly.
  EXPECT_TRUE(arc_set.count({static_cast<int>(std::lround(20 * std::cos(-8 * M_PI / 180))),
                             static_cast<int>(std::lround(20 * std::sin(-8 * M_PI / 180)))}));
}

// The table against an independent brute-force computation: for random
// shapes, spaces and frames, the vote count of every cell is |P ∩ S_U|,
// with S_U = { m + (kx, ky) : m in model, kx, ky integer translations of U }.
// The builder's fast translation sweep (a shift, or a bitmap over the
// bounding box) against the definition: every arc pixel plus every integer
// translation of the cell, sorted and de-duplicated.
TEST(Stencil, TranslationSweepEqualsTheDefinition) {
  app::Rng rng(5);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Point> arcs;
    for (int i = 0; i < 40; ++i) arcs.push_back({rng.uniform_int(-20, 20), rng.uniform_int(-20, 20)});
    std::sort(arcs.begin(), arcs.end());
    arcs.erase(std::unique(arcs.begin(), arcs.end()), arcs.end());
    CellBounds cell;
    cell.x_lo = static_cast<float>(rng.uniform_int(-8, 4)) + 0.25f * static_cast<float>(rng.uniform_int(0, 3));
    cell.x_hi = cell.x_lo + 0.5f * static_cast<float>(rng.uniform_int(0, 8));
    cell.y_lo = static_cast<float>(rng.uniform_int(-8, 4)) + 0.25f * static_cast<float>(rng.uniform_int(0, 3));
    cell.y_hi = cell.y_lo + 0.5f * static_cast<float>(rng.uniform_int(0, 8));
    const host::IntegerRange tx = host::integer_translations(cell.x_lo, cell.x_hi), ty = host::integer_translations(cell.y_lo, cell.y_hi);
    std::vector<Point> want;
    for (const Point& a : arcs)
      for (std::int32_t dx = tx.first; dx <= tx.last; ++dx)
        for (std::int32_t dy = ty.first; dy <= ty.last; ++dy) want.push_back({a.x + dx, a.y + dy});
    std::sort(want.begin(), want.end());
    want.erase(std::unique(want.begin(), want.end()), want.end());
    EXPECT_EQ(host::translate_sweep(arcs, cell), want) << "trial " << trial;
  }
}

TEST(Stencil, TableVotesEqualBruteForceIntersectionCounts) {
  app::Rng rng(4242);
  for (int round = 0; round < 40; ++round) {
    const auto pts = testing::random_points(rng, 1 + rng.next_u32() % 40, 1 + static_cast<std::int32_t>(rng.next_u32() % 15));
    const double lo = -static_cast<double>(rng.next_u32() % 8) - 0.5 * (rng.next_u32() % 2);
    const double hi = lo + 1 + rng.next_u32() % 10 + 0.25 * (rng.next_u32() % 4);
    const std::uint32_t xc = 1 + rng.next_u32() % 7, yc = 1 + rng.next_u32() % 7;
    char x[64], y[64];
    std::snprintf(x, sizeof x, "%g:%g:%u", xc == 1 ? lo : lo, xc == 1 ? lo : hi, xc);
    std::snprintf(y, sizeof y, "%g:%g:%u", yc == 1 ? hi : lo, hi, yc);
    SCOPED_TRACE(::testing::Message() << "round " << round << " x " << x << " y " << y << " points " << pts.size());
    const auto bytes = testing::build(testing::point_model(pts), x, y);
    const TableView t = testing::open_table(bytes);

    std::set<Point> frame;
    std::vector<RoiPoint> features;
    const double density = 0.05 + 0.5 * rng.next_unit();
    for (std::uint16_t r = 0; r < t.roi_height(); ++r)
      for (std::uint16_t c = 0; c < t.roi_width(); ++c)
        if (rng.bernoulli(density)) {
          features.push_back({c, r});
          frame.insert({t.roi_origin_x() + c, t.roi_origin_y() + r});
        }
    std::vector<VoteCounter> counters(t.cell_count(), 0);
    VoteTally tally;
    ASSERT_EQ(accumulate_votes(t, features, counters, tally), Status::kOk);

    for (std::uint32_t cell = 0; cell < t.cell_count(); ++cell) {
      const CellBounds b = t.cell(cell);
      auto range = [](float l, float h) {
        int first = static_cast<int>(std::ceil(l)), last = static_cast<int>(std::floor(h));
        if (first > last) first = last = static_cast<int>(std::lround((l + h) / 2));
        return std::pair(first, last);
      };
      const auto [x0, x1] = range(b.x_lo, b.x_hi);
      const auto [y0, y1] = range(b.y_lo, b.y_hi);
      std::set<Point> s;
      for (int kx = x0; kx <= x1; ++kx)
        for (int ky = y0; ky <= y1; ++ky)
          for (const Point& m : pts) s.insert({m.x + kx, m.y + ky});
      std::size_t hits = 0;
      for (const Point& p : s) hits += frame.count(p);
      ASSERT_EQ(counters[cell], hits) << "cell " << cell;
      ASSERT_EQ(t.stencil_size(cell), s.size()) << "cell " << cell;
    }
  }
}

// Thesis Theorem 1, for translations: when the span of every cell is smaller
// than the minimum distance between model points, the cell holding the true
// motion is the unique argmax (noise-free frame).
TEST(Stencil, TheoremOneTrueCellIsTheUniqueArgmax) {
  app::Rng rng(99);
  struct Space {
    const char* axis;
    double span;  // largest distance between two translations of a cell
  } spaces[] = {{"-5:5:11", 0.0}, {"-6:6:5", 2 * std::sqrt(2.0)}, {"-10:10:5", 4 * std::sqrt(2.0)}};
  for (const Space& sp : spaces) {
    for (int round = 0; round < 25; ++round) {
      const auto pts = testing::random_points(rng, 5 + rng.next_u32() % 40, 20, sp.span);
      const auto bytes = testing::build(testing::point_model(pts), sp.axis, sp.axis);
      const TableView t = testing::open_table(bytes);
      const int tx = rng.uniform_int(-5, 5), ty = rng.uniform_int(-5, 5);
      std::vector<RoiPoint> features;
      for (const Point& m : pts) {
        features.push_back({static_cast<std::uint16_t>(m.x + tx - t.roi_origin_x()), static_cast<std::uint16_t>(m.y + ty - t.roi_origin_y())});
      }
      std::vector<VoteCounter> counters(t.cell_count(), 0);
      VoteTally tally;
      ASSERT_EQ(accumulate_votes(t, features, counters, tally), Status::kOk);
      CellScore top[2];
      ASSERT_EQ(select_top_cells(t, counters, top), Status::kOk);
      const CellBounds best = t.cell(top[0].cell);
      EXPECT_TRUE(best.x_lo <= tx && tx <= best.x_hi && best.y_lo <= ty && ty <= best.y_hi)
          << sp.axis << " round " << round << " true (" << tx << "," << ty << ")";
      EXPECT_EQ(top[0].votes, pts.size());
      EXPECT_LT(top[1].votes, top[0].votes) << "not unique: " << sp.axis << " round " << round;
    }
  }
}

}  // namespace
}  // namespace gabarit
