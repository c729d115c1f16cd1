#include "gabarit/host/stencil.hpp"

#include <algorithm>
#include <cmath>

#include "gabarit/deterministic_math.hpp"

namespace gabarit::host {

IntegerRange integer_translations(float lo, float hi) {
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

std::vector<Point> stencil(const std::vector<Point>& points, const CellBounds& cell) {
  const std::vector<Point> arcs = swept_arcs(points, cell.theta_lo_deg, cell.theta_hi_deg);
  const IntegerRange tx = integer_translations(cell.x_lo, cell.x_hi);
  const IntegerRange ty = integer_translations(cell.y_lo, cell.y_hi);
  std::vector<Point> out;
  out.reserve(arcs.size() * static_cast<std::size_t>(tx.last - tx.first + 1) * static_cast<std::size_t>(ty.last - ty.first + 1));
  for (std::int32_t dx = tx.first; dx <= tx.last; ++dx)
    for (std::int32_t dy = ty.first; dy <= ty.last; ++dy)
      for (const Point& a : arcs) out.push_back({a.x + dx, a.y + dy});
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace gabarit::host
