#include "gabarit/refinement.hpp"

#include "gabarit/assert.hpp"

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

}  // namespace gabarit
