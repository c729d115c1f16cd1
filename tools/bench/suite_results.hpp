// What `gabarit bench --suite` measures: one method on one scene (Measure),
// a scene's methods (SceneResult), the methods' names, and the helpers the
// report's tables share (suite.cpp, suite_section64.cpp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "gabarit/host/scenes/scene_synth.hpp"
#include "suite_ledger.hpp"

namespace gabarit::bench {

// One method on one scene.
struct Measure {
  double within_1px = 0, within_2px = 0, within_5px = 0, within_1deg = 0;  // % of visible frames
  double failures_per_100 = 0;  // VOT-style losses of the track (app::Accuracy::failures) per 100 visible frames
  double depth = -1;            // % depth exact; -1: one depth, or depths not distinguishable
  int reacquired = 0;           // worst frames to reacquire after an occlusion (-1: never)
  int reacquired_in_reach = 0;  // the same over occlusions the recovery search can reach (-2: none)
  double mean_us = 0, p50_us = 0, p99_us = 0, max_us = 0;
  // The precision of the frames tracked: the mean position error (px) over
  // the visible frames within 1 px (-1: none).
  double subpixel_error = -1;
  // The thesis's error buckets (Fig. 6.60; app::Accuracy): visible frames
  // with a pose, and those < 6, < 12, > 12, > 20, > 40 px off; the mean error.
  std::size_t frames = 0, below_6px = 0, below_12px = 0, above_12px = 0, above_20px = 0, above_40px = 0;
  double mean_error_px = 0;
  std::size_t timed_frames = 0;  // every frame, visible or not
  // Every method: returns to view (occlusions ending), and those re-acquired
  // (app::evaluate: within 2 px) within 5 and within 10 frames.
  int returns = 0, back_within_5 = 0, back_within_10 = 0;
  // The frames that searched (a session lost or re-acquiring; the particle
  // filter's detection stage) with their mean time.
  std::size_t search_frames = 0;
  double search_us = 0;
  LedgerMeans ledger;  // sessions and the particle filter: the frame-cost ledger's means per frame
};

// A detector over every frame of a scene, without a starting pose.
struct DetectionMeasure {
  bool ran = false;
  int visible = 0, top1 = 0, top5 = 0;  // true pose within 2 px and 1 deg (and the depth, on tilted stacks)
  int invisible = 0, false_frames = 0;  // frames without the target, and those with a detection
  double mean_us = 0;
};

struct SceneResult {
  DetectionMeasure detection, opencv_detection;
  std::uint32_t index = 0;
  std::string name;
  host::SceneFamily family = host::SceneFamily::kMixed;
  bool held_out = false;
  std::vector<Measure> methods;  // plain, session, then NCC (with the peer), then the particle filter (with particles)
  std::vector<const char*> names;
  // With --particle-seeds N > 1: the particle filter (kParticle's run) with
  // seeds 1..N, seed 1 being kParticle's row; issue 31's targets are then
  // also counted over these scene-seeds.
  std::vector<Measure> particle_seeds;
};

inline constexpr const char* kPlain = "plain loop (thesis)";
inline constexpr const char* kSession = "gabarit default session";
inline constexpr const char* kNcc = "OpenCV NCC bank";
// No commas in a method name: the CSV does not quote its fields.
inline constexpr const char* kParticle = "particle filter (1000 particles; its default measure: intensity)";
inline constexpr const char* kParticleUnguided = "particle filter without vote proposals";
inline constexpr const char* kSessionParticles = "default session with particle re-acquisition";
inline constexpr const char* kSessionDetection = "default session with re-acquisition by detection";

inline std::string fmt(double v, int digits = 1) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The index of the method called `name` in every scene's results, or -1.
inline int index_of(const std::vector<SceneResult>& scenes, const char* name) {
  if (scenes.empty()) return -1;
  for (std::size_t m = 0; m < scenes[0].names.size(); ++m)
    if (scenes[0].names[m] == std::string(name)) return static_cast<int>(m);
  return -1;
}

}  // namespace gabarit::bench
