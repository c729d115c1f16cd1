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

}  // namespace

Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack,
                          std::uint16_t& depth) noexcept {
  if (!frame.valid() || stack.images.empty() || stack.images.size() > 65535u || stack.step == 0 || !finite(pose.x) ||
      !finite(pose.y) || !finite(pose.theta_deg) || !finite(stack.ref_x) || !finite(stack.ref_y)) {
    return Status::kInvalidArgument;
  }
  const ImageView& first = stack.images[0];
  for (const ImageView& m : stack.images) {
    if (!m.valid() || m.width != first.width || m.height != first.height) return Status::kInvalidArgument;
  }
  if (!(pose.x > -1e6f && pose.x < 1e6f && pose.y > -1e6f && pose.y < 1e6f)) return Status::kInvalidArgument;

  const SinCos r = sin_cos_deg(pose.theta_deg);
  bool have_best = false;
  double best_score = 0.0;
  std::uint16_t best_depth = depth;
  for (std::size_t d = 0; d < stack.images.size(); ++d) {
    const ImageView& m = stack.images[d];
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
    if (s.n < 16) return Status::kOk;  // too little of the object in the frame to tell
    // n^2 times the covariance and the variances. The sums are exact; the
    // products are taken in double, the same IEEE operations on every target.
    const double n = static_cast<double>(s.n);
    const double cov = n * static_cast<double>(s.ab) - static_cast<double>(s.a) * static_cast<double>(s.b);
    const double va = n * static_cast<double>(s.aa) - static_cast<double>(s.a) * static_cast<double>(s.a);
    const double vb = n * static_cast<double>(s.bb) - static_cast<double>(s.b) * static_cast<double>(s.b);
    if (va <= 0.0 || vb <= 0.0) continue;  // a flat image or frame patch correlates with nothing
    // The sign of the correlation times its square: ordered like the
    // correlation itself, without a square root.
    const double score = (cov >= 0.0 ? cov * cov : -cov * cov) / (va * vb);
    if (!have_best || score > best_score) {
      have_best = true;
      best_score = score;
      best_depth = static_cast<std::uint16_t>(d);
    }
  }
  if (have_best) depth = best_depth;
  return Status::kOk;
}

}  // namespace gabarit
