// The focus-stack depth by intensity: the stack image that was pasted into
// the frame, at the pose (rotated about the reference point), is the one
// chosen; bad arguments are refused and leave the depth alone.
#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/verification.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/image_io.hpp"

namespace gabarit {
namespace {

using app::GrayImage;

// Three 41x41 stack images that differ in texture, as blurring a tilted
// object does: depth d has stripes of period 4 + 3d, so they correlate poorly.
std::vector<GrayImage> make_stack() {
  std::vector<GrayImage> stack;
  for (int d = 0; d < 3; ++d) {
    GrayImage m(41, 41);
    for (std::uint32_t y = 0; y < 41; ++y)
      for (std::uint32_t x = 0; x < 41; ++x)
        m.at(x, y) = static_cast<std::uint8_t>(((x + 2 * y) / (4 + 3 * d)) % 2 ? 200 : 40);
    stack.push_back(m);
  }
  return stack;
}

// The frame: background 120, and image `d` placed with its reference point
// (20, 20) at (px, py), rotated by theta degrees (nearest-pixel backward map).
GrayImage frame_with(const GrayImage& m, float px, float py, float theta) {
  GrayImage f(120, 100, 120);
  const SinCos r = sin_cos_deg(theta);
  for (std::uint32_t y = 0; y < f.height; ++y)
    for (std::uint32_t x = 0; x < f.width; ++x) {
      const float dx = static_cast<float>(x) - px, dy = static_cast<float>(y) - py;
      const std::int32_t u = round_to_int(20.0f + r.cos * dx + r.sin * dy);
      const std::int32_t v = round_to_int(20.0f - r.sin * dx + r.cos * dy);
      if (u >= 0 && v >= 0 && u < 41 && v < 41) f.at(x, y) = m.at(static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v));
    }
  return f;
}

struct Views {
  std::vector<ImageView> views;
  explicit Views(const std::vector<GrayImage>& images) {
    for (const GrayImage& i : images) views.push_back(i.view());
  }
};

TEST(DepthByIntensity, ChoosesThePastedStackImageAtThePose) {
  const auto stack = make_stack();
  const Views v(stack);
  const FocusStack fs{v.views, 20.0f, 20.0f, 1};
  for (int d = 0; d < 3; ++d) {
    for (const float theta : {0.0f, 17.0f, -40.0f}) {
      const GrayImage f = frame_with(stack[static_cast<std::size_t>(d)], 60.0f, 48.0f, theta);
      std::uint16_t depth = 7;
      ASSERT_EQ(depth_by_intensity(f.view(), Pose{60.0f, 48.0f, theta, 0}, fs, depth), Status::kOk);
      EXPECT_EQ(depth, d) << "theta " << theta;
    }
  }
}

TEST(DepthByIntensity, SparseSamplingStillChoosesIt) {
  const auto stack = make_stack();
  const Views v(stack);
  const GrayImage f = frame_with(stack[2], 55.0f, 50.0f, 5.0f);
  std::uint16_t depth = 0;
  ASSERT_EQ(depth_by_intensity(f.view(), Pose{55.0f, 50.0f, 5.0f, 0}, FocusStack{v.views, 20.0f, 20.0f, 2}, depth), Status::kOk);
  EXPECT_EQ(depth, 2);
}

// Hysteresis: the current depth stays unless another correlates better by
// the margin. Image 2 pasted, with image 1 as the current depth: a margin of
// 0 switches to 2, a margin of 2 (the score's whole range) never does.
TEST(DepthByIntensity, ASwitchMarginKeepsTheCurrentDepth) {
  const auto stack = make_stack();
  const Views v(stack);
  const FocusStack fs{v.views, 20.0f, 20.0f, 1};
  const GrayImage f = frame_with(stack[2], 60.0f, 48.0f, 0.0f);
  std::uint16_t depth = 1;
  ASSERT_EQ(depth_by_intensity(f.view(), Pose{60.0f, 48.0f, 0.0f, 1}, fs, depth, 0.0f), Status::kOk);
  EXPECT_EQ(depth, 2);
  depth = 1;
  ASSERT_EQ(depth_by_intensity(f.view(), Pose{60.0f, 48.0f, 0.0f, 1}, fs, depth, 2.0f), Status::kOk);
  EXPECT_EQ(depth, 1);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{60.0f, 48.0f, 0.0f, 1}, fs, depth, -0.5f), Status::kInvalidArgument);
}

// A texture at any real model position, fine (a period of about 3 px) over
// coarse (about 10 px), so that a blur changes its shape, not only its
// contrast: sampled at whole model pixels it is the sharp stack image; the
// frame samples it at fractional positions, as a sharp object placed
// between pixels is seen.
float fine_texture(float u, float v) {
  constexpr float kTwoPi = 6.2831853f;
  return 128.0f + 50.0f * std::sin(kTwoPi * u / 3.1f) * std::cos(kTwoPi * v / 3.7f) + 35.0f * std::sin(kTwoPi * u / 11.0f) +
         30.0f * std::cos(kTwoPi * v / 9.0f);
}

// The frame's bilinear samples at half a pixel blur it by a quarter of a
// pixel squared along each axis. A second stack image, the sharp one blurred
// by as much ([1 6 1] / 8 along each axis), then correlates better with the
// sharp object than the sharp image itself (correlation_at, below); the
// depth must still be the sharp one's: the model is blurred as the frame's
// samples are before the depths are compared.
TEST(DepthByIntensity, TheFramesInterpolationDoesNotFavourABlurrierImage) {
  GrayImage sharp(41, 41), blurred(41, 41);
  for (std::uint32_t v = 0; v < 41; ++v)
    for (std::uint32_t u = 0; u < 41; ++u)
      sharp.at(u, v) = static_cast<std::uint8_t>(round_to_int(fine_texture(static_cast<float>(u), static_cast<float>(v))));
  const auto at = [&](std::int32_t u, std::int32_t v) {
    const auto clamp = [](std::int32_t i) { return static_cast<std::uint32_t>(i < 0 ? 0 : (i > 40 ? 40 : i)); };
    return static_cast<float>(sharp.at(clamp(u), clamp(v)));
  };
  for (std::int32_t v = 0; v < 41; ++v)
    for (std::int32_t u = 0; u < 41; ++u) {
      float sum = 0.0f;
      for (std::int32_t j = -1; j <= 1; ++j)
        for (std::int32_t i = -1; i <= 1; ++i) sum += (i == 0 ? 6.0f : 1.0f) * (j == 0 ? 6.0f : 1.0f) * at(u + i, v + j);
      blurred.at(static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(v)) = static_cast<std::uint8_t>(round_to_int(sum / 64.0f));
    }
  const std::vector<GrayImage> images{sharp, blurred};
  const Views views(images);
  const FocusStack fs{views.views, 20.0f, 20.0f, 1};
  for (const float theta : {0.0f, 17.0f}) {
    const Pose pose{60.5f, 48.5f, theta, 0};
    const SinCos r = sin_cos_deg(theta);
    GrayImage f(120, 100, 128);
    for (std::uint32_t y = 0; y < f.height; ++y)
      for (std::uint32_t x = 0; x < f.width; ++x) {
        const float dx = static_cast<float>(x) - pose.x, dy = static_cast<float>(y) - pose.y;
        const float u = 20.0f + r.cos * dx + r.sin * dy, v = 20.0f - r.sin * dx + r.cos * dy;
        if (u >= -1.0f && v >= -1.0f && u <= 41.0f && v <= 41.0f)
          f.at(x, y) = static_cast<std::uint8_t>(round_to_int(fine_texture(u, v)));
      }
    float sharp_score = 0.0f, blurred_score = 0.0f;
    ASSERT_TRUE(correlation_at(f.view(), pose, fs, 0, sharp_score));
    ASSERT_TRUE(correlation_at(f.view(), pose, fs, 1, blurred_score));
    EXPECT_GT(blurred_score, sharp_score) << "theta " << theta << ": the bias this guards against is gone from the frame";
    std::uint16_t depth = 1;
    ASSERT_EQ(depth_by_intensity(f.view(), pose, fs, depth), Status::kOk);
    EXPECT_EQ(depth, 0) << "theta " << theta;
  }
}

// Stack images of an object on a flat grey are compared over the object's
// own samples (tests/tools/tracking_test.cpp shows why); where those are too
// few to correlate (a 5 x 5 object, 3 x 3 inside its rim, sampled every
// pixel: 9 samples), every sample is compared, as for any other stack.
TEST(DepthByIntensity, AnObjectTooSmallForItsOwnSamplesIsComparedOverEverySample) {
  std::vector<GrayImage> stack;
  for (int d = 0; d < 3; ++d) {
    GrayImage m(41, 41, 128);
    for (std::uint32_t y = 18; y < 23; ++y)
      for (std::uint32_t x = 18; x < 23; ++x) m.at(x, y) = static_cast<std::uint8_t>(((x + 2 * y + d) % 3) * 60 + 20);
    stack.push_back(m);
  }
  const Views v(stack);
  const FocusStack fs{v.views, 20.0f, 20.0f, 1};
  for (std::uint16_t d = 0; d < 3; ++d) {
    const GrayImage f = frame_with(stack[d], 60.0f, 48.0f, 0.0f);
    std::uint16_t depth = 7;  // no current depth: the best is taken
    ASSERT_EQ(depth_by_intensity(f.view(), Pose{60.0f, 48.0f, 0.0f, 0}, fs, depth), Status::kOk);
    EXPECT_EQ(depth, d);
  }
}

// A disc of radius 12 about (20, 20) in a 41 x 41 image of flat grey 128:
// fine_texture scaled by `contrast` about `mean`.
GrayImage textured_disc(float mean, float contrast) {
  GrayImage disc(41, 41, 128);
  for (std::uint32_t v = 0; v < 41; ++v)
    for (std::uint32_t u = 0; u < 41; ++u) {
      const float du = static_cast<float>(u) - 20.0f, dv = static_cast<float>(v) - 20.0f;
      if (du * du + dv * dv <= 144.0f)
        disc.at(u, v) = static_cast<std::uint8_t>(
            round_to_int(mean + contrast * (fine_texture(static_cast<float>(u), static_cast<float>(v)) - 128.0f)));
    }
  return disc;
}

// The disc's own pixels (not its flat grey) pasted into `f` with (20, 20) at (60, 48).
void paste_disc(GrayImage& f, const GrayImage& disc) {
  for (std::uint32_t v = 0; v < 41; ++v)
    for (std::uint32_t u = 0; u < 41; ++u)
      if (disc.at(u, v) != 128) f.at(40 + u, 28 + v) = disc.at(u, v);
}

// A 120 x 100 frame of uniform random grey levels (a linear congruential generator).
GrayImage clutter(std::uint32_t seed) {
  GrayImage f(120, 100);
  std::uint32_t state = seed;
  for (std::uint8_t& p : f.pixels) {
    state = state * 1664525u + 1013904223u;
    p = static_cast<std::uint8_t>(state >> 24);
  }
  return f;
}

// A textured disc drawn on a flat grey, pasted over clutter: scoring a pose,
// the model's flat surround is not compared with the clutter behind it (the
// disc and a one-pixel ring around it are), so the true pose correlates as
// the disc does. The same model with a border that is not quite flat (a
// camera's crop) is compared over every sample, and the clutter pulls its
// score down (r^2 0.10 against 0.65): that is what the support changes.
TEST(CorrelationAt, AModelOnAFlatSurroundIsComparedOverItsOutlineNotTheClutter) {
  const GrayImage disc = textured_disc(128.0f, 1.0f);
  GrayImage cropped = disc;  // its border one grey level off in places
  for (std::uint32_t u = 0; u < 41; u += 2) cropped.at(u, 0) = 129;
  GrayImage f = clutter(12345u);
  paste_disc(f, disc);
  const Pose truth{60.0f, 48.0f, 0.0f, 0};
  const std::vector<GrayImage> flat{disc}, not_flat{cropped};
  const Views flat_views(flat), crop_views(not_flat);
  float on_outline = 0.0f, everywhere = 0.0f;
  ASSERT_TRUE(correlation_at(f.view(), truth, FocusStack{flat_views.views, 20.0f, 20.0f, 1}, 0, on_outline));
  ASSERT_TRUE(correlation_at(f.view(), truth, FocusStack{crop_views.views, 20.0f, 20.0f, 1}, 0, everywhere));
  // The ring of clutter just outside the disc still costs a third.
  EXPECT_GT(on_outline, 0.6f);
  EXPECT_LT(everywhere, 0.2f);
}

// A bright, faintly textured coin drawn on mid-grey, over a white page with
// dark print: the model's surround is darker than the coin, the frame's
// brighter. Its ring would pull the pose to where it falls on something
// darker than the page (the coin's own edge, the print), so it is left out:
// the true pose scores best of the pixel grid around it.
TEST(CorrelationAt, TheOutlinesRingIsLeftOutWhereTheFrameIsBrighterAroundTheObject) {
  const GrayImage coin = textured_disc(190.0f, 0.2f);
  GrayImage f(120, 100, 235);
  for (std::uint32_t y = 0; y < f.height; ++y)
    for (std::uint32_t x = 0; x < f.width; ++x)
      if ((y / 3) % 3 == 0 && (x * 7 + y * 3) % 11 < 5) f.at(x, y) = 40;  // lines of print
  paste_disc(f, coin);
  const std::vector<GrayImage> images{coin};
  const Views views(images);
  const FocusStack fs{views.views, 20.0f, 20.0f, 1};
  float at_truth = 0.0f;
  ASSERT_TRUE(correlation_at(f.view(), Pose{60.0f, 48.0f, 0.0f, 0}, fs, 0, at_truth));
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      float off = 0.0f;
      ASSERT_TRUE(correlation_at(f.view(), Pose{60.0f + static_cast<float>(dx), 48.0f + static_cast<float>(dy), 0.0f, 0}, fs, 0, off));
      EXPECT_LT(off, at_truth) << dx << "," << dy;
    }
}

// The frame's contrast over the samples a pose is scored on: the same
// object at half the contrast has a quarter of the variance; outside the
// frame there is none to tell.
TEST(FrameVarianceAt, MeasuresTheContrastTheFrameShowsAtThePose) {
  const auto stack = make_stack();
  const Views v(stack);
  const FocusStack fs{v.views, 20.0f, 20.0f, 1};
  GrayImage bright = frame_with(stack[1], 60.0f, 48.0f, 0.0f), dim = bright;
  for (std::uint8_t& p : dim.pixels) p = static_cast<std::uint8_t>(64 + p / 2);
  float full = 0.0f, half = 0.0f;
  ASSERT_TRUE(frame_variance_at(bright.view(), Pose{60.0f, 48.0f, 0.0f, 1}, fs, 1, full));
  ASSERT_TRUE(frame_variance_at(dim.view(), Pose{60.0f, 48.0f, 0.0f, 1}, fs, 1, half));
  EXPECT_NEAR(full, 6400.0f, 200.0f);  // stripes of 40 and 200, half each: (80)^2
  EXPECT_NEAR(half / full, 0.25f, 0.01f);
  float none = 0.0f;
  EXPECT_FALSE(frame_variance_at(bright.view(), Pose{-500.0f, -500.0f, 0.0f, 1}, fs, 1, none));
}

TEST(DepthByIntensity, OutsideTheFrameLeavesTheDepthAlone) {
  const auto stack = make_stack();
  const Views v(stack);
  const GrayImage f = frame_with(stack[1], 60.0f, 48.0f, 0.0f);
  std::uint16_t depth = 2;
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{-500.0f, -500.0f, 0.0f, 2}, FocusStack{v.views, 20.0f, 20.0f, 1}, depth), Status::kOk);
  EXPECT_EQ(depth, 2);
}

TEST(DepthByIntensity, RefusesBadArgumentsAndLeavesTheDepthAlone) {
  auto stack = make_stack();
  const GrayImage f(120, 100, 120);
  std::uint16_t depth = 1;
  const Views ok(stack);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{60, 48, 0, 0}, FocusStack{{}, 20, 20, 1}, depth), Status::kInvalidArgument);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{60, 48, 0, 0}, FocusStack{ok.views, 20, 20, 0}, depth), Status::kInvalidArgument);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{NAN, 48, 0, 0}, FocusStack{ok.views, 20, 20, 1}, depth), Status::kInvalidArgument);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{60, 48, INFINITY, 0}, FocusStack{ok.views, 20, 20, 1}, depth), Status::kInvalidArgument);
  stack[1] = GrayImage(40, 41);
  const Views mixed(stack);
  EXPECT_EQ(depth_by_intensity(f.view(), Pose{60, 48, 0, 0}, FocusStack{mixed.views, 20, 20, 1}, depth), Status::kInvalidArgument);
  EXPECT_EQ(depth, 1);
}

TEST(AngleByIntensity, FindsTheAngleBetweenTheVotesCells) {
  const auto stack = make_stack();
  const Views v(stack);
  const FocusStack fs{v.views, 20.0f, 20.0f, 1};
  for (const float truth : {10.0f, 10.4f, 11.1f}) {
    const GrayImage f = frame_with(stack[1], 60.0f, 48.0f, truth);
    float theta = 0.0f;
    // The votes said 10.5 degrees; the intensities put it within 0.25 of the truth.
    ASSERT_EQ(angle_by_intensity(f.view(), Pose{60.0f, 48.0f, 10.5f, 1}, fs, theta), Status::kOk);
    EXPECT_NEAR(theta, truth, 0.25f);
  }
  float theta = 3.0f;
  EXPECT_EQ(angle_by_intensity(frame_with(stack[1], 60, 48, 0).view(), Pose{60, 48, 0, 3}, fs, theta), Status::kInvalidArgument);
  EXPECT_EQ(theta, 3.0f);
}

// A bright coin over a page that is white left of the coin's centre and
// grey right of it: the frame's ring around the coin stands near the coin's
// own mean, so whether it stands on the model's side (darker than the coin)
// changes between poses half a pixel apart.
struct CoinOverTwoGreys {
  GrayImage coin = textured_disc(190.0f, 0.2f);
  GrayImage frame = GrayImage(120, 100, 235);
  std::vector<GrayImage> images{coin};
  Views views{images};
  FocusStack stack{views.views, 20.0f, 20.0f, 1};
  Pose truth{60.0f, 48.0f, 0.0f, 0}, left{59.5f, 48.0f, 0.0f, 0};
  CoinOverTwoGreys() {
    for (std::uint32_t y = 0; y < frame.height; ++y)
      for (std::uint32_t x = 60; x < frame.width; ++x) frame.at(x, y) = 140;
    paste_disc(frame, coin);
  }
};

// At the true pose the frame's ring is darker than the coin, as the model's
// is: compared (r^2 0.04, the model's mid-grey against the white page),
// and left out when the caller says so (1.0, the coin alone). Half a pixel
// to the left it is brighter: left out by itself (0.44).
TEST(CorrelationAt, TheRingIsComparedOrLeftOutAsTheCallerSays) {
  const CoinOverTwoGreys c;
  const ImageView f = c.frame.view();
  float where = 0.0f, with = 0.0f, without = 0.0f, plain = 0.0f;
  bool compared = false;
  ASSERT_TRUE(correlation_at(f, c.truth, c.stack, 0, OutlineRing::kWhereItAgrees, where, compared));
  EXPECT_TRUE(compared);
  ASSERT_TRUE(correlation_at(f, c.truth, c.stack, 0, OutlineRing::kCompared, with, compared));
  EXPECT_TRUE(compared);
  EXPECT_EQ(where, with);
  ASSERT_TRUE(correlation_at(f, c.truth, c.stack, 0, OutlineRing::kLeftOut, without, compared));
  EXPECT_FALSE(compared);
  EXPECT_GT(without, 0.99f);
  EXPECT_LT(with, 0.1f);
  ASSERT_TRUE(correlation_at(f, c.truth, c.stack, 0, plain));  // the five-argument form: where it agrees
  EXPECT_EQ(plain, where);
  ASSERT_TRUE(correlation_at(f, c.left, c.stack, 0, OutlineRing::kWhereItAgrees, where, compared));
  EXPECT_FALSE(compared);
  EXPECT_GT(where, 0.4f);
}

// Scored pose by pose, the pose half a pixel off won over the truth (0.44
// without its ring against 0.04 with it). A verification scores every
// proposal over the same samples, the ring as the first proposal scored
// has it, and the truth wins whichever comes first.
TEST(Verification, EveryProposalOfAFrameIsScoredOverTheSameSamples) {
  const CoinOverTwoGreys c;
  const Pose& truth = c.truth;
  const Pose& left = c.left;
  VerifyOptions o;
  o.refine = false;
  for (const bool truth_first : {true, false}) {
    Proposals p;
    p.add(truth_first ? truth : left);
    p.add(truth_first ? left : truth);
    Verdict v;
    ASSERT_EQ(verify(c.frame.view(), c.stack, p, o, v), Status::kOk);
    ASSERT_TRUE(v.found);
    EXPECT_EQ(v.pose.x, truth.x) << "truth first: " << truth_first;
  }
}

// The particle filter's intensity measure (particle_measures.hpp): the
// verified score on a list of the model's samples made once. A textured disc
// on a flat grey over clutter: the list holds only the disc and its ring (at
// most the samples asked for), the true pose scores as correlation_at does
// on every sample at the list's step, poses off it score less; a pose
// outside the frame or at a missing depth scores 0; with 0 samples the
// measure is correlation_at itself.
TEST(IntensityCorrelationMeasure, ScoresTheListedOutlineAsTheVerifiedScoreDoes) {
  const GrayImage disc = textured_disc(128.0f, 1.0f);
  GrayImage f = clutter(99u);
  paste_disc(f, disc);
  const std::vector<GrayImage> images{disc};
  const Views views(images);
  const FocusStack stack{views.views, 20.0f, 20.0f, 1};
  const Pose truth{60.0f, 48.0f, 0.0f, 0};
  IntensityCorrelationMeasure sparse(stack, 64), every(stack, 0);
  EXPECT_LE(sparse.samples(), 64u);
  EXPECT_GE(sparse.samples(), 16u);
  EXPECT_GE(sparse.step(), 2u);  // the disc and its ring hold about 490 pixels
  EXPECT_EQ(every.samples(), 0u);
  EXPECT_EQ(every.step(), 1u);
  EXPECT_EQ(sparse.prepare(GrayImage(0, 0).view(), truth), Status::kInvalidArgument);
  ASSERT_EQ(sparse.prepare(f.view(), truth), Status::kOk);
  ASSERT_EQ(every.prepare(f.view(), truth), Status::kOk);
  const float at_truth = sparse.score(truth);
  EXPECT_GT(at_truth, 0.8f);
  EXPECT_LE(at_truth, 1.0f);
  for (const Pose& off : {Pose{62.0f, 48.0f, 0.0f, 0}, Pose{60.0f, 45.5f, 0.0f, 0}, Pose{60.0f, 48.0f, 20.0f, 0}})
    EXPECT_LT(sparse.score(off), at_truth - 0.2f) << off.x << "," << off.y << "," << off.theta_deg;
  std::vector<Particle> cloud{{truth, 0.0f}, {Pose{61.0f, 48.0f, 0.0f, 0}, 0.0f}, {Pose{500.0f, 48.0f, 0.0f, 0}, 0.0f},
                              {Pose{60.0f, 48.0f, 0.0f, 1}, 0.0f}};
  sparse.weigh(cloud);
  EXPECT_EQ(cloud[0].weight, at_truth);
  EXPECT_GT(cloud[1].weight, 0.0f);
  EXPECT_EQ(cloud[2].weight, 0.0f);  // outside the frame
  EXPECT_EQ(cloud[3].weight, 0.0f);  // no such depth
  // Every sample: correlation_at's score, the ring as at the prediction.
  float r2 = 0.0f;
  bool ring = false;
  ASSERT_TRUE(correlation_at(f.view(), truth, stack, 0, OutlineRing::kWhereItAgrees, r2, ring));
  const float r = correlation_from_signed_square(r2);
  EXPECT_EQ(every.score(truth), r > 0.0f ? r : 0.0f);
  // The listed samples are the outline's at the list's step: the same sums
  // as correlation_at over the grid of that step (only the positions'
  // arithmetic differs, by at most a 1/65536 pixel).
  const FocusStack at_step{views.views, 20.0f, 20.0f, sparse.step()};
  ASSERT_TRUE(correlation_at(f.view(), truth, at_step, 0, OutlineRing::kWhereItAgrees, r2, ring));
  EXPECT_NEAR(at_truth, correlation_from_signed_square(r2), 1.0e-3f);
}

// The listed score's faster path (every sample in the frame: no bounds
// check, the model's sums precomputed, the grid's lines placed once, the
// samples walked run by run along the grid's rows) gives
// the bits the plain loop over the samples gave: a digest of the scores of
// poses all over the frame, inside it, across its edges and off it, at two
// depths and many angles, measured on x86-64 with the faster path switched
// off and the square root's 12 Newton steps always taken (the arithmetic of
// main at cf4ec23), and checked on every target with both on.
TEST(IntensityCorrelationMeasure, TheFasterPathScoresTheSameBitsAsTheSampleLoop) {
  const GrayImage disc = textured_disc(128.0f, 1.0f), dimmer = textured_disc(100.0f, 0.8f);
  GrayImage f = clutter(7u);
  paste_disc(f, disc);
  const std::vector<GrayImage> images{disc, dimmer};
  const Views views(images);
  const FocusStack stack{views.views, 20.0f, 20.0f, 1};
  IntensityCorrelationMeasure sparse(stack, 64), dense(stack, 400);
  ASSERT_EQ(sparse.prepare(f.view(), Pose{60.0f, 48.0f, 0.0f, 0}), Status::kOk);
  ASSERT_EQ(dense.prepare(f.view(), Pose{60.0f, 48.0f, 0.0f, 0}), Status::kOk);
  std::uint32_t digest = 0, scored = 0;
  for (float y = -14.0f; y < 116.0f; y += 6.1f)
    for (float x = -14.0f; x < 136.0f; x += 7.3f)
      for (float theta = -45.0f; theta < 50.0f; theta += 13.7f)
        for (std::uint16_t depth = 0; depth < 2; ++depth)
          for (IntensityCorrelationMeasure* m : {&sparse, &dense}) {
            const float score = m->score(Pose{x, y, theta, depth});
            std::uint32_t bits = 0;
            std::memcpy(&bits, &score, sizeof(bits));
            digest = digest * 16777619u ^ bits;  // FNV-style: order matters
            scored += score > 0.0f;
          }
  EXPECT_GT(scored, 1000u);
  EXPECT_EQ(digest, 117163229u) << "scores digest";
}

}  // namespace
}  // namespace gabarit
