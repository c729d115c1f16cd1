// The acceptance scenario, in-process (so it also runs cross-built
// under qemu): a ~200-point shape translated by up to +-4 px per frame,
// 1-pixel cells over +-5 px, full stencils; every frame must be exact at 0%
// and 30% salt-and-pepper noise.
#include <gtest/gtest.h>

#include <filesystem>

#include "gabarit/app/evaluation.hpp"
#include "gabarit/host/scenes/synth.hpp"
#include "gabarit/host/runs/tracking_run.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

app::Accuracy track_synthetic(double noise, double keep, std::uint64_t seed, std::uint32_t frames) {
  const auto dir = std::filesystem::temp_directory_path() / ("gabarit_track_" + std::to_string(seed) + "_" + std::to_string(noise));
  host::SynthOptions o;
  o.shape = host::random_closed_curve(200, seed);
  o.frames = frames;
  o.max_step = 4;
  o.noise = noise;
  o.seed = seed;
  const auto truth = host::write_synthetic_sequence(o, dir.string());
  const auto bytes = testing::build(testing::point_model(o.shape), "-5:5:11", "-5:5:11", "0:0:1", keep, seed);
  const TableView table = testing::open_table(bytes);
  auto frames_in = app::open_frames((dir / "frames.y4m").string());
  std::vector<app::PoseSample> poses, gt;
  host::run_tracking(table, *frames_in, Pose{static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), 0, 0}, std::nullopt,
                     [&](const app::TrackRow& r) { poses.push_back({r.frame, r.step.pose.x, r.step.pose.y, 0, 0, true}); });
  for (const auto& t : truth) gt.push_back({t.frame, double(t.x), double(t.y), 0, 0, true});
  std::filesystem::remove_all(dir);
  return app::evaluate(poses, gt);
}

TEST(Tracking, ExactInEveryFrameWithoutNoise) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const auto a = track_synthetic(0.0, 1.0, seed, 150);
    EXPECT_EQ(a.frames, 150u);
    EXPECT_EQ(a.exact, a.frames) << "seed " << seed;
  }
}

TEST(Tracking, ExactInEveryFrameAtThirtyPercentSaltAndPepper) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const auto a = track_synthetic(0.3, 1.0, seed, 150);
    EXPECT_EQ(a.frames, 150u);
    EXPECT_EQ(a.exact, a.frames) << "seed " << seed << ", first wrong frame "
                                 << (a.wrong_frames.empty() ? -1 : static_cast<long>(a.wrong_frames[0]));
  }
}

TEST(Tracking, DecimatedToHalfStillExactAtTwentyPercent) {
  const auto a = track_synthetic(0.2, 0.5, 4, 100);
  EXPECT_EQ(a.exact, a.frames);
}

}  // namespace
}  // namespace gabarit
