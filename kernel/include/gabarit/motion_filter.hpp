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
// (recovery_search.hpp). A TrackingSession (tracking_session.hpp) runs this
// filter around each frame's vote: predict, choose (the gate), grade, then
// update or coast.
#pragma once

#include <cstdint>
#include <span>

#include "gabarit/pose.hpp"
#include "gabarit/status.hpp"
#include "gabarit/table_view.hpp"
#include "gabarit/voter.hpp"

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

// The measurement the gate lets through: the first of the n best cells
// within the gate, possibly replaced by the current depth's best cell
// (depth inertia). found is false when no voted candidate lies in the gate.
struct GatedChoice {
  bool found = false;
  CellScore cell;
  float score = 0.0f;       // normalised score of `cell`
  float next_score = 0.0f;  // of the candidate ranked after the chosen one
  bool outranked = false;   // a better-ranked candidate lay outside the gate (a distractor)
};

// The filter's state over a session. Precondition for every call:
// valid(params) (TrackingSession::start checks it).
class MotionFilter {
 public:
  void reset(const MotionFilterParams& params) noexcept {
    params_ = params;
    state_ = {};
    reference_ = 0.0f;
  }
  // Velocity and uncertainty back to zero (a reacquired target); the
  // reference score is kept.
  void restart() noexcept { state_ = {}; }

  // Where the next ROI goes: pose + v.
  Pose predict(const Pose& pose) const noexcept;
  // The gate: the n best cells of this frame's vote (counters, ROI centred on
  // (cx, cy), measured from `predicted`) in rank order; the first within
  // gate_px + uncertainty of the prediction. A cell of another depth than
  // current_depth must beat the current depth's best cell by
  // depth_switch_margin. Errors: select_top_cells'.
  Status choose(const TableView& table, std::span<const VoteCounter> counters, const Pose& predicted, std::int32_t cx,
                std::int32_t cy, std::uint16_t current_depth, GatedChoice& out) const noexcept;
  // classify against the reference score; a high-confidence score then moves
  // the reference (the first graded score sets it).
  Confidence grade(float score, float next_score) noexcept;
  // classify without touching the reference.
  Confidence classify(float score, float next_score) const noexcept {
    return gabarit::classify(score, next_score, reference_, params_);
  }
  // A measurement of confidence high or intermediate, taken from `previous`.
  void update(Confidence confidence, const Pose& previous, const Pose& measured) noexcept;
  // No measurement: v <- K3 v, uncertainty += U2.
  void coast() noexcept;
  // The uncertainty has passed lost_uncertainty_px.
  bool lost() const noexcept { return state_.uncertainty_px > params_.lost_uncertainty_px; }

  const MotionFilterState& state() const noexcept { return state_; }
  float reference() const noexcept { return reference_; }

 private:
  MotionFilterParams params_;
  MotionFilterState state_;
  float reference_ = 0.0f;  // running score of high-confidence frames
};

}  // namespace gabarit
