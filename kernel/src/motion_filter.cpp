#include "gabarit/motion_filter.hpp"

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

}  // namespace gabarit
