// The focus-stack depth by intensity: the stack image that was pasted into
// the frame, at the pose (rotated about the reference point), is the one
// chosen; bad arguments are refused and leave the depth alone.
#include "gabarit/depth_by_intensity.hpp"

#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace
}  // namespace gabarit
