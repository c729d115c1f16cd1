#include "gabarit/motion_filter.hpp"

// Eigen: fixed-size float matrices only, never the heap (EIGEN_NO_MALLOC,
// set for the kernel in CMake, asserts that), and scalar code on every target
// (EIGEN_DONT_VECTORIZE) so the sums run in one order and the session's
// poses are the same bytes on x86-64, aarch64, armhf and Cortex-M.
#include <Eigen/Core>

#include "gabarit/tracker.hpp"

namespace gabarit {

Confidence classify(float score, float next_score, float reference, const MotionFilterParams& p) noexcept {
  if (!(score > 0.0f) || score < p.low_ratio * reference) return Confidence::kNone;
  if (score >= p.high_ratio * reference && score - next_score >= p.high_margin * reference) return Confidence::kHigh;
  return Confidence::kIntermediate;
}

bool valid(const MotionFilterParams& p) noexcept {
  const auto unit = [](float v) { return v >= 0.0f && v <= 1.0f; };
  const auto nonneg = [](float v) { return v >= 0.0f && v < 1.0e6f; };
  const auto variance = [](float v) { return v > 1.0e-6f && v < 1.0e6f; };
  return unit(p.high_ratio) && unit(p.low_ratio) && p.low_ratio <= p.high_ratio && unit(p.high_margin) &&
         unit(p.reference_gain) && variance(p.accel_var) && variance(p.meas_var_high) && variance(p.meas_var_intermediate) &&
         variance(p.theta_accel_var) && variance(p.theta_meas_var_high) && variance(p.theta_meas_var_intermediate) &&
         variance(p.initial_speed_var) && nonneg(p.gate_px) && nonneg(p.lost_uncertainty_px) && p.candidates >= 1 &&
         p.candidates <= kMaxCandidates && nonneg(p.depth_switch_margin);
}

namespace {

using Matrix2 = Eigen::Matrix<float, 2, 2, Eigen::RowMajor>;
using Vector2 = Eigen::Matrix<float, 2, 1>;

void start_axis(KalmanAxis& a, float position, float position_var, float speed_var) noexcept {
  a.position = position;
  a.velocity = 0.0f;
  Eigen::Map<Matrix2>(a.covariance) << position_var, 0.0f, 0.0f, speed_var;
}

// x <- F x, P <- F P F' + Q: constant velocity over one frame, white-noise
// acceleration of variance q (Q = q [1/4 1/2; 1/2 1]).
void predict_axis(KalmanAxis& a, float q) noexcept {
  Matrix2 f;
  f << 1.0f, 1.0f, 0.0f, 1.0f;
  Matrix2 noise;
  noise << 0.25f * q, 0.5f * q, 0.5f * q, q;
  Eigen::Map<Matrix2> p(a.covariance);
  const Matrix2 predicted = f * p * f.transpose() + noise;
  p = predicted;
  a.position += a.velocity;
}

// The position measured as z with variance r: K = P H' / (H P H' + r), H = [1 0].
void correct_axis(KalmanAxis& a, float z, float r) noexcept {
  Eigen::Map<Matrix2> p(a.covariance);
  const Vector2 gain = p.col(0) / (p(0, 0) + r);
  const float innovation = z - a.position;
  a.position += gain(0) * innovation;
  a.velocity += gain(1) * innovation;
  // P <- (I - K H) P, kept symmetric.
  Matrix2 corrected = p - gain * p.row(0);
  corrected(0, 1) = corrected(1, 0) = 0.5f * (corrected(0, 1) + corrected(1, 0));
  p = corrected;
}

float predicted_variance(const KalmanAxis& a, float q) noexcept {
  // H (F P F' + Q) H' for H = [1 0].
  return a.covariance[0] + 2.0f * a.covariance[1] + a.covariance[3] + 0.25f * q;
}

}  // namespace

void MotionFilter::reset(const MotionFilterParams& params, const Pose& pose) noexcept {
  params_ = params;
  reference_ = 0.0f;
  restart(pose);
}

void MotionFilter::restart(const Pose& pose) noexcept {
  start_axis(axes_[0], pose.x, params_.meas_var_high, params_.initial_speed_var);
  start_axis(axes_[1], pose.y, params_.meas_var_high, params_.initial_speed_var);
  start_axis(axes_[2], pose.theta_deg, params_.theta_meas_var_high, params_.initial_speed_var);
  publish();
}

void MotionFilter::publish() noexcept {
  state_.vx = axes_[0].velocity;
  state_.vy = axes_[1].velocity;
  state_.vtheta = axes_[2].velocity;
  state_.position_variance = axes_[0].covariance[0] + axes_[1].covariance[0];
}

Pose MotionFilter::predict(const Pose& pose) const noexcept {
  Pose p = pose;
  p.x += state_.vx;
  p.y += state_.vy;
  p.theta_deg += state_.vtheta;
  return p;
}

Status MotionFilter::choose(const TableView& table, std::span<const VoteCounter> counters, const Pose& predicted,
                            std::int32_t cx, std::int32_t cy, std::uint16_t current_depth, GatedChoice& out) const noexcept {
  out = GatedChoice{};
  CellScore candidates[kMaxCandidates];
  const std::size_t n = table.cell_count() < params_.candidates ? table.cell_count() : params_.candidates;
  GABARIT_TRY(select_top_cells(table, counters, std::span<CellScore>(candidates, n)));
  const float gate2 = params_.gate_px * params_.gate_px +
                     4.0f * (predicted_variance(axes_[0], params_.accel_var) + predicted_variance(axes_[1], params_.accel_var));
  const auto in_gate = [&](std::uint32_t cell) {
    const Pose p = pose_of_cell(table, cell, predicted, cx, cy);
    const float dx = p.x - predicted.x, dy = p.y - predicted.y;
    return dx * dx + dy * dy <= gate2;
  };
  std::size_t chosen = n;
  for (std::size_t i = 0; i < n && candidates[i].votes > 0; ++i) {
    if (in_gate(candidates[i].cell)) {
      chosen = i;
      break;
    }
  }
  if (chosen == n) return Status::kOk;
  // Depth changes slowly: a cell of another depth must beat the best cell of
  // the current depth by depth_switch_margin (relative) to change it.
  if (table.cell(candidates[chosen].cell).depth != current_depth && current_depth < table.depth_count()) {
    const CellScore same = best_cell_in(table, counters, table.depth_cells(current_depth));
    if (same.votes > 0 && in_gate(same.cell) &&
        normalised_score(candidates[chosen]) < (1.0f + params_.depth_switch_margin) * normalised_score(same)) {
      candidates[chosen] = same;
    }
  }
  out.found = true;
  out.cell = candidates[chosen];
  out.score = normalised_score(candidates[chosen]);
  out.next_score = chosen + 1 < n ? normalised_score(candidates[chosen + 1]) : 0.0f;
  out.outranked = chosen > 0;
  return Status::kOk;
}

Confidence MotionFilter::grade(float score, float next_score) noexcept {
  if (reference_ <= 0.0f) reference_ = score;
  const Confidence c = classify(score, next_score);
  if (c == Confidence::kHigh) reference_ = (1.0f - params_.reference_gain) * reference_ + params_.reference_gain * score;
  return c;
}

void MotionFilter::update(Confidence confidence, const Pose& measured, bool theta_measured) noexcept {
  const bool high = confidence == Confidence::kHigh;
  predict_axis(axes_[0], params_.accel_var);
  predict_axis(axes_[1], params_.accel_var);
  predict_axis(axes_[2], params_.theta_accel_var);
  const float r = high ? params_.meas_var_high : params_.meas_var_intermediate;
  correct_axis(axes_[0], measured.x, r);
  correct_axis(axes_[1], measured.y, r);
  if (theta_measured) {
    correct_axis(axes_[2], measured.theta_deg, high ? params_.theta_meas_var_high : params_.theta_meas_var_intermediate);
  }
  publish();
}

void MotionFilter::coast() noexcept {
  predict_axis(axes_[0], params_.accel_var);
  predict_axis(axes_[1], params_.accel_var);
  predict_axis(axes_[2], params_.theta_accel_var);
  publish();
}

}  // namespace gabarit
