#include "gabarit/depth_by_intensity.hpp"

#include <cstddef>

#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

// x * 65536 rounded, halves away from zero (|x| < 2^46).
std::int64_t round_fixed(double x) noexcept {
  const double scaled = x * 65536.0;
  return static_cast<std::int64_t>(scaled >= 0.0 ? scaled + 0.5 : scaled - 0.5);
}

bool finite(float v) noexcept { return v == v && v - v == 0.0f; }  // not NaN, not infinite

// Stack images correlated in one pass over the frame: the frame samples (and
// their sums) are shared, each image adds its own. Up to kGroup at a time,
// so the sums live on the stack.
constexpr std::size_t kGroup = 8;

// Sums of stack images against the frame: exact integers (8-bit model values,
// frame values in 1/256 units up to 255 * 256; exact for fewer than 2^32
// samples), so the correlation is the same on every target.
struct FrameSums {
  std::uint64_t n = 0, b = 0, bb = 0;
};
struct ImageSums {
  std::uint64_t a = 0, aa = 0, ab = 0;
};

// The correlation of each of `images` (at most kGroup, all of the stack's
// size) with the frame at a pose, as the sign of the correlation times its
// square (ordered like the correlation, no square root); ok[i] is false when
// too few samples fall in the frame or either side is flat.
void correlations(const ImageView& frame, std::span<const ImageView> images, const Pose& pose, const FocusStack& stack,
                  double* scores, bool* ok) noexcept {
  const SinCos r = sin_cos_deg(pose.theta_deg);
  const ImageView& shape = images[0];
  FrameSums f;
  ImageSums s[kGroup];
  // Sample positions in 1/65536-pixel fixed point: each row's first from the
  // pose (in double, the same IEEE operations on every target), the rest by
  // adding the rotated step, so the inner loop is integer only.
  const double c = static_cast<double>(r.cos), sn = static_cast<double>(r.sin);
  const double step = static_cast<double>(stack.step);
  const std::int64_t step_x = round_fixed(c * step), step_y = round_fixed(sn * step);
  const double du0 = -static_cast<double>(stack.ref_x);
  const std::uint32_t columns = (shape.width + stack.step - 1) / stack.step;  // samples per row
  const std::int64_t x_limit = (std::int64_t{frame.width} - 1) * 65536, y_limit = (std::int64_t{frame.height} - 1) * 65536;
  for (std::uint32_t v = 0; v < shape.height; v += stack.step) {
    const double dv = static_cast<double>(v) - static_cast<double>(stack.ref_y);
    const std::int64_t px0 = round_fixed(static_cast<double>(pose.x) + c * du0 - sn * dv);
    const std::int64_t py0 = round_fixed(static_cast<double>(pose.y) + sn * du0 + c * dv);
    // The samples whose 2 x 2 neighbourhood lies in the frame: positions are
    // linear in k, so they form one run [k_begin, k_end), found from both ends.
    const auto inside = [&](std::uint32_t k) {
      const std::int64_t x = px0 + std::int64_t{k} * step_x, y = py0 + std::int64_t{k} * step_y;
      return x >= 0 && y >= 0 && x < x_limit && y < y_limit;
    };
    std::uint32_t k_begin = 0, k_end = columns;
    while (k_begin < k_end && !inside(k_begin)) ++k_begin;
    while (k_end > k_begin && !inside(k_end - 1)) --k_end;
    std::int64_t px = px0 + std::int64_t{k_begin} * step_x, py = py0 + std::int64_t{k_begin} * step_y;
    const std::uint8_t* model_rows[kGroup];
    for (std::size_t i = 0; i < images.size(); ++i) model_rows[i] = images[i].pixels + std::size_t{v} * images[i].stride;
    for (std::uint32_t k = k_begin; k < k_end; ++k, px += step_x, py += step_y) {
      // The frame sampled bilinearly (weights in 1/256): the correlation then
      // varies smoothly with the angle, which the angle's parabola relies on.
      const auto fx = static_cast<std::uint32_t>(px >> 8), fy = static_cast<std::uint32_t>(py >> 8);
      const std::uint32_t wx = fx & 255u, wy = fy & 255u;
      const std::uint8_t* row0 = frame.pixels + static_cast<std::size_t>(py >> 16) * frame.stride + static_cast<std::size_t>(px >> 16);
      const std::uint8_t* row1 = row0 + frame.stride;
      const std::uint32_t top = row0[0] * (256u - wx) + row0[1] * wx;
      const std::uint32_t bottom = row1[0] * (256u - wx) + row1[1] * wx;
      const std::uint64_t b = (top * (256u - wy) + bottom * wy + 128u) >> 8;  // 0 .. 255 * 256
      f.b += b;
      f.bb += b * b;
      const std::uint32_t u = k * stack.step;
      for (std::size_t i = 0; i < images.size(); ++i) {
        const std::uint64_t a = model_rows[i][u];
        s[i].a += a;
        s[i].aa += a * a;
        s[i].ab += a * b;
      }
    }
    f.n += k_end - k_begin;
  }
  // n^2 times the covariance and the variances. The sums are exact; the
  // products are taken in double, the same IEEE operations on every target.
  const double n = static_cast<double>(f.n);
  const double vb = n * static_cast<double>(f.bb) - static_cast<double>(f.b) * static_cast<double>(f.b);
  for (std::size_t i = 0; i < images.size(); ++i) {
    const double cov = n * static_cast<double>(s[i].ab) - static_cast<double>(s[i].a) * static_cast<double>(f.b);
    const double va = n * static_cast<double>(s[i].aa) - static_cast<double>(s[i].a) * static_cast<double>(s[i].a);
    ok[i] = f.n >= 16 && va > 0.0 && vb > 0.0;
    scores[i] = ok[i] ? (cov >= 0.0 ? cov * cov : -cov * cov) / (va * vb) : 0.0;
  }
}

bool correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack,
                 double& score) noexcept {
  bool ok = false;
  correlations(frame, std::span<const ImageView>(&m, 1), pose, stack, &score, &ok);
  return ok;
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
  for (std::size_t first = 0; first < stack.images.size(); first += kGroup) {
    const std::span<const ImageView> group =
        stack.images.subspan(first, stack.images.size() - first < kGroup ? stack.images.size() - first : kGroup);
    double scores[kGroup];
    bool ok[kGroup];
    correlations(frame, group, pose, stack, scores, ok);
    for (std::size_t i = 0; i < group.size(); ++i) {
      if (ok[i] && (!have_best || scores[i] > best_score)) {
        have_best = true;
        best_score = scores[i];
        best_depth = static_cast<std::uint16_t>(first + i);
      }
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
