#include "gabarit/refinement.hpp"

// Eigen as in motion_filter.cpp: fixed-size floats, no heap, scalar code.
#include <Eigen/Core>
#include <Eigen/Cholesky>

#include "gabarit/assert.hpp"
#include "gabarit/deterministic_math.hpp"

namespace gabarit {
namespace {

float score_of(const TableView& table, std::span<const VoteCounter> counters, std::uint32_t cell) noexcept {
  return normalised_score({cell, counters[cell], table.cell(cell).stencil_size});
}

// Offset (in spacings) of the parabola's vertex through three scores.
float vertex(float before, float at, float after) noexcept {
  const float curvature = before - 2.0f * at + after;
  if (!(curvature < 0.0f)) return 0.0f;  // not a peak (flat or a valley): keep the centre
  float t = 0.5f * (before - after) / curvature;
  if (t > 0.5f) t = 0.5f;
  if (t < -0.5f) t = -0.5f;
  return t;
}

float spacing(const Axis& a) noexcept { return a.cells > 1 ? (a.max - a.min) / static_cast<float>(a.cells - 1) : 0.0f; }

}  // namespace

SubCellOffset refine_within_cell(const TableView& table, std::span<const VoteCounter> counters, std::uint32_t cell) noexcept {
  GABARIT_ASSERT(cell < table.cell_count() && counters.size() == voter_counter_count(table.cell_count()));
  const Axis ax = table.axis_x(), ay = table.axis_y(), at = table.axis_theta();
  // index = ((depth * theta_cells + i_theta) * y_cells + i_y) * x_cells + i_x
  const std::uint32_t ix = cell % ax.cells;
  const std::uint32_t iy = (cell / ax.cells) % ay.cells;
  const std::uint32_t it = (cell / (ax.cells * ay.cells)) % at.cells;
  const std::uint32_t stride_y = ax.cells, stride_t = ax.cells * ay.cells;
  const float s0 = score_of(table, counters, cell);
  SubCellOffset out;
  if (ix > 0 && ix + 1 < ax.cells)
    out.x = spacing(ax) * vertex(score_of(table, counters, cell - 1), s0, score_of(table, counters, cell + 1));
  if (iy > 0 && iy + 1 < ay.cells)
    out.y = spacing(ay) * vertex(score_of(table, counters, cell - stride_y), s0, score_of(table, counters, cell + stride_y));
  if (it > 0 && it + 1 < at.cells)
    out.theta_deg = spacing(at) * vertex(score_of(table, counters, cell - stride_t), s0, score_of(table, counters, cell + stride_t));
  return out;
}

bool refine_by_alignment(const TableView& table, std::span<const RoiPoint> features, std::span<std::uint8_t> occupancy,
                         std::uint32_t cell, SubCellOffset& out) noexcept {
  out = SubCellOffset{};
  GABARIT_ASSERT(cell < table.cell_count());
  const std::uint32_t w = table.roi_width(), h = table.roi_height();
  if (occupancy.size() < (std::size_t{w} * h + 7) / 8) return false;
  // The features as a bitmap over the ROI.
  for (std::size_t i = 0; i < (std::size_t{w} * h + 7) / 8; ++i) occupancy[i] = 0;
  for (const RoiPoint& f : features) {
    const std::size_t at = std::size_t{f.row} * w + table.feature_column(f);  // the pixel, whatever its channel
    occupancy[at >> 3] = static_cast<std::uint8_t>(occupancy[at >> 3] | (1u << (at & 7u)));
  }
  const auto feature_at = [&](std::int32_t col, std::int32_t row) {
    if (col < 0 || row < 0 || col >= static_cast<std::int32_t>(w) || row >= static_cast<std::int32_t>(h)) return false;
    const std::size_t at = static_cast<std::size_t>(row) * w + static_cast<std::size_t>(col);
    return ((static_cast<unsigned>(occupancy[at >> 3]) >> (at & 7u)) & 1u) != 0;
  };
  const CellBounds c = table.cell(cell);
  const std::uint16_t depth = c.depth;
  std::uint32_t first = 0;
  for (std::uint16_t d = 0; d < depth; ++d) first += table.model_point_count(d);
  const std::uint32_t count = table.model_point_count(depth);
  const float ox = static_cast<float>(table.roi_origin_x()), oy = static_cast<float>(table.roi_origin_y());
  constexpr float kRadians = 3.14159265358979f / 180.0f;

  float dx = 0.0f, dy = 0.0f, dtheta_deg = 0.0f;
  for (int iteration = 0; iteration < 2; ++iteration) {
    const SinCos sc = sin_cos_deg(c.theta_centre_deg() + dtheta_deg);
    const float tx = c.x_centre() + dx, ty = c.y_centre() + dy;
    Eigen::Matrix3f normal = Eigen::Matrix3f::Zero();
    Eigen::Vector3f rhs = Eigen::Vector3f::Zero();
    std::uint32_t matches = 0;
    for (std::uint32_t i = 0; i < count; ++i) {
      const ModelPoint m = table.model_point(first + i);
      // The model point placed, relative to the reference (qx, qy) and in ROI pixels (px, py).
      const float qx = sc.cos * m.x - sc.sin * m.y, qy = sc.sin * m.x + sc.cos * m.y;
      const float px = tx + qx - ox, py = ty + qy - oy;
      const std::int32_t cx = round_to_int(px), cy = round_to_int(py);
      float best = 1.0e9f, fx = 0.0f, fy = 0.0f;
      for (std::int32_t v = -kAlignRadius; v <= kAlignRadius; ++v)
        for (std::int32_t u = -kAlignRadius; u <= kAlignRadius; ++u) {
          if (!feature_at(cx + u, cy + v)) continue;
          const float ex = static_cast<float>(cx + u) - px, ey = static_cast<float>(cy + v) - py;
          if (ex * ex + ey * ey < best) best = ex * ex + ey * ey, fx = ex, fy = ey;
        }
      if (best > static_cast<float>(2 * kAlignRadius * kAlignRadius)) continue;
      ++matches;
      // Residual (fx, fy) = feature - placed point; d(placed)/d(x, y, theta) = [1 0 -qy; 0 1 qx].
      const Eigen::Vector3f jx(1.0f, 0.0f, -qy), jy(0.0f, 1.0f, qx);
      normal += jx * jx.transpose() + jy * jy.transpose();
      rhs += jx * fx + jy * fy;
    }
    if (matches < kAlignMinMatches) return false;
    const Eigen::LDLT<Eigen::Matrix3f> solver(normal);
    if (solver.info() != Eigen::Success || !(solver.vectorD().minCoeff() > 1.0e-3f)) return false;
    const Eigen::Vector3f step = solver.solve(rhs);
    if (!is_finite(step(0)) || !is_finite(step(1)) || !is_finite(step(2))) return false;
    dx += step(0);
    dy += step(1);
    dtheta_deg += step(2) / kRadians;
  }
  const Axis ax = table.axis_x(), ay = table.axis_y(), at = table.axis_theta();
  const auto clamp_half = [](float v, float spacing_of_axis) {
    const float half = 0.5f * spacing_of_axis;
    return v > half ? half : (v < -half ? -half : v);
  };
  out.x = ax.cells > 1 ? clamp_half(dx, spacing(ax)) : 0.0f;
  out.y = ay.cells > 1 ? clamp_half(dy, spacing(ay)) : 0.0f;
  out.theta_deg = at.cells > 1 ? clamp_half(dtheta_deg, spacing(at)) : 0.0f;
  return true;
}

}  // namespace gabarit
