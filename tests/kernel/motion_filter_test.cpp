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
  bad.accel_var = std::nanf("");
  EXPECT_FALSE(valid(bad));
  bad = {};
  bad.meas_var_high = 0.0f;  // a variance must be positive
  EXPECT_FALSE(valid(bad));
}

// The constant-velocity Kalman filter, checked against its equations
// written out here in double precision.
TEST(MotionFilter, PredictsUpdatesAndCoastsByTheKalmanEquations) {
  MotionFilterParams p;  // q 0.5, r 0.25 (high) / 2 (intermediate), velocity variance 4 at the start
  MotionFilter f;
  f.reset(p, Pose{10, 20, 1, 0});
  EXPECT_EQ(f.grade(0.8f, 0.1f), Confidence::kHigh);  // the first graded score is the reference
  EXPECT_FLOAT_EQ(f.reference(), 0.8f);
  // One axis by hand: P0 = diag(r_high, 4); predict P = F P F' + Q; correct with z.
  struct Axis {
    double x, v, p00, p01, p11;
    void predict(double q) {
      x += v;
      const double a = p00 + 2 * p01 + p11 + q / 4, b = p01 + p11 + q / 2, c = p11 + q;
      p00 = a, p01 = b, p11 = c;
    }
    void correct(double z, double r) {
      const double s = p00 + r, k0 = p00 / s, k1 = p01 / s, e = z - x;
      x += k0 * e, v += k1 * e;
      const double a = p00 - k0 * p00, b = p01 - k0 * p01, c = p11 - k1 * p01;
      p00 = a, p01 = b, p11 = c;
    }
  };
  Axis ax{10, 0, 0.25, 0, 4}, ay{20, 0, 0.25, 0, 4}, at{1, 0, 0.1, 0, 4};
  f.update(Confidence::kHigh, Pose{14, 18, 2, 0});
  ax.predict(0.5), ay.predict(0.5), at.predict(0.05);
  ax.correct(14, 0.25), ay.correct(18, 0.25), at.correct(2, 0.1);
  EXPECT_NEAR(f.state().vx, ax.v, 1e-5);
  EXPECT_NEAR(f.state().vy, ay.v, 1e-5);
  EXPECT_NEAR(f.state().vtheta, at.v, 1e-5);
  EXPECT_NEAR(f.state().position_variance, ax.p00 + ay.p00, 1e-5);
  EXPECT_GT(f.state().vx, 3.0f);  // most of the 4-px step is taken as velocity
  const Pose next = f.predict(Pose{14, 18, 2, 3});
  EXPECT_FLOAT_EQ(next.x, 14.0f + f.state().vx);
  EXPECT_FLOAT_EQ(next.theta_deg, 2.0f + f.state().vtheta);
  EXPECT_EQ(next.depth, 3);
  // An intermediate measurement weighs less; an unmeasured angle keeps its velocity.
  const float vtheta = f.state().vtheta;
  f.update(Confidence::kIntermediate, Pose{17, 17, 9, 0}, false);
  ax.predict(0.5), ay.predict(0.5), at.predict(0.05);
  ax.correct(17, 2.0), ay.correct(17, 2.0);
  EXPECT_NEAR(f.state().vx, ax.v, 1e-4);
  EXPECT_NEAR(f.state().position_variance, ax.p00 + ay.p00, 1e-4);
  EXPECT_FLOAT_EQ(f.state().vtheta, vtheta);
  // Coasting: the velocity is kept, the variance grows until the target is lost.
  int coasted = 0;
  while (!f.lost() && coasted < 100) {
    f.coast();
    ax.predict(0.5), ay.predict(0.5);
    ++coasted;
  }
  EXPECT_NEAR(f.state().position_variance, ax.p00 + ay.p00, 1e-2);
  EXPECT_GT(ax.p00 + ay.p00, 144.0);  // lost_uncertainty_px 12
  EXPECT_GE(coasted, 4);
  EXPECT_LE(coasted, 9);
  EXPECT_NEAR(f.state().vx, ax.v, 1e-4);
  f.restart(Pose{0, 0, 0, 0});
  EXPECT_FALSE(f.lost());
  EXPECT_EQ(f.state().vx, 0.0f);
  EXPECT_FLOAT_EQ(f.reference(), 0.8f);  // kept across a restart
}

// The gate: a better-ranked cell far from the prediction is a distractor and
// is skipped; with none inside the gate there is no measurement.
TEST(MotionFilter, TheGateSkipsADistractorOutsideIt) {
  app::Rng rng(4);
  const auto bytes = build(point_model(testing::random_points(rng, 30, 10)), "-10:10:21", "0:0:1");
  const TableView t = testing::open_table(bytes);
  std::vector<VoteCounter> counters(t.cell_count(), 0);
  const auto cell_at = [](int dx) { return static_cast<std::uint32_t>(dx + 10); };  // x cells of 1 px from -10
  counters[cell_at(9)] = static_cast<VoteCounter>(t.stencil_size(cell_at(9)));       // the best: 9 px away
  counters[cell_at(2)] = static_cast<VoteCounter>(t.stencil_size(cell_at(2)) / 2);   // the runner-up: 2 px away
  MotionFilterParams p;
  p.gate_px = 4.0f;
  // A filter sure of its prediction, so the gate is gate_px (its square plus
  // 4 x the predicted position variance, here 0.26 px^2).
  p.initial_speed_var = p.meas_var_high = p.accel_var = 0.01f;
  MotionFilter f;
  f.reset(p, Pose{50, 50, 0, 0});
  GatedChoice choice;
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  ASSERT_TRUE(choice.found);
  EXPECT_EQ(choice.cell.cell, cell_at(2));
  EXPECT_TRUE(choice.outranked);
  EXPECT_NEAR(choice.score, 0.5f, 0.05f);
  p.gate_px = 1.0f;
  f.reset(p, Pose{50, 50, 0, 0});
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  EXPECT_FALSE(choice.found);
  p.gate_px = 20.0f;  // both inside: the best is taken, nothing outranked it
  f.reset(p, Pose{50, 50, 0, 0});
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  EXPECT_EQ(choice.cell.cell, cell_at(9));
  EXPECT_FALSE(choice.outranked);
  // An uncertain prediction widens the gate: 1 px plus two standard deviations.
  p.gate_px = 1.0f;
  p.initial_speed_var = 4.0f;
  f.reset(p, Pose{50, 50, 0, 0});
  ASSERT_EQ(f.choose(t, counters, Pose{50, 50, 0, 0}, 50, 50, 0, choice), Status::kOk);
  ASSERT_TRUE(choice.found);
  EXPECT_EQ(choice.cell.cell, cell_at(2));
}

}  // namespace
}  // namespace gabarit
