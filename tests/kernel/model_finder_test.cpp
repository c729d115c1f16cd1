// Detection anywhere (model_finder.hpp): the orientation quantiser, finding a
// target at any place and angle, nothing found where there is nothing,
// errors for bad input, determinism, and a session re-acquiring by detection
// a target that reappears beyond the grid search's reach.
#include "gabarit/detection_recovery.hpp"
#include "gabarit/model_finder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "gabarit/app/scratch.hpp"
#include "gabarit/tracking_session.hpp"
#include "finder_rig.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

constexpr std::uint32_t kSide = testing::kFinderSide;

TEST(Orientation, AxesDiagonalsAndFolding) {
  EXPECT_EQ(orientation_256(1, 0), 0);
  EXPECT_EQ(orientation_256(-7, 0), 0);  // a half turn away: the same edge
  EXPECT_EQ(orientation_256(0, 5), 128);
  EXPECT_EQ(orientation_256(0, -5), 128);
  EXPECT_EQ(orientation_256(3, 3), 64);
  EXPECT_EQ(orientation_256(-3, 3), 192);
  EXPECT_EQ(orientation_256(0, 0), 0);
  EXPECT_EQ(orientation_channel(orientation_256(0, 5)), 8);
}

TEST(Orientation, FollowsTheAngleWithinAStep) {
  for (int tenth = 0; tenth < 3600; tenth += 7) {
    const double a = tenth / 10.0 * M_PI / 180.0;
    const auto gx = static_cast<std::int32_t>(std::lround(1000 * std::cos(a)));
    const auto gy = static_cast<std::int32_t>(std::lround(1000 * std::sin(a)));
    const double want = std::fmod(tenth / 10.0, 180.0) * 256.0 / 180.0;
    const double got = orientation_256(gx, gy);
    double diff = std::fabs(got + 0.5 - want);
    diff = std::min(diff, 256.0 - diff);
    EXPECT_LE(diff, 1.0) << tenth / 10.0 << " deg";
    EXPECT_EQ(orientation_256(gx, gy), orientation_256(-gx, -gy));
  }
}

using Rig = testing::FinderRig;
using testing::Finding;
using testing::twins;

double angle_error(double a, double b) { return std::fabs(std::remainder(a - b, 360.0)); }

TEST(ModelFinder, FindsTheTargetAnywhereAtAnyAngle) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  app::Rng where(5), noise(6);
  for (int trial = 0; trial < 8; ++trial) {
    const float x = static_cast<float>((40 + where.next_unit() * (kSide - 80))), y = static_cast<float>((40 + where.next_unit() * (kSide - 80)));
    const float theta = static_cast<float>((-180 + 360 * where.next_unit()));
    const app::GrayImage f = rig.frame(x, y, theta, true, noise);
    std::vector<Detection> out(options.max_count);
    std::uint32_t count = 0;
    ASSERT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), out, count), Status::kOk);
    ASSERT_GE(count, 1u) << "trial " << trial;
    EXPECT_LE(std::hypot(out[0].pose.x - x, out[0].pose.y - y), 2.0) << "trial " << trial;
    // Points at most ~28 px out, drawn to whole pixels: 2 degrees move the
    // farthest by a pixel, which is as far as a binary frame pins the angle.
    EXPECT_LE(angle_error(out[0].pose.theta_deg, theta), 2.0) << "trial " << trial << ": " << out[0].pose.theta_deg << " vs " << theta;
    EXPECT_GE(out[0].score, options.min_score);
    for (std::uint32_t i = 1; i < count; ++i) {
      EXPECT_LE(out[i].score, out[i - 1].score);  // best first
      EXPECT_GE(std::hypot(out[i].pose.x - out[0].pose.x, out[i].pose.y - out[0].pose.y),
                buffers.geometry().min_distance_px);  // no duplicates
    }
  }
}

TEST(ModelFinder, NothingFoundWhereThereIsNothing) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  app::Rng noise(8);
  std::vector<Detection> out(options.max_count);
  std::uint32_t count = 7;
  const app::GrayImage f = rig.frame(0, 0, 0, false, noise);
  ASSERT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), out, count), Status::kOk);
  EXPECT_EQ(count, 0u);
}

TEST(ModelFinder, SameInputSameBytes) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  app::Rng noise(9);
  const app::GrayImage f = rig.frame(150, 170, 77, true, noise);
  std::vector<Detection> a(options.max_count), b(options.max_count);
  std::uint32_t na = 0, nb = 0;
  ASSERT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), a, na), Status::kOk);
  ASSERT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), b, nb), Status::kOk);
  ASSERT_EQ(na, nb);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), na * sizeof(Detection)), 0);
}

TEST(ModelFinder, RefusesBadInputAndShortBuffers) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  app::Rng noise(10);
  const app::GrayImage f = rig.frame(100, 100, 0, true, noise);
  std::vector<Detection> out(options.max_count);
  std::uint32_t count = 0;
  EXPECT_EQ(finder.find(ImageView{}, options, buffers.scratch(fine.view()), out, count), Status::kInvalidArgument);
  EXPECT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), std::span<Detection>(out).first(1), count),
            Status::kBufferTooSmall);
  FinderScratch shorter = buffers.scratch(fine.view());
  shorter.accumulator = shorter.accumulator.first(shorter.accumulator.size() - 1);
  EXPECT_EQ(finder.find(f.view(), options, shorter, out, count), Status::kBufferTooSmall);
  FinderScratch few = buffers.scratch(fine.view());
  few.candidates = few.candidates.first(options.candidates - 1);
  EXPECT_EQ(finder.find(f.view(), options, few, out, count), Status::kBufferTooSmall);
  // A larger frame than the buffers were sized for.
  const app::GrayImage big(kSide + 64, kSide);
  EXPECT_EQ(finder.find(big.view(), options, buffers.scratch(fine.view()), out, count), Status::kBufferTooSmall);
  std::vector<FinderOptions> bad(5, options);
  bad[0].candidates = 0;
  bad[1].max_count = bad[1].candidates + 1;
  bad[2].min_score = 1.5f;
  bad[3].theta_max_deg = bad[3].theta_min_deg - 1;
  bad[4].pyramid_factor = kMaxPyramidFactor + 1;
  for (const FinderOptions& o : bad) {
    EXPECT_FALSE(valid(o));
    EXPECT_EQ(finder.find(f.view(), o, buffers.scratch(fine.view()), out, count), Status::kInvalidArgument);
  }
  options.coarse_depth = 1;  // the table has one depth
  EXPECT_EQ(finder.find(f.view(), options, buffers.scratch(fine.view()), out, count), Status::kInvalidArgument);
}

// A session losing the target (4 frames in view, 12 hidden), and it
// reappearing at (rx, ry): frames until the session is within 2 px of it
// (-1: not within `budget` frames), and the work of the frames.
struct Reacquisition {
  int frames = -1;
  std::uint64_t most_lost_work = 0;     // the costliest frame of the lost period
  std::uint64_t tracked_work = 0;       // the tracked frames' mean
};
Reacquisition reacquisition(const Rig& rig, bool detection, float rx, float ry, int budget, std::uint32_t detect_after,
                            float recovery_frames) {
  testing::TrackerTestScratch scratch(rig.table);
  TrackingSession session(rig.table, nullptr, detector_of(rig.table));
  SessionOptions so;
  so.recovery.detect_after = detect_after;
  so.recovery_frames = recovery_frames;
  EXPECT_EQ(session.start(so, {60, 60, 0, 0}), Status::kOk);
  ModelFinder finder(rig.table, detector_of(rig.table));
  const FinderOptions options;
  app::FinderBuffers buffers(rig.table, detector_of(rig.table), options, kSide, kSide);
  DetectionRecovery stage(finder, options, buffers.scratch(scratch.view()));
  if (detection) session.use_detection_recovery(&stage);
  app::Rng noise(4);
  SessionResult r;
  Reacquisition out;
  for (int f = 0; f < 4; ++f) {
    EXPECT_EQ(session.step(rig.frame(60, 60, 0, true, noise).view(), {scratch.view(), {}}, r), Status::kOk);
    out.tracked_work += r.work / 4;
  }
  for (int f = 0; f < 12; ++f) {
    EXPECT_EQ(session.step(rig.frame(0, 0, 0, false, noise).view(), {scratch.view(), {}}, r), Status::kOk);
    out.most_lost_work = std::max(out.most_lost_work, r.work);
  }
  EXPECT_TRUE(session.lost());
  for (int f = 0; f < budget; ++f) {
    EXPECT_EQ(session.step(rig.frame(rx, ry, 40, true, noise).view(), {scratch.view(), {}}, r), Status::kOk);
    out.most_lost_work = std::max(out.most_lost_work, r.work);
    if (!session.lost() && std::hypot(session.pose().x - rx, session.pose().y - ry) <= 2.0) {
      out.frames = f + 1;
      break;
    }
  }
  return out;
}

// Each search in one frame (recovery_frames 0), as these tests of where the
// target is taken want.
int reacquire(const Rig& rig, bool detection, float rx, float ry, int budget = 10, std::uint32_t detect_after = 0) {
  return reacquisition(rig, detection, rx, ry, budget, detect_after, 0.0f).frames;
}

TEST(DetectionRecovery, FindsATargetThatReappearsFarAway) {
  const Rig rig;
  // 71 px and 40 deg from where it was lost, 12 frames before: beyond the
  // grid's reach, within the table's (12 frames of 5.7 px).
  EXPECT_EQ(reacquire(rig, false, 110, 110), -1);
  const int frames = reacquire(rig, true, 110, 110);
  EXPECT_GE(frames, 1);
  EXPECT_LE(frames, 3);
  // The first detect_after lost frames search with the grid only: far
  // away, detection then finds it later, and never if it never starts.
  EXPECT_EQ(reacquire(rig, true, 110, 110, 10, 1000), -1);
  const int later = reacquire(rig, true, 110, 110, 30, 20);
  EXPECT_GT(later, frames + 2);
  EXPECT_LE(later, 24);
}

// 276 px away: the table bounds a frame's motion to 5.7 px (x and y within
// +-4), so the target cannot be there until about 49 frames after it was
// last seen; it is taken then, not before.
TEST(DetectionRecovery, TakesATargetOnlyWhereItCanHaveGotTo) {
  const Rig rig;
  const double bound = std::hypot(4.0, 4.0), distance = std::hypot(200.0, 190.0);
  // Last seen in the 4th frame; the reappearance's frame f (from 1) is
  // 12 + f frames after it.
  const int reachable = static_cast<int>(std::ceil(distance / bound)) - 1 - 12;
  const int frames = reacquire(rig, true, 260, 250, 60);
  EXPECT_GE(frames, reachable);
  EXPECT_LE(frames, reachable + 3);
}

// Spread over frames (recovery_frames 2), the search costs each lost frame about
// two tracked frames' work (and the catch-up votes on the frame it ends):
// whole in one frame it is well over ten; the target is found a few frames later.
TEST(DetectionRecovery, ASearchSpreadOverFramesBoundsEachFrameAndStillFindsTheTarget) {
  const Rig rig;
  const Reacquisition whole = reacquisition(rig, true, 110, 110, 10, 0, 0.0f);
  const Reacquisition spread = reacquisition(rig, true, 110, 110, 40, 0, 2.0f);
  ASSERT_GT(spread.tracked_work, 0u);
  EXPECT_GT(whole.most_lost_work, 10 * whole.tracked_work);
  EXPECT_LE(spread.most_lost_work, 6 * spread.tracked_work);
  EXPECT_GE(whole.frames, 1);
  EXPECT_GT(spread.frames, whole.frames);
  EXPECT_LE(spread.frames, 30);
}

// The target at (80, 80), surveyed with a copy 184 px off, at (220, 200).
constexpr Pose kSurveyedTarget{80, 80, 0, 0};
void survey_with_a_copy(Finding& t, DetectionRecovery& stage) {
  ASSERT_EQ(stage.survey(twins(t.rig, 80, 80, 0, 220, 200, 30).view(), kSurveyedTarget, t.fine.view(), kUnlimitedWork), Status::kOk);
  ASSERT_NEAR(stage.lookalike_distance_squared(), 140.0f * 140 + 120 * 120, 200.0f);
}

TEST(DetectionRecovery, ALookalikeSeenBoundsWhereTheTargetIsTakenAgain) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  DetectionRecovery stage(finder, options, buffers.scratch(fine.view()));
  // Surveyed with a copy 184 px off: the reach is at most half that.
  const Pose target = kSurveyedTarget;
  ASSERT_NO_FATAL_FAILURE(survey_with_a_copy(t, stage));
  const LastSighting last{target, {}, 1000};  // long lost: the table's bound alone would reach anywhere
  EXPECT_TRUE(stage.within_reach(last, {150, 140, 0, 0}));
  EXPECT_FALSE(stage.within_reach(last, {160, 150, 0, 0}));
  EXPECT_FALSE(stage.within_reach(last, {220, 200, 30, 0}));
  // The copy alone (the target hidden) is not taken ...
  SearchResult found;
  const app::GrayImage copy_only = testing::draw_points(rig.points, 220, 200, 30, kSide);
  ASSERT_EQ(stage.run(copy_only.view(), last, fine.view(), kUnlimitedWork, found), Status::kOk);
  EXPECT_TRUE(found.searched);
  EXPECT_EQ(found.vote.best.votes, 0u);
  // ... the target, back near where it was, is, though the copy is there too.
  ASSERT_EQ(stage.run(twins(rig, 100, 95, 10, 220, 200, 30).view(), last, fine.view(), kUnlimitedWork, found), Status::kOk);
  EXPECT_LE(std::hypot(found.from.x - 100, found.from.y - 95), 2.0);
  // Without a survey nothing bounds the reach but the table.
  DetectionRecovery fresh(finder, options, buffers.scratch(fine.view()));
  EXPECT_EQ(fresh.lookalike_distance_squared(), 0.0f);
  EXPECT_TRUE(fresh.within_reach(last, {220, 200, 30, 0}));
}

// A copy that orbits the hidden target comes nearer its last sighting than
// the midpoint: followed from where it was first seen in the loss, it is
// still not taken, and the target, reappearing beyond the midpoint, is.
TEST(DetectionRecovery, ALookalikeFollowedThroughALossIsNotTakenNearerThanTheMidpoint) {
  Finding t;
  auto& [rig, finder, options, buffers, fine] = t;
  DetectionRecovery stage(finder, options, buffers.scratch(fine.view()));
  const Pose target = kSurveyedTarget;
  ASSERT_NO_FATAL_FAILURE(survey_with_a_copy(t, stage));  // the midpoint 92 px off
  stage.reset();
  SearchResult found;
  std::uint32_t since = 20;  // frames since the last sighting: the table's bound reaches 119 px
  for (int step = 0; step <= 20; ++step, ++since) {
    // 4 px a frame in x and y (the table's bound), from 184 px off to 78.
    const float cx = 220.0f - 4.0f * static_cast<float>(step), cy = 200.0f - 4.0f * static_cast<float>(step);
    const app::GrayImage copy_only = testing::draw_points(rig.points, cx, cy, 30, kSide);
    ASSERT_EQ(stage.run(copy_only.view(), {target, {}, since}, fine.view(), kUnlimitedWork, found), Status::kOk);
    EXPECT_TRUE(found.searched);
    EXPECT_EQ(found.vote.best.votes, 0u) << "the copy taken at " << cx << "," << cy;
    EXPECT_FALSE(stage.within_reach({target, {}, since}, {cx, cy, 30, 0})) << cx << "," << cy;
  }
  // The target back 102 px off, beyond the midpoint, the copy still 80 px from it.
  ASSERT_EQ(stage.run(twins(rig, 180, 60, 10, 140, 120, 30).view(), {target, {}, since}, fine.view(), kUnlimitedWork, found),
            Status::kOk);
  EXPECT_LE(std::hypot(found.from.x - 180, found.from.y - 60), 2.0);
  // Another sighting: the copy is no longer followed, and the midpoint bounds the reach again.
  const LastSighting elsewhere{{82, 80, 0, 0}, {}, 30};
  EXPECT_TRUE(stage.within_reach(elsewhere, {140, 120, 30, 0}));
  EXPECT_FALSE(stage.within_reach(elsewhere, {184, 60, 10, 0}));
}

}  // namespace
}  // namespace gabarit
