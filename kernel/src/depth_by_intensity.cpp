#include "gabarit/depth_by_intensity.hpp"

#include <cstddef>

#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

// round(x * 2^shift), halves away from zero, exactly: x * 2^shift is exact in
// float, and so is its fractional part. Precondition: |x * 2^shift| < 2^62.
std::int64_t round_scaled(float x, int shift) noexcept {
  float scaled = x;
  for (int i = 0; i < shift; ++i) scaled *= 2.0f;
  const auto whole = static_cast<std::int64_t>(scaled);  // towards zero
  const float fraction = scaled - static_cast<float>(whole);
  return whole + (fraction >= 0.5f ? 1 : 0) - (fraction <= -0.5f ? 1 : 0);
}

// (a * b) >> shift, rounded to nearest (halves up), for |a * b| < 2^62.
std::int64_t mul_shift(std::int64_t a, std::int64_t b, int shift) noexcept {
  return (a * b + (std::int64_t{1} << (shift - 1))) >> shift;  // arithmetic shift (C++20)
}

// An exact unsigned 128-bit integer from 64 x 64-bit products: the
// correlation's n * sum - sum * sum terms need up to ~2^80, and 32-bit
// targets have no native 128-bit type.
struct Wide {
  std::uint64_t hi = 0, lo = 0;
};
Wide multiply(std::uint64_t a, std::uint64_t b) noexcept {
  const std::uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
  const std::uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const std::uint64_t middle = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
  return {p11 + (p01 >> 32) + (p10 >> 32) + (middle >> 32), (middle << 32) | (p00 & 0xFFFFFFFFu)};
}
bool less(const Wide& a, const Wide& b) noexcept { return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo); }
Wide minus(const Wide& a, const Wide& b) noexcept {  // precondition: b <= a
  return {a.hi - b.hi - (a.lo < b.lo ? 1u : 0u), a.lo - b.lo};
}
float to_float(const Wide& w) noexcept {
  return static_cast<float>(w.hi) * 18446744073709551616.0f + static_cast<float>(w.lo);
}
// n * p - q * r as a float with its sign (exact until the final conversion).
float difference(std::uint64_t n, std::uint64_t p, std::uint64_t q, std::uint64_t r) noexcept {
  const Wide x = multiply(n, p), y = multiply(q, r);
  return less(x, y) ? -to_float(minus(y, x)) : to_float(minus(x, y));
}

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
                  float* scores, bool* ok) noexcept {
  const SinCos r = sin_cos_deg(pose.theta_deg);
  const ImageView& shape = images[0];
  FrameSums f;
  ImageSums s[kGroup];
  // Sample positions in 1/65536-pixel fixed point, all integer: the pose and
  // the reference point in 16.16, the rotation in 2.30; each row's first
  // sample from the pose, the rest by adding the rotated step.
  const std::int64_t c = round_scaled(r.cos, 30), sn = round_scaled(r.sin, 30);
  const std::int64_t x0 = round_scaled(pose.x, 16), y0 = round_scaled(pose.y, 16);
  const std::int64_t step_x = mul_shift(c, std::int64_t{stack.step}, 14), step_y = mul_shift(sn, std::int64_t{stack.step}, 14);
  const std::int64_t du0 = -round_scaled(stack.ref_x, 16), ref_y = round_scaled(stack.ref_y, 16);
  const std::uint32_t columns = (shape.width + stack.step - 1) / stack.step;  // samples per row
  const std::int64_t x_limit = (std::int64_t{frame.width} - 1) * 65536, y_limit = (std::int64_t{frame.height} - 1) * 65536;
  for (std::uint32_t v = 0; v < shape.height; v += stack.step) {
    const std::int64_t dv = (std::int64_t{v} << 16) - ref_y;
    const std::int64_t px0 = x0 + mul_shift(c, du0, 30) - mul_shift(sn, dv, 30);
    const std::int64_t py0 = y0 + mul_shift(sn, du0, 30) + mul_shift(c, dv, 30);
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
  // n^2 times the covariance and the variances, exact in 128 bits, then
  // rounded once to float; the score sign(cov) cov^2 / (va vb) is taken as
  // (cov / va) (cov / vb), whose factors cannot overflow (|cov| <= sqrt(va vb)).
  const float vb = difference(f.n, f.bb, f.b, f.b);
  for (std::size_t i = 0; i < images.size(); ++i) {
    const float cov = difference(f.n, s[i].ab, s[i].a, f.b);
    const float va = difference(f.n, s[i].aa, s[i].a, s[i].a);
    ok[i] = f.n >= 16 && va > 0.0f && vb > 0.0f;
    scores[i] = ok[i] ? (cov >= 0.0f ? 1.0f : -1.0f) * (cov / va) * (cov / vb) : 0.0f;
  }
}

bool correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack,
                 float& score) noexcept {
  bool ok = false;
  correlations(frame, std::span<const ImageView>(&m, 1), pose, stack, &score, &ok);
  return ok;
}

bool valid_inputs(const ImageView& frame, const Pose& pose, const FocusStack& stack) noexcept {
  // The bounds keep the 16.16 geometry's products below 2^62.
  return frame.valid() && pose_in_range(pose) && within_limit(pose.theta_deg, 1.0e5f) && valid_focus_stack(stack);
}

}  // namespace

bool valid_focus_stack(const FocusStack& stack) noexcept {
  if (stack.images.empty() || stack.images.size() > 65535u || stack.step == 0 || stack.step > kMaxStackStep ||
      !within_limit(stack.ref_x, static_cast<float>(kMaxStackSide)) ||
      !within_limit(stack.ref_y, static_cast<float>(kMaxStackSide))) {
    return false;
  }
  for (const ImageView& m : stack.images) {
    if (!m.valid() || m.width != stack.images[0].width || m.height != stack.images[0].height || m.width > kMaxStackSide ||
        m.height > kMaxStackSide) {
      return false;
    }
  }
  return true;
}

bool correlation_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                    float& signed_r2) noexcept {
  return correlation(frame, stack.images[depth], pose, stack, signed_r2);
}

Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t& depth,
                          float switch_margin) noexcept {
  if (!valid_inputs(frame, pose, stack) || !(switch_margin >= 0.0f && switch_margin <= 2.0f)) return Status::kInvalidArgument;
  bool have_best = false, have_current = false;
  float best_score = 0.0f, current_score = 0.0f;
  std::uint16_t best_depth = depth;
  for (std::size_t first = 0; first < stack.images.size(); first += kGroup) {
    const std::span<const ImageView> group =
        stack.images.subspan(first, stack.images.size() - first < kGroup ? stack.images.size() - first : kGroup);
    float scores[kGroup];
    bool ok[kGroup];
    correlations(frame, group, pose, stack, scores, ok);
    for (std::size_t i = 0; i < group.size(); ++i) {
      if (!ok[i]) continue;
      if (first + i == depth) have_current = true, current_score = scores[i];
      if (!have_best || scores[i] > best_score) {
        have_best = true;
        best_score = scores[i];
        best_depth = static_cast<std::uint16_t>(first + i);
      }
    }
  }
  // Hysteresis: the current depth stays unless another correlates better by the margin.
  if (have_best && (!have_current || best_score > current_score + switch_margin)) depth = best_depth;
  return Status::kOk;
}

Status angle_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, float& theta_deg) noexcept {
  if (!valid_inputs(frame, pose, stack) || pose.depth >= stack.images.size()) return Status::kInvalidArgument;
  const ImageView& m = stack.images[pose.depth];
  float scores[2 * kAngleSteps + 1];
  int best = -1;
  for (int k = -kAngleSteps; k <= kAngleSteps; ++k) {
    Pose p = pose;
    p.theta_deg = pose.theta_deg + static_cast<float>(k) * kAngleIncrementDeg;
    float score = 0.0f;
    if (!correlation(frame, m, p, stack, score)) return Status::kOk;  // leaving the frame: keep the angle
    scores[k + kAngleSteps] = score;
    if (best < 0 || score > scores[best]) best = k + kAngleSteps;
  }
  float offset = static_cast<float>(best - kAngleSteps) * kAngleIncrementDeg;
  if (best > 0 && best < 2 * kAngleSteps) {
    // A parabola through the peak and its neighbours places it between samples.
    const float a = scores[best - 1], b = scores[best], c = scores[best + 1];
    const float curvature = a - 2.0f * b + c;
    if (curvature < 0.0f) offset += kAngleIncrementDeg * (0.5f * (a - c) / curvature);
  }
  theta_deg = pose.theta_deg + offset;
  return Status::kOk;
}

}  // namespace gabarit
