// The tracking session composed: the plain session must be track_step, frame
// for frame, and bad options are refused. Its parts are tested on their own
// (motion_filter_test.cpp, refinement_test.cpp, recovery_search_test.cpp).
#include "gabarit/tracking_session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <bit>
#include <cstring>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
using testing::build;
using testing::point_model;

using Scratch = testing::TrackerTestScratch;

GrayImage draw(const std::vector<host::Point>& pts, float x, float y) { return testing::draw_points(pts, x, y, 0.0f, 160); }

TEST(TrackingSession, PlainSessionIsTrackStepFrameForFrame) {
  host::Rng rng(8);
  const auto pts = testing::random_points(rng, 60, 15);
  const auto bytes = build(point_model(pts), "-5:5:11", "-5:5:11");
  const TableView t = testing::open_table(bytes);
  Scratch a(t), b(t);
  TrackingSession session(t, nullptr, detector_of(t));
  ASSERT_EQ(session.start(kPlainSession, Pose{80, 80, 0, 0}), Status::kOk);
  Pose pose{80, 80, 0, 0};
  float x = 80, y = 80;
  for (int f = 0; f < 40; ++f) {
    x += static_cast<float>(rng.uniform_int(-4, 4));
    y += static_cast<float>(rng.uniform_int(-4, 4));
    GrayImage frame = draw(pts, x, y);
    for (auto& v : frame.pixels)
      if (rng.bernoulli(0.1)) v = static_cast<std::uint8_t>(255 - v);
    StepResult plain;
    ASSERT_EQ(track_step(t, frame.view(), pose, a.view(), plain), Status::kOk);
    if (plain.state != TrackState::kLost) pose = plain.pose;
    SessionResult r;
    ASSERT_EQ(session.step(frame.view(), {b.view(), {}}, r), Status::kOk);
    // Bit for bit (Pose has padding, so field by field).
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.x), std::bit_cast<std::uint32_t>(pose.x)) << "frame " << f;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.y), std::bit_cast<std::uint32_t>(pose.y)) << "frame " << f;
    EXPECT_EQ(std::bit_cast<std::uint32_t>(r.pose.theta_deg), std::bit_cast<std::uint32_t>(pose.theta_deg)) << "frame " << f;
    EXPECT_EQ(r.pose.depth, pose.depth) << "frame " << f;
    EXPECT_EQ(r.step.best.cell, plain.best.cell);
    EXPECT_EQ(r.state, plain.state);
  }
}

TEST(TrackingSession, BadOptionsAreRefused) {
  host::Rng rng(1);
  const auto bytes = build(point_model(testing::random_points(rng, 20, 8)), "-2:2:5", "-2:2:5");
  const TableView t = testing::open_table(bytes);
  TrackingSession session(t, nullptr, detector_of(t));
  SessionOptions o;
  o.filter.candidates = 0;
  EXPECT_EQ(session.start(o, Pose{10, 10, 0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(session.start(SessionOptions{}, Pose{std::nanf(""), 10, 0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(session.start(SessionOptions{}, Pose{10, 10, 0, 3}), Status::kInvalidArgument);  // no depth 3
  for (const auto bad_option : {+[](SessionOptions& b) { b.recovery.interval = 0; }, +[](SessionOptions& b) { b.recovery.screen_stride = 0; },
                                +[](SessionOptions& b) { b.recovery.coarse_proposals = 0; },
                                +[](SessionOptions& b) { b.recovery.coarse_proposals = kMaxCoarseProposals + 1; }}) {
    SessionOptions b;
    bad_option(b);
    EXPECT_EQ(session.start(b, Pose{10, 10, 0, 0}), Status::kInvalidArgument);
  }
}

}  // namespace
}  // namespace gabarit
