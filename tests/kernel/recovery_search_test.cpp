// Recovery after the target disappears: the grid search (full, screened from
// shared features, spread by a budget, every n-th frame), its angle offsets,
// and the search on its own.
#include "gabarit/recovery_search.hpp"

#include "gabarit/tracking_session.hpp"
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

GrayImage draw(const std::vector<host::Point>& pts, float x, float y) { return testing::draw_points(pts, x, y, 0.0f, 160); }

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
  app::Rng rng(12);
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
  app::Rng rng(31);
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

// The search alone: a target 24 px from where it was last seen (beyond the
// table's +-4 px) is the result of the first search; an interval of 2 makes
// every other lost frame a frame between searches.
TEST(RecoverySearch, FindsATargetBeyondTheTableAndKeepsItsInterval) {
  app::Rng rng(12);
  const auto pts = testing::random_points(rng, 80, 14);
  const auto bytes = build(point_model(pts), "-4:4:9", "-4:4:9");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  std::vector<RoiPoint> search_features(search_feature_capacity(t));
  const GrayImage frame = draw(pts, 84, 60);
  RecoverySearch search(t, nullptr, detector_of(t));
  RecoveryOptions options;
  options.interval = 2;
  search.reset();
  const LastSighting last{Pose{60, 60, 0, 0}, {}, 5};
  for (int lost_frame = 0; lost_frame < 4; ++lost_frame) {
    SearchResult r;
    ASSERT_EQ(search.run(frame.view(), options, last, 0, {s.view(), {}, search_features}, r), Status::kOk);
    EXPECT_EQ(r.searched, lost_frame % 2 == 0) << "lost frame " << lost_frame;
    if (!r.searched) continue;
    EXPECT_FALSE(r.searched_coarse);
    EXPECT_LE(std::hypot(r.vote.pose.x - 84.0f, r.vote.pose.y - 60.0f), 1.0f) << "lost frame " << lost_frame;
    EXPECT_GT(r.vote.score, 0.9f);
  }
  EXPECT_FALSE(valid(RecoveryOptions{3.0f, 0, 0, 2, 8}));  // interval 0
  EXPECT_TRUE(valid(RecoveryOptions{}));
  // The sizes are compile-time formulas a firmware can static_assert against.
  static_assert(search_feature_capacity(Axis{-4, 4, 9}, Axis{-4, 4, 9}, 40, 40, -20, -20) ==
                (2 * std::size_t{search_reach(Axis{-4, 4, 9}, Axis{-4, 4, 9}, 40, 40, -20, -20)} + 1) *
                    (2 * std::size_t{search_reach(Axis{-4, 4, 9}, Axis{-4, 4, 9}, 40, 40, -20, -20)} + 1));
  static_assert(search_reach(Axis{-4, 4, 9}, Axis{-4, 4, 9}, 40, 40, -20, -20) == 4 * 9 + 1 + 59 / 2 + 1);  // window side 59 for a 40 x 40 ROI
}

// A long lost period: the last confident velocity, extrapolated over 340,000
// frames (about 3 hours at 30 fps), would put the centre past the kernel's
// +-1e6 px pose range, and every search used to fail. The centre stays in the
// frame instead (and the turn within half a turn), so a target that
// reappears near where the motion led is found.
TEST(RecoverySearch, ALongLostPeriodKeepsSearchingInsideTheFrame) {
  app::Rng rng(12);
  const auto pts = testing::random_points(rng, 80, 14);
  const auto bytes = build(point_model(pts), "-4:4:9", "-4:4:9");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  std::vector<RoiPoint> search_features(search_feature_capacity(t));
  const GrayImage frame = draw(pts, 140, 60);
  RecoverySearch search(t, nullptr, detector_of(t));
  search.reset();
  MotionFilterState moving;
  moving.vx = 3.0f;
  moving.vtheta = 36000.0f / 340000.0f;  // 100 whole turns over the period
  const LastSighting last{Pose{60, 60, 0, 0}, moving, 340000};
  SearchResult r;
  ASSERT_EQ(search.run(frame.view(), RecoveryOptions{}, last, 0, {s.view(), {}, search_features}, r), Status::kOk);
  ASSERT_TRUE(r.searched);
  EXPECT_LE(std::hypot(r.vote.pose.x - 140.0f, r.vote.pose.y - 60.0f), 1.0f);
  EXPECT_LE(std::fabs(r.from.theta_deg), 180.0f + 9.0f + 1.0f);
  EXPECT_GT(r.vote.score, 0.9f);
}

}  // namespace
}  // namespace gabarit
