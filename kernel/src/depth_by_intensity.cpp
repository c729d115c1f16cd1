#include "gabarit/depth_by_intensity.hpp"

#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

bool finite(float v) noexcept { return v == v && v - v == 0.0f; }  // not NaN, not infinite

// Sums of one stack image against the frame: exact integers (n <= 2^32 samples
// of 8-bit values), so the correlation is the same on every target.
struct Sums {
  std::uint64_t n = 0, a = 0, b = 0, aa = 0, bb = 0, ab = 0;
};

// The correlation of one stack image with the frame at a pose, as the sign of
// the correlation times its square (ordered like the correlation, no square
// root). false when too few samples fall in the frame or either side is flat.
bool correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack,
                 double& score) noexcept {
  const SinCos r = sin_cos_deg(pose.theta_deg);
  Sums s;
  for (std::uint32_t v = 0; v < m.height; v += stack.step) {
    const float dv = static_cast<float>(v) - stack.ref_y;
    for (std::uint32_t u = 0; u < m.width; u += stack.step) {
      const float du = static_cast<float>(u) - stack.ref_x;
      const std::int32_t fx = round_to_int(pose.x + r.cos * du - r.sin * dv);
      const std::int32_t fy = round_to_int(pose.y + r.sin * du + r.cos * dv);
      if (fx < 0 || fy < 0 || static_cast<std::uint32_t>(fx) >= frame.width || static_cast<std::uint32_t>(fy) >= frame.height) {
        continue;
      }
      const std::uint64_t a = m.at(u, v);
      const std::uint64_t b = frame.at(static_cast<std::uint32_t>(fx), static_cast<std::uint32_t>(fy));
      ++s.n;
      s.a += a;
      s.b += b;
      s.aa += a * a;
      s.bb += b * b;
      s.ab += a * b;
    }
  }
  if (s.n < 16) return false;
  // n^2 times the covariance and the variances. The sums are exact; the
  // products are taken in double, the same IEEE operations on every target.
  const double n = static_cast<double>(s.n);
  const double cov = n * static_cast<double>(s.ab) - static_cast<double>(s.a) * static_cast<double>(s.b);
  const double va = n * static_cast<double>(s.aa) - static_cast<double>(s.a) * static_cast<double>(s.a);
  const double vb = n * static_cast<double>(s.bb) - static_cast<double>(s.b) * static_cast<double>(s.b);
  if (va <= 0.0 || vb <= 0.0) return false;
  score = (cov >= 0.0 ? cov * cov : -cov * cov) / (va * vb);
  return true;
}

bool valid_inputs(const ImageView& frame, const Pose& pose, const FocusStack& stack) noexcept {
  if (!frame.valid() || stack.images.empty() || stack.images.size() > 65535u || stack.step == 0 || !finite(pose.x) ||
      !finite(pose.y) || !finite(pose.theta_deg) || !finite(stack.ref_x) || !finite(stack.ref_y)) {
    return false;
  }
  if (!(pose.x > -1e6f && pose.x < 1e6f && pose.y > -1e6f && pose.y < 1e6f && pose.theta_deg > -1e5f && pose.theta_deg < 1e5f))
    return false;
  for (const ImageView& m : stack.images) {
    if (!m.valid() || m.width != stack.images[0].width || m.height != stack.images[0].height) return false;
  }
  return true;
}

}  // namespace

Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack,
                          std::uint16_t& depth) noexcept {
  if (!valid_inputs(frame, pose, stack)) return Status::kInvalidArgument;
  bool have_best = false;
  double best_score = 0.0;
  std::uint16_t best_depth = depth;
  for (std::size_t d = 0; d < stack.images.size(); ++d) {
    double score = 0.0;
    if (!correlation(frame, stack.images[d], pose, stack, score)) continue;
    if (!have_best || score > best_score) {
      have_best = true;
      best_score = score;
      best_depth = static_cast<std::uint16_t>(d);
    }
  }
  if (have_best) depth = best_depth;
  return Status::kOk;
}

Status angle_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, float& theta_deg) noexcept {
  if (!valid_inputs(frame, pose, stack) || pose.depth >= stack.images.size()) return Status::kInvalidArgument;
  const ImageView& m = stack.images[pose.depth];
  double scores[2 * kAngleSteps + 1];
  int best = -1;
  for (int k = -kAngleSteps; k <= kAngleSteps; ++k) {
    Pose p = pose;
    p.theta_deg = pose.theta_deg + static_cast<float>(k) * kAngleIncrementDeg;
    double score = 0.0;
    if (!correlation(frame, m, p, stack, score)) return Status::kOk;  // leaving the frame: keep the angle
    scores[k + kAngleSteps] = score;
    if (best < 0 || score > scores[best]) best = k + kAngleSteps;
  }
  float offset = static_cast<float>(best - kAngleSteps) * kAngleIncrementDeg;
  if (best > 0 && best < 2 * kAngleSteps) {
    // A parabola through the peak and its neighbours places it between samples.
    const double a = scores[best - 1], b = scores[best], c = scores[best + 1];
    const double curvature = a - 2.0 * b + c;
    if (curvature < 0.0) offset += kAngleIncrementDeg * static_cast<float>(0.5 * (a - c) / curvature);
  }
  theta_deg = pose.theta_deg + offset;
  return Status::kOk;
}

}  // namespace gabarit
