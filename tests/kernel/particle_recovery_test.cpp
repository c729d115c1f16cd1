// Re-acquisition by particle filter: a target that reappears far beyond the
// grid search's reach is found within a few frames, and the session's
// acceptance rule (high confidence) still holds.
#include "gabarit/particle_recovery.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "gabarit/particle_measures.hpp"
#include "gabarit/tracking_session.hpp"
#include "test_tables.hpp"

namespace gabarit {
namespace {

constexpr std::uint32_t kSide = 320;

struct Rig : testing::PointScene {
  Rig() : PointScene(21, 60, 18, "-4:4:9", "-2:2:5", kSide, 0.01) {}
};

// Frames until the session is within 2 px of the target after it reappears at
// (rx, ry), or -1 within `budget` frames.
int reacquire(const Rig& rig, bool particles, float rx, float ry, int budget = 12) {
  testing::TrackerTestScratch scratch(rig.table);
  TrackingSession session(rig.table, nullptr, detector_of(rig.table));
  EXPECT_EQ(session.start(SessionOptions{}, {60, 60, 0, 0}), Status::kOk);
  std::vector<std::uint64_t> bits(edge_map_words(kSide, kSide));
  std::vector<RoiPoint> strip(kSide * 8);
  const Detector binary{table_format::DetectorKind::kBinary, 0};
  EdgeMapLoader loader(binary, bits, strip, kSide, kSide);
  EdgeCorrelationMeasure coarse(rig.table, loader, 1, 1), fine(rig.table, loader, 1, 0);
  EdgeParticleFilter filter(coarse, &fine, &loader);
  std::vector<Particle> cloud(1500), next(1500);
  std::vector<std::uint32_t> order(3000);
  EXPECT_EQ(filter.start({}, {60, 60, 0, 0}, 1, 3, {cloud, next, order}), Status::kOk);
  ParticleRecovery stage(rig.table, binary, filter);
  if (particles) session.use_particle_recovery(&stage);
  app::Rng noise(4);
  SessionResult r;
  for (int f = 0; f < 4; ++f) EXPECT_EQ(session.step(rig.frame(60, 60, 0, true, noise).view(), {scratch.view(), {}}, r), Status::kOk);
  for (int f = 0; f < 20; ++f) EXPECT_EQ(session.step(rig.frame(0, 0, 0, false, noise).view(), {scratch.view(), {}}, r), Status::kOk);
  EXPECT_TRUE(session.lost());
  for (int f = 0; f < budget; ++f) {
    EXPECT_EQ(session.step(rig.frame(rx, ry, 1, true, noise).view(), {scratch.view(), {}}, r), Status::kOk);
    if (!session.lost() && std::hypot(r.pose.x - rx, r.pose.y - ry) <= 2) return f;
  }
  return -1;
}

TEST(ParticleRecovery, FindsATargetThatReappearsBeyondTheGridsReach) {
  const Rig rig;
  const int grid = reacquire(rig, false, 250, 240), particle = reacquire(rig, true, 250, 240);
  EXPECT_EQ(grid, -1) << "the grid reaches about 36 px: the test would not tell the stages apart";
  EXPECT_GE(particle, 0);
  EXPECT_LE(particle, 10);
}

TEST(ParticleRecovery, FindsItNearbyToo) {
  const Rig rig;
  const int particle = reacquire(rig, true, 70, 66);
  EXPECT_GE(particle, 0);
  EXPECT_LE(particle, 10);
}

TEST(ParticleRecovery, BadOptionsAreRefused) {
  const Rig rig;
  std::vector<std::uint64_t> bits(edge_map_words(kSide, kSide));
  std::vector<RoiPoint> strip(kSide);
  EdgeMapLoader loader({table_format::DetectorKind::kBinary, 0}, bits, strip, kSide, kSide);
  EdgeCorrelationMeasure m(rig.table, loader, 1, 0);
  EdgeParticleFilter filter(m, nullptr, &loader);
  testing::TrackerTestScratch scratch(rig.table);
  app::Rng noise(1);
  const app::GrayImage g = rig.frame(60, 60, 0, true, noise);
  SearchResult out;
  ParticleRecovery unstarted(rig.table, detector_of(rig.table), filter);
  EXPECT_EQ(unstarted.run(g.view(), LastSighting{}, scratch.view(), out), Status::kInvalidArgument);
  ParticleRecoveryOptions bad;
  bad.rescatter = 0;
  EXPECT_FALSE(valid(bad));
  bad = {};
  bad.candidates = 0;
  EXPECT_FALSE(valid(bad));
  ParticleRecovery invalid(rig.table, detector_of(rig.table), filter, bad);
  EXPECT_EQ(invalid.run(g.view(), LastSighting{}, scratch.view(), out), Status::kInvalidArgument);
}

}  // namespace
}  // namespace gabarit
