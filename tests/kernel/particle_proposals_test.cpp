// The particle filter's vote-guided proposals (issue 31): the stencil vote's
// best cells as places to draw particles around, the share of the cloud
// drawn there, the weight correction prior / proposal, a re-acquisition they
// speed up, and the same bits on every target.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <vector>

#include "gabarit/crc32.hpp"
#include "gabarit/deterministic_math.hpp"
#include "gabarit/finder_search.hpp"
#include "gabarit/frame_ledger.hpp"
#include "gabarit/particle_filter.hpp"
#include "gabarit/particle_measures.hpp"
#include "gabarit/particle_recovery.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

using app::GrayImage;

// A binary frame of a point model, and its table (x, y +-5 in 1-px cells, theta +-2 in 1-deg cells).
struct Scene {
  std::vector<host::Point> points;
  std::vector<std::byte> bytes;
  TableView table;
  explicit Scene(const char* xy = "-5:5:11") {
    app::Rng rng(11);
    points = testing::random_points(rng, 60, 20, 2.0);
    bytes = testing::build(testing::point_model(points), xy, xy, "-2:2:5");
    table = testing::open_table(bytes);
  }
  GrayImage frame(float x, float y, float theta) const { return testing::draw_points(points, x, y, theta, 160); }
};

TEST(StencilVoteProposer, ProposesTheVotesBestCellsAsTheirPoses) {
  const Scene s;
  const GrayImage g = s.frame(83, 78, 1);
  testing::TrackerTestScratch scratch(s.table), reference(s.table);
  StencilVoteProposer proposer(s.table, detector_of(s.table), scratch.view(), 3);
  const Pose predicted{80.3f, 79.6f, 0.2f, 0};
  ParticleProposals out;
  ASSERT_EQ(proposer.propose(g.view(), predicted, out), Status::kOk);
  StepResult step;
  ASSERT_EQ(track_step(s.table, g.view(), predicted, reference.view(), step), Status::kOk);
  CellScore top[3];
  ASSERT_EQ(select_top_cells(s.table, reference.counters, top), Status::kOk);
  ASSERT_EQ(out.count, 3u);
  for (std::uint32_t k = 0; k < 3; ++k) {
    const Pose p = pose_of_cell(s.table, top[k].cell, predicted, step.roi_centre_x, step.roi_centre_y);
    EXPECT_EQ(out.poses[k].x, p.x);
    EXPECT_EQ(out.poses[k].y, p.y);
    EXPECT_EQ(out.poses[k].theta_deg, p.theta_deg);
  }
  EXPECT_LT(std::hypot(out.poses[0].x - 83, out.poses[0].y - 78), 1.0f) << "the best cell is the true motion";
  EXPECT_EQ(out.sigma_px, 1.0f);   // the cell spacing
  EXPECT_EQ(out.sigma_deg, 1.0f);
  EXPECT_EQ(out.region_volume, 11.0f * 11.0f * 5.0f);
  // A frame with no features proposes nothing.
  const GrayImage blank(160, 160);
  ASSERT_EQ(proposer.propose(blank.view(), predicted, out), Status::kOk);
  EXPECT_EQ(out.count, 0u);
}

// A likelihood of 1 everywhere, so that a weight is its correction alone.
class Flat {
 public:
  Status prepare(const ImageView&, const Pose&) noexcept { return Status::kOk; }
  void weigh(std::span<Particle> ps) noexcept {
    for (Particle& p : ps) p.weight = 1.0f;
  }
  float score(const Pose&) noexcept { return 1.0f; }
  std::uint32_t reach_px() const noexcept { return 0; }
};

// Proposes one fixed place.
struct OnePlace {
  Pose place;
  Status propose(const ImageView&, const Pose&, ParticleProposals& out) noexcept {
    out.poses[0] = place;
    out.count = 1;
    out.sigma_px = 1.0f;
    out.sigma_deg = 0.5f;
    out.region_volume = 1000.0f;
    return Status::kOk;
  }
};

TEST(ParticleFilter, VoteProposalsDrawTheirShareAndCorrectTheirWeights) {
  Flat flat;
  OnePlace place{{40, 30, 2, 0}};
  ParticleFilter<Flat, Flat, NoFrameLoader, DefaultPropagation, KinematicCompensation, ModeAnalysis, OnePlace> filter(flat);
  filter.propose_with(&place);
  ParticleFilterOptions o;
  o.proposal_fraction = 0.25f;
  std::vector<Particle> cloud(400), next(400);
  std::vector<std::uint32_t> order(800);
  const GrayImage frame(100, 100);
  const auto near_place = [&] {
    return std::count_if(filter.particles().begin(), filter.particles().end(),
                         [](const Particle& p) { return std::hypot(p.pose.x - 40, p.pose.y - 30) < 6; });
  };
  ASSERT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kOk);
  ParticleEstimate e;
  ASSERT_EQ(filter.step(frame.view(), e), Status::kOk);
  EXPECT_EQ(e.proposed, 100u);
  EXPECT_EQ(near_place(), 100);
  // No confidence yet: the prior is the proposer's uniform (1 / 1000), so a
  // proposed particle weighs (1 / 1000) / g, g the Gaussian it was drawn from.
  for (const Particle& p : filter.particles()) {
    if (std::hypot(p.pose.x - 40, p.pose.y - 30) >= 6) continue;
    const float dx = p.pose.x - 40, dy = p.pose.y - 30, dt = (p.pose.theta_deg - 2) / 0.5f;
    const double g = std::exp(-0.5 * (dx * dx + dy * dy + dt * dt)) / (std::pow(2 * 3.14159265358979, 1.5) * 0.5);
    ASSERT_NEAR(p.weight / (1e-3 / g), 1.0, 2e-3) << p.pose.x << "," << p.pose.y;
  }
  // Without the correction every particle keeps its likelihood.
  o.proposal_correction = false;
  ASSERT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kOk);
  ASSERT_EQ(filter.step(frame.view(), e), Status::kOk);
  EXPECT_EQ(near_place(), 100);
  for (const Particle& p : filter.particles()) EXPECT_EQ(p.weight, 1.0f);
  // No share, or plain CONDENSATION: none drawn.
  o.proposal_fraction = 0.0f;
  ASSERT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kOk);
  ASSERT_EQ(filter.step(frame.view(), e), Status::kOk);
  EXPECT_EQ(e.proposed, 0u);
  EXPECT_EQ(near_place(), 0);
  EXPECT_EQ(plain_condensation().proposal_fraction, 0.0f);
  // A malformed proposal is not drawn from.
  o.proposal_fraction = 0.25f;
  place.place.x = std::nanf("");
  ASSERT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kOk);
  ASSERT_EQ(filter.step(frame.view(), e), Status::kOk);
  EXPECT_EQ(e.proposed, 0u);
  place.place = {40, 30, 2, 1};  // a depth the filter does not have
  ASSERT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kOk);
  ASSERT_EQ(filter.step(frame.view(), e), Status::kOk);
  EXPECT_EQ(e.proposed, 0u);
  o.proposal_fraction = 1.5f;
  EXPECT_EQ(filter.start(o, {10, 10, 0, 0}, 1, 5, {cloud, next, order}), Status::kInvalidArgument);
}

// The point scene (its table reaching 12 px, in 2-px cells) tracked with the
// edge measure while the target vanishes for two frames and comes back 10 px
// and 1.5 deg from where it went; the frames the filter takes to be
// within 1 px and tracking again, and the digest of every estimate.
struct Reacquisition {
  int frames = -1;
  std::uint32_t crc = 0;
};
Reacquisition reacquire(const Scene& s, std::uint32_t proposals, std::uint64_t seed) {
  testing::TrackerTestScratch scratch(s.table);
  std::vector<std::uint64_t> bits(edge_map_words(160, 160));
  std::vector<RoiPoint> features(160);
  EdgeMapLoader loader({table_format::DetectorKind::kBinary, 0}, bits, features, 160, 160);
  EdgeCorrelationMeasure coarse(s.table, loader, 2, 0), fine(s.table, loader, 1, 0);
  StencilVoteProposer proposer(s.table, detector_of(s.table), scratch.view(), proposals == 0 ? 1 : proposals);
  ParticleFilter<EdgeCorrelationMeasure, EdgeCorrelationMeasure, EdgeMapLoader, DefaultPropagation, KinematicCompensation,
                 ModeAnalysis, StencilVoteProposer>
      filter(coarse, &fine, &loader);
  if (proposals > 0) filter.propose_with(&proposer);
  std::vector<Particle> cloud(300), next(300);
  std::vector<std::uint32_t> order(600);
  Reacquisition r;
  EXPECT_EQ(filter.start({}, {80, 80, 0, 0}, 1, seed, {cloud, next, order}), Status::kOk);
  const GrayImage blank(160, 160);
  for (int f = 0; f < 30; ++f) {
    const bool away = f >= 10 && f < 12, back = f >= 12;
    const float x = back ? 90.0f : 80.0f, theta = back ? 1.5f : 0.0f;
    const GrayImage g = away ? blank : s.frame(x, 80, theta);
    ParticleEstimate e;
    EXPECT_EQ(filter.step(g.view(), e), Status::kOk);
    const std::uint32_t words[3] = {std::bit_cast<std::uint32_t>(e.pose.x), std::bit_cast<std::uint32_t>(e.pose.y),
                                    std::bit_cast<std::uint32_t>(e.pose.theta_deg)};
    r.crc = crc32c_update(r.crc, std::as_bytes(std::span(words)));
    if (back && r.frames < 0 && e.state == TrackState::kTracking && std::hypot(e.pose.x - x, e.pose.y - 80) < 1.0f)
      r.frames = f - 12 + 1;
  }
  return r;
}

TEST(ParticleFilter, VoteProposalsReacquireWithinAFewFrames) {
  const Scene s("-12:12:13");
  int with = 0, without = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Reacquisition a = reacquire(s, 4, seed), b = reacquire(s, 0, seed);
    ASSERT_GE(a.frames, 1) << "seed " << seed;
    EXPECT_LE(a.frames, 2) << "seed " << seed;
    with += a.frames;
    without += b.frames < 0 ? 17 : b.frames;
  }
  EXPECT_LT(with, without) << "proposals re-acquire sooner than diffusion";
  // The same bits on every target (the kernel tests run on x86-64, aarch64
  // and armhf; the Cortex-M builds replay particle.gbp, ctest
  // firmware.particle): the digest measured on x86-64.
  const Reacquisition a = reacquire(s, 4, 1), b = reacquire(s, 4, 1);
  EXPECT_EQ(a.crc, b.crc);
  EXPECT_EQ(a.crc, 1608966699u) << "proposals digest";
}

// A clock that advances one tick per reading.
std::uint64_t g_ticks = 0;
std::uint64_t counting_clock() noexcept { return ++g_ticks; }

TEST(ParticleFilter, TheLedgerChargesTheVoteTheLoaderTheMeasureAndTheRest) {
  const Scene s;
  testing::TrackerTestScratch scratch(s.table);
  std::vector<std::uint64_t> bits(edge_map_words(160, 160));
  std::vector<RoiPoint> features(160);
  EdgeMapLoader loader({table_format::DetectorKind::kBinary, 0}, bits, features, 160, 160);
  EdgeCorrelationMeasure coarse(s.table, loader, 2, 0), fine(s.table, loader, 1, 0);
  StencilVoteProposer proposer(s.table, detector_of(s.table), scratch.view());
  EdgeParticleFilter filter(coarse, &fine, &loader);
  filter.propose_with(&proposer);
  std::vector<Particle> cloud(200), next(200);
  std::vector<std::uint32_t> order(400);
  ASSERT_EQ(filter.start({}, {80, 80, 0, 0}, 1, 3, {cloud, next, order}), Status::kOk);
  ParticleEstimate e;
  ASSERT_EQ(filter.step(s.frame(81, 80, 0.5f).view(), e), Status::kOk);
  const FrameLedger& l = filter.ledger();
  EXPECT_EQ(l.total_ticks(), 0u) << "no clock: nothing timed";
  EXPECT_EQ(l.votes, proposer.votes());
  EXPECT_GT(l.votes, 0u);
  EXPECT_EQ(l.work[static_cast<int>(FramePhase::kVote)], track_features_work(s.table) + proposer.votes());
  EXPECT_EQ(l.correlations, 200u + std::min(e.modes, ParticleFilterOptions{}.disambiguate_modes)) << "every particle, the scored modes";
  filter.use_clock(&counting_clock);
  const std::uint64_t before = g_ticks;
  ASSERT_EQ(filter.step(s.frame(82, 80, 1.0f).view(), e), Status::kOk);
  for (const FramePhase p : {FramePhase::kVote, FramePhase::kFeatures, FramePhase::kVerify, FramePhase::kOther})
    EXPECT_GT(l.ticks[static_cast<int>(p)], 0u) << frame_phase_name(p);
  EXPECT_EQ(l.ticks[static_cast<int>(FramePhase::kRecovery)], 0u);
  EXPECT_EQ(l.total_ticks(), g_ticks - before - 1) << "every tick between the first reading and the last, once";
  // Without disambiguation no mode is scored by the finer measure before the
  // choice: the chosen one is scored then, and counted.
  ParticleFilterOptions plain_modes;
  plain_modes.disambiguate = false;
  EdgeParticleFilter undisambiguated(coarse, &fine, &loader);
  ASSERT_EQ(undisambiguated.start(plain_modes, {80, 80, 0, 0}, 1, 3, {cloud, next, order}), Status::kOk);
  ASSERT_EQ(undisambiguated.step(s.frame(81, 80, 0.5f).view(), e), Status::kOk);
  ASSERT_GT(e.modes, 0u);
  EXPECT_EQ(undisambiguated.ledger().correlations, 200u + 1u) << "every particle, the chosen mode";
}

}  // namespace
}  // namespace gabarit
