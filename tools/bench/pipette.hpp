// gabarit bench --pipette: the thesis's section 6.4 re-run on the glass
// pipette scenes (scene_synth.hpp, pipette_scene): the stencil tracker with
// the custom edge detector (gradient rows) and with Canny, each without and
// with the motion model (the plain loop and the default session), against
// the particle filter with each of its measures. Per method and half
// (tuning, held out): Fig. 6.60's buckets of the tip's error (< 6, < 12,
// > 12, > 20, > 40 px), the reference point's within 2 px, and Fig. 6.61's
// timings (mean, max, min per frame).
#pragma once

#include <cstdint>
#include <string>

namespace gabarit::bench {

struct PipetteOptions {
  std::string out = "bench-out";
  bool quick = false;           // 4 scenes (2 per half) of 80 frames
  std::uint32_t frames = 0;     // 0: 200 (quick: 80)
  std::uint32_t particles = 1000;
};

// Writes DIR/pipette.md and DIR/pipette.csv; returns the exit code.
int run_pipette(const PipetteOptions& options);

}  // namespace gabarit::bench
