#include "gabarit/tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gabarit/deterministic_math.hpp"
#include "gabarit/app/image_io.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
using testing::build;
using testing::point_model;

using Scratch = testing::TrackerTestScratch;

GrayImage draw(const std::vector<host::Point>& pts, float x, float y, float theta_deg, std::uint32_t size = 96) {
  return testing::draw_points(pts, x, y, theta_deg, size);
}

TEST(Tracker, FindsATranslationExactly) {
  app::Rng rng(21);
  const auto pts = testing::random_points(rng, 60, 15);
  const auto bytes = build(point_model(pts), "-5:5:11", "-5:5:11");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  for (int dx = -5; dx <= 5; dx += 2) {
    for (int dy = -5; dy <= 5; dy += 3) {
      const GrayImage frame = draw(pts, 48.0f + static_cast<float>(dx), 47.0f + static_cast<float>(dy), 0);
      StepResult r;
      ASSERT_EQ(track_step(t, frame.view(), Pose{48, 47, 0, 0}, s.view(), r), Status::kOk);
      EXPECT_EQ(r.pose.x, 48.0f + static_cast<float>(dx));
      EXPECT_EQ(r.pose.y, 47.0f + static_cast<float>(dy));
      EXPECT_EQ(r.best.votes, pts.size());
      EXPECT_EQ(r.state, TrackState::kTracking);
      EXPECT_EQ(r.features, pts.size());
      EXPECT_FLOAT_EQ(r.score, 1.0f);
    }
  }
}

TEST(Tracker, ReportsLostOnAnEmptyFrameAndUncertainOnATie) {
  const auto bytes = build(point_model({{0, 0}, {2, 0}}), "-2:2:5", "0:0:1");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  StepResult r;
  GrayImage empty(32, 32);
  ASSERT_EQ(track_step(t, empty.view(), Pose{16, 16, 0, 0}, s.view(), r), Status::kOk);
  EXPECT_EQ(r.state, TrackState::kLost);
  EXPECT_EQ(r.best.votes, 0);
  // A single lit pixel is explained equally well by translations 0 and -2.
  GrayImage one(32, 32);
  one.at(16, 16) = 255;
  ASSERT_EQ(track_step(t, one.view(), Pose{16, 16, 0, 0}, s.view(), r), Status::kOk);
  EXPECT_EQ(r.state, TrackState::kUncertain);
}

TEST(Tracker, EstimatesRotationAndTracksInTheRotatedFrame) {
  app::Rng rng(8);
  const auto pts = testing::random_points(rng, 80, 14, 1.5);
  const auto bytes = build(point_model(pts), "-3:3:7", "-3:3:7", "-10:10:5");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  StepResult r;
  // From theta = 0 the object turned by 10 degrees and moved by (2, -1).
  GrayImage frame = draw(pts, 50, 45, 10.0f);
  ASSERT_EQ(track_step(t, frame.view(), Pose{48, 46, 0, 0}, s.view(), r), Status::kOk);
  EXPECT_EQ(r.pose.theta_deg, 10.0f);
  EXPECT_EQ(r.pose.x, 50.0f);
  EXPECT_EQ(r.pose.y, 45.0f);
  // From theta = 10 the object turned by another 5 and moved by (-2, 2): the
  // features are taken into the table frame by R(-10).
  frame = draw(pts, 48, 47, 15.0f);
  ASSERT_EQ(track_step(t, frame.view(), r.pose, s.view(), r), Status::kOk);
  EXPECT_NEAR(r.pose.theta_deg, 15.0f, 1e-5);
  EXPECT_NEAR(r.pose.x, 48.0f, 1.0f);
  EXPECT_NEAR(r.pose.y, 47.0f, 1.0f);
  EXPECT_EQ(r.features_dropped, 0u);
}

TEST(Tracker, CountsFeaturesDroppedByASmallBuffer) {
  const auto bytes = build(point_model({{0, 0}, {1, 0}}), "-1:1:3", "-1:1:3");
  const TableView t = testing::open_table(bytes);
  std::vector<RoiPoint> features(2);
  std::vector<VoteCounter> counters(t.cell_count());
  GrayImage full(16, 16, 255);
  StepResult r;
  ASSERT_EQ(track_step(t, full.view(), Pose{8, 8, 0, 0}, {features, counters, {}}, r), Status::kOk);
  EXPECT_EQ(r.features, 2u);
  EXPECT_EQ(r.features_dropped, t.roi_pixels() - 2);
}

TEST(Tracker, RejectsBadArguments) {
  const auto bytes = build(point_model({{0, 0}, {1, 0}}), "-1:1:3", "-1:1:3");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  GrayImage img(16, 16);
  StepResult r;
  EXPECT_EQ(track_step(t, ImageView{}, Pose{}, s.view(), r), Status::kInvalidArgument);
  EXPECT_EQ(track_step(t, img.view(), Pose{0.0f / 0.0f, 0, 0, 0}, s.view(), r), Status::kInvalidArgument);
  EXPECT_EQ(track_step(t, img.view(), Pose{1e9f, 0, 0, 0}, s.view(), r), Status::kInvalidArgument);
  EXPECT_EQ(track_step(t, img.view(), Pose{8, 8, 5, 0}, {s.features, s.counters, {}}, r), Status::kBufferTooSmall);
  EXPECT_EQ(track_step(t, img.view(), Pose{8, 8, 0, 0}, {s.features, {}, s.mask}, r), Status::kBufferTooSmall);
  EXPECT_EQ(track_step(t, Detector{table_format::DetectorKind::kGradientRows, 0}, img.view(), Pose{8, 8, 0, 0}, s.view(), r),
            Status::kInvalidArgument);
}

TEST(Tracker, ScratchSizesAreCompileTimeFormulas) {
  static_assert(tracker_window_side(11, 11, -5, -5) == 2 * 8 + 1);  // corner (5,5): r = 7.07 -> 8
  static_assert(tracker_feature_capacity(4, 4, 0, 0) == 11 * 11);   // corner (3,3): r = 4.24 -> 5, side 11
  static_assert(tracker_mask_bytes(3, 3) == 2);
  SUCCEED();
}

}  // namespace
}  // namespace gabarit

namespace gabarit {
namespace {

// map_features on features detected once over a large window gives exactly
// prepare_frame's features for the detectors whose features do not depend on
// the window (binary; Canny, which at an angle scans only the rotated ROI's
// columns, with rows of magnitudes or without), at any angle and wherever the
// ROI sits in the window, even half outside the image.
TEST(MapFeatures, MatchesPrepareFrameForAWindowIndependentDetector) {
  app::Rng rng(77);
  const auto pts = testing::random_points(rng, 40, 12);
  const auto bytes = build(point_model(pts), "-3:3:7", "-3:3:7", "-1.5:1.5:3");
  const TableView t = testing::open_table(bytes);
  app::GrayImage image(180, 150);
  for (auto& v : image.pixels) v = rng.bernoulli(0.15) ? 255 : static_cast<std::uint8_t>(rng.uniform_int(0, 90));
  const ImageWindow big{-20, -30, 230, 210};  // the whole image and beyond
  std::vector<std::uint16_t> magnitudes(tracker_magnitude_entries(t));
  for (const Detector detector : {Detector{table_format::DetectorKind::kBinary, 0}, Detector{table_format::DetectorKind::kCanny, 400}}) {
    std::vector<RoiPoint> detected(feature_capacity(big.width, big.height));
    FeatureCount found;
    ASSERT_EQ(extract_features(image.view(), big, detector.kind, detector.threshold, detected, found), Status::kOk);
    detected.resize(found.written);
    for (const bool rows : {false, true}) {
      Scratch a(t), b(t);
      TrackerScratch prepared = a.view();
      if (rows) prepared.magnitudes = magnitudes;
      for (const Pose pose : {Pose{90, 75, 0, 0}, Pose{90.4f, 74.6f, 7.3f, 0}, Pose{60, 40, -33.0f, 0}, Pose{3, 140, 90.5f, 0},
                              Pose{175.2f, 2.7f, 181.0f, 0}, Pose{120, 100, 0.01f, 0}, Pose{88, 70, 45.0f, 0}}) {
        SCOPED_TRACE(pose.theta_deg);
        PreparedFrame expected, got;
        ASSERT_EQ(prepare_frame(t, detector, image.view(), pose, prepared, expected), Status::kOk);
        ASSERT_EQ(map_features(t, image.view(), detected, big, pose, b.view(), got), Status::kOk);
        EXPECT_EQ(got.roi_centre_x, expected.roi_centre_x);
        EXPECT_EQ(got.roi_centre_y, expected.roi_centre_y);
        ASSERT_EQ(got.features, expected.features);
        EXPECT_GT(got.features, 0u);
        for (std::uint32_t i = 0; i < got.features; ++i) {
          ASSERT_EQ(b.features[i].col, a.features[i].col) << i;
          ASSERT_EQ(b.features[i].row, a.features[i].row) << i;
        }
      }
    }
  }
}

TEST(MapFeatures, RefusesBadArgumentsAndCountsWhatDoesNotFit) {
  app::Rng rng(78);
  const auto bytes = build(point_model(testing::random_points(rng, 30, 10)), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  const std::vector<RoiPoint> detected = {{10, 10}, {11, 10}, {12, 11}, {30, 12}};
  const ImageWindow window{0, 0, 40, 40};
  Scratch s(t);
  PreparedFrame out;
  EXPECT_EQ(map_features(t, ImageView{}, detected, window, Pose{std::nanf(""), 10, 0, 0}, s.view(), out), Status::kInvalidArgument);
  TrackerScratch no_mask = s.view();
  no_mask.roi_mask = {};
  EXPECT_EQ(map_features(t, ImageView{}, detected, window, Pose{11, 10, 0, 0}, no_mask, out), Status::kBufferTooSmall);
  TrackerScratch two = s.view();
  two.features = two.features.first(2);
  ASSERT_EQ(map_features(t, ImageView{}, detected, window, Pose{11, 10, 0, 0}, two, out), Status::kOk);
  EXPECT_EQ(out.features, 2u);
  EXPECT_EQ(out.features_dropped, 1u);  // (30, 12) lies outside the ROI: not counted
}

}  // namespace
}  // namespace gabarit
