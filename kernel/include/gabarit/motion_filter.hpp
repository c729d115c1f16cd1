// The motion filter (after the thesis's Algorithm 4): how much to trust each
// frame's vote, a constant-velocity prediction that places the next ROI, and
// a check of the best candidate cells against that prediction.
//
// Confidence, from the chosen cell's normalised score s1 (votes / stencil
// size) relative to the session's reference score r, and its margin over the
// next candidate s2. Scores depend on the scene (clutter, the detector, the
// decimation), so the thresholds are ratios of r, the running average of the
// scores of high-confidence frames, started by the first frame (whose pose is
// given): it works without tuning on binary and on cluttered grey images.
//   high          s1 >= high_ratio * r and s1 - s2 >= high_margin * r
//   none          s1 < low_ratio * r, or no candidate within the gate
//   intermediate  otherwise
// Per frame, with m the measured motion (this frame's pose - the previous one):
//   high          v <- (1 - K1) v + K1 m     uncertainty <- 0
//   intermediate  v <- (1 - K2) v + K2 m     uncertainty += U1
//   none          v <- K3 v (pose = the prediction)   uncertainty += U2
// The ROI of the next frame is centred on pose + v. The n best cells are taken
// in rank order and the first whose position lies within gate_px +
// uncertainty of the prediction is chosen; a better-ranked cell outside the
// gate is a distractor and is skipped. The depth has inertia too: the chosen
// cell changes it only if it beats the current depth's best cell by
// depth_switch_margin. When the uncertainty passes
// lost_uncertainty_px the target is lost and recovery takes over
// (tracking_session.hpp).
#pragma once

#include <cstdint>

namespace gabarit {

enum class Confidence : std::uint8_t { kHigh = 0, kIntermediate = 1, kNone = 2 };
const char* confidence_name(Confidence confidence) noexcept;

struct MotionFilterParams {
  float high_ratio = 0.7f;
  float high_margin = 0.0f;     // neighbouring cells score alike: off by default
  float low_ratio = 0.5f;
  float reference_gain = 0.1f;  // r <- (1 - g) r + g s1 on high-confidence frames
  float k1 = 0.5f;
  float k2 = 0.2f;
  float k3 = 0.8f;
  float u1 = 0.5f;
  float u2 = 2.0f;
  float gate_px = 8.0f;
  float lost_uncertainty_px = 12.0f;
  std::uint8_t candidates = 4;  // 1..kMaxCandidates
  // A cell of another focus-stack depth replaces the current depth only if its
  // score beats the current depth's best cell by this fraction.
  float depth_switch_margin = 0.1f;
};
inline constexpr std::uint8_t kMaxCandidates = 16;

struct MotionFilterState {
  float vx = 0.0f;      // pixels per frame
  float vy = 0.0f;
  float vtheta = 0.0f;  // degrees per frame
  float uncertainty_px = 0.0f;
};

Confidence classify(float score, float next_score, float reference, const MotionFilterParams& params) noexcept;

// True if the parameters are usable (finite, ordered, gains in [0, 1]).
bool valid(const MotionFilterParams& params) noexcept;

}  // namespace gabarit
