// The particle tracker's re-acquisition by detection (ParticleRunOptions::
// detection): a target that reappears far from where it was hidden, beyond
// what the vote proposals and the cloud's diffusion reach, is found again
// within a few frames with it, and not without.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/app/particle_run.hpp"
#include "gabarit/app/pose_row.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"
#include "gabarit/host/tables/model.hpp"
#include "test_tables.hpp"

namespace gabarit::app {
namespace {

constexpr std::uint32_t kFrames = 36, kHiddenFrom = 10, kHidden = 10;
// Where the target reappears: this far to the right of its path, within the
// reach of a ±3 px table after the hiding (11 frames x 3 px) but beyond
// where the lost cloud's diffusion finds it within the run.
constexpr std::uint32_t kJumpPx = 32;

// A grayscale scene (two depths) whose target is hidden for kHidden frames;
// every frame from the hiding on is the scene's frame moved kJumpPx to the
// right (the left edge repeated), so the target reappears far from where it
// was hidden. The truth is moved likewise.
struct JumpScene {
  JumpScene() : dir(std::filesystem::temp_directory_path() / ("gabarit-particle-jump-" + std::to_string(::getpid()))) {
    host::SceneOptions so;
    so.frames = kFrames;
    so.depths = 2;
    so.occlusion_start = kHiddenFrom;
    so.occlusion_frames = kHidden;
    so.blur_every = 0;
    so.max_speed_px = 1.0;
    host::write_scene_sequence(so, dir.string());
    host::ImageModelOptions mo;
    mo.canny = true;
    model = host::model_from_images({(dir / "model_00.pgm").string(), (dir / "model_01.pgm").string()}, mo);
    truth = read_pose_csv((dir / "gt.csv").string());
    auto source = open_frames((dir / "frames.y4m").string());
    GrayImage frame;
    for (std::uint32_t n = 0; source->next(frame); ++n) {
      if (n >= kHiddenFrom) {
        GrayImage moved(frame.width, frame.height);
        for (std::uint32_t y = 0; y < frame.height; ++y)
          for (std::uint32_t x = 0; x < frame.width; ++x) moved.at(x, y) = frame.at(x >= kJumpPx ? x - kJumpPx : 0, y);
        frame = moved;
        truth[n].x += kJumpPx;
      }
      frames.push_back(frame);
    }
    start = {static_cast<float>(truth[0].x), static_cast<float>(truth[0].y), static_cast<float>(truth[0].theta_deg), 0};
  }
  ~JumpScene() { std::filesystem::remove_all(dir); }
  std::filesystem::path dir;
  host::ModelStack model;
  std::vector<PoseSample> truth;
  std::vector<GrayImage> frames;
  Pose start;
};

struct TrackedRun {
  std::vector<ParticleEstimate> estimates;
  std::uint64_t recovery_work = 0, survey_work = 0;
  bool detects = false;
};

TrackedRun track(const JumpScene& scene, const TableView& table, const ParticleRunOptions& options) {
  ParticleTracker tracker(table, scene.frames[0].width, scene.frames[0].height, options);
  tracker.start(scene.start);
  TrackedRun run;
  run.detects = tracker.detects();
  for (const GrayImage& frame : scene.frames) {
    run.estimates.push_back(tracker.step(frame));
    run.recovery_work += tracker.ledger().work[static_cast<std::uint32_t>(FramePhase::kRecovery)];
    run.survey_work += tracker.ledger().work[static_cast<std::uint32_t>(FramePhase::kSurvey)];
  }
  return run;
}

// The first visible frame after the hiding on which the estimate is within
// 3 px of the truth and stays there to the end; kFrames if none.
std::uint32_t back_from(const JumpScene& scene, const TrackedRun& run) {
  std::uint32_t back = kFrames;
  for (std::uint32_t n = kFrames; n-- > 0;) {
    if (!scene.truth[n].visible) break;
    const Pose& p = run.estimates[n].pose;
    if (std::hypot(p.x - scene.truth[n].x, p.y - scene.truth[n].y) > 3.0) break;
    back = n;
  }
  return back;
}

TEST(ParticleDetection, FindsATargetThatReappearsFarFromWhereItWasHidden) {
  const JumpScene scene;
  const std::vector<std::byte> bytes = testing::build(scene.model, "-3:3:7", "-3:3:7", "-1:1:3");
  const TableView table = testing::open_table(bytes);
  std::uint32_t reappears = kHiddenFrom;
  while (reappears < kFrames && !scene.truth[reappears].visible) ++reappears;
  ASSERT_LT(reappears, kFrames - 10);
  ASSERT_GE(reappears, kHiddenFrom + kHidden);

  ParticleRunOptions options;
  options.particles = 500;
  const TrackedRun with = track(scene, table, options);
  ASSERT_TRUE(with.detects);
  for (std::uint32_t n = 0; n < kHiddenFrom; ++n) EXPECT_EQ(with.estimates[n].state, TrackState::kTracking) << n;
  const std::uint32_t back = back_from(scene, with);
  EXPECT_LE(back, reappears + 5) << "re-acquired " << back - reappears << " frames after the target reappeared";
  EXPECT_GT(with.recovery_work, 0u);
  EXPECT_GT(with.survey_work, 0u);

  options.detection = false;
  const TrackedRun without = track(scene, table, options);
  EXPECT_FALSE(without.detects);
  EXPECT_EQ(without.recovery_work + without.survey_work, 0u);
  EXPECT_GT(back_from(scene, without), reappears + 5);


  // A binary detector's table does not verify: no detection stage.
  options.detection = true;
  options.detector = Detector{table_format::DetectorKind::kBinary, 0};
  options.measure = ParticleMeasureKind::kEdges;
  ParticleTracker binary(table, scene.frames[0].width, scene.frames[0].height, options);
  EXPECT_FALSE(binary.detects());
}

}  // namespace
}  // namespace gabarit::app
