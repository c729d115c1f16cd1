// The correlation's Gauss-Newton ascent (depth_by_intensity.hpp,
// correlation_ascent_at), over the samples correlation_at compares.
#include "gabarit/depth_by_intensity.hpp"

#include "gabarit/deterministic_math.hpp"
#include "float_lanes.hpp"
#include "intensity_samples.hpp"

// Eigen as in motion_filter.cpp: fixed-size floats, no heap, scalar code.
#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace gabarit {

using namespace intensity;

namespace {

// The float sums over the samples: j is d/d(x, y, theta) of the model's
// value seen through the pose (its slope, and the slope along the rotation),
// t and b the model's and the frame's values less mid-grey. Kept four to a
// FloatLanes, each lane one sum in sample order (the same bits as one sum
// at a time): lane 3 of j, jt and jb adds zeros; the gain's lanes add their
// terms times 1, exactly.
struct AscentSums {
  FloatLanes j, jt, jb;
  FloatLanes jj_low, jj_high;  // xx, xy, xt, yy; yt, tt, then the gain's two sums
  // jj: xx, xy, xt, yy, yt, tt (k = 0..5).
  float jj(int k) const noexcept { return k < 4 ? jj_low[k] : jj_high[k - 4]; }
  float gain_num() const noexcept { return jj_high[2]; }  // sum frame slope . model slope
  float gain_den() const noexcept { return jj_high[3]; }  // sum |model slope|^2
  // One sample: its slopes js, the model's and the frame's values t and b
  // (less mid-grey) and the frame's slope (fx, fy).
  void add_sample(const float (&js)[3], float t, float b, float fx, float fy) noexcept {
    const FloatLanes lanes(js[0], js[1], js[2], 0.0f);
    j += lanes;
    jt += lanes * t;
    jb += lanes * b;
    jj_low += FloatLanes(js[0], js[0], js[0], js[1]) * FloatLanes(js[0], js[1], js[2], js[1]);
    jj_high += FloatLanes(js[1], js[2], fx * js[0] + fy * js[1], js[0] * js[0] + js[1] * js[1]) *
               FloatLanes(js[2], js[2], 1.0f, 1.0f);
  }
  void add(const AscentSums& o) noexcept {
    j += o.j;
    jt += o.jt;
    jb += o.jb;
    jj_low += o.jj_low;
    jj_high += o.jj_high;
  }
};

using Vector3 = Eigen::Matrix<float, 3, 1>;
using Matrix3 = Eigen::Matrix<float, 3, 3>;

// x = H^-1 g for the leading `dims` x `dims` block of a positive definite
// H; false where H is singular within float precision along some direction.
bool solve_normal(const Matrix3& h, const Vector3& g, int dims, Vector3& x) noexcept {
  x = Vector3::Zero();
  const float scale = h.diagonal().head(dims).maxCoeff();
  if (!(scale > 0.0f)) return false;
  if (dims == 3) {
    const Eigen::LDLT<Matrix3> ldlt(h);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1.0e-5f * scale)) return false;
    x = ldlt.solve(g);
  } else {
    const Eigen::Matrix<float, 2, 2> h2 = h.topLeftCorner<2, 2>();
    const Eigen::LDLT<Eigen::Matrix<float, 2, 2>> ldlt(h2);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1.0e-5f * scale)) return false;
    x.head<2>() = ldlt.solve(g.head<2>());
  }
  return is_finite(x(0)) && is_finite(x(1)) && is_finite(x(2));
}

// The ECC step from the sums (zero-mean by subtracting n times the means);
// false where the linearised correlation has no maximum. The frame's slope
// is taken as the model's times the gain (the frame's slope per the model's,
// least squares: the clutter's and the noise's slopes, unrelated to the
// model's, average out). So the clutter does not inflate the curvature and
// shorten every step, and the step's fixed point is where the frame's
// residual is orthogonal to the model's slopes: the object's own structure
// aligned, wherever the model image's background and the frame's clutter
// disagree. On the scene suite this placed the object better than the
// correlation's own maximum (docs/tracking.md, "Vote, then verify").
bool ecc_step(const AscentSums& s, float n, float t_sum, float b_sum, float tb, float bb, int dims, Vector3& step) noexcept {
  const float gain_num = s.gain_num(), gain_den = s.gain_den();
  if (!(gain_num > 0.0f && gain_den > 0.0f)) return false;
  const float gain = gain_num / gain_den;
  Matrix3 h;
  const int pair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) h(r, c) = gain * gain * (s.jj(pair[r][c]) - s.j[r] * s.j[c] / n);
  Vector3 gt, gb;
  for (int i = 0; i < 3; ++i) gt(i) = gain * (s.jt[i] - s.j[i] * t_sum / n), gb(i) = gain * (s.jb[i] - s.j[i] * b_sum / n);
  Vector3 h_gb;
  if (!solve_normal(h, gb, dims, h_gb)) return false;
  // lambda scales the model to the frame: the frame's variance and its
  // covariance with the model, each less the part the Jacobian explains.
  const float numerator = bb - gb.dot(h_gb), denominator = tb - gt.dot(h_gb);
  if (!(denominator > 0.0f) || !(numerator > 0.0f)) return false;
  const float lambda = numerator / denominator;
  return solve_normal(h, lambda * gt - gb, dims, step);
}

}  // namespace

namespace {

bool ascent_over(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth, bool with_angle,
                 const ObjectSupport* support, OutlineRing ring, CorrelationAscent& out) noexcept {
  out = CorrelationAscent{};
  const ImageView& m = stack.images[depth];
  OutlineParts parts;  // every sample counts as the object's without a support
  AscentSums total, row, ring_total, ring_row;
  const std::uint8_t* model_row = nullptr;
  std::uint32_t model_v = 0;
  std::ptrdiff_t up = 0, down = 0;  // to the model rows above and below (0 at the image's edge)
  constexpr float kOffsetUnit = 1.0f / 65536.0f;
  const SinCos rotation = sin_cos_deg(pose.theta_deg);
  walk_samples(
      frame, m.width, m.height, pose, stack,
      [&](std::uint32_t v) {
        total.add(row);
        ring_total.add(ring_row);
        row = AscentSums{};
        ring_row = AscentSums{};
        model_v = v;
        model_row = m.pixels + std::size_t{v} * m.stride;
        up = v > 0 ? -static_cast<std::ptrdiff_t>(m.stride) : 0;
        down = v + 1 < m.height ? static_cast<std::ptrdiff_t>(m.stride) : 0;
        return support != nullptr ? support->row_columns(v) : ColumnSpan{0, m.width};
      },
      [&](std::uint32_t u, const FrameSample& at) {
        const ObjectSupport::Place place = support != nullptr ? support->place(u, model_v) : ObjectSupport::kObject;
        if (place == ObjectSupport::kOutside) return;
        const std::uint64_t a = model_row[u], b = at.value();
        const bool object = place == ObjectSupport::kObject;
        // The model's slope (differences across the pixel, one-sided at the
        // image's edge) turned into the frame's axes, and the frame's (for
        // the gain between them).
        const std::uint8_t* p = model_row + u;
        // Halving is the division by 2, exactly (a power of two), and cheaper.
        // A support's samples lie a pixel inside the image (row_columns):
        // both neighbours always, without asking.
        float mx = 0.0f, my = 0.0f;
        if (support != nullptr) {
          const auto s = static_cast<std::ptrdiff_t>(m.stride);
          mx = static_cast<float>(static_cast<std::int32_t>(p[1]) - p[-1]) * 0.5f;
          my = static_cast<float>(static_cast<std::int32_t>(p[s]) - p[-s]) * 0.5f;
        } else {
          const std::ptrdiff_t left = u > 0 ? -1 : 0, right = u + 1 < m.width ? 1 : 0;
          mx = static_cast<float>(static_cast<std::int32_t>(p[right]) - p[left]) * (right - left == 2 ? 0.5f : 1.0f);
          my = static_cast<float>(static_cast<std::int32_t>(p[down]) - p[up]) * (up != 0 && down != 0 ? 0.5f : 1.0f);
        }
        const float gx = rotation.cos * mx - rotation.sin * my, gy = rotation.sin * mx + rotation.cos * my;
        const float fx = static_cast<float>(at.central_x()) * (1.0f / 512.0f);
        const float fy = static_cast<float>(at.central_y()) * (1.0f / 512.0f);
        // d/d(x, y, theta): the slope, and the slope along the rotation of
        // the sample's offset q from the pose, (-q_y, q_x).
        const float qx = static_cast<float>(at.dx) * kOffsetUnit, qy = static_cast<float>(at.dy) * kOffsetUnit;
        const float j[3] = {gx, gy, gy * qx - gx * qy};
        const float t = static_cast<float>(a) - 128.0f, bc = static_cast<float>(b) - 32640.0f;
        // A branch rather than a reference to either side's sums, so that
        // the compiler may keep the object's (most samples) in registers.
        if (object) {
          add_sample(parts.object_frame, parts.object_model, a, b);
          row.add_sample(j, t, bc, fx, fy);
        } else {
          add_sample(parts.ring_frame, parts.ring_model, a, b);
          ring_row.add_sample(j, t, bc, fx, fy);
        }
      });
  total.add(row);
  ring_total.add(ring_row);
  // The ring as `ring` says (OutlineParts), as correlation_at compares.
  FrameSums f;
  ImageSums s;
  const std::uint8_t surround = support != nullptr ? support->surround() : 0;
  parts.compared(surround, ring, f, s);
  if (parts.ring_used(surround, ring)) total.add(ring_total);
  const float vb = difference(f.n, f.bb, f.b, f.b), cov = difference(f.n, s.ab, s.a, f.b);
  const float va = difference(f.n, s.aa, s.a, s.a);
  if (!(f.n >= 16 && va > 0.0f && vb > 0.0f)) return false;
  out.signed_r2 = (cov >= 0.0f ? 1.0f : -1.0f) * (cov / va) * (cov / vb);
  // The centred sums: n times the means of t and b, the frame's variance
  // and covariance with the model times n (the exact sums over n).
  const float n = static_cast<float>(f.n);
  const float t_sum = static_cast<float>(static_cast<std::int64_t>(s.a) - 128 * static_cast<std::int64_t>(f.n));
  const float b_sum = static_cast<float>(static_cast<std::int64_t>(f.b) - 32640 * static_cast<std::int64_t>(f.n));
  Vector3 step;
  if (!ecc_step(total, n, t_sum, b_sum, cov / n, vb / n, with_angle ? 3 : 2, step) &&
      !(with_angle && ecc_step(total, n, t_sum, b_sum, cov / n, vb / n, 2, step))) {
    return true;
  }
  constexpr float kDegrees = 57.2957795f;
  out.has_step = true;
  out.dx = step(0);
  out.dy = step(1);
  out.dtheta_deg = step(2) * kDegrees;
  return true;
}

}  // namespace

// Over the model's outline, as correlation_at.
bool correlation_ascent_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                           bool with_angle, CorrelationAscent& out, OutlineRing ring) noexcept {
  const ObjectSupport outline(stack.images.subspan(depth, 1), ObjectSupport::kOutline);
  return (outline.flat() && ascent_over(frame, pose, stack, depth, with_angle, &outline, ring, out)) ||
         ascent_over(frame, pose, stack, depth, with_angle, nullptr, ring, out);
}

}  // namespace gabarit
