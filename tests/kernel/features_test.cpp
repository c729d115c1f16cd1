#include "gabarit/features.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "gabarit/app/image_io.hpp"

namespace gabarit {
namespace {

using app::GrayImage;

std::vector<RoiPoint> run_binary(const GrayImage& img, ImageWindow w, std::size_t capacity, FeatureCount& count) {
  std::vector<RoiPoint> out(capacity);
  EXPECT_EQ(extract_binary(img.view(), w, out, count), Status::kOk);
  out.resize(count.written);
  return out;
}

TEST(Features, BinaryReportsNonZeroPixelsInWindowCoordinates) {
  GrayImage img(10, 8);
  img.at(3, 2) = 1;
  img.at(7, 5) = 255;
  FeatureCount c;
  const auto f = run_binary(img, {2, 1, 6, 6}, 36, c);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0].col, 1);
  EXPECT_EQ(f[0].row, 1);
  EXPECT_EQ(f[1].col, 5);
  EXPECT_EQ(f[1].row, 4);
  EXPECT_EQ(c.dropped, 0u);
}

TEST(Features, WindowsPartlyOrWhollyOutsideTheImageAreClipped) {
  GrayImage img(4, 4, 9);
  FeatureCount c;
  EXPECT_EQ(run_binary(img, {-2, -2, 4, 4}, 16, c).size(), 4u);  // only the 2x2 overlap
  EXPECT_EQ(run_binary(img, {100, -50, 5, 5}, 25, c).size(), 0u);
  EXPECT_EQ(run_binary(img, {-3, 3, 10, 10}, 100, c).size(), 4u);  // bottom row of the image
}

TEST(Features, OverflowIsCountedAndNothingIsWrittenPastCapacity) {
  GrayImage img(5, 5, 1);
  std::vector<RoiPoint> out(7, RoiPoint{999, 999});
  FeatureCount c;
  ASSERT_EQ(extract_binary(img.view(), {0, 0, 5, 5}, std::span(out).first(3), c), Status::kOk);
  EXPECT_EQ(c.written, 3u);
  EXPECT_EQ(c.dropped, 22u);
  for (std::size_t i = 3; i < out.size(); ++i) EXPECT_EQ(out[i].col, 999);
}

TEST(Features, GradientRowsKeepsTheStrongestPixelOfEachRun) {
  // A vertical step edge between columns 4 and 5: Sobel responds on columns 4
  // and 5 with equal strength; the leftmost of the run is kept.
  GrayImage img(12, 6);
  for (std::uint32_t y = 0; y < 6; ++y)
    for (std::uint32_t x = 5; x < 12; ++x) img.at(x, y) = 200;
  std::vector<RoiPoint> out(72);
  FeatureCount c;
  ASSERT_EQ(extract_gradient_rows(img.view(), {0, 0, 12, 6}, 100, out, c), Status::kOk);
  ASSERT_EQ(c.written, 4u);  // interior rows 1..4, one feature each
  for (std::uint32_t i = 0; i < c.written; ++i) {
    EXPECT_EQ(out[i].col, 4);
    EXPECT_EQ(out[i].row, i + 1);
  }
}

TEST(Features, GradientRowsPicksThePeakOfARamp) {
  GrayImage img(9, 3);
  const std::uint8_t row[9] = {0, 0, 10, 40, 120, 200, 230, 240, 240};
  for (std::uint32_t y = 0; y < 3; ++y)
    for (std::uint32_t x = 0; x < 9; ++x) img.at(x, y) = row[x];
  std::uint16_t best = 0;
  std::uint32_t best_x = 0;
  for (std::uint32_t x = 1; x < 8; ++x) {
    if (gradient_magnitude(img.view(), x, 1) > best) best = gradient_magnitude(img.view(), x, 1), best_x = x;
  }
  std::vector<RoiPoint> out(27);
  FeatureCount c;
  ASSERT_EQ(extract_gradient_rows(img.view(), {0, 0, 9, 3}, 1, out, c), Status::kOk);
  ASSERT_EQ(c.written, 1u);
  EXPECT_EQ(out[0].col, best_x);
}

TEST(Features, BorderPixelsAreNeverGradientFeatures) {
  GrayImage img(6, 6);
  for (std::uint32_t x = 0; x < 6; ++x) img.at(x, 0) = 255;  // an edge on the top border only
  EXPECT_EQ(gradient_magnitude(img.view(), 0, 0), 0);
  EXPECT_EQ(gradient_magnitude(img.view(), 5, 3), 0);
  std::vector<RoiPoint> out(36);
  FeatureCount c;
  ASSERT_EQ(extract_gradient_rows(img.view(), {0, 0, 6, 6}, 1, out, c), Status::kOk);
  for (std::uint32_t i = 0; i < c.written; ++i) EXPECT_GE(out[i].row, 1);
}

TEST(Features, RejectsBadArguments) {
  GrayImage img(6, 6);
  std::vector<RoiPoint> out(36);
  FeatureCount c;
  EXPECT_EQ(extract_gradient_rows(img.view(), {0, 0, 6, 6}, 0, out, c), Status::kInvalidArgument);
  EXPECT_EQ(extract_binary(ImageView{}, {0, 0, 6, 6}, out, c), Status::kInvalidArgument);
  EXPECT_EQ(extract_binary(img.view(), {0, 0, 0, 6}, out, c), Status::kInvalidArgument);
  ImageView bad_stride = img.view();
  bad_stride.stride = 3;
  EXPECT_EQ(extract_binary(bad_stride, {0, 0, 6, 6}, out, c), Status::kInvalidArgument);
}

}  // namespace
}  // namespace gabarit

namespace gabarit {
namespace {

// A vertical step edge of height 120 between columns 9 and 10 of a 20x12 image.
app::GrayImage step_edge(std::uint8_t left, std::uint8_t right) {
  app::GrayImage img(20, 12);
  for (std::uint32_t y = 0; y < 12; ++y)
    for (std::uint32_t x = 0; x < 20; ++x) img.at(x, y) = x < 10 ? left : right;
  return img;
}

TEST(Canny, AStepEdgeGivesOnePixelWideLineAfterNonMaximumSuppression) {
  const app::GrayImage img = step_edge(20, 140);
  std::vector<RoiPoint> out(240);
  FeatureCount n;
  ASSERT_EQ(extract_canny(img.view(), {0, 0, 20, 12}, 200, out, n), Status::kOk);
  // Sobel responds on both columns 9 and 10 equally; NMS keeps one per row
  // (m >= the neighbour ahead, > the one behind), the interior rows 1..10.
  ASSERT_EQ(n.written, 10u);
  for (std::uint32_t i = 0; i < n.written; ++i) {
    EXPECT_EQ(out[i].col, out[0].col);
    EXPECT_EQ(out[i].row, i + 1);
  }
  EXPECT_TRUE(out[0].col == 9 || out[0].col == 10);
}

TEST(Canny, WeakEdgesSurviveOnlyNextToStrongOnes) {
  // Magnitude of a step of h grey levels is 4h: a 40-level step gives 160.
  const app::GrayImage weak = step_edge(100, 140);
  std::vector<RoiPoint> out(240);
  FeatureCount n;
  ASSERT_EQ(extract_canny(weak.view(), {0, 0, 20, 12}, 300, out, n), Status::kOk);  // low = 150 <= 160 < 300 = high
  EXPECT_EQ(n.written, 0u) << "a weak edge with no strong neighbour is not an edge";
  app::GrayImage mixed = weak;
  for (std::uint32_t x = 10; x < 20; ++x) mixed.at(x, 6) = 220;  // one row makes a strong edge there
  ASSERT_EQ(extract_canny(mixed.view(), {0, 0, 20, 12}, 300, out, n), Status::kOk);
  bool strong_row = false, neighbour_row = false, far_row = false;
  for (std::uint32_t i = 0; i < n.written; ++i) {
    strong_row |= out[i].row == 6;
    neighbour_row |= out[i].row == 5 || out[i].row == 7;
    far_row |= out[i].row == 2;
  }
  EXPECT_TRUE(strong_row);
  EXPECT_TRUE(neighbour_row) << "weak pixels next to the strong ones are kept (one step of hysteresis)";
  EXPECT_FALSE(far_row);
  EXPECT_EQ(extract_canny(weak.view(), {0, 0, 20, 12}, 1, out, n), Status::kInvalidArgument);
  EXPECT_EQ(extract_features(weak.view(), {0, 0, 20, 12}, table_format::DetectorKind::kCanny, 300, out, n), Status::kOk);
}

// The rows of magnitudes, and the vector bodies that decide whole vectors of
// a row where the build has them (kernel/src/canny_rows.hpp: AVX2 or SSE4 on
// x86-64, NEON on AArch64), are optimisations only: on noisy images of awkward
// sizes, windows that leave the image and feature buffers that overflow, the
// features, their order and the dropped count are the per-pixel path's.
TEST(Canny, RowsOfMagnitudesGiveTheReferenceFeaturesBitForBit) {
  std::uint32_t state = 12345u;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 24;
  };
  // Wider than 64 columns (the vector bodies decide up to 64 at a time) and
  // not a whole number of vectors of any width (canny_rows.hpp).
  const std::uint32_t sizes[][2] = {{3, 3}, {1, 9}, {9, 1}, {4, 5}, {37, 23}, {131, 7}, {64, 64}, {203, 11}};
  std::size_t compared = 0, features_seen = 0;
  for (const auto& size : sizes) {
    GrayImage img(size[0], size[1]);
    // Blocks of a few grey levels plus noise: strong, weak and absent edges.
    for (std::uint32_t y = 0; y < size[1]; ++y)
      for (std::uint32_t x = 0; x < size[0]; ++x)
        img.at(x, y) = static_cast<std::uint8_t>(((x / 5 + y / 3) % 3) * 60 + next() % 40);
    const std::int32_t w = static_cast<std::int32_t>(size[0]), h = static_cast<std::int32_t>(size[1]);
    const ImageWindow windows[] = {{0, 0, static_cast<std::uint16_t>(w), static_cast<std::uint16_t>(h)},
                                   {-3, -2, static_cast<std::uint16_t>(w + 6), static_cast<std::uint16_t>(h + 4)},
                                   {1, 1, static_cast<std::uint16_t>(w > 2 ? w - 2 : 1), static_cast<std::uint16_t>(h > 2 ? h - 2 : 1)},
                                   {w / 2, h / 3, 5, 4},
                                   {w - 2, h - 2, 9, 9},
                                   {w + 4, 0, 3, 3}};
    for (const ImageWindow& window : windows) {
      for (const std::uint16_t threshold : {2, 3, 61, 180, 400}) {
        for (const std::size_t capacity : {std::size_t{3}, feature_capacity(window.width, window.height)}) {
          std::vector<RoiPoint> reference(capacity), buffered(capacity);
          FeatureCount n_reference, n_buffered;
          ASSERT_EQ(extract_canny(img.view(), window, threshold, reference, n_reference), Status::kOk);
          std::vector<std::uint16_t> rows(canny_scratch_entries(window.width));
          ASSERT_EQ(extract_canny(img.view(), window, threshold, buffered, n_buffered, rows), Status::kOk);
          ASSERT_EQ(n_buffered.written, n_reference.written) << size[0] << "x" << size[1] << " threshold " << threshold;
          ASSERT_EQ(n_buffered.dropped, n_reference.dropped);
          for (std::uint32_t i = 0; i < n_reference.written; ++i) {
            ASSERT_EQ(buffered[i].col, reference[i].col);
            ASSERT_EQ(buffered[i].row, reference[i].row);
          }
          // Too few rows: the per-pixel path, the same answer.
          std::vector<std::uint16_t> short_rows(rows.size() > 0 ? rows.size() - 1 : 0);
          ASSERT_EQ(extract_canny(img.view(), window, threshold, buffered, n_buffered, short_rows), Status::kOk);
          ASSERT_EQ(n_buffered.written, n_reference.written);
          ++compared;
          features_seen += n_reference.written;
        }
      }
    }
  }
  EXPECT_EQ(compared, 8u * 6u * 5u * 2u);
  EXPECT_GT(features_seen, 1000u) << "the images must have edges for the comparison to mean something";
}

// Which body decides the rows is reported by name; where the build made
// vector bodies (x86-64 and AArch64 with Google Highway) the CPUs CI runs on
// get one, so a build that silently lost them fails here.
TEST(Canny, TheVectorBodyIsNamedAndUsedWhereBuilt) {
  const std::string body = canny_vector_body();
  EXPECT_TRUE(body == "AVX2" || body == "SSE4" || body == "NEON" || body == "scalar") << body;
#if defined(GABARIT_EXPECT_CANNY_VECTOR_BODY)
  EXPECT_NE(body, "scalar");
#endif
}

// A turned rectangle to keep (a tracker's rotated ROI): of each row only the
// columns it covers are scanned. The features are a subsequence of the whole
// window's that holds every one within the rectangle: Canny's the same with
// rows of magnitudes or without, and the binary detector's likewise.
TEST(Canny, ARotatedRectangleScansLessAndKeepsEveryFeatureInIt) {
  std::uint32_t state = 777u;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 24;
  };
  GrayImage img(97, 83);
  for (std::uint32_t y = 0; y < img.height; ++y)
    for (std::uint32_t x = 0; x < img.width; ++x)
      img.at(x, y) = static_cast<std::uint8_t>(((x / 4 + y / 6) % 3) * 70 + next() % 30);
  std::size_t inside_total = 0, kept_total = 0, whole_total = 0;
  const float angles[] = {0.0f, 0.003f, 0.5f, 1.0f, 1.5707963f, 2.6f, -0.7f, 3.1415926f};
  for (const float angle : angles) {
    for (const ImageWindow window : {ImageWindow{-5, -5, 110, 95}, ImageWindow{20, 10, 60, 60}, ImageWindow{70, 60, 50, 40}}) {
      const TurnedRectangle keep{48.0f, 41.0f, std::cos(angle), std::sin(angle), -20.5f, 17.5f, -9.5f, 12.5f};
      const std::size_t capacity = feature_capacity(window.width, window.height);
      std::vector<RoiPoint> whole(capacity), kept(capacity), kept_rows(capacity);
      std::vector<std::uint16_t> rows(canny_scratch_entries(window.width));
      FeatureCount n_whole, n_kept, n_rows;
      ASSERT_EQ(extract_canny(img.view(), window, 60, whole, n_whole), Status::kOk);
      ASSERT_EQ(extract_canny(img.view(), window, 60, kept, n_kept, {}, &keep), Status::kOk);
      ASSERT_EQ(extract_canny(img.view(), window, 60, kept_rows, n_rows, rows, &keep), Status::kOk);
      ASSERT_EQ(n_rows.written, n_kept.written);
      for (std::uint32_t i = 0; i < n_kept.written; ++i) {
        ASSERT_EQ(kept_rows[i].col, kept[i].col);
        ASSERT_EQ(kept_rows[i].row, kept[i].row);
      }
      // The binary detector on the same image (its brighter pixels).
      GrayImage bright = img;
      for (auto& v : bright.pixels) v = v >= 140 ? 255 : 0;
      std::vector<RoiPoint> binary_whole(capacity), binary_kept(capacity);
      FeatureCount b_whole, b_kept;
      ASSERT_EQ(extract_binary(bright.view(), window, binary_whole, b_whole), Status::kOk);
      ASSERT_EQ(extract_binary(bright.view(), window, binary_kept, b_kept, &keep), Status::kOk);
      EXPECT_LT(b_kept.scanned, b_whole.scanned);
      std::uint32_t j = 0;
      for (std::uint32_t i = 0; i < b_whole.written && j < b_kept.written; ++i)
        if (binary_whole[i].col == binary_kept[j].col && binary_whole[i].row == binary_kept[j].row) ++j;
      EXPECT_EQ(j, b_kept.written) << "the binary features kept are a subsequence of the window's";
      EXPECT_LT(n_kept.scanned, n_whole.scanned);
      // A subsequence of the whole window's, missing none within the rectangle.
      std::uint32_t k = 0;
      for (std::uint32_t i = 0; i < n_whole.written; ++i) {
        const float dx = static_cast<float>(window.x0 + whole[i].col) - keep.centre_x;
        const float dy = static_cast<float>(window.y0 + whole[i].row) - keep.centre_y;
        const float u = keep.cos * dx + keep.sin * dy, v = -keep.sin * dx + keep.cos * dy;
        const bool inside = u >= keep.u_min && u <= keep.u_max && v >= keep.v_min && v <= keep.v_max;
        const bool listed = k < n_kept.written && kept[k].col == whole[i].col && kept[k].row == whole[i].row;
        if (listed) ++k;
        if (inside) {
          EXPECT_TRUE(listed) << "angle " << angle << " feature " << whole[i].col << "," << whole[i].row;
          ++inside_total;
        }
      }
      EXPECT_EQ(k, n_kept.written) << "every kept feature is one of the whole window's, in order";
      kept_total += n_kept.written;
      whole_total += n_whole.written;
    }
  }
  EXPECT_GT(inside_total, 500u);
  EXPECT_LT(kept_total, whole_total * 3 / 4) << "the rectangle is smaller than the windows: less is scanned";
}

}  // namespace
}  // namespace gabarit
