// Sub-cell refinement: the parabola through the winning cell and its neighbours.
#include "gabarit/refinement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/tracker.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
using testing::build;
using testing::point_model;
using Scratch = testing::TrackerTestScratch;

TEST(Refinement, AParabolaThroughThePeakFindsTheSubCellOffset) {
  app::Rng rng(3);
  const auto pts = testing::random_points(rng, 40, 12);
  const auto bytes = build(point_model(pts), "-3:3:7", "-3:3:7");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> counters(t.cell_count(), 0);
  // Scores along x around cell (ix 3, iy 3): 0.5, 0.9, 0.7 of each stencil.
  const std::uint32_t centre = 3 * 7 + 3;
  const auto set = [&](std::uint32_t cell, float share) {
    counters[cell] = static_cast<VoteCounter>(std::lround(share * static_cast<float>(t.cell(cell).stencil_size)));
  };
  set(centre - 1, 0.5f);
  set(centre, 0.9f);
  set(centre + 1, 0.7f);
  set(centre - 7, 0.8f);  // y: symmetric, no offset
  set(centre + 7, 0.8f);
  const SubCellOffset o = refine_within_cell(t, counters, centre);
  const auto score = [&](std::uint32_t c) { return normalised_score({c, counters[c], t.cell(c).stencil_size}); };
  const float a = score(centre - 1), b = score(centre), c = score(centre + 1);
  EXPECT_NEAR(o.x, 0.5f * (a - c) / (a - 2 * b + c), 1e-6f);
  EXPECT_GT(o.x, 0.0f);  // towards the better neighbour
  EXPECT_LE(o.x, 0.5f);
  EXPECT_NEAR(o.y, 0.0f, 0.05f);
  EXPECT_EQ(o.theta_deg, 0.0f);  // one theta cell: nothing to refine
  // Border cells and valleys keep the centre.
  EXPECT_EQ(refine_within_cell(t, counters, 0).x, 0.0f);
  std::fill(counters.begin(), counters.end(), 0);
  set(centre - 1, 0.9f);
  set(centre + 1, 0.9f);
  set(centre, 0.2f);
  EXPECT_EQ(refine_within_cell(t, counters, centre).x, 0.0f);
}

// The alignment: features exactly where the cell puts the model give no
// offset; the model one pixel to the right gives +1, clamped to half a cell;
// too few features, or short scratch, give none (and false).
TEST(Refinement, AligningTheFeaturesFindsTheirOffsetWithinTheCell) {
  app::Rng rng(9);
  const auto pts = testing::random_points(rng, 40, 10);
  const auto bytes = build(point_model(pts), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  const std::uint32_t centre_cell = 2 * 5 + 2;  // x 0, y 0
  const auto features_at = [&](int dx, std::size_t count) {
    std::vector<RoiPoint> f;
    for (std::size_t i = 0; i < pts.size() && f.size() < count; ++i)
      f.push_back({static_cast<std::uint16_t>(pts[i].x + dx - t.roi_origin_x()), static_cast<std::uint16_t>(pts[i].y - t.roi_origin_y())});
    return f;
  };
  std::vector<std::uint8_t> occupancy(tracker_mask_bytes(t));
  SubCellOffset o;
  ASSERT_TRUE(refine_by_alignment(t, features_at(0, pts.size()), occupancy, centre_cell, o));
  EXPECT_NEAR(o.x, 0.0f, 1e-4f);
  EXPECT_NEAR(o.y, 0.0f, 1e-4f);
  ASSERT_TRUE(refine_by_alignment(t, features_at(1, pts.size()), occupancy, centre_cell, o));
  EXPECT_FLOAT_EQ(o.x, 0.5f);  // +1 px, clamped to half of the 1-px spacing
  EXPECT_NEAR(o.y, 0.0f, 1e-3f);
  EXPECT_FALSE(refine_by_alignment(t, features_at(0, 2), occupancy, centre_cell, o));  // two features match few points
  EXPECT_EQ(o.x, 0.0f);
  std::vector<std::uint8_t> short_scratch(tracker_mask_bytes(t) - 1);
  EXPECT_FALSE(refine_by_alignment(t, features_at(0, pts.size()), short_scratch, centre_cell, o));
}

}  // namespace
}  // namespace gabarit
