#include "gabarit/host/tables/stencil.hpp"

#include <algorithm>
#include <cmath>

#include "gabarit/deterministic_math.hpp"

namespace gabarit::host {

IntegerRange integer_translations(float lo, float hi, TranslationPolicy policy) {
  if (policy == TranslationPolicy::kEnclosing)
    return {static_cast<std::int32_t>(std::floor(lo)), static_cast<std::int32_t>(std::ceil(hi))};
  const auto first = static_cast<std::int32_t>(std::ceil(lo));
  const auto last = static_cast<std::int32_t>(std::floor(hi));
  if (first <= last) return {first, last};
  const std::int32_t nearest = round_to_int((lo + hi) * 0.5f);
  return {nearest, nearest};
}

std::vector<Point> swept_arcs(const std::vector<Point>& points, float theta_lo_deg, float theta_hi_deg) {
  double radius = 0;
  for (const Point& p : points) radius = std::max(radius, std::hypot(double(p.x), double(p.y)));
  const double span_rad = (static_cast<double>(theta_hi_deg) - theta_lo_deg) * 3.14159265358979323846 / 180.0;
  // Samples 0..steps: consecutive samples move the farthest point by <= 0.5 px.
  const auto steps = static_cast<std::uint32_t>(std::max(0.0, std::ceil(span_rad * radius / 0.5)));
  std::vector<Point> out;
  out.reserve(points.size() * (steps + 1));
  for (std::uint32_t s = 0; s <= steps; ++s) {
    const float angle = steps == 0 ? theta_lo_deg
                                   : static_cast<float>(theta_lo_deg + (static_cast<double>(theta_hi_deg) - theta_lo_deg) * s / steps);
    // Kernel's deterministic sin/cos: the same rotation the tracker applies.
    const SinCos sc = sin_cos_deg(angle);
    for (const Point& p : points) {
      const float x = static_cast<float>(p.x), y = static_cast<float>(p.y);
      out.push_back({round_to_int(sc.cos * x - sc.sin * y), round_to_int(sc.sin * x + sc.cos * y)});
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<Point> translate_sweep(const std::vector<Point>& arcs, const CellBounds& cell, TranslationPolicy policy) {
  const IntegerRange tx = integer_translations(cell.x_lo, cell.x_hi, policy);
  const IntegerRange ty = integer_translations(cell.y_lo, cell.y_hi, policy);
  std::vector<Point> out;
  if (arcs.empty()) return out;
  if (tx.first == tx.last && ty.first == ty.last) {
    // One translation (cells up to a pixel wide): a shift keeps the order.
    out.reserve(arcs.size());
    for (const Point& a : arcs) out.push_back({a.x + tx.first, a.y + ty.first});
    return out;
  }
  // Several: mark the swept pixels in a bitmap over the stencil's bounding box
  // and read it column by column, which is (x, y) order.
  std::int32_t min_x = arcs.front().x, max_x = arcs.back().x, min_y = arcs.front().y, max_y = min_y;
  for (const Point& a : arcs) {
    min_y = std::min(min_y, a.y);
    max_y = std::max(max_y, a.y);
  }
  const auto w = static_cast<std::size_t>(max_x - min_x + 1 + tx.last - tx.first);
  const auto h = static_cast<std::size_t>(max_y - min_y + 1 + ty.last - ty.first);
  std::vector<std::uint8_t> covered(w * h, 0);  // column-major: index = x * h + y
  for (const Point& a : arcs) {
    const auto x0 = static_cast<std::size_t>(a.x - min_x), y0 = static_cast<std::size_t>(a.y - min_y);
    for (std::int32_t dx = 0; dx <= tx.last - tx.first; ++dx) {
      std::uint8_t* column = &covered[(x0 + static_cast<std::size_t>(dx)) * h + y0];
      for (std::int32_t dy = 0; dy <= ty.last - ty.first; ++dy) column[dy] = 1;
    }
  }
  for (std::size_t x = 0; x < w; ++x)
    for (std::size_t y = 0; y < h; ++y)
      if (covered[x * h + y])
        out.push_back({min_x + tx.first + static_cast<std::int32_t>(x), min_y + ty.first + static_cast<std::int32_t>(y)});
  return out;
}

}  // namespace gabarit::host
