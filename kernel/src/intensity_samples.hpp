// Internal to the kernel: the frame sampling and exact sums that depth by
// intensity (depth_by_intensity.cpp) and the correlation's Gauss-Newton
// ascent (correlation_ascent.cpp) share. Not installed.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>

#include "gabarit/depth_by_intensity.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit::intensity {

// round(x * 2^shift), halves away from zero, exactly: x * 2^shift is exact in
// float (one multiplication by the power of two, as exact as doubling
// `shift` times), and so is its fractional part. Preconditions:
// 0 <= shift < 63, |x * 2^shift| < 2^62.
inline std::int64_t round_scaled(float x, int shift) noexcept {
  const float scaled = x * static_cast<float>(std::int64_t{1} << shift);
  const auto whole = static_cast<std::int64_t>(scaled);  // towards zero
  const float fraction = scaled - static_cast<float>(whole);
  return whole + (fraction >= 0.5f ? 1 : 0) - (fraction <= -0.5f ? 1 : 0);
}

// (a * b) >> shift, rounded to nearest (halves up), for |a * b| < 2^62.
inline std::int64_t mul_shift(std::int64_t a, std::int64_t b, int shift) noexcept {
  return (a * b + (std::int64_t{1} << (shift - 1))) >> shift;  // arithmetic shift (C++20)
}

// An exact unsigned 128-bit integer from 64 x 64-bit products: the
// correlation's n * sum - sum * sum terms need up to ~2^80, and 32-bit
// targets have no native 128-bit type.
struct Wide {
  std::uint64_t hi = 0, lo = 0;
};
inline Wide multiply(std::uint64_t a, std::uint64_t b) noexcept {
  const std::uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
  const std::uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const std::uint64_t middle = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
  return {p11 + (p01 >> 32) + (p10 >> 32) + (middle >> 32), (middle << 32) | (p00 & 0xFFFFFFFFu)};
}
inline bool less(const Wide& a, const Wide& b) noexcept { return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo); }
inline Wide minus(const Wide& a, const Wide& b) noexcept {  // precondition: b <= a
  return {a.hi - b.hi - (a.lo < b.lo ? 1u : 0u), a.lo - b.lo};
}
inline float to_float(const Wide& w) noexcept {
  return static_cast<float>(w.hi) * 18446744073709551616.0f + static_cast<float>(w.lo);
}
// n * p - q * r as a float with its sign (exact until the final conversion).
inline float difference(std::uint64_t n, std::uint64_t p, std::uint64_t q, std::uint64_t r) noexcept {
  const Wide x = multiply(n, p), y = multiply(q, r);
  return less(x, y) ? -to_float(minus(y, x)) : to_float(minus(x, y));
}

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
// the pose) over the frame: row(v) at each sampled model row (which may
// return the ColumnSpan of the row worth walking), then
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
  // Written as a * 256 + (b - a) * w rather than a * (256 - w) + b * w: the
  // same integer (unsigned arithmetic wraps exactly and the result is in
  // range), without a register holding 256 in the hot loops that call it.
  std::uint32_t value() const noexcept {
    const std::uint32_t top = (std::uint32_t{row0[0]} << 8) + (std::uint32_t{row0[1]} - row0[0]) * wx;
    const std::uint32_t bottom = (std::uint32_t{row1[0]} << 8) + (std::uint32_t{row1[1]} - row1[0]) * wx;
    return ((top << 8) + (bottom - top) * wy + 128u) >> 8;
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

// The model columns of a row worth walking, [begin, end): a row callback may
// return one (ObjectSupport::row_columns) so that the walk skips, without
// placing them, samples its sample callback would ignore.
struct ColumnSpan {
  std::uint32_t begin = 0, end = 0;
};

template <typename Row, typename Sample>
inline void walk_samples(const ImageView& frame, std::uint32_t width, std::uint32_t height, const Pose& pose, const FocusStack& stack,
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
    if constexpr (std::is_same_v<decltype(row(v)), ColumnSpan>) {
      const ColumnSpan span = row(v);
      const std::uint32_t first = (span.begin + stack.step - 1) / stack.step, last = (span.end + stack.step - 1) / stack.step;
      if (first > k_begin) k_begin = first;
      if (last < k_end) k_end = last;
      if (k_end < k_begin) k_end = k_begin;
    } else {
      row(v);
    }
    while (k_begin < k_end && !inside(k_begin)) ++k_begin;
    while (k_end > k_begin && !inside(k_end - 1)) --k_end;
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

// The first column in [from, to) whose pixel differs from `value`, or `to`;
// eight pixels at a time over a flat run (the surround around a model).
inline std::uint32_t first_differing(const std::uint8_t* row, std::uint32_t from, std::uint32_t to, std::uint8_t value) noexcept {
  const std::uint64_t all = std::uint64_t{value} * 0x0101010101010101u;
  std::uint32_t x = from;
  for (; x + 8 <= to; x += 8) {
    std::uint64_t word;
    std::memcpy(&word, row + x, sizeof word);
    if (word != all) break;
  }
  while (x < to && row[x] == value) ++x;
  return x;
}
// One past the last column in [from, to) whose pixel differs from `value`,
// or `from`; eight at a time from the end.
inline std::uint32_t end_of_differing(const std::uint8_t* row, std::uint32_t from, std::uint32_t to, std::uint8_t value) noexcept {
  const std::uint64_t all = std::uint64_t{value} * 0x0101010101010101u;
  std::uint32_t x = to;
  for (; x >= from + 8; x -= 8) {
    std::uint64_t word;
    std::memcpy(&word, row + x - 8, sizeof word);
    if (word != all) break;
  }
  while (x > from && row[x - 1] == value) --x;
  return x;
}

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
  std::uint8_t surround() const noexcept { return surround_; }
  // Whether model pixel (u, v) shows the object itself (kOutline's ring: not).
  bool on_object(std::uint32_t u, std::uint32_t v) const noexcept { return object_at(u, v); }
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

  // Where model pixel (u, v) lies: outside the support, on its ring (in the
  // support, not on the object) or on the object; contains() and on_object() in one.
  enum Place { kOutside, kRing, kObject };
  Place place(std::uint32_t u, std::uint32_t v) const noexcept {
    if (images_.size() == 1) {  // one image (scoring and refining a pose): its pixels read directly
      const ImageView& m = images_[0];
      if (u == 0 || v == 0 || u + 1 >= m.width || v + 1 >= m.height) return kOutside;
      const std::uint8_t* p = m.pixels + std::size_t{v} * m.stride + u;
      const auto s = static_cast<std::ptrdiff_t>(m.stride);
      const bool here = p[0] != surround_;
      const bool all_around = p[-1] != surround_ && p[1] != surround_ && p[-s] != surround_ && p[s] != surround_;
      const bool any_around = p[-1] != surround_ || p[1] != surround_ || p[-s] != surround_ || p[s] != surround_;
      if (extent_ == kInterior) return here && all_around ? kObject : kOutside;
      return here ? kObject : (any_around ? kRing : kOutside);
    }
    return place_in_any(u, v);
  }
  // Columns [begin, end) of row v outside which contains(u, v) is false:
  // from the first and last object pixels of the row (kInterior) or of it
  // and its neighbours (kOutline), found by scanning in from each side.
  // Cheaper than asking contains() of every sample of the surround.
  ColumnSpan row_columns(std::uint32_t v) const noexcept {
    const ImageView& m = images_[0];
    if (v == 0 || v + 1 >= m.height || m.width < 3) return {};
    std::uint32_t begin = m.width - 1, end = 1;  // contained columns lie in [1, width - 1)
    const auto widen = [&](std::uint32_t r, std::uint32_t grow) {
      // The row's first and last object pixels: the first and the last
      // that differ from the surround in any image.
      std::uint32_t first = m.width;
      for (const ImageView& image : images_) first = first_differing(image.pixels + std::size_t{r} * image.stride, 0, first, surround_);
      if (first == m.width) return;
      std::uint32_t past_last = first + 1;
      for (const ImageView& image : images_)
        past_last = end_of_differing(image.pixels + std::size_t{r} * image.stride, past_last, m.width, surround_);
      const std::uint32_t last = past_last - 1;
      const std::uint32_t lo = first > grow ? first - grow : 0, hi = last + grow + 1;
      if (lo < begin) begin = lo;
      if (hi > end) end = hi;
    };
    if (extent_ == kInterior) {
      widen(v, 0);
    } else {
      widen(v - 1, 0);
      widen(v, 1);
      widen(v + 1, 0);
    }
    if (begin < 1) begin = 1;
    if (end > m.width - 1) end = m.width - 1;
    return begin < end ? ColumnSpan{begin, end} : ColumnSpan{};
  }

 private:
  Place place_in_any(std::uint32_t u, std::uint32_t v) const noexcept {
    if (!contains(u, v)) return kOutside;
    return object_at(u, v) ? kObject : kRing;
  }
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

// The sums over an outline's two parts, the object's samples and the
// ring's. The ring is compared only where the frame's surround stands
// against the object on the side the model's surround does (brighter or
// darker than the object's mean): the model's flat grey stands for a
// background it does not know, and where the frame's is on the other side
// (a bright coin drawn on mid-grey, over a white page) the ring pulled the
// pose off the object, to where the ring fell on the page's dark print.
// Exact integer comparisons: the same choice on every target.
struct OutlineParts {
  FrameSums object_frame, ring_frame;
  ImageSums object_model, ring_model;
  bool ring_agrees(std::uint8_t surround) const noexcept {
    const std::uint64_t on = object_frame.n, rn = ring_frame.n;
    if (on == 0 || rn == 0) return true;
    // sign(surround - the model's object mean) and sign(the frame's ring
    // mean - its object mean), each side scaled by the sample counts.
    const Wide model_surround = multiply(surround, on), model_object = multiply(object_model.a, 1);
    const Wide frame_ring = multiply(ring_frame.b, on), frame_object = multiply(object_frame.b, rn);
    const int model_side = less(model_object, model_surround) ? 1 : (less(model_surround, model_object) ? -1 : 0);
    const int frame_side = less(frame_object, frame_ring) ? 1 : (less(frame_ring, frame_object) ? -1 : 0);
    return model_side * frame_side >= 0;
  }
  // Whether the ring is compared: as `ring` says, or where it agrees.
  bool ring_used(std::uint8_t surround, OutlineRing ring) const noexcept {
    if (ring_frame.n == 0) return false;
    return ring == OutlineRing::kCompared || (ring == OutlineRing::kWhereItAgrees && ring_agrees(surround));
  }
  // The sums compared: the object's, with the ring's where it is used.
  void compared(std::uint8_t surround, OutlineRing ring, FrameSums& f, ImageSums& s) const noexcept {
    f = object_frame;
    s = object_model;
    if (!ring_used(surround, ring)) return;
    f.n += ring_frame.n, f.b += ring_frame.b, f.bb += ring_frame.bb;
    s.a += ring_model.a, s.aa += ring_model.aa, s.ab += ring_model.ab;
  }
};

// Samples gathered for the bilinear blend: each one's frame pixels (two
// bytes of the row at or above it, FrameSample's row0[0] in the low byte and
// row0[1] in the high, and the two below), its weights (1/256) and its
// model pixel, each in its own array. The blend and the sums run over these
// arrays alone, a loop the compiler vectorises in 16-bit lanes; gathering
// the pixels from all over the frame, which it does not vectorise, is the
// caller's loop. The
// same sums as FrameSample::value and add_sample give sample by sample
// (exact integers in another order).
struct GatheredSamples {
  static constexpr std::uint32_t kCapacity = 128;
  // The blend runs over whole blocks of kBlock samples, the last one padded
  // with black pixels (whose b is 0, adding nothing to any sum): no sample
  // takes a vector loop's slower scalar tail.
  static constexpr std::uint32_t kBlock = 16;
  std::uint16_t top_pair[kCapacity + kBlock], bottom_pair[kCapacity + kBlock];
  std::uint8_t wx[kCapacity + kBlock], wy[kCapacity + kBlock];
  std::uint8_t model[kCapacity + kBlock];
  std::uint32_t count = 0;
  // The sums so far: of the frame values b, their squares and their
  // products with the model pixels.
  std::uint64_t b_sum = 0, bb = 0, ab = 0;

  // Two horizontally adjacent pixels as top_pair holds them, whatever the
  // target's byte order.
  static std::uint16_t pair(const std::uint8_t* p) noexcept { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
  // Adds the gathered samples to the sums and empties the arrays.
  void flush() noexcept;
};

// The correlation from its exact sums, as sign(r) r^2: n^2 times the
// covariance and the variances, exact in 128 bits, then rounded once to
// float; sign(cov) cov^2 / (va vb) is taken as (cov / va) (cov / vb), whose
// factors cannot overflow (|cov| <= sqrt(va vb)). False when fewer than 16
// samples were summed or either side is flat.
inline bool signed_r2(const FrameSums& f, const ImageSums& s, float& out) noexcept {
  const float vb = difference(f.n, f.bb, f.b, f.b), cov = difference(f.n, s.ab, s.a, f.b);
  const float va = difference(f.n, s.aa, s.a, s.a);
  if (!(f.n >= 16 && va > 0.0f && vb > 0.0f)) return false;
  out = (cov >= 0.0f ? 1.0f : -1.0f) * (cov / va) * (cov / vb);
  return true;
}

inline void add_sample(FrameSums& f, ImageSums& s, std::uint64_t a, std::uint64_t b) noexcept {
  ++f.n;
  f.b += b;
  f.bb += b * b;
  s.a += a;
  s.aa += a * a;
  s.ab += a * b;
}

}  // namespace gabarit::intensity
