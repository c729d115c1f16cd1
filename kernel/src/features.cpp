#include "gabarit/features.hpp"

#include <bit>

#include "canny_rows.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

// The part of the window that lies inside [lo_x, hi_x) x [lo_y, hi_y) of the
// image, in image coordinates; empty when they do not meet.
struct Span2 {
  std::int64_t x_begin, x_end, y_begin, y_end;
  bool empty() const noexcept { return x_begin >= x_end || y_begin >= y_end; }
};

Span2 clip(const ImageWindow& w, std::int64_t lo_x, std::int64_t hi_x, std::int64_t lo_y, std::int64_t hi_y) noexcept {
  auto max = [](std::int64_t a, std::int64_t b) { return a > b ? a : b; };
  auto min = [](std::int64_t a, std::int64_t b) { return a < b ? a : b; };
  return {max(w.x0, lo_x), min(std::int64_t{w.x0} + w.width, hi_x), max(w.y0, lo_y),
          min(std::int64_t{w.y0} + w.height, hi_y)};
}

inline void emit(std::span<RoiPoint> out, FeatureCount& count, const ImageWindow& w, std::int64_t x,
                 std::int64_t y) noexcept {
  if (count.written < out.size()) {
    out[count.written++] = {static_cast<std::uint16_t>(x - w.x0), static_cast<std::uint16_t>(y - w.y0)};
  } else {
    ++count.dropped;
  }
}

Status check(const ImageView& image, const ImageWindow& window) noexcept {
  return image.valid() && window.width > 0 && window.height > 0 ? Status::kOk : Status::kInvalidArgument;
}

inline std::int32_t abs32(std::int32_t v) noexcept { return v < 0 ? -v : v; }

// The columns [xb, xe) of image row y that `keep` covers, widened by two
// pixels on each side (rounding and float differences between targets then
// never leave out a covered pixel), within [lo, hi); empty: xb >= xe.
void kept_columns(const TurnedRectangle* keep, std::int64_t y, std::int64_t lo, std::int64_t hi, std::int64_t& xb,
                  std::int64_t& xe) noexcept {
  xb = lo, xe = hi;
  if (keep == nullptr) return;
  const float dy = static_cast<float>(y) - keep->centre_y;
  float from = -1.0e9f, to = 1.0e9f;
  // a dx + b within [low, high]: an interval of dx. Where |a| is tiny, b
  // decides, with the largest |a dx| over the row (and a pixel) as slack.
  const float reach = static_cast<float>(hi - lo) + (keep->centre_x > static_cast<float>(lo) ? keep->centre_x - static_cast<float>(lo)
                                                                                             : static_cast<float>(lo) - keep->centre_x);
  const float slack = 1.0f + 1.0e-4f * reach;
  const auto bound = [&](float a, float b, float low, float high) {
    if (a > 1.0e-4f || a < -1.0e-4f) {
      float p = (low - b) / a, q = (high - b) / a;
      if (p > q) {
        const float t = p;
        p = q, q = t;
      }
      from = p > from ? p : from;
      to = q < to ? q : to;
    } else if (b < low - slack || b > high + slack) {
      from = 1.0f, to = 0.0f;
    }
  };
  bound(keep->cos, keep->sin * dy, keep->u_min, keep->u_max);
  bound(-keep->sin, keep->cos * dy, keep->v_min, keep->v_max);
  if (from > to) {
    xe = xb;
    return;
  }
  // Truncation, not floor: one pixel more of margin covers it.
  const auto b = static_cast<std::int64_t>(keep->centre_x + from) - 3, e = static_cast<std::int64_t>(keep->centre_x + to) + 4;
  xb = b > lo ? b : lo;
  xe = e < hi ? e : hi;
  if (xe < xb) xe = xb;
}

// The 3x3 Sobel operator at an interior pixel (1 <= x < width - 1, likewise
// y): the one body every detector and every orientation uses.
inline SobelGradient sobel_interior(const ImageView& image, std::size_t x, std::size_t y) noexcept {
  const std::uint8_t* up = image.pixels + (y - 1) * image.stride + x;
  const std::uint8_t* mid = up + image.stride;
  const std::uint8_t* down = mid + image.stride;
  return {(up[1] + 2 * mid[1] + down[1]) - (up[-1] + 2 * mid[-1] + down[-1]),
          (down[-1] + 2 * down[0] + down[1]) - (up[-1] + 2 * up[0] + up[1])};
}

}  // namespace

std::uint16_t gradient_magnitude(const ImageView& image, std::uint32_t x, std::uint32_t y) noexcept {
  if (x == 0 || y == 0 || x + 1 >= image.width || y + 1 >= image.height) return 0;
  const SobelGradient g = sobel_interior(image, x, y);
  return static_cast<std::uint16_t>(abs32(g.gx) + abs32(g.gy));
}

SobelGradient sobel_gradient(const ImageView& image, std::uint32_t x, std::uint32_t y) noexcept {
  if (x == 0 || y == 0 || x + 1 >= image.width || y + 1 >= image.height) return {};
  return sobel_interior(image, x, y);
}

namespace {
// Directions k * 180 / 256 degrees, k = 0..255, as (cos, sin) scaled by 2^20
// and rounded: integers, so the comparisons below are exact on every target.
struct Direction {
  std::int64_t c, s;
};
struct DirectionTable {
  Direction d[kOrientationSteps];
};
constexpr DirectionTable make_directions() noexcept {
  DirectionTable t{};
  for (std::uint32_t k = 0; k < kOrientationSteps; ++k) {
    const SinCos sc = sin_cos_deg(static_cast<float>(k) * (180.0f / static_cast<float>(kOrientationSteps)));
    t.d[k] = {round_to_int(sc.cos * 1048576.0f), round_to_int(sc.sin * 1048576.0f)};
  }
  return t;
}
constexpr DirectionTable kDirections = make_directions();
}  // namespace

std::uint8_t orientation_256(std::int32_t gx, std::int32_t gy) noexcept {
  if (gx == 0 && gy == 0) return 0;  // no edge: every direction compares equal
  // Fold into [0, 180): the upper half-plane, +x included, -x excluded.
  if (gy < 0 || (gy == 0 && gx < 0)) {
    gx = -gx;
    gy = -gy;
  }
  // The largest k whose direction is at or before the gradient's angle phi:
  // phi >= alpha_k iff cross(u_k, g) >= 0, for phi and alpha_k in [0, 180).
  std::uint32_t lo = 0, hi = kOrientationSteps;  // invariant: alpha_lo <= phi < alpha_hi
  while (hi - lo > 1) {
    const std::uint32_t mid = (lo + hi) / 2;
    const Direction& u = kDirections.d[mid];
    if (u.c * gy - u.s * gx >= 0) lo = mid; else hi = mid;
  }
  return static_cast<std::uint8_t>(lo);
}

std::uint8_t edge_orientation_at(const ImageView& img, std::int32_t px, std::int32_t py) noexcept {
  SobelGradient best{};
  std::int32_t best_mag = -1;
  for (std::int32_t ring = 0; ring <= 1 && best_mag <= 0; ++ring) {
    // ring 0: the point itself; 1: its neighbours (only if the point has no gradient).
    for (std::int32_t oy = -ring; oy <= ring; ++oy)
      for (std::int32_t ox = -ring; ox <= ring; ++ox) {
        if (ring == 1 && ox == 0 && oy == 0) continue;
        const std::int32_t x = px + ox, y = py + oy;
        if (x < 0 || y < 0 || static_cast<std::uint32_t>(x) >= img.width || static_cast<std::uint32_t>(y) >= img.height) continue;
        const SobelGradient g = sobel_gradient(img, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
        const std::int32_t mag = abs32(g.gx) + abs32(g.gy);
        if (mag > best_mag) {
          best_mag = mag;
          best = g;
        }
      }
  }
  return orientation_256(best.gx, best.gy);
}

Status extract_binary(const ImageView& image, const ImageWindow& window, std::span<RoiPoint> out, FeatureCount& count,
                      const TurnedRectangle* keep) noexcept {
  GABARIT_TRY(check(image, window));
  count = {};
  const Span2 s = clip(window, 0, image.width, 0, image.height);
  if (s.empty()) return Status::kOk;
  for (std::int64_t y = s.y_begin; y < s.y_end; ++y) {
    std::int64_t xb = 0, xe = 0;
    kept_columns(keep, y, s.x_begin, s.x_end, xb, xe);
    const auto width = static_cast<std::size_t>(xe - xb);
    count.scanned += width;
    const std::uint8_t* row = image.pixels + static_cast<std::size_t>(y) * image.stride;
    if (out.size() - count.written >= width) {
      // Room for a whole row: write every pixel's slot and advance only past
      // features. Noise makes "is this a feature" unpredictable, and this
      // loop has no branch on it (measured 2-5x faster on noisy frames).
      RoiPoint* o = out.data();
      std::uint32_t n = count.written;
      const auto r = static_cast<std::uint16_t>(y - window.y0);
      for (std::int64_t x = xb; x < xe; ++x) {
        o[n] = {static_cast<std::uint16_t>(x - window.x0), r};
        n += row[x] != 0;
      }
      count.written = n;
    } else {
      for (std::int64_t x = xb; x < xe; ++x) {
        if (row[x] != 0) emit(out, count, window, x, y);
      }
    }
  }
  return Status::kOk;
}

Status extract_gradient_rows(const ImageView& image, const ImageWindow& window, std::uint16_t threshold,
                             std::span<RoiPoint> out, FeatureCount& count) noexcept {
  GABARIT_TRY(check(image, window));
  if (threshold == 0) return Status::kInvalidArgument;  // every pixel would pass: rows, not edges
  count = {};
  // Only interior pixels have a full 3x3 neighbourhood.
  const Span2 s = clip(window, 1, std::int64_t{image.width} - 1, 1, std::int64_t{image.height} - 1);
  if (s.empty()) return Status::kOk;
  count.scanned = static_cast<std::uint64_t>(s.x_end - s.x_begin) * static_cast<std::uint64_t>(s.y_end - s.y_begin);
  for (std::int64_t y = s.y_begin; y < s.y_end; ++y) {
    bool in_run = false;
    std::uint16_t best = 0;
    std::int64_t best_x = 0;
    for (std::int64_t x = s.x_begin; x < s.x_end; ++x) {
      const std::uint16_t m = gradient_magnitude(image, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
      if (m >= threshold) {
        if (!in_run || m > best) {
          best = m;
          best_x = x;
        }
        in_run = true;
      } else if (in_run) {
        emit(out, count, window, best_x, y);
        in_run = false;
      }
    }
    if (in_run) emit(out, count, window, best_x, y);
  }
  return Status::kOk;
}

namespace {

inline std::uint16_t magnitude_at(const ImageView& image, std::int64_t x, std::int64_t y) noexcept {
  return gradient_magnitude(image, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y));
}

// A pixel whose magnitude m has passed the low threshold: kept if it is a
// maximum across the edge (m >= the neighbour ahead, m > the one behind) and
// strong, or weak with a strong 8-neighbour. at(i, j) is the magnitude at
// (x + i, y + j); both paths below answer it the same.
template <typename MagnitudeAt>
inline bool canny_keeps(std::int32_t gx, std::int32_t gy, std::uint16_t m, std::uint16_t high, const MagnitudeAt& at) noexcept {
  const std::int32_t ax = abs32(gx), ay = abs32(gy);
  // Neighbours across the edge: tan(22.5 deg) = 0.41421 in integers.
  std::int32_t dx = 0, dy = 0;
  if (std::int64_t{ay} * 100000 <= std::int64_t{ax} * 41421) {
    dx = 1;  // gradient mostly horizontal
  } else if (std::int64_t{ay} * 41421 >= std::int64_t{ax} * 100000) {
    dy = 1;  // mostly vertical
  } else {
    dx = 1;
    dy = (gx > 0) == (gy > 0) ? 1 : -1;
  }
  if (m < at(dx, dy) || m <= at(-dx, -dy)) return false;
  if (m >= high) return true;
  for (std::int32_t j = -1; j <= 1; ++j)
    for (std::int32_t i = -1; i <= 1; ++i)
      if ((i != 0 || j != 0) && at(i, j) >= high) return true;
  return false;
}

// Magnitudes of image row y over columns [x_first, x_last], 0 on the image
// border (as gradient_magnitude).
void magnitude_row(const ImageView& image, std::int64_t y, std::int64_t x_first, std::int64_t x_last, std::uint16_t* row) noexcept {
  const std::int64_t inner_first = x_first < 1 ? 1 : x_first;
  const std::int64_t inner_last = x_last > std::int64_t{image.width} - 2 ? std::int64_t{image.width} - 2 : x_last;
  for (std::int64_t x = x_first; x <= x_last; ++x) row[x - x_first] = 0;
  if (y < 1 || y + 1 >= std::int64_t{image.height}) return;
  if (inner_first > inner_last) return;
  const std::uint8_t* up = image.pixels + static_cast<std::size_t>(y - 1) * image.stride + inner_first;
  const std::uint8_t* mid = up + image.stride;
  const std::uint8_t* down = mid + image.stride;
  canny_rows::sobel_magnitudes(up, mid, down, static_cast<std::size_t>(inner_last - inner_first + 1),
                               row + (inner_first - x_first));
}

}  // namespace

Status extract_canny(const ImageView& image, const ImageWindow& window, std::uint16_t threshold, std::span<RoiPoint> out,
                     FeatureCount& count, std::span<std::uint16_t> magnitude_rows, const TurnedRectangle* keep) noexcept {
  GABARIT_TRY(check(image, window));
  if (threshold < 2) return Status::kInvalidArgument;  // the low threshold would be 0
  count = {};
  const std::uint16_t high = threshold, low = static_cast<std::uint16_t>(threshold / 2);
  const Span2 s = clip(window, 1, std::int64_t{image.width} - 1, 1, std::int64_t{image.height} - 1);
  if (s.empty()) return Status::kOk;
  const auto columns = static_cast<std::size_t>(s.x_end - s.x_begin) + 2;  // one more on each side
  std::int64_t xb = 0, xe = 0;
  if (magnitude_rows.size() < 3 * columns) {
    // The reference: every magnitude from the image, as often as it is needed.
    for (std::int64_t y = s.y_begin; y < s.y_end; ++y) {
      kept_columns(keep, y, s.x_begin, s.x_end, xb, xe);
      count.scanned += static_cast<std::uint64_t>(xe - xb);
      for (std::int64_t x = xb; x < xe; ++x) {
        const SobelGradient g = sobel_interior(image, static_cast<std::size_t>(x), static_cast<std::size_t>(y));
        const auto m = static_cast<std::uint16_t>(abs32(g.gx) + abs32(g.gy));
        if (m < low) continue;
        const auto at = [&](std::int32_t i, std::int32_t j) { return magnitude_at(image, x + i, y + j); };
        if (canny_keeps(g.gx, g.gy, m, high, at)) emit(out, count, window, x, y);
      }
    }
    return Status::kOk;
  }
  // Rows y - 1, y and y + 1 of magnitudes, at columns x_begin - 1 .. x_end
  // (entry c is column x_begin - 1 + c). A row's magnitudes are computed
  // where the rows it serves (itself and its neighbours) scan, a column more
  // on each side: nothing else is read.
  const std::int64_t base = s.x_begin - 1;
  const auto fill = [&](std::int64_t k, std::uint16_t* row) {
    std::int64_t first = s.x_end, last = s.x_begin - 1;
    for (std::int64_t j = k - 1; j <= k + 1; ++j) {
      if (j < s.y_begin || j >= s.y_end) continue;
      kept_columns(keep, j, s.x_begin, s.x_end, xb, xe);
      if (xb >= xe) continue;
      first = xb < first ? xb : first;
      last = xe - 1 > last ? xe - 1 : last;
    }
    if (first <= last) magnitude_row(image, k, first - 1, last + 1, row + (first - 1 - base));
  };
  std::uint16_t* rows[3] = {magnitude_rows.data(), magnitude_rows.data() + columns, magnitude_rows.data() + 2 * columns};
  fill(s.y_begin - 1, rows[0]);
  fill(s.y_begin, rows[1]);
  for (std::int64_t y = s.y_begin; y < s.y_end; ++y) {
    fill(y + 1, rows[2]);
    kept_columns(keep, y, s.x_begin, s.x_end, xb, xe);
    count.scanned += static_cast<std::uint64_t>(xe - xb);
    // Whole vectors of the row decided at once where there is a vector
    // body (canny_rows.hpp), the rest pixel by pixel below.
    const std::uint8_t* const up = image.pixels + static_cast<std::size_t>(y - 1) * image.stride + base;
    const canny_rows::DecisionRow decision{rows[0], rows[1], rows[2], up, up + image.stride, up + 2 * image.stride,
                                           low, high};
    std::int64_t x = xb;
    for (std::size_t done = 1; done > 0 && x < xe; x += static_cast<std::int64_t>(done)) {
      const auto begin = static_cast<std::size_t>(x - base), end = static_cast<std::size_t>(xe - base);
      const std::uint64_t kept = canny_rows::decide(decision, begin, end, done);
      // 32 bits at a time: a 64-bit count of trailing zeros is a libgcc call
      // on 32-bit targets (__ctzdi2), which the firmware's stack analysis cannot see into.
      for (std::int64_t half = 0; half < 2; ++half) {
        for (auto bits = static_cast<std::uint32_t>(kept >> (32 * half)); bits != 0; bits &= bits - 1)
          emit(out, count, window, x + 32 * half + std::countr_zero(bits), y);
      }
    }
    for (; x < xe; ++x) {
      const std::int64_t c = x - base;
      const std::uint16_t m = rows[1][c];
      if (m < low) continue;
      const SobelGradient g = sobel_interior(image, static_cast<std::size_t>(x), static_cast<std::size_t>(y));
      const auto at = [&](std::int32_t i, std::int32_t j) { return rows[1 + j][c + i]; };
      if (canny_keeps(g.gx, g.gy, m, high, at)) emit(out, count, window, x, y);
    }
    std::uint16_t* const oldest = rows[0];
    rows[0] = rows[1];
    rows[1] = rows[2];
    rows[2] = oldest;
  }
  return Status::kOk;
}

const char* canny_vector_body() noexcept { return canny_rows::vector_target(); }

Status extract_features(const ImageView& image, const ImageWindow& window, table_format::DetectorKind kind,
                        std::uint16_t threshold, std::span<RoiPoint> out, FeatureCount& count,
                        std::span<std::uint16_t> magnitude_rows, const TurnedRectangle* keep) noexcept {
  switch (kind) {
    case table_format::DetectorKind::kBinary: return extract_binary(image, window, out, count, keep);
    case table_format::DetectorKind::kGradientRows:
      return extract_gradient_rows(image, window, threshold, out, count);
    case table_format::DetectorKind::kCanny: return extract_canny(image, window, threshold, out, count, magnitude_rows, keep);
  }
  return Status::kInvalidArgument;
}

}  // namespace gabarit
