#include "gabarit/depth_by_intensity.hpp"

#include <cstddef>

#include "gabarit/deterministic_math.hpp"

// Eigen as in motion_filter.cpp: fixed-size floats, no heap, scalar code.
#include <Eigen/Cholesky>
#include <Eigen/Core>

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

// Walks the model's samples (every stack.step-th pixel of a width x height
// image, rotated by the pose's angle about the reference point and placed at
// the pose) over the frame: row(v) at each sampled model row, then
// sample(u, at) for each sample whose 2 x 2 frame neighbourhood lies in the
// frame, in row order. Sample positions are in 1/65536-pixel fixed point,
// all integer: the pose and the reference point in 16.16, the rotation in
// 2.30; each row's first sample from the pose, the rest by adding the
// rotated step.
struct FrameSample {
  const std::uint8_t* row0;  // the frame pixel at or left of and above the sample
  const std::uint8_t* row1;  // the one below it
  std::uint32_t wx, wy;      // the bilinear weights, 1/256
  std::int64_t dx, dy;       // the sample's offset from the pose, 16.16 (the rotated model offset)
  // The frame sampled bilinearly, in 1/256 (0 .. 255 * 256): the correlation
  // then varies smoothly with the pose.
  std::uint32_t value() const noexcept {
    const std::uint32_t top = row0[0] * (256u - wx) + row0[1] * wx;
    const std::uint32_t bottom = row1[0] * (256u - wx) + row1[1] * wx;
    return (top * (256u - wy) + bottom * wy + 128u) >> 8;
  }
  // The bilinear interpolant's derivatives along x and y at the sample, in
  // the same 1/256 units per pixel (-255 * 256 .. 255 * 256).
  std::int32_t gradient_x() const noexcept {
    return (static_cast<std::int32_t>(row0[1]) - row0[0]) * static_cast<std::int32_t>(256u - wy) +
           (static_cast<std::int32_t>(row1[1]) - row1[0]) * static_cast<std::int32_t>(wy);
  }
  std::int32_t gradient_y() const noexcept {
    return (static_cast<std::int32_t>(row1[0]) - row0[0]) * static_cast<std::int32_t>(256u - wx) +
           (static_cast<std::int32_t>(row1[1]) - row0[1]) * static_cast<std::int32_t>(wx);
  }
  // Central differences of the interpolant one pixel either side, times
  // 256 (so 512 times the units above): a smoother slope than the
  // interpolant's own. Where the 4 x 4 neighbourhood leaves the frame, the
  // interpolant's own derivatives.
  std::ptrdiff_t stride = 0;
  bool interior = false;
  std::int32_t central_x() const noexcept {
    if (!interior) return gradient_x() * 512;
    const auto d = [&](const std::uint8_t* r) {
      return (static_cast<std::int32_t>(r[1]) - r[-1]) * static_cast<std::int32_t>(256u - wx) +
             (static_cast<std::int32_t>(r[2]) - r[0]) * static_cast<std::int32_t>(wx);
    };
    return d(row0) * static_cast<std::int32_t>(256u - wy) + d(row1) * static_cast<std::int32_t>(wy);
  }
  std::int32_t central_y() const noexcept {
    if (!interior) return gradient_y() * 512;
    const auto d = [&](const std::uint8_t* r) {  // r: the sample's row in one of its two columns
      return (static_cast<std::int32_t>(r[stride]) - r[-stride]) * static_cast<std::int32_t>(256u - wy) +
             (static_cast<std::int32_t>(r[2 * stride]) - r[0]) * static_cast<std::int32_t>(wy);
    };
    return d(row0) * static_cast<std::int32_t>(256u - wx) + d(row0 + 1) * static_cast<std::int32_t>(wx);
  }
};

template <typename Row, typename Sample>
void walk_samples(const ImageView& frame, std::uint32_t width, std::uint32_t height, const Pose& pose, const FocusStack& stack,
                  Row&& row, Sample&& sample) noexcept {
  const SinCos r = sin_cos_deg(pose.theta_deg);
  const std::int64_t c = round_scaled(r.cos, 30), sn = round_scaled(r.sin, 30);
  const std::int64_t x0 = round_scaled(pose.x, 16), y0 = round_scaled(pose.y, 16);
  const std::int64_t step_x = mul_shift(c, std::int64_t{stack.step}, 14), step_y = mul_shift(sn, std::int64_t{stack.step}, 14);
  const std::int64_t du0 = -round_scaled(stack.ref_x, 16), ref_y = round_scaled(stack.ref_y, 16);
  const std::uint32_t columns = (width + stack.step - 1) / stack.step;  // samples per row
  const std::int64_t x_limit = (std::int64_t{frame.width} - 1) * 65536, y_limit = (std::int64_t{frame.height} - 1) * 65536;
  for (std::uint32_t v = 0; v < height; v += stack.step) {
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
    row(v);
    std::int64_t px = px0 + std::int64_t{k_begin} * step_x, py = py0 + std::int64_t{k_begin} * step_y;
    for (std::uint32_t k = k_begin; k < k_end; ++k, px += step_x, py += step_y) {
      const auto fx = static_cast<std::uint32_t>(px >> 8), fy = static_cast<std::uint32_t>(py >> 8);
      FrameSample at;
      at.row0 = frame.pixels + static_cast<std::size_t>(py >> 16) * frame.stride + static_cast<std::size_t>(px >> 16);
      at.row1 = at.row0 + frame.stride;
      at.wx = fx & 255u;
      at.wy = fy & 255u;
      at.dx = px - x0;
      at.dy = py - y0;
      at.stride = static_cast<std::ptrdiff_t>(frame.stride);
      const std::int64_t col = px >> 16, line = py >> 16;
      at.interior = col >= 1 && line >= 1 && col + 2 < std::int64_t{frame.width} && line + 2 < std::int64_t{frame.height};
      sample(k * stack.step, at);
    }
  }
}

// A model pixel blurred as much as the frame's sample is by the bilinear
// interpolation. Interpolating at a fraction f of a pixel averages the frame
// with a kernel of variance f (1 - f) along each axis (up to a quarter of a
// pixel squared at half a pixel); the model's pixels are not interpolated,
// so a sharper stack image correlated worse than a blurrier one at most
// poses, and comparing depths favoured the blurrier (docs/tracking.md, "Vote,
// then verify", item 6). The model gets the same variance, the mean of the
// two axes' (its axes are turned against the frame's), from a symmetric
// five-point kernel (k on each of the four neighbours, 1 - 4k at the
// centre: variance 2k along each axis), which moves no edge. At the image's
// border the edge pixel repeats.
struct MatchedBlur {
  std::uint32_t k = 0, centre = 256;           // in 1/256
  std::uint32_t left = 0, right = 0;           // the neighbours' columns
  std::ptrdiff_t up = 0, down = 0;             // and offsets to their rows
  MatchedBlur() noexcept = default;
  MatchedBlur(const ImageView& m, std::uint32_t u, std::uint32_t v, const FrameSample& at) noexcept {
    // The axes' variances in 1/65536 of a pixel squared; k, half their
    // mean, in 1/256: 0 .. 32 (a quarter of a pixel squared at half a pixel).
    k = (at.wx * (256u - at.wx) + at.wy * (256u - at.wy)) >> 10;
    centre = 256u - 4u * k;
    left = u > 0 ? u - 1 : u;
    right = u + 1 < m.width ? u + 1 : u;
    up = v > 0 ? -static_cast<std::ptrdiff_t>(m.stride) : 0;
    down = v + 1 < m.height ? static_cast<std::ptrdiff_t>(m.stride) : 0;
  }
  // Row `row` of an image of the model's size, at column u: in 1/256 (0 .. 255 * 256).
  std::uint32_t value(const std::uint8_t* row, std::uint32_t u) const noexcept {
    const std::uint32_t around = std::uint32_t{row[left]} + row[right] + row[static_cast<std::ptrdiff_t>(u) + up] +
                                 row[static_cast<std::ptrdiff_t>(u) + down];
    return centre * row[u] + k * around;
  }
};

// The object's own pixels in stack images drawn on a flat surround (every
// pixel of the first image's border one grey value, as a model rendered or
// cut out onto a uniform background is). Where the images show that value
// there is no object, and the frame shows whatever lies behind it: its
// samples there tell nothing of the pose or the depth, yet they weighed in
// the correlation through the model's mean and variance, as much as the
// object's own. A stack cut from a camera's images has no flat border:
// every sample is used.
//  - Comparing depths (kInterior): the object's pixels but the one-pixel rim
//    next to the surround, part object and part surround. Over every sample
//    the depth followed how the object's mean grey stood against the frame's
//    surround, which the depths' blur shifts slightly at the rim: on a cat
//    over a printed page the true depth of a 7-depth stack won at the true
//    pose on 30 of 160 frames (145 over the object).
//  - Scoring and refining a pose (kOutline): the object's pixels and the
//    surround's one-pixel ring around them, so that the outline's contrast
//    still places a plain object (a silhouette, a glass pipette).
// (docs/tracking.md, "Vote, then verify", items 2 and 6.)
class ObjectSupport {
 public:
  enum Extent { kInterior, kOutline };
  ObjectSupport(std::span<const ImageView> images, Extent extent) noexcept : images_(images), extent_(extent) {
    const ImageView& m = images[0];
    const std::uint8_t value = m.pixels[0];
    for (std::uint32_t x = 0; x < m.width; ++x)
      if (m.at(x, 0) != value || m.at(x, m.height - 1) != value) return;
    for (std::uint32_t y = 0; y < m.height; ++y)
      if (m.at(0, y) != value || m.at(m.width - 1, y) != value) return;
    surround_ = value;
    flat_ = true;
  }
  bool flat() const noexcept { return flat_; }
  // Whether model pixel (u, v) is in the support: kInterior, it and its four
  // neighbours show the object (some image differs from the surround there);
  // kOutline, it or one of them does. The border is surround.
  bool contains(std::uint32_t u, std::uint32_t v) const noexcept {
    const ImageView& m = images_[0];
    if (u == 0 || v == 0 || u + 1 >= m.width || v + 1 >= m.height) return false;
    const bool here = object_at(u, v);
    if (extent_ == kInterior) {
      return here && object_at(u - 1, v) && object_at(u + 1, v) && object_at(u, v - 1) && object_at(u, v + 1);
    }
    return here || object_at(u - 1, v) || object_at(u + 1, v) || object_at(u, v - 1) || object_at(u, v + 1);
  }

 private:
  bool object_at(std::uint32_t u, std::uint32_t v) const noexcept {
    for (const ImageView& image : images_)
      if (image.at(u, v) != surround_) return true;
    return false;
  }
  std::span<const ImageView> images_;
  Extent extent_;
  std::uint8_t surround_ = 0;
  bool flat_ = false;
};

// The correlation of each of `images` (at most kGroup, all of the stack's
// size) with the frame at a pose, as the sign of the correlation times its
// square (ordered like the correlation, no square root); ok[i] is false when
// too few samples fall in the frame or either side is flat. With
// matched_blur, each model value is blurred as MatchedBlur says (for
// comparing stack images with each other); with a support, only the samples
// inside it are compared (the same ones for every image).
void correlations(const ImageView& frame, std::span<const ImageView> images, const Pose& pose, const FocusStack& stack,
                  float* scores, bool* ok, bool matched_blur = false, const ObjectSupport* support = nullptr) noexcept {
  FrameSums f;
  ImageSums s[kGroup];
  const std::uint8_t* model_rows[kGroup];
  std::uint32_t row_v = 0;
  walk_samples(
      frame, images[0].width, images[0].height, pose, stack,
      [&](std::uint32_t v) {
        row_v = v;
        for (std::size_t i = 0; i < images.size(); ++i) model_rows[i] = images[i].pixels + std::size_t{v} * images[i].stride;
      },
      [&](std::uint32_t u, const FrameSample& at) {
        if (support != nullptr && !support->contains(u, row_v)) return;
        const std::uint64_t b = at.value();
        ++f.n;
        f.b += b;
        f.bb += b * b;
        const MatchedBlur blur = matched_blur ? MatchedBlur(images[0], u, row_v, at) : MatchedBlur{};
        for (std::size_t i = 0; i < images.size(); ++i) {
          const std::uint64_t a = matched_blur ? blur.value(model_rows[i], u) : model_rows[i][u];
          s[i].a += a;
          s[i].aa += a * a;
          s[i].ab += a * b;
        }
      });
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

// Over the model's outline where it has a flat surround (ObjectSupport);
// over every sample if it has none, or too few of the outline's fall in the
// frame.
bool correlation(const ImageView& frame, const ImageView& m, const Pose& pose, const FocusStack& stack,
                 float& score) noexcept {
  const std::span<const ImageView> image(&m, 1);
  const ObjectSupport outline(image, ObjectSupport::kOutline);
  bool ok = false;
  if (outline.flat()) correlations(frame, image, pose, stack, &score, &ok, false, &outline);
  if (!ok) correlations(frame, image, pose, stack, &score, &ok);
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

bool frame_variance_at(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t depth,
                       float& variance) noexcept {
  const std::span<const ImageView> image = stack.images.subspan(depth, 1);
  const ObjectSupport outline(image, ObjectSupport::kOutline);
  // The samples correlation_at compares: the outline's, or every one.
  for (const bool on_outline : {true, false}) {
    if (on_outline && !outline.flat()) continue;
    FrameSums f;
    std::uint32_t model_v = 0;
    walk_samples(
        frame, image[0].width, image[0].height, pose, stack, [&](std::uint32_t v) { model_v = v; },
        [&](std::uint32_t u, const FrameSample& at) {
          if (on_outline && !outline.contains(u, model_v)) return;
          const std::uint64_t b = at.value();
          ++f.n;
          f.b += b;
          f.bb += b * b;
        });
    if (f.n < 16) continue;
    // n^2 times the variance in (1/256 grey level)^2, exact, then to grey levels^2.
    const float n = static_cast<float>(f.n);
    variance = difference(f.n, f.bb, f.b, f.b) / (n * n) * (1.0f / 65536.0f);
    return true;
  }
  return false;
}

namespace {

// The float sums over the samples: j is d/d(x, y, theta) of the model's
// value seen through the pose (its slope, and the slope along the rotation),
// t and b the model's and the frame's values less mid-grey.
struct AscentSums {
  float j[3] = {}, jj[6] = {}, jt[3] = {}, jb[3] = {};  // jj: xx, xy, xt, yy, yt, tt
  float gain_num = 0.0f, gain_den = 0.0f;              // sum frame slope . model slope, sum |model slope|^2
  void add(const AscentSums& o) noexcept {
    for (int i = 0; i < 3; ++i) j[i] += o.j[i], jt[i] += o.jt[i], jb[i] += o.jb[i];
    for (int i = 0; i < 6; ++i) jj[i] += o.jj[i];
    gain_num += o.gain_num, gain_den += o.gain_den;
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
  if (!(s.gain_num > 0.0f && s.gain_den > 0.0f)) return false;
  const float gain = s.gain_num / s.gain_den;
  Matrix3 h;
  const int pair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) h(r, c) = gain * gain * (s.jj[pair[r][c]] - s.j[r] * s.j[c] / n);
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
                 const ObjectSupport* support, CorrelationAscent& out) noexcept {
  out = CorrelationAscent{};
  const ImageView& m = stack.images[depth];
  FrameSums f;
  ImageSums s;
  AscentSums total, row;
  const std::uint8_t* model_row = nullptr;
  std::uint32_t model_v = 0;
  std::ptrdiff_t up = 0, down = 0;  // to the model rows above and below (0 at the image's edge)
  constexpr float kOffsetUnit = 1.0f / 65536.0f;
  const SinCos rotation = sin_cos_deg(pose.theta_deg);
  walk_samples(
      frame, m.width, m.height, pose, stack,
      [&](std::uint32_t v) {
        total.add(row);
        row = AscentSums{};
        model_v = v;
        model_row = m.pixels + std::size_t{v} * m.stride;
        up = v > 0 ? -static_cast<std::ptrdiff_t>(m.stride) : 0;
        down = v + 1 < m.height ? static_cast<std::ptrdiff_t>(m.stride) : 0;
      },
      [&](std::uint32_t u, const FrameSample& at) {
        if (support != nullptr && !support->contains(u, model_v)) return;
        const std::uint64_t a = model_row[u], b = at.value();
        ++f.n;
        f.b += b;
        f.bb += b * b;
        s.a += a;
        s.aa += a * a;
        s.ab += a * b;
        // The model's slope (differences across the pixel, one-sided at the
        // image's edge) turned into the frame's axes, and the frame's (for
        // the gain between them).
        const std::uint8_t* p = model_row + u;
        const std::ptrdiff_t left = u > 0 ? -1 : 0, right = u + 1 < m.width ? 1 : 0;
        const float mx =
            right != left ? static_cast<float>(static_cast<std::int32_t>(p[right]) - p[left]) / static_cast<float>(right - left) : 0.0f;
        const float rows_apart = static_cast<float>((down != 0 ? 1 : 0) + (up != 0 ? 1 : 0));
        const float my = rows_apart > 0.0f ? static_cast<float>(static_cast<std::int32_t>(p[down]) - p[up]) / rows_apart : 0.0f;
        const float gx = rotation.cos * mx - rotation.sin * my, gy = rotation.sin * mx + rotation.cos * my;
        const float fx = static_cast<float>(at.central_x()) * (1.0f / 512.0f);
        const float fy = static_cast<float>(at.central_y()) * (1.0f / 512.0f);
        row.gain_num += fx * gx + fy * gy;
        row.gain_den += gx * gx + gy * gy;
        // d/d(x, y, theta): the slope, and the slope along the rotation of
        // the sample's offset q from the pose, (-q_y, q_x).
        const float qx = static_cast<float>(at.dx) * kOffsetUnit, qy = static_cast<float>(at.dy) * kOffsetUnit;
        const float j[3] = {gx, gy, gy * qx - gx * qy};
        const float t = static_cast<float>(a) - 128.0f, bc = static_cast<float>(b) - 32640.0f;
        for (int i = 0; i < 3; ++i) row.j[i] += j[i], row.jt[i] += j[i] * t, row.jb[i] += j[i] * bc;
        row.jj[0] += j[0] * j[0], row.jj[1] += j[0] * j[1], row.jj[2] += j[0] * j[2];
        row.jj[3] += j[1] * j[1], row.jj[4] += j[1] * j[2], row.jj[5] += j[2] * j[2];
      });
  total.add(row);
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
                           bool with_angle, CorrelationAscent& out) noexcept {
  const ObjectSupport outline(stack.images.subspan(depth, 1), ObjectSupport::kOutline);
  return (outline.flat() && ascent_over(frame, pose, stack, depth, with_angle, &outline, out)) ||
         ascent_over(frame, pose, stack, depth, with_angle, nullptr, out);
}

Status depth_by_intensity(const ImageView& frame, const Pose& pose, const FocusStack& stack, std::uint16_t& depth,
                          float switch_margin) noexcept {
  if (!valid_inputs(frame, pose, stack) || !(switch_margin >= 0.0f && switch_margin <= 2.0f)) return Status::kInvalidArgument;
  bool have_best = false, have_current = false;
  float best_score = 0.0f, current_score = 0.0f;
  std::uint16_t best_depth = depth;
  const ObjectSupport object(stack.images, ObjectSupport::kInterior);
  // Over the object's samples where the stack has a flat surround; over all
  // of them if it has none, or too few of the object's fall in the frame.
  for (const bool on_object : {true, false}) {
    if (have_best || (on_object && !object.flat())) continue;
    for (std::size_t first = 0; first < stack.images.size(); first += kGroup) {
      const std::span<const ImageView> group =
          stack.images.subspan(first, stack.images.size() - first < kGroup ? stack.images.size() - first : kGroup);
      float scores[kGroup];
      bool ok[kGroup];
      correlations(frame, group, pose, stack, scores, ok, true, on_object ? &object : nullptr);
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
