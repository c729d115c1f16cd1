// The grayscale 4-DOF scene (gabarit synth --scene) and the accuracy measures
// for angle, depth and reacquisition (gabarit eval).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "gabarit/app/evaluation.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/host/scenes/scene_synth.hpp"

namespace gabarit::host {
namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Scene, IsDeterministicWithTruthOcclusionAndADistinctFocusStack) {
  const auto dir = std::filesystem::temp_directory_path() / ("gabarit-scene-test-" + std::to_string(::getpid()));
  SceneOptions o;
  o.frames = 30;
  o.depths = 3;
  o.occlusion_start = 10;
  o.occlusion_frames = 5;
  o.blur_every = 7;
  const SceneSummary a = write_scene_sequence(o, (dir / "a").string());
  write_scene_sequence(o, (dir / "b").string());
  for (const char* f : {"frames.y4m", "gt.csv", "model_00.pgm", "model_02.pgm"})
    EXPECT_EQ(slurp(dir / "a" / f), slurp(dir / "b" / f)) << f;
  EXPECT_EQ(a.visible_frames, 25u);

  const auto truth = app::read_pose_csv((dir / "a" / "gt.csv").string());
  ASSERT_EQ(truth.size(), 30u);
  double max_step = 0, max_turn = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    EXPECT_EQ(truth[i].visible, !(i >= 10 && i < 15)) << i;
    EXPECT_LT(truth[i].depth, 3u);
    if (i > 0) {
      max_step = std::max(max_step, std::hypot(truth[i].x - truth[i - 1].x, truth[i].y - truth[i - 1].y));
      max_turn = std::max(max_turn, std::fabs(truth[i].theta_deg - truth[i - 1].theta_deg));
    }
  }
  EXPECT_LE(max_step, o.max_speed_px * std::sqrt(2.0) + 1e-3);
  EXPECT_LE(max_turn, o.max_turn_deg + 1e-3);
  // No two depths look alike.
  const app::GrayImage d0 = app::read_pgm((dir / "a" / "model_00.pgm").string());
  const app::GrayImage d1 = app::read_pgm((dir / "a" / "model_01.pgm").string());
  const app::GrayImage d2 = app::read_pgm((dir / "a" / "model_02.pgm").string());
  EXPECT_NE(d0.pixels, d1.pixels);
  EXPECT_NE(d1.pixels, d2.pixels);
  EXPECT_NE(d0.pixels, d2.pixels);
  auto frames = app::open_frames((dir / "a" / "frames.y4m").string());
  app::GrayImage frame;
  int n = 0;
  while (frames->next(frame)) ++n;
  EXPECT_EQ(n, 30);
  EXPECT_EQ(frame.width, o.width);
  std::filesystem::remove_all(dir);
}

TEST(Evaluation, AngleDepthAndReacquisitionAreMeasured) {
  std::vector<app::PoseSample> truth, poses;
  for (std::uint32_t f = 0; f < 12; ++f) {
    const bool hidden = f >= 4 && f < 7;
    truth.push_back({f, 10.0 + f, 20.0, 1.0 * f, f % 2, !hidden});
    app::PoseSample p{f, 10.0 + f, 20.0, 1.0 * f + (f == 2 ? 1.5 : 0.25), f % 2, true};
    if (f == 7 || f == 8) p.x += 5.5;  // two frames after the occlusion before it is found again
    if (f == 3) p.depth = 5;
    poses.push_back(p);
  }
  const app::Accuracy a = app::evaluate(poses, truth);
  EXPECT_EQ(a.frames, 9u);
  EXPECT_EQ(a.within_1deg, 8u);
  EXPECT_NEAR(a.max_error_deg, 1.5, 1e-9);
  EXPECT_EQ(a.depth_exact, 8u);
  ASSERT_EQ(a.reacquired_after.size(), 1u);
  EXPECT_EQ(a.reacquired_after[0], 2);
  EXPECT_EQ(a.within_5px, 7u);
  EXPECT_EQ(a.failures, 1u) << "frames 7 and 8 off: one loss of the track";
  poses[9].x += 5;
  poses[10].x += 5;
  poses[11].x += 5;
  const app::Accuracy never = app::evaluate(poses, truth);
  ASSERT_EQ(never.reacquired_after.size(), 1u);
  EXPECT_EQ(never.reacquired_after[0], -1);
  poses[10].x += 1;  // 6 px off after a frame 5 px off: a second loss
  poses[0].x += 6;   // the first visible frame off: a loss too
  const app::Accuracy lost = app::evaluate(poses, truth);
  EXPECT_EQ(lost.failures, 3u);
  // Fig. 6.60's buckets, strict at their bounds: of the 9 visible frames,
  // frames 0 and 10 are 6 px off, the others 0 to 5.5 px.
  EXPECT_EQ(lost.below_6px, 7u);
  EXPECT_EQ(lost.below_12px, 9u);
  EXPECT_EQ(lost.above_12px, 0u);
  poses[1].x += 12;   // exactly 12: in neither < 12 nor > 12
  poses[2].x += 20.5;
  poses[3].x -= 41;
  const app::Accuracy far = app::evaluate(poses, truth);
  EXPECT_EQ(far.below_6px, 4u);
  EXPECT_EQ(far.below_12px, 6u);
  EXPECT_EQ(far.above_12px, 2u);
  EXPECT_EQ(far.above_20px, 2u);
  EXPECT_EQ(far.above_40px, 1u);
}

// The scene suite: both halves hold every object twice, and each block of 8
// scenes gives an object another motion; every object renders, with its
// outline inside the model image, and a sliding occluder hides the object
// for a middle stretch of frames, not from the first covered frame.
TEST(PipetteScenes, AreTransparentChangeTheirLookAndSplitIntoHalves) {
  std::uint32_t held_out = 0;
  for (std::uint32_t i = 0; i < kPipetteScenes; ++i) {
    const SceneOptions o = pipette_scene(i);
    EXPECT_EQ(o.object, SceneObject::kGlassPipette);
    EXPECT_NE(o.background, SceneBackground::kSmooth) << "in clutter";
    EXPECT_NE(o.occlusion_side, OcclusionSide::kNone);
    EXPECT_GT(o.blur_every, 0u);
    held_out += pipette_held_out(i);
  }
  EXPECT_EQ(held_out, kPipetteScenes / 2);
  // Over a smooth background, no occluder, no noise: the bore lets the
  // background through (it differs from it by far less than the wall does),
  // and the wall's contrast changes with the illumination's phase.
  const auto dir = std::filesystem::temp_directory_path() / ("gabarit-pipette-test-" + std::to_string(::getpid()));
  SceneOptions o;
  o.object = SceneObject::kGlassPipette;
  o.width = o.height = 0;
  o.background = SceneBackground::kSmooth;
  o.occlusion_side = OcclusionSide::kNone;
  o.noise_sigma = 0;
  o.illumination = 0;
  o.blur_every = 0;
  o.max_speed_px = 0;
  o.max_turn_deg = 0;
  o.frames = 68;
  write_scene_sequence(o, dir.string());
  const auto truth = app::read_pose_csv((dir / "gt.csv").string());
  auto frames = app::open_frames((dir / "frames.y4m").string());
  app::GrayImage f0, f, f67;
  ASSERT_TRUE(frames->next(f0));
  for (int i = 1; i < 68; ++i) ASSERT_TRUE(frames->next(i == 67 ? f67 : f));
  const auto at = [](const app::GrayImage& g, double x, double y) {
    return static_cast<int>(g.pixels[static_cast<std::size_t>(std::lround(y)) * g.width + static_cast<std::size_t>(std::lround(x))]);
  };
  // Along the axis (theta from the truth), the bore at the centre, the wall
  // at the half-width (about 5.5 px there), the background 12 px out.
  const double c = std::cos(truth[0].theta_deg * 3.14159265358979 / 180), s = std::sin(truth[0].theta_deg * 3.14159265358979 / 180);
  const double x = truth[0].x, y = truth[0].y;
  const auto across = [&](const app::GrayImage& g, double d) { return at(g, x - s * d, y + c * d); };
  int wall0 = 255, wall67 = 255;
  for (double d = 4.0; d <= 6.5; d += 0.5) wall0 = std::min(wall0, across(f0, d)), wall67 = std::min(wall67, across(f67, d));
  const int bore = across(f0, 0), background = across(f0, 14);
  EXPECT_LT(std::abs(bore - background), std::abs(wall0 - background)) << "the bore is transparent, the wall is not";
  EXPECT_GT(std::abs(wall67 - wall0), 10) << "the wall's look changes with the illumination's phase";
  std::filesystem::remove_all(dir);
}

TEST(SceneSuite, MixesObjectsMotionsAndHalvesAndEveryObjectRenders) {
  int per_half[2][8] = {};
  for (std::uint32_t i = 0; i < kSuiteMixedScenes; ++i) {
    const SceneOptions o = suite_scene(i);
    ++per_half[suite_held_out(i) ? 1 : 0][static_cast<int>(o.object)];
    if (i >= 8) {
      EXPECT_NE(static_cast<int>(suite_scene(i - 8).motion), static_cast<int>(o.motion)) << i;
    }
    EXPECT_EQ(o.seed, i + 1u);
  }
  for (const auto& half : per_half)
    for (int n : half) EXPECT_EQ(n, 2);

  const auto dir = std::filesystem::temp_directory_path() / ("gabarit-suite-test-" + std::to_string(::getpid()));
  for (const SceneObject object : {SceneObject::kCog, SceneObject::kCoin, SceneObject::kHorse, SceneObject::kPipette, SceneObject::kCat,
                                   SceneObject::kAstronaut, SceneObject::kCup, SceneObject::kLarge, SceneObject::kGlassPipette,
                                   SceneObject::kSmall}) {
    SceneOptions o;
    o.object = object;
    o.width = o.height = 0;
    o.frames = 30;
    o.motion = SceneMotion::kWalk;
    o.occlusion_side = OcclusionSide::kLeft;
    o.occlusion_start = 5;
    o.occlusion_frames = 4;  // 8 frames sliding in, 4 covered, 8 out
    const std::string name = name_of(object);
    SceneObject parsed{};
    ASSERT_TRUE(parse_scene_name(name, parsed));
    EXPECT_EQ(parsed, object);
    const SceneSummary summary = write_scene_sequence(o, (dir / name).string());
    const app::GrayImage model = app::read_pgm((dir / name / "model_00.pgm").string());
    std::size_t object_pixels = 0, border_changed = 0;
    for (std::uint32_t y = 0; y < model.height; ++y)
      for (std::uint32_t x = 0; x < model.width; ++x) {
        const bool edge = x < 4 || y < 4 || x + 4 >= model.width || y + 4 >= model.height;
        const bool changed = model.pixels[y * model.width + x] != 128;
        object_pixels += changed;
        border_changed += changed && edge;
      }
    EXPECT_GT(object_pixels, 400u) << name;
    EXPECT_EQ(border_changed, 0u) << name << ": the outline must stay inside the model image";
    const auto truth = app::read_pose_csv((dir / name / "gt.csv").string());
    ASSERT_EQ(truth.size(), 30u);
    EXPECT_TRUE(truth[5].visible) << name << ": the occluder only starts sliding in";
    EXPECT_FALSE(truth[14].visible) << name << ": covered";
    EXPECT_TRUE(truth[29].visible) << name << ": the occluder has left";
    EXPECT_LT(summary.visible_frames, 30u);
    for (const app::PoseSample& p : truth) {
      EXPECT_GT(p.x, summary.object_radius) << name;
      EXPECT_LT(p.x, summary.width - summary.object_radius) << name;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(SceneSuite, EachFamilyHasATuningAndAHeldOutSceneWithItsDifficulty) {
  int per_family[kSceneFamilies + 1][2] = {};
  for (std::uint32_t i = kSuiteMixedScenes; i < kSuiteScenes; ++i) {
    const SceneOptions o = suite_scene(i);
    const SceneFamily family = suite_family(i);
    ASSERT_NE(family, SceneFamily::kMixed) << i;
    ++per_family[static_cast<int>(family)][suite_held_out(i) ? 1 : 0];
    EXPECT_EQ(o.seed, i + 1u);
    const SceneOptions defaults;
    switch (family) {
      case SceneFamily::kMixed: break;
      case SceneFamily::kSmallObject: EXPECT_EQ(o.object, SceneObject::kSmall) << i; break;
      case SceneFamily::kFastSpin:
        EXPECT_EQ(o.motion, SceneMotion::kSpin) << i;
        EXPECT_GT(o.max_turn_deg * 1.2, 1.4) << i << ": near the tables' 1.5 deg";
        EXPECT_GE(o.noise_sigma, 4 * defaults.noise_sigma) << i;
        break;
      case SceneFamily::kDeepStack: EXPECT_EQ(o.depths, 7) << i; EXPECT_EQ(o.stack, FocusStackKind::kTilted) << i; break;
      case SceneFamily::kIllumination: EXPECT_GE(o.illumination, 0.5) << i; EXPECT_LE(o.illumination_period, 60) << i; break;
      case SceneFamily::kDistractor: EXPECT_TRUE(o.distractor) << i; break;
    }
    EXPECT_NE(scene_name(o), scene_name(suite_scene(i ^ 1u))) << i;
  }
  for (std::uint32_t f = 1; f <= kSceneFamilies; ++f) {
    EXPECT_EQ(per_family[f][0], 1) << name_of(static_cast<SceneFamily>(f));
    EXPECT_EQ(per_family[f][1], 1) << name_of(static_cast<SceneFamily>(f));
  }
  // The mixed scenes are as they were: the families come after them.
  EXPECT_EQ(suite_family(kSuiteMixedScenes - 1), SceneFamily::kMixed);
  EXPECT_EQ(scene_name(suite_scene(0)), "cog-gravel-smooth-cover-d1-s1");
}

// The look-alike is drawn clear of the target, away from it, and not in the truth.
TEST(Scene, TheDistractorIsALookAlikeClearOfTheTarget) {
  const auto dir = std::filesystem::temp_directory_path() / ("gabarit-twin-test-" + std::to_string(::getpid()));
  SceneOptions o;
  o.frames = 12;
  o.occlusion_side = OcclusionSide::kNone;
  o.width = 512, o.height = 384;
  o.noise_sigma = 0, o.illumination = 0, o.blur_every = 0;  // the two sequences differ only by the look-alike
  write_scene_sequence(o, (dir / "alone").string());
  o.distractor = true;
  const SceneSummary summary = write_scene_sequence(o, (dir / "twin").string());
  EXPECT_EQ(slurp(dir / "alone" / "gt.csv"), slurp(dir / "twin" / "gt.csv"));
  const auto alone = app::open_frames((dir / "alone" / "frames.y4m").string());
  const auto twin = app::open_frames((dir / "twin" / "frames.y4m").string());
  const auto truth = app::read_pose_csv((dir / "twin" / "gt.csv").string());
  app::GrayImage a, b;
  for (std::size_t f = 0; f < truth.size(); ++f) {
    ASSERT_TRUE(alone->next(a) && twin->next(b));
    std::size_t near_differ = 0, far_differ = 0;
    for (std::uint32_t y = 0; y < b.height; ++y)
      for (std::uint32_t x = 0; x < b.width; ++x) {
        if (a.pixels[y * b.width + x] == b.pixels[y * b.width + x]) continue;
        const double d = std::hypot(x - truth[f].x, y - truth[f].y);
        (d <= summary.object_radius + 2.0 ? near_differ : far_differ) += 1;
      }
    EXPECT_EQ(near_differ, 0u) << "frame " << f << ": the look-alike overlaps the target";
    EXPECT_GT(far_differ, 1000u) << "frame " << f << ": the look-alike is missing";
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace gabarit::host
