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
// Motion: a constant-velocity Kalman filter per axis (x, y, theta; state =
// position and velocity, unit time step, white-noise acceleration of
// variance accel_var, theta's theta_accel_var). Each frame's measurement is
// the chosen cell's pose with a variance set by its confidence:
//   high          position variance meas_var_high, angle theta_meas_var_high
//   intermediate  meas_var_intermediate, theta_meas_var_intermediate
//   none          no measurement: the filter only predicts (coasts)
// An angle the votes do not constrain (TrackingSession's observability test)
// is not measured. The uncertainty is the position's variance var x + var y;
// the target is lost when it passes lost_uncertainty_px^2 (about 7 frames
// without a measurement after a confident one). The filter is Eigen fixed-size algebra on
// floats (no heap; Eigen is a private dependency of the kernel).
// The ROI of the next frame is centred on pose + v. The n best cells are taken
// in rank order and the first whose squared distance from the prediction is
// within gate_px^2 + 4 (predicted var x + var y) (two standard deviations
// beyond the gate) is chosen; a better-ranked cell outside the
// gate is a distractor and is skipped. The depth has inertia too: the chosen
// cell changes it only if it beats the current depth's best cell by
// depth_switch_margin. When the target is lost, recovery takes over
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

struct MotionFilterParams {
  float high_ratio = 0.7f;
  float high_margin = 0.0f;     // neighbouring cells score alike: off by default
  float low_ratio = 0.5f;
  float reference_gain = 0.1f;  // r <- (1 - g) r + g s1 on high-confidence frames
  // The Kalman filter's noise (pixels^2, degrees^2; per frame).
  float accel_var = 0.5f;
  float meas_var_high = 0.25f;
  float meas_var_intermediate = 2.0f;
  float theta_accel_var = 0.05f;
  float theta_meas_var_high = 0.1f;
  float theta_meas_var_intermediate = 1.0f;
  float initial_speed_var = 4.0f;    // velocity variance at the start and after a reacquisition
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
  float position_variance = 0.0f;  // var x + var y (pixels^2) after this frame
};

// One axis of the constant-velocity Kalman filter: [position, velocity] and
// its covariance (row-major 2x2), plain floats so the header needs no Eigen.
struct KalmanAxis {
  float position = 0.0f, velocity = 0.0f;
  float covariance[4] = {0.0f, 0.0f, 0.0f, 0.0f};
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
  // Starts at `pose`, at rest, with the velocity uncertain.
  void reset(const MotionFilterParams& params, const Pose& pose) noexcept;
  // At `pose` again, velocity zero (a reacquired target); the reference
  // score is kept.
  void restart(const Pose& pose) noexcept;

  // Where the next ROI goes: pose + v.
  Pose predict(const Pose& pose) const noexcept;
  // The gate: the n best cells of this frame's vote (counters, ROI centred on
  // (cx, cy), measured from `predicted`) in rank order; the first within
  // gate (above) of the prediction. A cell of another depth than
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
  // One frame with a measurement of confidence high or intermediate (the
  // angle only if theta_measured): predict, then correct.
  void update(Confidence confidence, const Pose& measured, bool theta_measured = true) noexcept;
  // One frame without a measurement: predict only.
  void coast() noexcept;
  // The position's standard deviation has passed lost_uncertainty_px.
  bool lost() const noexcept {
    return state_.position_variance > params_.lost_uncertainty_px * params_.lost_uncertainty_px;
  }

  const MotionFilterState& state() const noexcept { return state_; }
  float reference() const noexcept { return reference_; }

 private:
  void publish() noexcept;  // state_ from the axes

  MotionFilterParams params_;
  KalmanAxis axes_[3];      // x, y, theta
  MotionFilterState state_;
  float reference_ = 0.0f;  // running score of high-confidence frames
};

}  // namespace gabarit
