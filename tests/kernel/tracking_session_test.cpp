// The tracking session's additions to track_step: sub-cell refinement, the
// motion filter's confidence and gating, and recovery after the target
// disappears. The plain session must be track_step, frame for frame.
#include "gabarit/tracking_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <bit>
#include <cstring>
#include <vector>

#include "gabarit/host/image_io.hpp"
#include "gabarit/refinement.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using host::GrayImage;
using testing::build;
using testing::point_model;

using Scratch = testing::TrackerTestScratch;

GrayImage draw(const std::vector<host::Point>& pts, float x, float y) { return testing::draw_points(pts, x, y, 0.0f, 160); }

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

TEST(Refinement, AParabolaThroughThePeakFindsTheSubCellOffset) {
  host::Rng rng(3);
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

TEST(TrackingSession, PlainSessionIsTrackStepFrameForFrame) {
  host::Rng rng(8);
  const auto pts = testing::random_points(rng, 60, 15);
  const auto bytes = build(point_model(pts), "-5:5:11", "-5:5:11");
  const TableView t = testing::open_table(bytes);
  Scratch a(t), b(t);
  TrackingSession session(t, nullptr, detector_of(t));
  ASSERT_EQ(session.start(kPlainSession, Pose{80, 80, 0, 0}), Status::kOk);
  Pose pose{80, 80, 0, 0};
  float x = 80, y = 80;
  for (int f = 0; f < 40; ++f) {
    x += static_cast<float>(rng.uniform_int(-4, 4));
    y += static_cast<float>(rng.uniform_int(-4, 4));
    GrayImage frame = draw(pts, x, y);
    for (auto& v : frame.pixels)
      if (rng.bernoulli(0.1)) v = static_cast<std::uint8_t>(255 - v);
    StepResult plain;
    ASSERT_EQ(track_step(t, frame.view(), pose, a.view(), plain), Status::kOk);
    if (plain.state != TrackState::kLost) pose = plain.pose;
    SessionResult r;
    ASSERT_EQ(session.step(frame.view(), {b.view(), {}}, r), Status::kOk);
    // Bit for bit (Pose has padding, so field by field).
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.x), std::bit_cast<std::uint32_t>(pose.x)) << "frame " << f;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.y), std::bit_cast<std::uint32_t>(pose.y)) << "frame " << f;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.theta_deg), std::bit_cast<std::uint32_t>(pose.theta_deg)) << "frame " << f;
    EXPECT_EQ(r.pose.depth, pose.depth) << "frame " << f;
    EXPECT_EQ(r.step.best.cell, plain.best.cell);
    EXPECT_EQ(r.state, plain.state);
  }
}

// The full recovery grid every lost frame (search_budget 0), and the grid
// spread over lost frames (24 outer placements a frame).
TEST(TrackingSession, TheMotionFilterFollowsSmoothMotionAndRecoversAfterAnOcclusion) {
  for (const std::uint32_t budget : {0u, 24u}) {
  SCOPED_TRACE(budget);
  host::Rng rng(12);
  const auto pts = testing::random_points(rng, 80, 14);
  const auto bytes = build(point_model(pts), "-4:4:9", "-4:4:9");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  TrackingSession session(t, nullptr, detector_of(t));
  SessionOptions options;
  options.search_budget = budget;
  ASSERT_EQ(session.start(options, Pose{40, 60, 0, 0}), Status::kOk);
  // 2 px per frame to the right; hidden for 15 frames, by when it is 30 px
  // from where it was last seen, far beyond the table's +-4 px.
  int reacquired_at = -1, lost_frames = 0;
  for (int f = 0; f < 50; ++f) {
    const float x = 40.0f + 2.0f * static_cast<float>(f + 1), y = 60.0f;
    const bool hidden = f >= 15 && f < 30;
    GrayImage frame = hidden ? GrayImage(160, 160) : draw(pts, x, y);
    for (auto& v : frame.pixels)
      if (rng.bernoulli(0.02)) v = static_cast<std::uint8_t>(255 - v);
    SessionResult r;
    ASSERT_EQ(session.step(frame.view(), {s.view(), {}}, r), Status::kOk);
    if (hidden) {
      EXPECT_NE(r.confidence, Confidence::kHigh) << "frame " << f;
      lost_frames += r.state == TrackState::kLost;
    } else if (f < 15) {
      EXPECT_EQ(r.confidence, Confidence::kHigh) << "frame " << f;
      EXPECT_LE(std::hypot(r.pose.x - x, r.pose.y - y), 0.75f) << "frame " << f;
    } else if (reacquired_at < 0 && std::hypot(r.pose.x - x, r.pose.y - y) <= 1.0f) {
      reacquired_at = f;
    }
    if (f == 14) {
      EXPECT_NEAR(session.motion().vx, 2.0f, 0.25f);
    }
  }
  EXPECT_GT(lost_frames, 0) << "an empty frame sequence must end in the lost state";
  EXPECT_GE(reacquired_at, 30);
  EXPECT_LE(reacquired_at, 32) << "recovery took too long";
  }
}

TEST(TrackingSession, BadOptionsAreRefused) {
  host::Rng rng(1);
  const auto bytes = build(point_model(testing::random_points(rng, 20, 8)), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  TrackingSession session(t, nullptr, detector_of(t));
  SessionOptions o;
  o.filter.candidates = 0;
  EXPECT_EQ(session.start(o, Pose{10, 10, 0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(session.start(SessionOptions{}, Pose{std::nanf(""), 10, 0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(session.start(SessionOptions{}, Pose{10, 10, 0, 3}), Status::kInvalidArgument);  // no depth 3
}

}  // namespace
}  // namespace gabarit
