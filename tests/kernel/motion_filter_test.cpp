// The motion filter: confidence relative to the reference score, the
// constant-velocity prediction, the gate and depth inertia, update and coast.
#include "gabarit/motion_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
using testing::build;
using testing::point_model;
using Scratch = testing::TrackerTestScratch;

TEST(MotionFilter, ConfidenceIsGradedRelativeToTheReferenceScore) {
  MotionFilterParams p;  // high >= 0.7 r, none < 0.5 r
  EXPECT_EQ(classify(0.40f, 0.1f, 0.5f, p), Confidence::kHigh);
  EXPECT_EQ(classify(0.30f, 0.1f, 0.5f, p), Confidence::kIntermediate);
  EXPECT_EQ(classify(0.20f, 0.1f, 0.5f, p), Confidence::kNone);
  EXPECT_EQ(classify(0.0f, 0.0f, 0.0f, p), Confidence::kNone);  // no vote is never confident
  p.high_margin = 0.2f;                                          // margin over the next candidate, relative to r
  EXPECT_EQ(classify(0.40f, 0.35f, 0.5f, p), Confidence::kIntermediate);
  EXPECT_TRUE(valid(MotionFilterParams{}));
  MotionFilterParams bad;
  bad.low_ratio = 0.9f;  // above high_ratio
  EXPECT_FALSE(valid(bad));
  bad = {};
  bad.candidates = 0;
  EXPECT_FALSE(valid(bad));
  bad = {};
  bad.k1 = std::nanf("");
  EXPECT_FALSE(valid(bad));
}

TEST(MotionFilter, PredictsUpdatesAndCoastsByItsEquations) {
  MotionFilterParams p;  // k1 0.5, k2 0.2, k3 0.8, u1 0.5, u2 2, lost above 12 px
  MotionFilter f;
  f.reset(p);
  EXPECT_EQ(f.grade(0.8f, 0.1f), Confidence::kHigh);  // the first graded score is the reference
  EXPECT_FLOAT_EQ(f.reference(), 0.8f);
  f.update(Confidence::kHigh, Pose{10, 20, 1, 0}, Pose{14, 18, 2, 0});
  EXPECT_FLOAT_EQ(f.state().vx, 2.0f);  // (1 - k1) 0 + k1 4
  EXPECT_FLOAT_EQ(f.state().vy, -1.0f);
  EXPECT_FLOAT_EQ(f.state().vtheta, 0.5f);
  EXPECT_EQ(f.state().uncertainty_px, 0.0f);
  const Pose next = f.predict(Pose{14, 18, 2, 3});
  EXPECT_FLOAT_EQ(next.x, 16.0f);
  EXPECT_FLOAT_EQ(next.y, 17.0f);
  EXPECT_FLOAT_EQ(next.theta_deg, 2.5f);
  EXPECT_EQ(next.depth, 3);
  f.update(Confidence::kIntermediate, Pose{14, 18, 2, 0}, Pose{14, 18, 2, 0});
  EXPECT_FLOAT_EQ(f.state().vx, 1.6f);  // (1 - k2) 2 + k2 0
  EXPECT_FLOAT_EQ(f.state().uncertainty_px, 0.5f);
  for (int i = 0; i < 6; ++i) {
    EXPECT_FALSE(f.lost()) << "coast " << i;
    f.coast();
  }
  EXPECT_FLOAT_EQ(f.state().uncertainty_px, 12.5f);  // 0.5 + 6 x 2 > 12: lost
  EXPECT_TRUE(f.lost());
  EXPECT_NEAR(f.state().vx, 1.6f * std::pow(0.8f, 6.0f), 1e-6f);
  f.restart();
  EXPECT_FALSE(f.lost());
  EXPECT_EQ(f.state().vx, 0.0f);
  EXPECT_FLOAT_EQ(f.reference(), 0.8f);  // kept across a restart
}

// The gate: a better-ranked cell far from the prediction is a distractor and
// is skipped; with none inside the gate there is no measurement.
TEST(MotionFilter, TheGateSkipsADistractorOutsideIt) {
  host::Rng rng(4);
  const auto bytes = build(point_model(testing::random_points(rng, 30, 10)), "-10:10:21", "0:0:1");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> counters(t.cell_count(), 0);
  const auto cell_at = [](int dx) { return static_cast<std::uint32_t>(dx + 10); };  // x cells of 1 px from -10
  counters[cell_at(9)] = static_cast<VoteCounter>(t.stencil_size(cell_at(9)));       // the best: 9 px away
  counters[cell_at(2)] = static_cast<VoteCounter>(t.stencil_size(cell_at(2)) / 2);   // the runner-up: 2 px away
  MotionFilterParams p;
  p.gate_px = 4.0f;
  MotionFilter f;
  f.reset(p);
  GatedChoice choice;
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  ASSERT_TRUE(choice.found);
  EXPECT_EQ(choice.cell.cell, cell_at(2));
  EXPECT_TRUE(choice.outranked);
  EXPECT_NEAR(choice.score, 0.5f, 0.05f);
  p.gate_px = 1.0f;
  f.reset(p);
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  EXPECT_FALSE(choice.found);
  p.gate_px = 20.0f;  // both inside: the best is taken, nothing outranked it
  f.reset(p);
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  EXPECT_EQ(choice.cell.cell, cell_at(9));
  EXPECT_FALSE(choice.outranked);
}

}  // namespace
}  // namespace gabarit
