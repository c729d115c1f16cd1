// The intensity scan (intensity_scan.hpp): poses around the last sighting
// scored by the particle filter's intensity measure.
#include "gabarit/intensity_scan.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/deterministic_math.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;

// A 41 x 41 model: a textured disc of radius 14 on a flat grey (128), so the
// measure lists the disc and its ring only.
GrayImage textured_disc() {
  GrayImage disc(41, 41, 128);
  for (std::uint32_t v = 0; v < 41; ++v)
    for (std::uint32_t u = 0; u < 41; ++u) {
      const float du = static_cast<float>(u) - 20.0f, dv = static_cast<float>(v) - 20.0f;
      if (du * du + dv * dv <= 196.0f)
        disc.at(u, v) = static_cast<std::uint8_t>(60 + (((u / 3) * 7 + (v / 2) * 13 + u * v) % 17) * 9);
    }
  return disc;
}

// A 240 x 200 frame of uniform random grey levels, with the disc's own pixels
// (not its flat grey) pasted with its centre at (cx, cy) when `with_disc`.
GrayImage frame_with(const GrayImage& disc, std::uint32_t cx, std::uint32_t cy, bool with_disc) {
  GrayImage f(240, 200);
  std::uint32_t state = 77u;
  for (std::uint8_t& p : f.pixels) {
    state = state * 1664525u + 1013904223u;
    p = static_cast<std::uint8_t>(state >> 24);
  }
  if (with_disc)
    for (std::uint32_t v = 0; v < 41; ++v)
      for (std::uint32_t u = 0; u < 41; ++u)
        if (disc.at(u, v) != 128) f.at(cx - 20 + u, cy - 20 + v) = disc.at(u, v);
  return f;
}

struct Rig {
  GrayImage disc = textured_disc();
  std::vector<ImageView> views{disc.view()};
  FocusStack stack{views, 20.0f, 20.0f, 1};
  // The table only bounds the motion per frame: +-5 px, +-2 degrees.
  std::vector<std::byte> bytes = testing::build(testing::point_model({{0, 0}}), "-5:5:11", "-5:5:11", "-2:2:5");
  TableView table = testing::open_table(bytes);
};

// The disc reappears 24 px right of and 12 px above where it was last seen,
// 10 frames ago, turned back to 0 degrees from the sighting's 10: the grid
// (reach min(5 x 11, 44) px, angles min(2 x 11, 24) degrees either side, 6 px
// and 4 degrees apart) holds a pose within half a step of it, which scores
// best; 15 x 15 positions at 11 angles were screened on 64 samples, the best
// 16 scored on 256.
TEST(IntensityScan, FindsTheTargetWithinTheReachOfTheLastSighting) {
  Rig r;
  IntensityScan scan;
  scan.reset(r.table, r.stack, IntensityScanOptions{});
  const GrayImage f = frame_with(r.disc, 124, 88, true);
  LastSighting last;
  last.pose = Pose{100.0f, 100.0f, 10.0f, 0};
  last.frames_since = 10;
  IntensityScanResult out;
  ASSERT_EQ(scan.run(f.view(), last, out), Status::kOk);
  EXPECT_EQ(out.poses, 15u * 15u * 11u);
  // At most 64 and 256 samples each (the measures list fewer on a small disc).
  EXPECT_LE(out.work, 15u * 15u * 11u * 64u + 16u * 256u);
  EXPECT_GT(out.work, 15u * 15u * 11u * 16u);
  ASSERT_TRUE(out.scored);
  EXPECT_NEAR(out.best.x, 124.0f, 3.0f);
  EXPECT_NEAR(out.best.y, 88.0f, 3.0f);
  EXPECT_NEAR(out.best.theta_deg, 0.0f, 4.0f);
  EXPECT_EQ(out.best.depth, 0);
  EXPECT_GT(out.score, 0.5f);
  // Without the disc, clutter alone scores far less.
  IntensityScanResult empty;
  ASSERT_EQ(scan.run(frame_with(r.disc, 124, 88, false).view(), last, empty), Status::kOk);
  EXPECT_LT(empty.score, 0.5f * out.score);
}

// Just after the sighting the reach is one frame's: a grid of one pose at
// the sighting (5 px and 2 degrees are under a step), which does not reach
// a disc 24 px off; the same disc at the sighting is found there.
TEST(IntensityScan, TheReachGrowsWithTheFramesSinceTheSighting) {
  Rig r;
  IntensityScan scan;
  scan.reset(r.table, r.stack, IntensityScanOptions{});
  LastSighting last;
  last.pose = Pose{100.0f, 100.0f, 0.0f, 0};
  IntensityScanResult far, near;
  ASSERT_EQ(scan.run(frame_with(r.disc, 124, 88, true).view(), last, far), Status::kOk);
  EXPECT_EQ(far.poses, 1u);
  ASSERT_EQ(scan.run(frame_with(r.disc, 100, 100, true).view(), last, near), Status::kOk);
  EXPECT_EQ(near.poses, 1u);
  EXPECT_GT(near.score, 0.8f);
  EXPECT_LT(far.score, 0.5f * near.score);
}

TEST(IntensityScan, RejectsWhatItCannotScan) {
  Rig r;
  IntensityScan never_reset;
  LastSighting last;
  last.pose = Pose{100.0f, 100.0f, 0.0f, 0};
  IntensityScanResult out;
  const GrayImage f = frame_with(r.disc, 100, 100, true);
  EXPECT_EQ(never_reset.run(f.view(), last, out), Status::kInvalidArgument);
  IntensityScan scan;
  scan.reset(r.table, r.stack, IntensityScanOptions{});
  EXPECT_EQ(scan.run(ImageView{}, last, out), Status::kInvalidArgument);
  last.pose.x = 1.0e9f;
  EXPECT_EQ(scan.run(f.view(), last, out), Status::kInvalidArgument);
  for (const float bad : {0.0f, -1.0f, 1.0e4f, std::nanf("")}) {
    IntensityScanOptions o;
    o.step_px = bad;
    EXPECT_FALSE(valid(o)) << bad;
    o = {};
    o.max_turn_deg = bad;
    EXPECT_FALSE(valid(o)) << bad;
  }
  IntensityScanOptions few;
  few.samples = 8;
  EXPECT_FALSE(valid(few));
  IntensityScanOptions none_kept, too_many_kept, few_screened;
  none_kept.kept = 0;
  too_many_kept.kept = kMaxScanKept + 1;
  few_screened.screen_samples = 15;
  EXPECT_FALSE(valid(none_kept));
  EXPECT_FALSE(valid(too_many_kept));
  EXPECT_FALSE(valid(few_screened));
  EXPECT_TRUE(valid(IntensityScanOptions{}));
  // Invalid options leave the scan unable to run rather than half set.
  IntensityScan bad;
  bad.reset(r.table, r.stack, few);
  last.pose.x = 100.0f;
  EXPECT_EQ(bad.run(f.view(), last, out), Status::kInvalidArgument);
}

}  // namespace
}  // namespace gabarit
