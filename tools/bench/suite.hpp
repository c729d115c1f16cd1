// gabarit bench --suite: the default tracker, the thesis's plain loop, the
// OpenCV NCC bank and the particle filter over the scene suite (scene_synth.hpp, docs/scene-suite.md),
// each scene with its own table; per scene and per half (tuning, held out)
// the median and the worst scene of every metric, and mean and p99 us/frame.
#pragma once

#include <cstdint>
#include <string>

#include "gabarit/recovery_search.hpp"

namespace gabarit::bench {

struct SuiteOptions {
  std::string out = "bench-out";
  bool quick = false;             // every 5th scene (9 of 42), 60 frames each
  std::uint32_t scenes = 0;       // 0: every scene from `first` to the last of kSuiteScenes (quick: every 5th)
  std::uint32_t frames = 0;       // 0: 160 (quick: 60)
  bool peer = true;               // run the NCC bank too
  bool particles = true;          // run the particle filter too (gabarit track --tracker particle)
  std::uint32_t particle_seeds = 1;  // the particle filter with seeds 1..N: issue 31's targets over scene-seeds too
  bool detection = true;            // detection rows: gabarit detect, OpenCV's pyramid, re-acquisition by detection
  std::uint32_t orientation_channels = 0;  // the scenes' tables: 0 position only, else 2..16 channels (format 1.3)
  // The re-acquisition-by-detection row: lost frames searched by the grid first.
  std::uint32_t detect_after = RecoveryOptions{}.detect_after;
  std::uint32_t first = 0;          // the first scene's index (--first: a family alone, say 32 for the families)
};

// Writes DIR/suite.md and DIR/suite-scenes.csv; returns the exit code.
int run_suite(const SuiteOptions& options);

}  // namespace gabarit::bench
