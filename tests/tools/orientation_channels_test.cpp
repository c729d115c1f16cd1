// Orientation channels (table format 1.3): the builder writes them, the
// kernel opens them, every voter (CSR, expanded offsets, dense masks) gives
// the same counters, a feature votes only its channel and the nearer
// neighbour's, and the tracker still finds the pose.
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "gabarit/app/error.hpp"
#include "gabarit/app/image_io.hpp"
#include "gabarit/dense_voter.hpp"
#include "gabarit/host/tables/model.hpp"
#include "gabarit/app/rng.hpp"
#include "gabarit/host/tables/state_space.hpp"
#include "gabarit/host/tables/table_builder.hpp"
#include "gabarit/tracker.hpp"
#include "gabarit/voter.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

// An asymmetric grey shape (a disc with a square notch and a bar), drawn
// with 4x4 supersampling so its edges have graded, orientation-bearing
// gradients, rotated by theta about (cx, cy).
app::GrayImage draw_shape(std::uint32_t w, std::uint32_t h, double cx, double cy, double theta_deg, app::Rng* noise) {
  app::GrayImage g(w, h, 70);
  const double c = std::cos(theta_deg * M_PI / 180), s = std::sin(theta_deg * M_PI / 180);
  for (std::uint32_t y = 0; y < h; ++y)
    for (std::uint32_t x = 0; x < w; ++x) {
      int inside = 0;
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const double dx = x + (sx + 0.5) / 4 - 0.5 - cx, dy = y + (sy + 0.5) / 4 - 0.5 - cy;
          const double u = c * dx + s * dy, v = -s * dx + c * dy;  // model frame
          const bool disc = u * u + v * v < 22.0 * 22.0 && !(u > 4 && v > 4);
          const bool bar = u > -30 && u < 30 && v > -26 && v < -20;
          inside += disc || bar;
        }
      double value = 70 + 130.0 * inside / 16;
      if (noise) value += (noise->next_unit() - 0.5) * 12;
      g.at(x, y) = static_cast<std::uint8_t>(std::lround(std::fmin(255, std::fmax(0, value))));
    }
  return g;
}

struct Tables {
  std::vector<std::byte> plain_bytes, channel_bytes;
  TableView plain, channels;
  host::ModelStack model;
  Tables() {
    // Per process: ctest runs each test case as its own process, in parallel.
    const auto dir = std::filesystem::temp_directory_path() / ("gabarit_channels_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    app::write_pgm((dir / "model.pgm").string(), draw_shape(81, 81, 40, 40, 0, nullptr));
    host::ImageModelOptions mo;
    mo.canny = true;
    model = host::model_from_images({(dir / "model.pgm").string()}, mo);
    std::filesystem::remove_all(dir);
    host::BuildOptions bo;
    bo.space.x = host::parse_axis("-3:3:7", "x");
    bo.space.y = host::parse_axis("-3:3:7", "y");
    bo.space.theta = host::parse_axis("-1:1:5", "theta");
    plain_bytes = host::build_table(model, bo);
    bo.orientation_channels = 16;
    channel_bytes = host::build_table(model, bo);
    plain = testing::open_table(plain_bytes);
    channels = testing::open_table(channel_bytes);
  }
};

TEST(OrientationChannels, TheBuilderWritesFormat13) {
  const Tables t;
  EXPECT_EQ(t.plain.orientation_channels(), 1u);
  EXPECT_EQ(t.channels.orientation_channels(), 16u);
  EXPECT_EQ(static_cast<int>(t.channel_bytes[table_format::offset::kVersionMinor]), 3);
  EXPECT_EQ(t.channels.roi_pixels(), t.plain.roi_pixels());
  EXPECT_EQ(t.channels.roi_slots(), 16 * t.plain.roi_slots());
  // Every stencil pixel lies in at least one channel, sometimes in two (an
  // orientation turned across a channel boundary by the cell's angles).
  for (std::uint32_t c = 0; c < t.plain.cell_count(); ++c) {
    EXPECT_GE(t.channels.stencil_size(c), t.plain.stencil_size(c));
    EXPECT_LE(t.channels.stencil_size(c), 2 * t.plain.stencil_size(c));
  }
}

TEST(OrientationChannels, TheBuilderRefusesWhatCannotCarryOrientation) {
  const Tables t;
  host::BuildOptions bo;
  bo.space.x = host::parse_axis("-1:1:3", "x");
  bo.space.y = host::parse_axis("-1:1:3", "y");
  bo.orientation_channels = 3;
  EXPECT_THROW(host::build_table(t.model, bo), app::Error);
  bo.orientation_channels = 8;
  host::ModelStack points = t.model;
  points.images.clear();
  EXPECT_THROW(host::build_table(points, bo), app::Error);
  host::ModelStack binary = t.model;
  binary.detector.kind = table_format::DetectorKind::kBinary;
  EXPECT_THROW(host::build_table(binary, bo), app::Error);
}

TEST(OrientationChannels, EveryVoterGivesTheSameCountersAndFewerVotes) {
  const Tables t;
  app::Rng noise(3);
  const app::GrayImage frame = draw_shape(160, 150, 81.3, 72.6, 17.2, &noise);
  for (const Pose previous : {Pose{80, 73, 17, 0}, Pose{82, 71, 0, 0}, Pose{79.6f, 74.2f, 15.5f, 0}}) {
    testing::TrackerTestScratch csr(t.channels);
    PreparedFrame prepared;
    ASSERT_EQ(prepare_frame(t.channels, detector_of(t.channels), frame.view(), previous, csr.view(), prepared), Status::kOk);
    ASSERT_GT(prepared.features, 20u);
    const std::span<const RoiPoint> features = std::span<const RoiPoint>(csr.features).first(prepared.features);
    VoteTally a, b, c;
    std::vector<VoteCounter> ca(voter_counter_count(t.channels.cell_count())), cb = ca, cc = ca;
    ASSERT_EQ(accumulate_votes(t.channels, features, ca, a), Status::kOk);
    std::vector<std::uint32_t> expanded(expanded_offsets_count(t.channels));
    ASSERT_EQ(expand_offsets(t.channels, expanded), Status::kOk);
    ASSERT_EQ(accumulate_votes_expanded(t.channels, expanded, features, cb, b), Status::kOk);
    std::vector<std::uint64_t> masks(dense_mask_words(t.channels.roi_slots(), t.channels.cell_count()));
    std::vector<std::uint64_t> scratch(dense_scratch_words(t.channels.cell_count()));
    ASSERT_EQ(build_dense_masks(t.channels, masks), Status::kOk);
    ASSERT_EQ(accumulate_votes_dense(t.channels, masks, features, cc, scratch, c), Status::kOk);
    EXPECT_EQ(ca, cb);
    EXPECT_EQ(ca, cc);
    EXPECT_EQ(a.votes, b.votes);
    EXPECT_EQ(a.votes, c.votes);
    // The same frame on the position-only table: the same pixels, and more
    // votes (every cell covering a pixel, whatever the orientation).
    testing::TrackerTestScratch plain(t.plain);
    PreparedFrame pp;
    ASSERT_EQ(prepare_frame(t.plain, detector_of(t.plain), frame.view(), previous, plain.view(), pp), Status::kOk);
    ASSERT_EQ(pp.features, prepared.features);
    for (std::uint32_t i = 0; i < pp.features; ++i) {
      ASSERT_EQ(t.channels.feature_column(csr.features[i]), plain.features[i].col);
      ASSERT_EQ(csr.features[i].row, plain.features[i].row);
    }
    VoteTally pt;
    std::vector<VoteCounter> pc(voter_counter_count(t.plain.cell_count()));
    ASSERT_EQ(accumulate_votes(t.plain, std::span<const RoiPoint>(plain.features).first(pp.features), pc, pt), Status::kOk);
    EXPECT_LT(a.votes, pt.votes);
  }
}

TEST(OrientationChannels, TheTrackerFindsThePose) {
  const Tables t;
  app::Rng noise(4);
  const app::GrayImage frame = draw_shape(160, 150, 81, 73, 16.5, &noise);
  for (const TableView* table : {&t.plain, &t.channels}) {
    testing::TrackerTestScratch s(*table);
    StepResult r;
    ASSERT_EQ(track_step(*table, frame.view(), Pose{79, 74, 16, 0}, s.view(), r), Status::kOk);
    EXPECT_NEAR(r.pose.x, 81, 1.0) << table->orientation_channels();
    EXPECT_NEAR(r.pose.y, 73, 1.0) << table->orientation_channels();
    EXPECT_NEAR(r.pose.theta_deg, 16.5, 1.1) << table->orientation_channels();  // one unrefined vote: within two 0.5-deg cells
  }
}

// A feature votes its channel's slot and the nearer neighbour's (table_view.hpp).
TEST(OrientationChannels, FeatureSlots) {
  constexpr std::uint32_t bits = 5;  // 16 channels
  // Column 3, row 2 of a 10-wide ROI: pixel 23; channel 7, lower half: slots 23*16+7 and +6.
  const FeatureSlots lower = feature_slots((3u << bits) | (7u << 1) | 0u, 2, 10, bits);
  EXPECT_EQ(lower.first, 23u * 16 + 7);
  EXPECT_EQ(lower.second, 23u * 16 + 6);
  const FeatureSlots upper = feature_slots((3u << bits) | (15u << 1) | 1u, 2, 10, bits);
  EXPECT_EQ(upper.first, 23u * 16 + 15);
  EXPECT_EQ(upper.second, 23u * 16 + 0);  // wraps: orientation is modulo a half turn
  const FeatureSlots none = feature_slots(3, 2, 10, 0);
  EXPECT_EQ(none.first, 23u);
  EXPECT_FALSE(none.two);
}

}  // namespace
}  // namespace gabarit
