// The suite report's section 6.4 table (suite_section64.hpp): buckets pooled
// over scenes by frames, search frames split from tracking frames, and issue
// 31's targets counted scene by scene.
#include <gtest/gtest.h>

#include <sstream>

#include "suite_section64.hpp"

namespace gabarit::bench {
namespace {

Measure measured(std::size_t frames, std::size_t below_6, double mean_error, double mean_us) {
  Measure m;
  m.frames = frames, m.below_6px = below_6, m.below_12px = below_6, m.above_12px = frames - below_6;
  m.above_20px = frames - below_6, m.above_40px = 0, m.mean_error_px = mean_error;
  m.timed_frames = frames, m.mean_us = mean_us;
  return m;
}

SceneResult scene(const char* name, Measure session, Measure ncc, Measure particle) {
  SceneResult s;
  s.name = name;
  s.methods = {session, ncc, particle};
  s.names = {kSession, kNcc, kParticle};
  return s;
}

TEST(SuiteSection64, PoolsBucketsByFramesSplitsSearchesAndCountsTheTargets) {
  Measure session_a = measured(100, 100, 0.5, 1000.0);
  session_a.search_frames = 10, session_a.search_us = 5500.0;  // 90 tracking frames at 500 us
  const std::vector<SceneResult> scenes = {
      scene("easy", session_a, measured(100, 95, 1.0, 9000.0), measured(100, 96, 2.0, 1500.0)),
      // NCC reaches 90% here and the filter does not reach 95%; it is also over 2x the session's time.
      scene("hard", measured(300, 150, 8.0, 400.0), measured(300, 291, 1.0, 9000.0), measured(300, 270, 4.0, 920.0)),
      // NCC below 90%: the 95% target does not apply.
      scene("lost", measured(100, 0, 50.0, 400.0), measured(100, 10, 30.0, 9000.0), measured(100, 50, 10.0, 700.0)),
  };
  std::ostringstream md;
  section64_table(scenes, "held-out half", md);
  const std::string text = md.str();
  // The session: (100 + 150 + 0) of 500 frames under 6 px; its mean error
  // (50 + 2400 + 5000) / 500; tracking frames (100000 - 55000 + 120000 + 40000) / 490.
  EXPECT_NE(text.find("| " + std::string(kSession) + " | 50.0% | 50.0% | 50.0% | 50.0% | 0.0% | 14.90 | 1 of 3 | 418.4 | 10 | 5500.0 |"),
            std::string::npos)
      << text;
  // The filter: 416 of 500 under 6 px; no search frames.
  EXPECT_NE(text.find("| " + std::string(kParticle) + " | 83.2% | 83.2% | 16.8% | 16.8% | 0.0% | 4.80 | 1 of 3 | 992.0 | 0 | - |"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("within 6 px on >= 95% of frames on 1 of the 2 scenes where the NCC bank reaches 90% (short: hard 90.0% (NCC 97.0%))"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("mean error under 3 px on 1 of 3"), std::string::npos) << text;
  EXPECT_NE(text.find("at most 2x the default session's on 2 of 3 (over: hard 2.3x)."), std::string::npos) << text;
}

// With several seeds the targets are counted over scene-seeds, seed by seed
// beside the totals; a run of one seed prints no such line.
TEST(SuiteSection64, CountsIssue31sTargetsOverSceneSeeds) {
  const auto with_returns = [](Measure m, int returns, int back_within_5) {
    m.returns = returns, m.back_within_5 = back_within_5;
    return m;
  };
  std::vector<SceneResult> scenes = {
      scene("easy", measured(100, 100, 0.5, 1000.0), measured(100, 95, 1.0, 9000.0), measured(100, 96, 2.0, 1500.0)),
      scene("hard", measured(300, 150, 8.0, 400.0), measured(300, 291, 1.0, 9000.0), measured(300, 270, 4.0, 920.0)),
  };
  std::ostringstream one_seed;
  section64_table(scenes, "held-out half", one_seed);
  EXPECT_EQ(one_seed.str().find("over seeds"), std::string::npos) << one_seed.str();

  // easy: seed 1 meets every target, seed 2 is 94% within 6 px, 3.5 px off
  // on the mean, back late after its one return and 2.1x the session's time.
  scenes[0].particle_seeds = {with_returns(measured(100, 96, 2.0, 1500.0), 1, 1), with_returns(measured(100, 94, 3.5, 2100.0), 1, 0)};
  // hard: seed 1 short of 95% and slow (as its row), seed 2 meets them; no return to view.
  scenes[1].particle_seeds = {measured(300, 270, 4.0, 920.0), measured(300, 290, 2.5, 700.0)};
  std::ostringstream md;
  section64_table(scenes, "held-out half", md);
  const std::string text = md.str();
  EXPECT_NE(text.find("The same over seeds 1..2, counting scene-seeds: within 6 px on >= 95% of frames on 2 of 4 (seed by seed: 1 / 1); "
                      "mean error under 3 px on 2 of 4 (seed by seed: 1 / 1); every return to view re-acquired within 5 frames on 1 of 2 "
                      "(seed by seed: 1 / 0); mean time at most 2x the default session's on 2 of 4 (seed by seed: 1 / 1)."),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace gabarit::bench
