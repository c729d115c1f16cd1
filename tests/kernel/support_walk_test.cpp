// The object's support walked by rows (intensity_samples.hpp: a row's
// columns from its first and last object pixels, ObjectSupport::row_columns)
// must compare exactly the samples that asking contains() of every sample
// compared. A digest of every score, step, variance and depth the kernel's
// intensity functions give over poses all over a frame, across its edges
// and off it, at many angles and sampling steps, on a model whose rows hold
// the object in runs of every shape (a disc with a bar out of one side and a
// notch cut into the other, pixels alone, an empty row between two parts),
// measured on x86-64 before the row spans (main at 7987ad7) and checked on
// every target since.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/depth_by_intensity.hpp"

namespace gabarit {
namespace {

using app::GrayImage;

// A 47 x 43 model on flat grey 128 (its border all of it): the object's
// grey levels a texture about `mean`.
GrayImage ragged_object(int mean) {
  GrayImage m(47, 43, 128);
  const auto texture = [&](std::uint32_t u, std::uint32_t v) {
    const int t = mean + static_cast<int>((u * 37u + v * 91u + u * v * 13u) % 61u) - 30;
    return static_cast<std::uint8_t>(t == 128 ? 129 : t);  // never the surround's grey
  };
  for (std::uint32_t v = 1; v + 1 < m.height; ++v)
    for (std::uint32_t u = 1; u + 1 < m.width; ++u) {
      const int du = static_cast<int>(u) - 20, dv = static_cast<int>(v) - 20;
      const bool disc = du * du + dv * dv <= 121 && !(du > 4 && dv > -3 && dv < 3);  // a notch on the right
      const bool bar = dv >= -2 && dv <= 1 && du <= -10 && u >= 2;                      // a bar out to the left
      const bool lone = (u == 40 && v == 6) || (u == 44 && v == 38) || (u == 3 && v == 40);
      const bool lower = v >= 35 && v <= 39 && u >= 24 && u <= 33;  // a part below, row 33-34 empty between
      if ((disc || bar || lone || lower) && v != 33 && v != 34) m.at(u, v) = texture(u, v);
    }
  return m;
}

// A 130 x 104 frame of random grey levels with the object pasted at (65, 50).
GrayImage cluttered_frame(const GrayImage& object) {
  GrayImage f(130, 104);
  std::uint32_t state = 12345u;
  for (std::uint8_t& p : f.pixels) {
    state = state * 1664525u + 1013904223u;
    p = static_cast<std::uint8_t>(state >> 24);
  }
  for (std::uint32_t v = 0; v < object.height; ++v)
    for (std::uint32_t u = 0; u < object.width; ++u)
      if (object.at(u, v) != 128) f.at(45 + u, 30 + v) = object.at(u, v);
  return f;
}

std::uint32_t mix(std::uint32_t digest, float value) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));
  return digest * 16777619u ^ bits;  // FNV-style: order matters
}

TEST(SupportWalk, RowSpansScoreTheSameBitsAsAskingEverySample) {
  const std::vector<GrayImage> images{ragged_object(90), ragged_object(170)};
  std::vector<ImageView> views;
  for (const GrayImage& i : images) views.push_back(i.view());
  const GrayImage f = cluttered_frame(images[0]);
  std::uint32_t digest = 0, scored = 0, stepped = 0;
  for (std::uint32_t step = 1; step <= 3; ++step) {
    const FocusStack stack{views, 20.0f, 20.0f, step};
    for (float y = -16.0f; y < 122.0f; y += 9.1f)
      for (float x = -16.0f; x < 148.0f; x += 10.3f)
        for (float theta = -170.0f; theta < 180.0f; theta += 47.3f) {
          const Pose pose{x, y, theta, 0};
          for (std::uint16_t depth = 0; depth < 2; ++depth) {
            for (const OutlineRing ring : {OutlineRing::kWhereItAgrees, OutlineRing::kCompared, OutlineRing::kLeftOut}) {
              float r2 = -2.0f;
              bool compared = false;
              const bool ok = correlation_at(f.view(), pose, stack, depth, ring, r2, compared);
              digest = mix(digest, ok ? r2 : -3.0f);
              digest = mix(digest, compared ? 1.0f : 0.0f);
              scored += ok;
            }
            CorrelationAscent a;
            const bool ok = correlation_ascent_at(f.view(), pose, stack, depth, depth == 0, a);
            for (const float v : {ok ? 1.0f : 0.0f, a.signed_r2, a.has_step ? 1.0f : 0.0f, a.dx, a.dy, a.dtheta_deg})
              digest = mix(digest, v);
            stepped += a.has_step;
            float variance = -1.0f;
            digest = mix(digest, frame_variance_at(f.view(), pose, stack, depth, variance) ? variance : -3.0f);
          }
          std::uint16_t depth = 1;
          digest = mix(digest, depth_by_intensity(f.view(), pose, stack, depth) == Status::kOk ? depth : -3.0f);
        }
  }
  EXPECT_GT(scored, 3000u);
  EXPECT_GT(stepped, 500u);
  EXPECT_EQ(digest, 770696138u) << "digest";
}

// A focus stack whose images' objects differ in extent: the support (and
// each row's span) is where any image shows the object, so a row's first
// and last object pixels may come from different images. The second image
// adds pixels alone far out on rows the first leaves empty or short, a run
// along a row's right end, and two blocks beside the first's object. Measured on x86-64 before the rows were
// scanned eight pixels at a time (main at 008e944).
TEST(SupportWalk, RowSpansOfAStackCoverEveryImagesObject) {
  std::vector<GrayImage> images{ragged_object(90), ragged_object(170)};
  for (const auto& [u, v] : {std::pair{2u, 10u}, std::pair{45u, 10u}, std::pair{30u, 1u}, std::pair{12u, 34u}})
    images[1].at(u, v) = 60;
  for (std::uint32_t u = 36; u < 46; ++u) images[1].at(u, 25) = 200;
  // Blocks only the second image shows, left and right of the first's
  // object on their rows: the depths' interior support (kInterior) is there.
  for (std::uint32_t v = 24; v < 30; ++v)
    for (std::uint32_t u = 2; u < 7; ++u) images[1].at(u, v) = static_cast<std::uint8_t>(40 + 7 * u + 3 * v);
  for (std::uint32_t v = 8; v < 15; ++v)
    for (std::uint32_t u = 37; u < 45; ++u) images[1].at(u, v) = static_cast<std::uint8_t>(220 - 5 * u + 2 * v);
  std::vector<ImageView> views;
  for (const GrayImage& i : images) views.push_back(i.view());
  const GrayImage f = cluttered_frame(images[0]);
  std::uint32_t digest = 0, found = 0;
  for (std::uint32_t step = 1; step <= 2; ++step) {
    const FocusStack stack{views, 20.0f, 20.0f, step};
    for (float y = -6.0f; y < 112.0f; y += 7.3f)
      for (float x = -6.0f; x < 138.0f; x += 8.9f)
        for (float theta = -170.0f; theta < 180.0f; theta += 61.7f) {
          // From either depth, with margins that tell how far apart the
          // depths' scores are: each decision turns on the exact scores.
          for (const std::uint16_t start : {std::uint16_t{0}, std::uint16_t{1}})
            for (const float margin : {0.0f, 0.002f, 0.01f, 0.05f, 0.2f}) {
              std::uint16_t depth = start;
              const bool ok = depth_by_intensity(f.view(), Pose{x, y, theta, 0}, stack, depth, margin) == Status::kOk;
              digest = mix(digest, ok ? depth : -3.0f);
              found += ok && depth != start;
            }
        }
  }
  EXPECT_GT(found, 100u);  // depths changed
  EXPECT_EQ(digest, 4143972352u) << "digest";
}

}  // namespace
}  // namespace gabarit
