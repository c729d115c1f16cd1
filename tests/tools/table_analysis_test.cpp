#include "gabarit/host/tables/table_analysis.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "gabarit/app/error.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/tables/table_budget.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/host/tables/template_reduction.hpp"
#include "gabarit/host/scenes/thesis_shapes.hpp"
#include "gabarit/voter.hpp"
#include "test_tables.hpp"

namespace gabarit::host {
namespace {

std::vector<Point> shifts_3x3() {
  std::vector<Point> s;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) s.push_back({x, y});
  return s;
}

// A 7-pixel model in the manner of the thesis's section 4.4, over the 3 x 3
// translations of +-1 px. Worked by hand:
//   . . . . . .      (0,0) (1,0) (2,0) a row, (0,1) (0,2) a column,
//   X X X . . X      (2,2) alone on a diagonal, (5,0) far off.
//   X . . . . .
//   X . X . . .
// A single point is unambiguous when no other translation puts it on the
// model, i.e. no 8-neighbour of it is in the model: only (2,2) and (5,0).
// Two points {p, q} are ambiguous when one shift puts both on the model.
TEST(TableAnalysis, TheSevenPixelExampleOfReducedTemplates) {
  const std::vector<Point> m = {{0, 0}, {1, 0}, {2, 0}, {0, 1}, {0, 2}, {2, 2}, {5, 0}};
  const std::vector<Point> shifts = shifts_3x3();
  std::vector<Point> unambiguous_singles;
  for (const Point& p : m)
    if (characterising_value(m, {p}, shifts) >= 1) unambiguous_singles.push_back(p);
  ASSERT_EQ(unambiguous_singles.size(), 2u);
  EXPECT_EQ(unambiguous_singles[0].x, 2);
  EXPECT_EQ(unambiguous_singles[0].y, 2);
  EXPECT_EQ(unambiguous_singles[1].x, 5);
  // (0,0) and (1,0): shifted by (+1, 0) both land on the row.
  EXPECT_EQ(characterising_value(m, {{0, 0}, {1, 0}}, shifts), 0u);
  // (0,0) and (0,2): no shift puts both on the model; the worst, (0,+1),
  // keeps (0,0) on it ((0,1)) and puts (0,2) off ((0,3)).
  EXPECT_EQ(characterising_value(m, {{0, 0}, {0, 2}}, shifts), 1u);
  // (1,0) and (0,1): every shift puts at least one of them off the model
  // ((-1,0) takes (1,0) to (0,0) but (0,1) to (-1,1)), and some only one, so chi is 1.
  EXPECT_EQ(characterising_value(m, {{1, 0}, {0, 1}}, shifts), 1u);
  // The isolated (5,0) with anything: every shift puts it off.
  EXPECT_GE(characterising_value(m, {{5, 0}, {0, 0}}, shifts), 1u);
  // Whole model: (+1,0) keeps (0,0)->(1,0) and (1,0)->(2,0) on; the other five go off.
  EXPECT_EQ(characterising_value(m, m, {{0, 0}, {1, 0}}), 5u);
}

std::vector<std::byte> small_table(const std::vector<Point>& points, const char* x, const char* y, double keep = 1.0) {
  ModelStack model;
  model.depths.push_back(points);
  model.detector.kind = table_format::DetectorKind::kBinary;
  BuildOptions o;
  o.space.x = parse_axis(x, "x");
  o.space.y = parse_axis(y, "y");
  o.keep = keep;
  return build_table(model, o);
}

// The best cell for a feature set, by the voter's own rule.
std::uint32_t winner(const TableView& t, const std::vector<RoiPoint>& features) {
  std::vector<VoteCounter> counters(voter_counter_count(t.cell_count()));
  VoteTally tally;
  EXPECT_EQ(clear_counters(t, counters), Status::kOk);
  EXPECT_EQ(accumulate_votes(t, features, counters, tally), Status::kOk);
  CellScore top[1];
  EXPECT_EQ(select_top_cells(t, counters, top), Status::kOk);
  return top[0].cell;
}

// On a table small enough to try every feature set of its ROI, the margin of
// error of each cell is the fewest pixels whose flip (from the object at the
// cell's centre) makes another cell the winner.
TEST(TableAnalysis, MarginsAreTheFewestFlipsByExhaustiveSearch) {
  for (double keep : {1.0, 0.6}) {
    const auto bytes = small_table({{0, 0}, {1, 0}, {0, 1}, {2, 1}}, "-1:1:3", "0:0:1", keep);
    const TableView t = testing::open_table(bytes);
    ASSERT_LE(t.roi_pixels(), 20u);
    const TableAnalysis a = analyse_table(t);
    ASSERT_TRUE(a.exact);
    for (std::uint32_t T = 0; T < t.cell_count(); ++T) {
      // The object at T's centre: the model points moved by the centre.
      const CellBounds c = t.cell(T);
      std::uint32_t object = 0;
      for (std::uint32_t i = 0; i < t.model_point_count(); ++i) {
        const int col = t.model_point(i).x + static_cast<int>(c.x_centre()) - t.roi_origin_x();
        const int row = t.model_point(i).y + static_cast<int>(c.y_centre()) - t.roi_origin_y();
        object |= 1u << (row * t.roi_width() + col);
      }
      std::uint32_t fewest = 99;
      for (std::uint32_t set = 0; set < (1u << t.roi_pixels()); ++set) {
        const auto flips = static_cast<std::uint32_t>(__builtin_popcount(set ^ object));
        if (flips >= fewest) continue;
        std::vector<RoiPoint> features;
        for (std::uint32_t p = 0; p < t.roi_pixels(); ++p)
          if (set >> p & 1u) features.push_back({static_cast<std::uint16_t>(p % t.roi_width()), static_cast<std::uint16_t>(p / t.roi_width())});
        if (winner(t, features) != T) fewest = flips;
      }
      EXPECT_EQ(a.stencils[T].margin, fewest) << "keep " << keep << " cell " << T;
    }
    EXPECT_EQ(a.overall_margin, std::min_element(a.stencils.begin(), a.stencils.end(), [](auto& x, auto& y) { return x.margin < y.margin; })->margin);
  }
}

// Full stencils of a translation space have equal sizes, and the vote-count
// argument gives margin = |S| - the overlap with the rival: the robustness
// indicator, or one more where the most overlapping rival has the higher
// index (ties go to the lower index, so it must pass T, not equal it).
TEST(TableAnalysis, FullTranslationStencilsHaveTheRobustnessAsMargin) {
  const auto bytes = small_table(thesis_curve(), "-5:5:11", "-5:5:11");
  const TableView t = testing::open_table(bytes);
  const TableAnalysis a = analyse_table(t);
  for (const StencilMargin& s : a.stencils) {
    EXPECT_GE(static_cast<std::int64_t>(s.margin), s.robustness) << s.cell;
    EXPECT_LE(static_cast<std::int64_t>(s.margin), s.robustness + 1) << s.cell;
  }
  // And the whole model's characterising value over the space's relative moves is the same number.
  std::vector<std::int32_t> c;
  for (int i = -5; i <= 5; ++i) c.push_back(i);
  const ReductionResult r = reduce_template(thesis_curve(), translation_differences(c, c), 1, ReductionOrder::kGreedy, 1, 1);
  EXPECT_GE(a.overall_margin, r.full_value);
  EXPECT_LE(a.overall_margin, r.full_value + 1);
  std::uint64_t pixels = 0;
  for (std::uint64_t n : a.pixels_with) pixels += n;
  EXPECT_EQ(pixels, t.roi_pixels());
}

TEST(TemplateReduction, KeepsTheCharacterisingValueAndIsMinimal) {
  std::vector<std::int32_t> c;
  for (int i = -5; i <= 5; ++i) c.push_back(i);
  const std::vector<Point> shifts = translation_differences(c, c);
  const std::vector<Point> model = thesis_curve();
  for (ReductionOrder order : {ReductionOrder::kGreedy, ReductionOrder::kRandom}) {
    for (std::uint32_t k : {1u, 5u, 20u}) {
      const ReductionResult r = reduce_template(model, shifts, k, order, 4, 3);
      EXPECT_GE(r.characterising_value, k);
      EXPECT_EQ(characterising_value(model, r.points, shifts), r.characterising_value);
      EXPECT_LT(r.points.size(), model.size());
      // Minimal: without any one of its points, the value drops below k.
      for (std::size_t i = 0; i < r.points.size(); ++i) {
        std::vector<Point> fewer = r.points;
        fewer.erase(fewer.begin() + static_cast<std::ptrdiff_t>(i));
        ASSERT_LT(characterising_value(model, fewer, shifts), k) << "point " << i << " was not needed";
      }
      const ReductionResult again = reduce_template(model, shifts, k, order, 4, 3);
      EXPECT_EQ(again.points.size(), r.points.size());
    }
  }
  EXPECT_THROW((void)reduce_template(model, shifts, 100000, ReductionOrder::kGreedy, 1, 1), app::Error);
}

TEST(TableBudget, MaxBytesFitsWithinFivePercentAndMinMarginIsMet) {
  ModelStack model;
  model.depths.push_back(thesis_curve());
  model.detector.kind = table_format::DetectorKind::kBinary;
  BuildOptions o;
  o.space.x = parse_axis("-5:5:11", "x");
  o.space.y = parse_axis("-5:5:11", "y");
  const std::size_t full = build_table(model, o).size();
  for (double fraction : {0.8, 0.5, 0.35}) {
    Budget b;
    b.max_bytes = static_cast<std::uint64_t>(fraction * static_cast<double>(full));
    BudgetReport r;
    const auto bytes = build_table_to_budget(model, o, b, r);
    EXPECT_LE(bytes.size(), b.max_bytes);
    EXPECT_GE(static_cast<double>(bytes.size()), 0.95 * static_cast<double>(b.max_bytes)) << fraction;
    EXPECT_EQ(r.bytes, bytes.size());
    EXPECT_EQ(r.margin, overall_margin(testing::open_table(bytes)));
    EXPECT_TRUE(r.margin_exact);
  }
  Budget m;
  m.min_margin = 40;
  BudgetReport r;
  const auto bytes = build_table_to_budget(model, o, m, r);
  EXPECT_GE(r.margin, 40u);
  EXPECT_LT(bytes.size(), full);
  // Impossible budgets are refused with the closest figure.
  Budget tiny;
  tiny.max_bytes = 1000;
  EXPECT_THROW((void)build_table_to_budget(model, o, tiny, r), app::Error);
  Budget huge;
  huge.min_margin = 100000;
  EXPECT_THROW((void)build_table_to_budget(model, o, huge, r), app::Error);
}

TEST(TableBudget, TheMeasuredNoiseToleranceFallsWithTheReferencesKept) {
  ModelStack model;
  model.depths.push_back(thesis_curve());
  model.detector.kind = table_format::DetectorKind::kBinary;
  BuildOptions o;
  o.space.x = parse_axis("-5:5:11", "x");
  o.space.y = parse_axis("-5:5:11", "y");
  const double full = measured_noise_tolerance(build_table(model, o), model.depths[0], 20, 1);
  o.keep = 0.05;
  const double few = measured_noise_tolerance(build_table(model, o), model.depths[0], 20, 1);
  EXPECT_GE(full, 0.3);
  EXPECT_LT(few, full);
}

}  // namespace
}  // namespace gabarit::host
