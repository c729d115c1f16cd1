// The tracking session composed: the plain session must be track_step, frame
// for frame, and bad options are refused. Its parts are tested on their own
// (motion_filter_test.cpp, refinement_test.cpp, recovery_search_test.cpp).
#include "gabarit/tracking_session.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <bit>
#include <cstring>
#include <vector>

#include "gabarit/app/image_io.hpp"
#include "gabarit/finder_search.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;
using testing::build;
using testing::point_model;

using Scratch = testing::TrackerTestScratch;

GrayImage draw(const std::vector<host::Point>& pts, float x, float y) { return testing::draw_points(pts, x, y, 0.0f, 160); }

TEST(TrackingSession, PlainSessionIsTrackStepFrameForFrame) {
  app::Rng rng(8);
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
  app::Rng rng(1);
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
                                +[](SessionOptions& b) { b.recovery.coarse_proposals = kMaxCoarseProposals + 1; },
                                +[](SessionOptions& b) { b.theta_observability = -0.1f; },
                                +[](SessionOptions& b) { b.filter.accel_var = 0.0f; },
                                +[](SessionOptions& b) { b.depth_votes_decisive = -1.0f; },
                                +[](SessionOptions& b) { b.depth_switch_correlation = 3.0f; }}) {
    SessionOptions b;
    bad_option(b);
    EXPECT_EQ(session.start(b, Pose{10, 10, 0, 0}), Status::kInvalidArgument);
  }
}

// Never worse than the plain loop where a constant-velocity prediction is
// wrong: a target that turns back, a target that jumps at random each frame
// (the thesis's synthetic motion), and one half hidden, whose vote stays low
// but still wins at the right place. The default session must be exact on
// every frame the plain loop is exact on.
struct Motion {
  const char* name;
  float (*x)(int frame, app::Rng& rng, float previous);
  bool half_hidden;
  double noise = 0.05;  // salt and pepper
};

TEST(TrackingSession, TheDefaultSessionIsExactWhereThePlainLoopIs) {
  const Motion motions[] = {
      {"reverses after 12 frames at 3 px/frame",
       +[](int f, app::Rng&, float) { return 60.0f + 3.0f * static_cast<float>(f < 12 ? f : 24 - f); }, false},
      {"jumps by up to 4 px at random",
       +[](int, app::Rng& rng, float previous) { return std::clamp(previous + static_cast<float>(rng.uniform_int(-4, 4)), 40.0f, 120.0f); },
       false},
      {"half hidden from frame 8, moving 2 px/frame",
       +[](int f, app::Rng&, float) { return 50.0f + 2.0f * static_cast<float>(f); }, true},
      // The reversal again in heavy noise, where clutter scores much of what the target does.
      {"reverses after 12 frames, 30% of the pixels flipped",
       +[](int f, app::Rng&, float) { return 60.0f + 3.0f * static_cast<float>(f < 12 ? f : 24 - f); }, false, 0.30},
  };
  for (const Motion& m : motions) {
    SCOPED_TRACE(m.name);
    app::Rng rng(21);
    const auto pts = testing::random_points(rng, 120, 14);
    const auto bytes = build(point_model(pts), "-5:5:11", "-5:5:11");
    const TableView t = testing::open_table(bytes);
    Scratch s(t);
    std::vector<RoiPoint> search_features(search_feature_capacity(t));
    std::vector<GrayImage> frames;
    std::vector<float> truth;
    float x = 60.0f;
    app::Rng motion_rng(3);
    for (int f = 0; f < 24; ++f) {
      x = m.x(f, motion_rng, x);
      GrayImage frame = testing::draw_points(pts, x, 80.0f, 0.0f, 180);
      if (m.half_hidden && f >= 8)  // the left half of the image blanked
        for (std::uint32_t row = 0; row < frame.height; ++row)
          for (std::uint32_t col = 0; col < static_cast<std::uint32_t>(x); ++col) frame.pixels[row * frame.width + col] = 0;
      for (auto& v : frame.pixels)
        if (rng.bernoulli(m.noise)) v = static_cast<std::uint8_t>(255 - v);
      frames.push_back(frame);
      truth.push_back(x);
    }
    const auto run = [&](const SessionOptions& o) {
      TrackingSession session(t, nullptr, detector_of(t));
      EXPECT_EQ(session.start(o, Pose{60, 80, 0, 0}), Status::kOk);
      std::vector<bool> exact;
      for (std::size_t f = 0; f < frames.size(); ++f) {
        SessionResult r;
        EXPECT_EQ(session.step(frames[f].view(), {s.view(), {}, search_features}, r), Status::kOk);
        exact.push_back(std::fabs(r.pose.x - truth[f]) < 0.5f && std::fabs(r.pose.y - 80.0f) < 0.5f);
      }
      return exact;
    };
    const std::vector<bool> plain = run(kPlainSession), session = run(SessionOptions{});
    int plain_exact = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      plain_exact += plain[f];
      EXPECT_TRUE(session[f] || !plain[f]) << "frame " << f << ": the plain loop is exact, the session is not";
    }
    EXPECT_GE(plain_exact, 20);  // the scene is one the plain loop tracks
  }
}


// The frame-cost ledger: its work adds up to the frame's work, each phase is
// charged where it ran, and timing changes nothing the session computes.
std::uint64_t counting_ticks = 0;
std::uint64_t counting_clock() noexcept { return ++counting_ticks; }

TEST(TrackingSession, TheLedgerAddsUpAndTheClockChangesNothing) {
  app::Rng rng(34);
  const auto pts = testing::random_points(rng, 120, 14);
  const auto bytes = build(point_model(pts), "-5:5:11", "-5:5:11");
  const TableView t = testing::open_table(bytes);
  Scratch s(t);
  std::vector<RoiPoint> search_features(search_feature_capacity(t));
  std::vector<GrayImage> frames;
  for (int f = 0; f < 40; ++f) {
    GrayImage frame = testing::draw_points(pts, 60.0f + static_cast<float>(f), 80.0f, 0.0f, 180);
    if (f >= 12 && f < 24) std::fill(frame.pixels.begin(), frame.pixels.end(), std::uint8_t{0});  // hidden: lost, searched for
    for (auto& v : frame.pixels)
      if (rng.bernoulli(0.05)) v = static_cast<std::uint8_t>(255 - v);
    frames.push_back(frame);
  }
  const auto run = [&](TickSource clock) {
    TrackingSession session(t, nullptr, detector_of(t));
    session.use_clock(clock);
    EXPECT_EQ(session.start(SessionOptions{}, Pose{60, 80, 0, 0}), Status::kOk);
    std::vector<SessionResult> out;
    for (const GrayImage& frame : frames) {
      SessionResult r;
      EXPECT_EQ(session.step(frame.view(), {s.view(), {}, search_features}, r), Status::kOk);
      out.push_back(r);
    }
    return out;
  };
  const std::vector<SessionResult> untimed = run(nullptr);
  counting_ticks = 0;
  const std::vector<SessionResult> timed = run(&counting_clock);
  const auto phase = [](const FrameLedger& l, FramePhase p, bool ticks) {
    return ticks ? l.ticks[static_cast<std::uint32_t>(p)] : l.work[static_cast<std::uint32_t>(p)];
  };
  int lost = 0, searched_work = 0;
  std::uint64_t all_ticks = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    SCOPED_TRACE(f);
    const SessionResult &a = untimed[f], &b = timed[f];
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.pose.x), std::bit_cast<std::uint32_t>(b.pose.x));
    EXPECT_EQ(std::bit_cast<std::uint32_t>(a.pose.y), std::bit_cast<std::uint32_t>(b.pose.y));
    EXPECT_EQ(a.state, b.state);
    EXPECT_EQ(a.work, b.work);
    EXPECT_EQ(a.ledger.total_ticks(), 0u);  // no clock, nothing timed
    EXPECT_EQ(b.work, b.ledger.total_work());
    for (std::uint32_t p = 0; p < kFramePhaseCount; ++p) EXPECT_EQ(a.ledger.work[p], b.ledger.work[p]);
    // Binary frames: no verification, no intensities, no survey.
    for (FramePhase p : {FramePhase::kVerify, FramePhase::kDepth, FramePhase::kSurvey}) EXPECT_EQ(phase(b.ledger, p, false), 0u);
    EXPECT_EQ(b.ledger.correlations, 0u);
    const bool searched = phase(b.ledger, FramePhase::kRecovery, true) > 0;
    if (searched) {
      ++lost;  // the grid search: its extraction and votes counted as recovery
      searched_work += phase(b.ledger, FramePhase::kRecovery, false) > 0;
      EXPECT_EQ(phase(b.ledger, FramePhase::kFeatures, true), 0u);
    } else {
      // One or two votes (at the prediction, at the last pose): each charged
      // its ROI's extraction and its votes, and read the clock between.
      EXPECT_GE(phase(b.ledger, FramePhase::kFeatures, true), 1u);
      EXPECT_GE(phase(b.ledger, FramePhase::kVote, true), 1u);
      // No angle axis: the detector's window is the ROI, inside the frame here.
      const std::uint64_t votes_cast = phase(b.ledger, FramePhase::kFeatures, false) / track_features_work(t);
      EXPECT_EQ(phase(b.ledger, FramePhase::kFeatures, false), votes_cast * track_features_work(t));
      EXPECT_GE(votes_cast, 1u);
      EXPECT_LE(votes_cast, 2u);
      EXPECT_EQ(b.ledger.pixels_scanned, votes_cast * t.roi_pixels());
      EXPECT_EQ(phase(b.ledger, FramePhase::kVote, false), b.ledger.votes);
      EXPECT_GE(b.ledger.votes, b.step.votes);  // the reported vote is one of them
      EXPECT_GE(b.ledger.features, b.step.features);
    }
    all_ticks += b.ledger.total_ticks();
  }
  EXPECT_GE(lost, 5);  // the hidden frames searched
  EXPECT_GE(searched_work, 5);
  EXPECT_LE(all_ticks, counting_ticks);  // phases never charged more than the clock advanced
}

}  // namespace
}  // namespace gabarit
