#include "gabarit/motion_filter.hpp"

#include "gabarit/tracker.hpp"

namespace gabarit {

const char* confidence_name(Confidence confidence) noexcept {
  switch (confidence) {
    case Confidence::kHigh: return "high";
    case Confidence::kIntermediate: return "intermediate";
    case Confidence::kNone: return "none";
  }
  return "unknown";
}

Confidence classify(float score, float next_score, float reference, const MotionFilterParams& p) noexcept {
  if (!(score > 0.0f) || score < p.low_ratio * reference) return Confidence::kNone;
  if (score >= p.high_ratio * reference && score - next_score >= p.high_margin * reference) return Confidence::kHigh;
  return Confidence::kIntermediate;
}

bool valid(const MotionFilterParams& p) noexcept {
  const auto unit = [](float v) { return v >= 0.0f && v <= 1.0f; };
  const auto nonneg = [](float v) { return v >= 0.0f && v < 1.0e6f; };
  return unit(p.high_ratio) && unit(p.low_ratio) && p.low_ratio <= p.high_ratio && unit(p.high_margin) &&
         unit(p.reference_gain) && unit(p.k1) &&
         unit(p.k2) && unit(p.k3) && nonneg(p.u1) && nonneg(p.u2) && nonneg(p.gate_px) && nonneg(p.lost_uncertainty_px) &&
         p.candidates >= 1 && p.candidates <= kMaxCandidates && nonneg(p.depth_switch_margin);
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
  const float gate = params_.gate_px + state_.uncertainty_px;
  const auto in_gate = [&](std::uint32_t cell) {
    const Pose p = pose_of_cell(table, cell, predicted, cx, cy);
    const float dx = p.x - predicted.x, dy = p.y - predicted.y;
    return dx * dx + dy * dy <= gate * gate;
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

void MotionFilter::update(Confidence confidence, const Pose& previous, const Pose& measured) noexcept {
  const float k = confidence == Confidence::kHigh ? params_.k1 : params_.k2;
  state_.vx = (1.0f - k) * state_.vx + k * (measured.x - previous.x);
  state_.vy = (1.0f - k) * state_.vy + k * (measured.y - previous.y);
  state_.vtheta = (1.0f - k) * state_.vtheta + k * (measured.theta_deg - previous.theta_deg);
  state_.uncertainty_px = confidence == Confidence::kHigh ? 0.0f : state_.uncertainty_px + params_.u1;
}

void MotionFilter::coast() noexcept {
  state_.vx *= params_.k3;
  state_.vy *= params_.k3;
  state_.vtheta *= params_.k3;
  state_.uncertainty_px += params_.u2;
}

}  // namespace gabarit
