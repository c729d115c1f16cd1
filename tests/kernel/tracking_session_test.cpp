// The tracking session's additions to track_step: sub-cell refinement, the
// motion filter's confidence and gating, and recovery after the target
// disappears. The plain session must be track_step, frame for frame.
#include "gabarit/tracking_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <bit>
#include <cstring>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/refinement.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
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

// Recovery, several ways: the full grid every lost frame, with each
// placement a full track_step or screened from features detected once; the
// grid spread over searches (24 outer placements each); a search every third
// lost frame.
struct RecoveryCase {
  const char* name;
  bool shared;
  std::uint32_t budget, interval;
  int latest;  // the frame by which the target must be found again
};

TEST(TrackingSession, TheMotionFilterFollowsSmoothMotionAndRecoversAfterAnOcclusion) {
  for (const RecoveryCase c : {RecoveryCase{"full grid, track_step", false, 0, 1, 31}, RecoveryCase{"full grid, screened", true, 0, 1, 31},
                               RecoveryCase{"budget 24", true, 24, 1, 32}, RecoveryCase{"every 3rd frame", true, 0, 3, 33}}) {
  SCOPED_TRACE(c.name);
  host::Rng rng(12);
  const auto pts = testing::random_points(rng, 80, 14);
  const auto bytes = build(point_model(pts), "-4:4:9", "-4:4:9");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  std::vector<RoiPoint> search_features(c.shared ? search_feature_capacity(t) : 0);
  TrackingSession session(t, nullptr, detector_of(t));
  SessionOptions options;
  options.recovery.budget = c.budget;
  options.recovery.interval = c.interval;
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
    ASSERT_EQ(session.step(frame.view(), {s.view(), {}, search_features}, r), Status::kOk);
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
  EXPECT_LE(reacquired_at, c.latest) << "recovery took too long";
  }
}

// The grid's angle offsets: hidden, the target turns by 12 degrees (beyond the
// table's +-1.75 and the first offset's +-3) and moves 20 px; it is found at
// the first visible frame. (A model 100 px across, so 0.5-degree cells
// differ by about half a pixel at its rim, made of 3 x 3 blobs: single
// pixels, rounded once when drawn and again when rotated into the table
// frame, match a rotated stencil far worse than edges in real images do.)
TEST(TrackingSession, RecoveryFindsATargetThatTurnedWhileHidden) {
  host::Rng rng(31);
  std::vector<host::Point> pts;
  for (const host::Point& c : testing::random_points(rng, 60, 48, 5.0))
    for (std::int32_t dy = -1; dy <= 1; ++dy)
      for (std::int32_t dx = -1; dx <= 1; ++dx) pts.push_back({c.x + dx, c.y + dy});
  const auto bytes = build(point_model(pts), "-4:4:9", "-4:4:9", "-1.5:1.5:7");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  std::vector<RoiPoint> search_features(search_feature_capacity(t));
  TrackingSession session(t, nullptr, detector_of(t));
  ASSERT_EQ(session.start(SessionOptions{}, Pose{120, 120, 0, 0}), Status::kOk);
  SessionResult r;
  for (int f = 0; f < 12; ++f) {  // standing still, then hidden until lost
    const GrayImage frame = f < 3 ? testing::draw_points(pts, 120, 120, 0, 240) : GrayImage(240, 240);
    ASSERT_EQ(session.step(frame.view(), {s.view(), {}, search_features}, r), Status::kOk);
    if (f < 3) {
      EXPECT_NEAR(r.pose.theta_deg, 0.0f, 0.3f) << "frame " << f;
    }
  }
  ASSERT_TRUE(session.lost());
  const GrayImage back = testing::draw_points(pts, 140, 120, 12.0f, 240);
  ASSERT_EQ(session.step(back.view(), {s.view(), {}, search_features}, r), Status::kOk);
  EXPECT_TRUE(r.reacquired);
  EXPECT_LE(std::hypot(r.pose.x - 140.0f, r.pose.y - 120.0f), 1.0f);
  EXPECT_NEAR(r.pose.theta_deg, 12.0f, 0.5f);
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
  for (const auto bad_option : {+[](SessionOptions& b) { b.recovery.interval = 0; }, +[](SessionOptions& b) { b.recovery.screen_stride = 0; },
                                +[](SessionOptions& b) { b.recovery.coarse_proposals = 0; },
                                +[](SessionOptions& b) { b.recovery.coarse_proposals = kMaxCoarseProposals + 1; }}) {
    SessionOptions b;
    bad_option(b);
    EXPECT_EQ(session.start(b, Pose{10, 10, 0, 0}), Status::kInvalidArgument);
  }
}

}  // namespace
}  // namespace gabarit
